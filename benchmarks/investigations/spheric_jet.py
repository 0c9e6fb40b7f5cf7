"""SPHERIC Test 2: the jet that climbs the box's front face and the water's energy (issue 25,
rows P5/P7; docs/notes/benchmarks-diary.md, "Why the jet at the box's face rises faster than its feed").

    python benchmarks/investigations/spheric_jet.py TAG [--spacing 0.04] [--end 1.6] [--set key=value ...]
        [--dump T ...]

time.dt = "auto" unless --set says otherwise. At every output records the water's kinetic
and potential energy (particles), the largest specific energy v^2/2 + g z, the jet (the
highest particle within 2 h in front of the face over the box's width: height, mean
vertical velocity and specific energy of the 5 highest), the incoming flow 2-4 h upstream,
the probes, and the water behind the box; writes runs/spheric_jet_TAG.npz and .json (first
p > 500 Pa at P1, P3, P5, P7, impulses, energy at fixed times) and prints the json.
--dump T ...: every particle's x, v, p at those output times (runs/spheric_jet_TAG_dump.npz).
"""

import argparse
import json
import time as _time
from pathlib import Path

import numpy as np

from mpmflow import Simulation, load_case
from mpmflow.diagnostics import probes as P
from mpmflow.validation import spheric

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "runs"
OUT.mkdir(exist_ok=True)
FACE, Y0, Y1, TOP, BACK = 0.8245, 0.2955, 0.6985, 0.161, 0.6635
YC = 0.471
G = 9.81
ap = argparse.ArgumentParser()
ap.add_argument("tag")
ap.add_argument("--spacing", type=float, default=0.04)
ap.add_argument("--end", type=float, default=1.6)
ap.add_argument("--start", type=float, default=0.0)
ap.add_argument("--set", action="append", default=[])
ap.add_argument("--dump", type=float, nargs="*", default=[])
cli = ap.parse_args()
over = spheric.overrides(cli.spacing, cli.end) + ['time.dt="auto"'] + cli.set
case = load_case(ROOT / "examples" / "spheric_test2.toml", ["output.snapshots=false", *over])
sim = Simulation(case)
h = sim.grid.spacing
probes = {p.name: p for p in case.probes}
rec = {}
dumps = {}


def put(k, v):
    rec.setdefault(k, []).append(v)


t0 = _time.time()


def on_output(s):
    if s.time < cli.start - 1e-9:
        return
    x, v, m = s.particles.x, s.particles.v, s.particles.mass
    put("t", s.time)
    for td in cli.dump:
        if abs(s.time - td) < 1e-6:
            dumps[f"x_{td:g}"] = x.copy()
            dumps[f"v_{td:g}"] = v.copy()
            dumps[f"p_{td:g}"] = s.particles.pressure.copy()
    ke = 0.5 * float((m * (v**2).sum(1)).sum())
    pe = G * float((m * x[:, 2]).sum())
    put("ke", ke)
    put("pe", pe)
    e = 0.5 * (v**2).sum(1) + G * x[:, 2]  # specific energy J/kg
    put("emax", float(e.max()))
    put("e99", float(np.percentile(e, 99.9)))
    put("vmax", float(np.sqrt((v**2).sum(1)).max()))
    bins = s._bins()
    row = P.measure(case, s.grid, s.particles, bins, s.time, s.scheme.solids.distance)
    put("m_behind", float(m[x[:, 0] < BACK].sum()))
    put("m_x03", float(m[x[:, 0] < 0.3].sum()))
    put("m_air04", float(m[x[:, 2] > 0.4].sum()))
    put("m_behind_air", float(m[(x[:, 0] < BACK) & (x[:, 2] > 0.4)].sum()))
    for name in ("P1", "P3", "P5", "P6", "P7", "P8", "H1", "H2", "H3", "H4"):
        put(name, row[name])
    inbox_y = (x[:, 1] > Y0) & (x[:, 1] < Y1)
    jet = (x[:, 0] >= FACE - 0.5 * h) & (x[:, 0] < FACE + 2 * h) & inbox_y
    if jet.any():
        zj = x[jet, 2]
        top5 = np.argsort(zj)[-5:]
        put("jet_z", float(zj.max()))
        put("jet_w", float(v[jet, 2][top5].mean()))
        put("jet_e", float(e[jet][top5].mean()))
        put("jet_emax", float(e[jet].max()))
        hi = jet & (x[:, 2] > 0.22)
        put("jet_m22", float(m[hi].sum()))
        put("jet_wmax", float(v[jet, 2].max()))
    else:
        for k in ("jet_z", "jet_w", "jet_e", "jet_emax", "jet_m22", "jet_wmax"):
            put(k, np.nan)
    up = (x[:, 0] > FACE + 2 * h) & (x[:, 0] < FACE + 4 * h) & (np.abs(x[:, 1] - YC) < h)
    put("in_u", float(v[up, 0].mean()) if up.any() else np.nan)
    put("in_depth", float(s.particles.volume[up].sum() / (2 * h * 2 * h)))
    put("in_emax", float(e[up].max()) if up.any() else np.nan)
    # upstream of the face across the box's width, 0-6 h: specific energy
    upw = (x[:, 0] > FACE + 0.5 * h) & (x[:, 0] < FACE + 6 * h) & inbox_y
    put("up_emax", float(e[upw].max()) if upw.any() else np.nan)
    put("up_emean", float((m[upw] * e[upw]).sum() / m[upw].sum()) if upw.any() else np.nan)
    above = (x[:, 0] > BACK) & (x[:, 0] < FACE) & inbox_y & (x[:, 2] > TOP)
    put("top_n", int(above.sum()))


