"""The validation's granular collapse at any mesh, tank width and transfer, with the deposit's
shape (issue 26, item 4: is the over-run a discretisation error, i.e. does it go away with the
mesh, and do the transfers agree when refined?).

    python benchmarks/investigations/granular_mesh.py --aspect 2 --cells 25 --transfer flip [--width 3]
        [--set key=value ...]

The column of ``mpmflow.validation.materials._collapse`` (examples/granular_collapse.toml at
aspect ratio a, L0 = 0.05 m the half-width, dt = min(5e-4, 0.35 h / sqrt(2 g H0)), to
0.6 s + 6 sqrt(H0 / g)) with h = L0 / CELLS, in a tank of half-width
L0 + WIDTH x Lube's run-out + 0.02 m (the validation's WIDTH: 1.6). Prints one JSON line: the
run-out (L_inf - L0) / L0 from the furthest particle on each side (the validation's), the toe
of the deposit at least one cell thick (columns of width h holding a full cell's volume of
particles), Lube's law, H_inf / H0, the largest particle speed at the end, the flank slope
(least squares over the columns 20-80% of H_inf high, both sides) and whether a side wall
was reached.
"""

import argparse
import json

import numpy as np

from mpmflow.validation import common, materials

TRANSFERS = materials.TRANSFERS

ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
ap.add_argument("--aspect", type=float, default=2.0)
ap.add_argument("--cells", type=float, default=12.5, help="cells across L0")
ap.add_argument("--width", type=float, default=1.6)
ap.add_argument("--transfer", choices=list(TRANSFERS), default="apic")
ap.add_argument("--set", action="append", default=[], help="more overrides key=value")
cli = ap.parse_args()

a, L0 = cli.aspect, materials.L0
case = materials.Collapse(a, cli.cells, cli.width)
H0, half, h = case.H0, case.half, case.h
sim = common.run_example(
    "granular_collapse.toml", [*case.overrides(), *TRANSFERS[cli.transfer], *cli.set]
)
x, v = sim.particles.x, sim.particles.v
reach = 0.5 * ((x[:, 0].max() - half) + (half - x[:, 0].min()))
full = 1.0 / (sim.particles.volume.mean() / h**2)  # particles in a full cell
toes, slopes = [], []
for side in (1.0, -1.0):
    d = side * (x[:, 0] - half)
    k = np.floor(d / h).astype(int)
    keep = k >= 0
    count = np.bincount(k[keep])
    thick = np.flatnonzero(count >= full)
    toes.append((thick.max() + 1) * h if thick.size else 0.0)
    top = np.zeros(count.size)
    np.maximum.at(top, k[keep], x[keep, 1])
    hmax = top.max()
    flank = (top > 0.2 * hmax) & (top < 0.8 * hmax) & (np.arange(count.size) * h > 0.5 * L0)
    if flank.sum() > 2:
        slopes.append(-np.polyfit((np.flatnonzero(flank) + 0.5) * h, top[flank], 1)[0])
print(
    json.dumps(
        {
            "aspect": a,
            "cells": cli.cells,
            "width": cli.width,
            "transfer": cli.transfer,
            "set": cli.set,
            "particles": sim.particles.count,
            "runout": (reach - L0) / L0,
            "toe_one_cell": (0.5 * sum(toes) - L0) / L0,
            "law": materials.lube(a),
            "off": (reach - L0) / L0 / materials.lube(a) - 1,
            "height": float(x[:, 1].max() / H0),
            "speed_max_end": float(np.linalg.norm(v, axis=1).max()),
            "flank_deg": float(np.degrees(np.arctan(np.mean(slopes)))) if slopes else None,
            "walled": bool(x[:, 0].max() > 2 * half - 1.5 * h or x[:, 0].min() < 1.5 * h),
        }
    )
)
