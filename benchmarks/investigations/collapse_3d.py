"""A 3D granular column (mu(I), as examples/granular_collapse.toml) on a rough floor: run-out
radius against Lube et al. (2004), (r_inf - r0) / r0 = 1.24 a (a < 1.7), 1.6 a^(1/2) above.

    python benchmarks/investigations/collapse_3d.py A CELLS [--whole] [key=value ...]

A = H0 / r0 (r0 = 0.05 m), CELLS across r0; key=value are case overrides (e.g.
solver.flip=0.99, solver.transfer=apic; the example's transfer is PIC, flip = 0).

By default the quarter column: the column's axis is the domain's edge x = y = 0, whose two
walls are slip symmetry planes (domain.walls = {x = "slip", y = "slip", z_min = "no_slip"}):
the floor is rough, the far walls at x = L and y = L are slip and far enough (L = r0 (1 +
2.5 law) + 0.02 m) that the law's run-out stays 1.5 law r0 off them. --whole: the whole
column in the middle of a tank of side 2 L with every wall no-slip, as before. The set-up
and the measures are the validation's (mpmflow.validation.granular_3d).

Prints one JSON line: the furthest particle's radius as (r_inf - r0) / r0 (runout_max), the
deposit's toe, the outermost radius where the deposit is one particle layer thick (the
particles' volume over a ring one cell wide, h / 2 = one layer at 2 particles per cell
along an axis) (runout_toe), the law, each off the law, H_inf / H0 (the highest particle),
the largest particle speed at the end, whether a particle came within a cell of a far wall,
the particles and the wall time; then the run-out against time (t: runout_max: largest
speed).
"""

import json
import sys

from mpmflow.validation.granular_3d import measure_column

args = [a for a in sys.argv[1:] if a != "--whole"]
whole = "--whole" in sys.argv[1:]
a, cells = float(args[0]), float(args[1])
extra = args[2:]
m = measure_column(a, cells, whole, extra)
law = m["law"]
print(
    json.dumps(
        {
            "a": a,
            "cells": cells,
            "whole": whole,
            "extra": extra,
            "particles": m["particles"],
            "runout_max": m["runout"],
            "runout_toe": m["toe"],
            "law": law,
            "off_max": (m["runout"] - law) / law,
            "off_toe": (m["toe"] - law) / law,
            "H_inf/H0": m["height"],
            "vmax_end": m["speed"],
            "far_wall_reached": m["far"],
            "closest_to_far_wall": m["closest"],
            "wall": m["wall"],
        }
    )
)
print(" ".join(f"{t:.2f}:{q:.2f}:{v:.3f}" for t, q, v in m["history"][::2]))