sim.on_output = on_output
sim.run()
t = np.array(rec["t"])
out = {
    "tag": cli.tag,
    "set": cli.set,
    "spacing": cli.spacing,
    "steps": sim.steps,
    "wall": _time.time() - t0,
}
exp = spheric.data()
te = exp["time [s]"]
for name in ("P5", "P7"):
    out[name + "_first"] = spheric.first_above(t, np.array(rec[name]))
    out[name + "_first_exp"] = spheric.first_above(te, exp[f"{name} [Pa]"])
for name in ("P1", "P3"):
    p = np.array(rec[name])
    pe = exp[f"{name} [Pa]"]
    t_exp = spheric.first_above(te, pe)
    out[name + "_first"] = spheric.first_above(t, p)
    if t[-1] >= t_exp + 0.3:
        out[name + "_impulse"] = spheric.impulse(t, p, t_exp - 0.05, t_exp + 0.3)
        out[name + "_impulse_exp"] = spheric.impulse(te, pe, t_exp - 0.05, t_exp + 0.3)
E = np.array(rec["ke"]) + np.array(rec["pe"])


def at(k, tt):
    return float(np.interp(tt, t, np.array(rec[k], float)))


out["E0"] = float(E[0]) if t[0] < 1e-9 else None
for tt in (0.0, 0.3, 0.4, 0.45, 0.5, 0.55, 0.6, 0.8, 1.0, 1.4):
    if tt <= t[-1]:
        out[f"E_{tt}"] = float(np.interp(tt, t, E))
w = (t >= 0.3) & (t <= 0.6)
dE = np.diff(E[w])
out["E_max_rise_03_06"] = float(dE.max()) if dE.size else None
out["E_net_03_06"] = float(E[w][-1] - E[w][0]) if w.any() else None
w = (t >= 0.44) & (t <= 0.55)
out["jet"] = [
    [round(a, 3), round(b, 3), round(c, 2), round(d, 2), round(e_, 2)]
    for a, b, c, d, e_ in zip(
        t[w],
        np.array(rec["jet_z"])[w],
        np.array(rec["jet_w"])[w],
        np.array(rec["jet_e"])[w],
        np.array(rec["up_emax"])[w],
    )
]
np.savez(OUT / f"spheric_jet_{cli.tag}.npz", **{k: np.array(v) for k, v in rec.items()})
if dumps:
    np.savez(OUT / f"spheric_jet_{cli.tag}_dump.npz", m=sim.particles.mass, **dumps)
json.dump(out, open(OUT / f"spheric_jet_{cli.tag}.json", "w"), indent=1)
print(json.dumps(out, indent=1))
