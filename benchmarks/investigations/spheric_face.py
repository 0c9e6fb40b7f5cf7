"""SPHERIC Test 2: what the water does at the box's front face (issue 25, rows P3 impulse and
first water on the top face).

    python benchmarks/investigations/spheric_face.py TAG [--spacing 0.04] [--end 1.4] [--start 0.3]
        [--dump T ...] [--set key=value ...]

time.dt = "auto" unless --set says otherwise. At every output from --start (0.3 s) records
(runs/spheric_face_TAG.npz; the rows' measures in runs/spheric_face_TAG.json and printed:
first p > 500 Pa and the first-impact impulse at P1, P3, P5, P7, their mean over 0.45-0.7 s):
- every probe as configured, and the particle count in the windows of P1, P3, P5, P7;
- the water's height at the front face: the highest particle and the volume height
  (particle volume / strip area) in the strip [face, face + h] x [y_c - h, y_c + h], and the
  same over the whole face width;
- the particles' mean pressure in z bins of the same strip and the nodal pressure on the
  face's centre line (x = face, face + h) at the heights of the grid's nodes;
- the jet: the highest particle within 2 h in front of the face (over the box's width),
  the mean vertical velocity of the 5 highest, their distance from the face;
- the water above the top face: particle count, volume, highest particle;
- the incoming flow: mean u and depth of the particles 2-4 h upstream of the face;
- contact: how many obstacle nodes of the front face carry a pressure unknown and how many
  of those are released (not held) at the end of the last step;
- the nodes of the face's centre line (y nearest 0.471 m; x: the last node plane before
  the face and the next two; z = 0-0.24 m): whether each is a pressure unknown, held, and
  its pressure.
--dump T ...: the particles with x < 1.2 m at those output times (runs/..._dump.npz).
"""

import argparse
import json
from pathlib import Path

import numpy as np

from mpmflow import Simulation, load_case
from mpmflow.diagnostics import probes as P
from mpmflow.validation import spheric

ROOT = Path(__file__).resolve().parents[2]
FACE, Y0, Y1, TOP, BACK = 0.8245, 0.2955, 0.6985, 0.161, 0.6635
YC = 0.471

ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
ap.add_argument("tag")
ap.add_argument("--spacing", type=float, default=0.04)
ap.add_argument("--end", type=float, default=1.4)
ap.add_argument("--start", type=float, default=0.3)
ap.add_argument("--set", action="append", default=[])
ap.add_argument(
    "--dump",
    type=float,
    nargs="*",
    default=[],
    help="times (s) at which to keep the particles with x < 1.2 m",
)
cli = ap.parse_args()
over = spheric.overrides(cli.spacing, cli.end) + ['time.dt="auto"'] + cli.set
case = load_case(ROOT / "examples" / "spheric_test2.toml", ["output.snapshots=false", *over])
sim = Simulation(case)
grid = sim.grid
h = grid.spacing
nodes = np.array(grid.nodes)
probes = {p.name: p for p in case.probes}
ZS = np.arange(0.0, 0.6 + 1e-9, h / 2)
rec = {}
dumps = {}


def put(k, v):
    rec.setdefault(k, []).append(v)


def nodal(points):
    p = sim.scheme.p_node.reshape(-1)
    s = np.asarray(points) / h
    i0 = np.clip(np.floor(s).astype(int), 0, nodes - 2)
    w = s - i0
    val = np.zeros(len(points))
    for c in np.ndindex(2, 2, 2):
        c = np.array(c)
        idx = i0 + c
        flat = idx[:, 0] + nodes[0] * (idx[:, 1] + nodes[1] * idx[:, 2])
        val += np.prod(np.where(c, w, 1 - w), axis=1) * p[flat]
    return val


# the front face's obstacle nodes: corners of cut cells, normal (into the solid) along -x
tab = sim.scheme.solids
onode = np.asarray(tab.node)
onorm = np.asarray(tab.normal)
ix = np.stack(np.unravel_index(onode, tuple(nodes[::-1]))[::-1], axis=1)
xyz = ix * h
front = (onorm[:, 0] < -0.7) & (xyz[:, 1] > Y0 - h) & (xyz[:, 1] < Y1 + h)
IX0 = int(np.floor(FACE / h + 1e-9))
IY = int(round(YC / h))
IZ = np.arange(int(round(0.24 / h)) + 1)
LINE = np.array(
    [[ixx + nodes[0] * (IY + nodes[1] * iz) for iz in IZ] for ixx in (IX0, IX0 + 1, IX0 + 2)]
)  # (3, nz) flat node indices


