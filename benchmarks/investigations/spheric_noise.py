"""SPHERIC Test 2 to t = 1 s: the pressure noise at P1/P3 over 0.45-1.0 s (issue 25, item 2).

noise = RMS of (series - its 50 ms centred moving average: 11 outputs of 5 ms), over the
outputs in 0.45-1.0 s whose average is whole. time.dt = "auto" unless an override sets it.

    python benchmarks/investigations/spheric_noise.py TAG [--spacing 0.04] [--end 1.0] [--set key=value ...]

Reads at every output (one run, several readings): fit (the probe as configured), mean
(the window's mean), fit9/mean9 (a 9 mm window, MARIN's sensor; empty at these meshes),
node (the nodal pressure interpolated at the sensor's point), node1 (one cell off the
face), and the nodal pressure at points away from the box (x_*). Prints one JSON object
(also runs/spheric_noise_TAG.json, the series in runs/spheric_noise_TAG.npz).
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
EXAMPLES = ROOT / "examples"

ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
ap.add_argument("tag", help="the run's name in runs/spheric_noise_TAG.*")
ap.add_argument("--spacing", type=float, default=0.04)
ap.add_argument("--end", type=float, default=1.0)
ap.add_argument("--set", action="append", default=[], help="more overrides (key=value)")
cli = ap.parse_args()
tag, spacing, end = cli.tag, cli.spacing, cli.end
over = spheric.overrides(spacing, end) + ['time.dt="auto"'] + cli.set
case = load_case(EXAMPLES / "spheric_test2.toml", ["output.snapshots=false", *over])
sim = Simulation(case)
SENS = ("P1", "P3")
probes = {p.name: p for p in case.probes}
rec = {
    k: []
    for k in ["t"]
    + [f"{s}_{v}" for s in SENS for v in ("fit", "mean", "fit9", "mean9", "node", "node1")]
}
EXTRA = {
    "far_floor": (1.6, 0.5, 0.02),
    "end_wall": (3.2, 0.5, 0.05),
    "beside": (0.75, 0.2, 0.05),
    "above": (0.75, 0.471, 0.2),
    "front2": (0.9245, 0.471, 0.06),
}
for k in EXTRA:
    rec["x_" + k] = []
grid = sim.grid
h = grid.spacing
nodes = np.array(grid.nodes)


def nodal(point):
    p = sim.scheme.p_node.reshape(-1)
    s = np.asarray(point) / h
    i0 = np.clip(np.floor(s).astype(int), 0, nodes - 2)
    w = s - i0
    val = 0.0
    for c in np.ndindex(*(2,) * grid.dim):
        c = np.array(c)
        idx = i0 + c
        flat = idx[0] + nodes[0] * (idx[1] + nodes[1] * idx[2])
        val += np.prod(np.where(c, w, 1 - w)) * p[flat]
    return float(val)


def on_output(s):
    if s.time < 0.4 - 1e-9:
        return
    bins = s._bins()
    dist = s.scheme.solids.distance
    rec["t"].append(s.time)
    for name in SENS:
        pr = probes[name]
        for est, win, key in (
            ("fit", None, "fit"),
            ("mean", None, "mean"),
            ("fit", 0.009, "fit9"),
            ("mean", 0.009, "mean9"),
        ):
            q = pr.model_copy(update={"estimate": est, "window": win})
            rec[f"{name}_{key}"].append(P.pressure_at(grid, s.particles, bins, q, case, dist))
        pos = np.array(pr.position)
        rec[f"{name}_node"].append(nodal(pos))
        rec[f"{name}_node1"].append(nodal(pos + np.array([h, 0, 0])))
    for k, pt in EXTRA.items():
        rec["x_" + k].append(nodal(pt))


sim.on_output = on_output
reports = []
_adv = sim.scheme.advance


def advance(dt, nsteps, where=""):
    r = _adv(dt, nsteps, where)
    reports.append(
        (
            sim.time,
            r.released,
            r.pockets,
            r.solves,
            getattr(r, "steps", nsteps),
            r.unknowns,
            r.moved_inside,
        )
    )
    return r


sim.scheme.advance = advance
t0 = _time.perf_counter()
sim.run()
wall = _time.perf_counter() - t0
exp = spheric.data()
te = exp["time [s]"]
t = np.array(rec["t"])
keep = (t >= 0.45 - 1e-9) & (t <= 1.0 + 1e-9)


def noise(y):
    y = np.asarray(y)
    k = 5
    ma = np.convolve(y, np.ones(2 * k + 1) / (2 * k + 1), mode="same")
    valid = np.zeros(y.size, bool)
    valid[k : y.size - k] = True
    sel = keep & valid
    return float(np.sqrt(np.mean((y - ma)[sel] ** 2)))


out = {
    "tag": tag,
    "over": cli.set,
    "wall_s": wall,
    "steps": sim.steps,
    "particles": sim.particles.count,
}
wexp = (te >= 0.45) & (te <= 1.0)
for name in SENS:
    mexp = float(exp[f"{name} [Pa]"][wexp].mean())
    out[f"{name}_exp_mean"] = mexp
    out[f"{name}_exp_noise"] = None
    for key in ("fit", "mean", "fit9", "mean9", "node", "node1"):
        y = np.array(rec[f"{name}_{key}"])
        out[f"{name}_{key}_noise"] = noise(y)
        out[f"{name}_{key}_mean"] = float(y[keep].mean())
for k in EXTRA:
    out["x_" + k + "_noise"] = noise(rec["x_" + k])
    out["x_" + k + "_mean"] = float(np.array(rec["x_" + k])[keep].mean())
# the measured signal's own noise by the same metric (resampled to 5 ms)
tt = np.arange(0.40, 1.0501, 0.005)
for name in SENS:
    ye = np.interp(tt, te, exp[f"{name} [Pa]"])
    kk = (tt >= 0.45 - 1e-9) & (tt <= 1.0 + 1e-9)
    ma = np.convolve(ye, np.ones(11) / 11, mode="same")
    out[f"{name}_exp_noise"] = float(np.sqrt(np.mean((ye - ma)[kk] ** 2)))
runs = ROOT / "runs"
runs.mkdir(exist_ok=True)
np.savez(runs / f"spheric_noise_{tag}.npz", **{k: np.array(v) for k, v in rec.items()})
rep = np.array(reports)
out["contact_changes"] = int(rep[:, 1].sum())
out["solves"] = int(rep[:, 3].sum())
out["steps"] = int(rep[:, 4].sum())
with open(runs / f"spheric_noise_{tag}.json", "w") as f:
    json.dump(out, f, indent=1)
print(json.dumps(out, indent=1))
