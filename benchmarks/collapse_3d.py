"""A 3D granular column (mu(I), as examples/granular_collapse.toml) on a rough floor: run-out
radius against Lube et al. (2004), (r_inf - r0) / r0 = 1.24 a (a < 1.7), 1.6 a^(1/2) above.

    python benchmarks/collapse_3d.py A CELLS [key=value ...]

A = H0 / r0 (r0 = 0.05 m), CELLS across r0. The whole column stands in the middle of the
tank: domain.walls is one kind for every wall, so the quarter column between two slip
symmetry planes on a no-slip floor cannot be set up. Prints the furthest particle's radius
as (r_inf - r0) / r0, the law, H_inf / H0, the largest speed at the end, and the run-out
against time (t: run-out: largest speed).
"""
import json
import math
import sys
import tempfile
from pathlib import Path
import numpy as np
from mpmflow.validation import common
a, cells = float(sys.argv[1]), float(sys.argv[2]); extra = sys.argv[3:]
r0 = 0.05; H0 = a * r0; h = r0 / cells
law = 1.24 * a if a < 1.7 else 1.6 * a ** 0.5
half = r0 * (1 + 2.5 * law) + 0.02  # wide: APIC over-runs the law
half = h * math.ceil(half / h)
dt = min(5e-4, 0.35 * h / math.sqrt(2 * 9.81 * H0)); end = 0.6 + 6 * math.sqrt(H0 / 9.81)
src = (Path(__file__).resolve().parent.parent / "examples" / "granular_collapse.toml").read_text()
src = src.split("[[bodies]]")[0].split("[domain]")[0] + f"""
[domain]
size = [{2*half}, {2*half}, {H0*1.15 + 2*h}]
walls = "no_slip"
[grid]
spacing = {h}
[[bodies]]
type = "cylinder"
centre = [{half}, {half}, 0.0]   # the base's centre
axis = [0.0, 0.0, 1.0]
radius = {r0}
length = {H0}
particles_per_cell = 2
""" + "[material]" + src.split("[material]")[1]
src = src.replace("gravity = [0.0, -9.81]", "gravity = [0.0, 0.0, -9.81]")
p = Path(tempfile.mkdtemp()) / f"col3d_{a}.toml"; p.write_text(src)
case = common.load_case(p, ["output.snapshots=false", f"time.dt={dt:.4g}", f"time.end={end:.3f}", "output.interval=0.05", *extra])
sim = common.Simulation(case)
fr = []
def rec(s):
    x = s.particles.x; r = np.hypot(x[:, 0] - half, x[:, 1] - half)
    fr.append((s.time, r.max() / r0 - 1, float(np.linalg.norm(s.particles.v, axis=1).max())))
sim.on_output = rec
sim.run()
x = sim.particles.x; r = np.hypot(x[:, 0] - half, x[:, 1] - half)
print(json.dumps({"a": a, "cells": cells, "extra": extra, "particles": sim.particles.count,
    "runout_max": r.max() / r0 - 1, "runout_p99": float(np.percentile(r, 99.9)) / r0 - 1, "law": law,
    "off": (r.max() / r0 - 1 - law) / law, "H_inf/H0": float(x[:, 2].max()) / H0,
    "vmax_end": fr[-1][2], "wall": sim.summary["wall_seconds"]}))
print(" ".join(f"{t:.2f}:{q:.2f}:{v:.3f}" for t, q, v in fr[::2]))