def on_output(s):
    if s.time < cli.start - 1e-9:
        return
    x, v, pr, vol = s.particles.x, s.particles.v, s.particles.pressure, s.particles.volume
    put("t", s.time)
    for td in cli.dump:
        if abs(s.time - td) < 1e-6:
            near = x[:, 0] < 1.2
            dumps[f"x_{td:g}"] = x[near].copy()
            dumps[f"v_{td:g}"] = v[near].copy()
            dumps[f"p_{td:g}"] = pr[near].copy()
    bins = s._bins()
    dist = s.scheme.solids.distance
    row = P.measure(case, grid, s.particles, bins, s.time, dist)
    for name in probes:
        put(name, row[name])
    for name in ("P1", "P3", "P5", "P7"):
        q = probes[name]
        lo, hi = P.window_box(q.position, P.window(q, grid, case), grid.size, dist)
        inside = np.all((x >= lo) & (x <= hi), axis=1)
        put(name + "_n", int(inside.sum()))
    inbox_y = (x[:, 1] > Y0) & (x[:, 1] < Y1)
    strip = (x[:, 0] >= FACE) & (x[:, 0] < FACE + h)
    centre = strip & (np.abs(x[:, 1] - YC) < h)
    put("hc_max", float(x[centre, 2].max()) if centre.any() else 0.0)
    put("hc_vol", float(vol[centre].sum() / (h * 2 * h)))
    wide = strip & inbox_y
    put("hw_max", float(x[wide, 2].max()) if wide.any() else 0.0)
    put("hw_vol", float(vol[wide].sum() / (h * (Y1 - Y0))))
    # particle pressure in z bins of the centre strip
    zb = np.arange(0.0, 0.6 + 1e-9, h / 2)
    pb = np.full(zb.size - 1, np.nan)
    which = np.digitize(x[centre, 2], zb) - 1
    for k in range(zb.size - 1):
        sel = which == k
        if sel.any():
            pb[k] = pr[centre][sel].mean()
    put("p_strip", pb)
    pts = np.stack([np.full(ZS.size, FACE), np.full(ZS.size, YC), ZS], axis=1)
    put("p_face", nodal(pts))
    pts[:, 0] = FACE + h
    put("p_face1", nodal(pts))
    jet = (x[:, 0] >= FACE - 0.5 * h) & (x[:, 0] < FACE + 2 * h) & inbox_y
    if jet.any():
        zj = x[jet, 2]
        top5 = np.argsort(zj)[-5:]
        put("jet_z", float(zj.max()))
        put("jet_w", float(v[jet, 2][top5].mean()))
        put("jet_u", float(v[jet, 0][top5].mean()))
        put("jet_dx", float((x[jet, 0][top5] - FACE).mean()))
    else:
        for k in ("jet_z", "jet_w", "jet_u", "jet_dx"):
            put(k, np.nan)
    above = (x[:, 0] > BACK) & (x[:, 0] < FACE) & inbox_y & (x[:, 2] > TOP)
    put("top_n", int(above.sum()))
    put("top_vol", float(vol[above].sum()))
    put("top_zmax", float(x[above, 2].max()) if above.any() else np.nan)
    # anything above the box's footprint, including the jet in the air above the top
    over_ = (x[:, 0] > BACK - h) & (x[:, 0] < FACE + h) & inbox_y & (x[:, 2] > TOP + h)
    put("air_n", int(over_.sum()))
    up = (x[:, 0] > FACE + 2 * h) & (x[:, 0] < FACE + 4 * h) & (np.abs(x[:, 1] - YC) < h)
    put("in_u", float(v[up, 0].mean()) if up.any() else np.nan)
    put("in_depth", float(vol[up].sum() / (2 * h * 2 * h)))
    oc = np.asarray(s.scheme.core.ocontact)
    rows = np.asarray(s.scheme.core.rows)
    wet = np.isin(onode[front], rows)
    put("front_wet", int(wet.sum()))
    put("front_released", int((wet & ~oc[onode[front]].astype(bool)).sum()))
    # the nodes of the face's centre line: x = the last node plane inside the solid and the
    # first two in the water, z = 0 .. 0.24 m: unknown (1) or not (0), held (1) or not, p
    pn = np.asarray(s.scheme.p_node).reshape(-1)
    put("line_row", np.isin(LINE, rows).astype(int))
    put("line_held", oc[LINE].astype(int))
    put("line_p", pn[LINE])


sim.on_output = on_output
sim.run()
exp = spheric.data()
out = {"tag": cli.tag, "over": cli.set, "spacing": cli.spacing, "steps": sim.steps}
t = np.array(rec["t"])
te = exp["time [s]"]
for name in ("P1", "P3", "P5", "P7"):
    p = np.array(rec[name])
    pe = exp[f"{name} [Pa]"]
    t_exp = spheric.first_above(te, pe)
    out[name + "_first"] = spheric.first_above(t, p)
    out[name + "_first_exp"] = t_exp
    lo, hi = t_exp - 0.05, t_exp + 0.3
    if t[-1] >= hi:
        out[name + "_impulse"] = spheric.impulse(t, p, lo, hi)
        out[name + "_impulse_exp"] = spheric.impulse(te, pe, lo, hi)
    w = (t >= 0.45) & (t <= 0.7)
    out[name + "_mean_045_07"] = float(p[w].mean())
    out[name + "_mean_exp"] = float(pe[(te >= 0.45) & (te <= 0.7)].mean())
runs = ROOT / "runs"
runs.mkdir(exist_ok=True)
np.savez(
    runs / f"spheric_face_{cli.tag}.npz",
    zs=ZS,
    line_x=np.array([IX0, IX0 + 1, IX0 + 2]) * h,
    line_z=IZ * h,
    **{k: np.array(v) for k, v in rec.items()},
)
if dumps:
    np.savez(runs / f"spheric_face_{cli.tag}_dump.npz", **dumps)
with open(runs / f"spheric_face_{cli.tag}.json", "w") as f:
    json.dump(out, f, indent=1)
print(json.dumps(out, indent=1))
