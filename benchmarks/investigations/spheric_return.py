"""SPHERIC Test 2: the water that comes back behind the box (issue 25, rows P5/P7;
docs/notes/benchmarks-diary.md, "The water behind the box").

    python benchmarks/investigations/spheric_return.py TAG [--spacing 0.04] [--end 1.5] [--set key=value ...]
        [--trace T ...]

time.dt = "auto" unless --set says otherwise. At every output, on three vertical-column
lines along x (y = 0.1 m and 0.9 m beside the box, y = 0.471 m the box's centre line), in
columns of h x h: the water depth (particle volume / h^2; also of the water below
z = 0.2 m), the mean u and the highest particle; the water on the box's top (its mean
layer over the footprint, the column over P7 below z = 0.461 m and the volume fraction of
its lowest cell); the water that arched
over the box (particles that were above the box's top, z > 0.2 m over its footprint, at
some output before): its mass behind the box, in the air (z > 0.2 m) and on the floor
(z < 0.2 m) at x < 0.6635 m, and its mean u there; the probes. --trace T ...: the
particles on the box's top at T, and where they were every 0.05 s before. Writes
runs/spheric_return_TAG.npz and prints the rows (first p > 500 Pa at P5-P8, H1 at
0.95-1.2 s).
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
LINES = (0.1, 0.471, 0.9)
XMAX = 1.6
ap = argparse.ArgumentParser()
ap.add_argument("tag")
ap.add_argument("--spacing", type=float, default=0.04)
ap.add_argument("--end", type=float, default=1.5)
ap.add_argument("--set", action="append", default=[])
ap.add_argument("--trace", type=float, nargs="*", default=[])
cli = ap.parse_args()
over = spheric.overrides(cli.spacing, cli.end) + ['time.dt="auto"'] + cli.set
case = load_case(ROOT / "examples" / "spheric_test2.toml", ["output.snapshots=false", *over])
sim = Simulation(case)
h = sim.grid.spacing
nx = int(round(XMAX / h))
rec: dict[str, list] = {}
arched = None
track: dict[float, np.ndarray] = {}  # particle positions every 0.05 s (for --trace)
vel: dict[float, np.ndarray] = {}


def put(k, v):
    rec.setdefault(k, []).append(v)


t0 = _time.time()


def on_output(s):
    global arched
    x, v, m, vol = s.particles.x, s.particles.v, s.particles.mass, s.particles.volume
    if arched is None:
        arched = np.zeros(len(m), bool)
    put("t", s.time)
    if cli.trace and abs(s.time / 0.05 - round(s.time / 0.05)) < 1e-6:
        track[round(s.time, 3)] = x.copy()
    for tt in cli.trace:
        if abs(s.time - tt) < 1e-6:
            vel[tt] = v.copy()
    ix = np.floor(x[:, 0] / h).astype(int)
    depth, umean, ztop, low = [], [], [], []
    for yl in LINES:
        sel = (np.abs(x[:, 1] - yl) < 0.5 * h) & (ix < nx)
        d = np.bincount(ix[sel], vol[sel], nx) / h**2
        mm = np.bincount(ix[sel], m[sel], nx)
        mu = np.bincount(ix[sel], m[sel] * v[sel, 0], nx)
        lo = sel & (x[:, 2] < 0.2)
        low.append(np.bincount(ix[lo], vol[lo], nx) / h**2)
        zt = np.zeros(nx)
        np.maximum.at(zt, ix[sel], x[sel, 2])
        depth.append(d)
        umean.append(np.where(mm > 0, mu / np.maximum(mm, 1e-30), np.nan))
        ztop.append(zt)
    put("depth", np.array(depth))
    put("u", np.array(umean))
    put("ztop", np.array(ztop))
    put("depth_low", np.array(low))
    over_box = (x[:, 0] > BACK) & (x[:, 0] < FACE) & (x[:, 1] > Y0) & (x[:, 1] < Y1)
    arched |= over_box & (x[:, 2] > 0.2)
    behind = arched & (x[:, 0] < BACK)
    air = behind & (x[:, 2] > 0.2)
    floor = behind & (x[:, 2] <= 0.2)
    put("arched_m", float(m[arched].sum()))
    put("arched_air", float(m[air].sum()))
    put("arched_floor", float(m[floor].sum()))
    put("arched_floor_u", float((m[floor] * v[floor, 0]).sum() / max(m[floor].sum(), 1e-30)))
    put("arched_floor_x", float((m[floor] * x[floor, 0]).sum() / max(m[floor].sum(), 1e-30)))
    put("m_behind", float(m[x[:, 0] < BACK].sum()))
    put("m_behind_c", float(m[(x[:, 0] < BACK) & (x[:, 1] > Y0) & (x[:, 1] < Y1)].sum()))
    put("m_wall", float(m[x[:, 0] < 0.1].sum()))
    # water on the box's top: mean layer over its footprint, and the column over P7 (h x h)
    above = (x[:, 2] > TOP) & (x[:, 2] < TOP + 0.3)
    foot = above & (x[:, 0] > BACK) & (x[:, 0] < FACE) & (x[:, 1] > Y0) & (x[:, 1] < Y1)
    put("top_layer", float(vol[foot].sum()) / ((FACE - BACK) * (Y1 - Y0)))
    p7 = above & (np.abs(x[:, 0] - 0.7235) < 0.5 * h) & (np.abs(x[:, 1] - 0.471) < 0.5 * h)
    put("p7_layer", float(vol[p7].sum()) / h**2)
    put("p7_low", float(vol[p7 & (x[:, 2] < TOP + h)].sum()) / h**3)  # fraction of the cell
    row = P.measure(case, s.grid, s.particles, s._bins(), s.time, s.scheme.solids.distance)
    for name in ("P5", "P6", "P7", "P8", "H1"):
        put(name, row[name])


sim.on_output = on_output
sim.run()
t = np.array(rec["t"])
arrs = {k: np.array(v) for k, v in rec.items()}
np.savez(OUT / f"spheric_return_{cli.tag}.npz", h=h, lines=np.array(LINES), **arrs)
out = {"tag": cli.tag, "set": cli.set, "spacing": cli.spacing, "wall": _time.time() - t0}
for name in ("P5", "P6", "P7", "P8"):
    out[name + "_first"] = spheric.first_above(t, arrs[name])
for tt in (0.95, 1.0, 1.05, 1.1, 1.15, 1.2):
    if tt <= t[-1] + 1e-9:
        out[f"H1_{tt}"] = round(float(np.interp(tt, t, arrs["H1"])), 4)
for tt in cli.trace:
    # the particles on the box's top (within h of it, over its footprint) at tt: where they were
    xt = track[round(tt, 3)]
    on = (xt[:, 0] > BACK) & (xt[:, 0] < FACE) & (xt[:, 1] > Y0) & (xt[:, 1] < Y1)
    on &= (xt[:, 2] > TOP) & (xt[:, 2] < TOP + h)
    print(
        f"trace {tt:g} s: {on.sum()} particles on the top, u w now {vel[tt][on, 0].mean():+.2f}"
        f" {vel[tt][on, 2].mean():+.2f} m/s; earlier: time, mean x y z, share in the air"
        " (z > 0.25 m), share at x < 0.3 m, share beside the box (y < Y0 or y > Y1)"
    )
    for tp in sorted(track):
        if tp > tt + 1e-9 or tp < 0.4:
            continue
        q = track[tp][on]
        side = ((q[:, 1] < Y0) | (q[:, 1] > Y1)).mean()
        print(
            f"  {tp:.2f} {q[:, 0].mean():.2f} {q[:, 1].mean():.2f} {q[:, 2].mean():.2f} "
            f"{(q[:, 2] > 0.25).mean():.2f} {(q[:, 0] < 0.3).mean():.2f} {side:.2f}"
        )
json.dump(out, open(OUT / f"spheric_return_{cli.tag}.json", "w"), indent=1)
print(json.dumps(out))
