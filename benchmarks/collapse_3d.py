"""A 3D granular column (mu(I), as examples/granular_collapse.toml) on a rough floor: run-out
radius against Lube et al. (2004), (r_inf - r0) / r0 = 1.24 a (a < 1.7), 1.6 a^(1/2) above.

    python benchmarks/collapse_3d.py A CELLS [--whole] [key=value ...]

A = H0 / r0 (r0 = 0.05 m), CELLS across r0; key=value are case overrides (e.g.
solver.flip=0.99, solver.transfer=apic; the example's transfer is PIC, flip = 0).

By default the quarter column: the column's axis is the domain's edge x = y = 0, whose two
walls are slip symmetry planes (domain.walls = {x = "slip", y = "slip", z_min = "no_slip"}):
the floor is rough, the far walls at x = L and y = L are slip and far enough (L = r0 (1 +
2.5 law) + 0.02 m) that the law's run-out stays 1.5 law r0 off them. --whole: the whole
column in the middle of a tank of side 2 L with every wall no-slip, as before.

Prints one JSON line: the furthest particle's radius as (r_inf - r0) / r0 (runout_max), the
deposit's toe, the outermost radius where the deposit is one particle layer thick (the
particles' volume over a ring one cell wide, h / 2 = one layer at 2 particles per cell
along an axis) (runout_toe), the law, each off the law, H_inf / H0 (the highest particle),
the largest particle speed at the end, whether a particle came within a cell of a far wall,
the particles and the wall time; then the run-out against time (t: runout_max: largest
speed).
"""

import json
import math
import sys
import tempfile
from pathlib import Path

import numpy as np

from mpmflow.validation import common
from mpmflow.validation.granular_3d import R0, lube_3d, quarter_cylinder_obj

args = [a for a in sys.argv[1:] if a != "--whole"]
whole = "--whole" in sys.argv[1:]
a, cells = float(args[0]), float(args[1])
extra = args[2:]
r0 = R0
H0 = a * r0
h = r0 / cells
law = lube_3d(a)
L = r0 * (1 + 2.5 * law) + 0.02  # wide: APIC over-runs the law
L = h * math.ceil(L / h)
dt = min(5e-4, 0.35 * h / math.sqrt(2 * 9.81 * H0))
end = 0.6 + 6 * math.sqrt(H0 / 9.81)
folder = Path(tempfile.mkdtemp())


if whole:
    size, walls, centre = [2 * L, 2 * L], '"no_slip"', [L, L]
    body = f"""type = "cylinder"
centre = [{L}, {L}, 0.0]   # the base's centre
axis = [0.0, 0.0, 1.0]
radius = {r0}
length = {H0}"""
else:
    size, centre = [L, L], [0.0, 0.0]
    walls = '{x = "slip", y = "slip", z_min = "no_slip", z_max = "slip"}'
    (folder / "quarter.obj").write_text(quarter_cylinder_obj(r0, H0))
    body = 'type = "mesh"\npath = "quarter.obj"'
src = (Path(__file__).resolve().parent.parent / "examples" / "granular_collapse.toml").read_text()
src = (
    src.split("[domain]")[0]
    + f"""
[domain]
size = [{size[0]}, {size[1]}, {H0 * 1.15 + 2 * h}]
walls = {walls}
[grid]
spacing = {h}
[[bodies]]
{body}
particles_per_cell = 2
"""
    + "[material]"
    + src.split("[material]")[1]
)
src = src.replace("gravity = [0.0, -9.81]", "gravity = [0.0, 0.0, -9.81]")
p = folder / f"col3d_{a}.toml"
p.write_text(src)
case = common.load_case(
    p,
    [
        "output.snapshots=false",
        f"time.dt={dt:.4g}",
        f"time.end={end:.3f}",
        "output.interval=0.05",
        *extra,
    ],
)
sim = common.Simulation(case)
fr = []


def radius(x):
    return np.hypot(x[:, 0] - centre[0], x[:, 1] - centre[1])


def rec(s):
    fr.append(
        (
            s.time,
            radius(s.particles.x).max() / r0 - 1,
            float(np.linalg.norm(s.particles.v, axis=1).max()),
        )
    )


sim.on_output = rec
sim.run()
x = sim.particles.x
r = radius(x)
# the deposit's thickness on rings one cell wide: the particles' volume over the ring's area
edges = np.arange(0.0, r.max() + 2 * h, h)
vol, _ = np.histogram(r, bins=edges, weights=sim.particles.volume)
area = (1.0 if whole else 0.25) * math.pi * (edges[1:] ** 2 - edges[:-1] ** 2)
thick = np.nonzero(vol / area >= h / 2)[0]
toe = edges[thick[-1] + 1] if len(thick) else 0.0
far = (x[:, :2].max() > 2 * L - h or x[:, :2].min() < h) if whole else x[:, :2].max() > L - h
law_off = lambda q: (q - law) / law  # noqa: E731
print(
    json.dumps(
        {
            "a": a,
            "cells": cells,
            "whole": whole,
            "extra": extra,
            "particles": sim.particles.count,
            "runout_max": r.max() / r0 - 1,
            "runout_toe": toe / r0 - 1,
            "law": law,
            "off_max": law_off(r.max() / r0 - 1),
            "off_toe": law_off(toe / r0 - 1),
            "H_inf/H0": float(x[:, 2].max()) / H0,
            "vmax_end": fr[-1][2],
            "far_wall_reached": bool(far),
            "closest_to_far_wall": float(L - x[:, :2].max()) if not whole else None,
            "wall": sim.summary["wall_seconds"],
        }
    )
)
print(" ".join(f"{t:.2f}:{q:.2f}:{v:.3f}" for t, q, v in fr[::2]))
