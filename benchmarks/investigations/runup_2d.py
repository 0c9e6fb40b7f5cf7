"""The 2D dam break's run-up at the right wall and the water's energy (issue 25;
docs/notes/benchmarks-diary.md, "Why the jet at the box's face rises faster than its feed").

    python benchmarks/investigations/runup_2d.py TAG [--case dam_break] [--end 0.6] [--set key=value ...]

Every 5 ms: kinetic and potential energy of the particles, the largest specific energy
v^2/2 + g z and speed, the run-up (highest particle within 2 h of the right wall, mean
vertical velocity and specific energy of its 5 highest); prints every 4th row and writes
runs/runup_2d_TAG.npz.
"""

import argparse
import time as _t
from pathlib import Path

import numpy as np

from mpmflow import Simulation, load_case

ap = argparse.ArgumentParser()
ap.add_argument("tag")
ap.add_argument("--case", default="dam_break")
ap.add_argument("--set", action="append", default=[])
ap.add_argument("--end", type=float, default=0.6)
cli = ap.parse_args()
case = load_case(
    Path(__file__).resolve().parents[2] / "examples" / f"{cli.case}.toml",
    ["output.snapshots=false", f"time.end={cli.end}", "output.interval=0.005", *cli.set],
)
sim = Simulation(case)
h = sim.grid.spacing
W = case.domain.size[0]
rec = {}


def put(k, v):
    rec.setdefault(k, []).append(v)


t0 = _t.time()


def on_output(s):
    x, v, m = s.particles.x, s.particles.v, s.particles.mass
    put("t", s.time)
    put("ke", 0.5 * float((m * (v**2).sum(1)).sum()))
    put("pe", 9.81 * float((m * x[:, 1]).sum()))
    e = 0.5 * (v**2).sum(1) + 9.81 * x[:, 1]
    put("emax", float(e.max()))
    put("umax", float(np.sqrt((v**2).sum(1)).max()))
    near = x[:, 0] > W - 2 * h
    if near.any():
        z = x[near, 1]
        top5 = np.argsort(z)[-5:]
        put("run_z", float(z.max()))
        put("run_w", float(v[near, 1][top5].mean()))
        put("run_e", float(e[near][top5].mean()))
    else:
        put("run_z", np.nan)
        put("run_w", np.nan)
        put("run_e", np.nan)
    put("front_x", float(x[:, 0].max()))


sim.on_output = on_output
sim.run()
t = np.array(rec["t"])
E = np.array(rec["ke"]) + np.array(rec["pe"])
out = {"tag": cli.tag, "set": cli.set, "steps": sim.steps, "wall": _t.time() - t0}
runs = Path(__file__).resolve().parents[2] / "runs"
runs.mkdir(exist_ok=True)
np.savez(runs / f"runup_2d_{cli.tag}.npz", **{k: np.array(v) for k, v in rec.items()})
for i in range(0, len(t), 4):
    print(
        f"{t[i]:.3f} KE {rec['ke'][i]:7.3f} PE {rec['pe'][i]:7.3f} E {E[i]:7.3f} runup {rec['run_z'][i]:.3f} w {rec['run_w'][i]:5.2f} e {rec['run_e'][i]:5.2f} emax {rec['emax'][i]:5.2f} umax {rec['umax'][i]:5.2f} front {rec['front_x'][i]:.3f}"
    )
print(out)
