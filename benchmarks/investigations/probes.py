"""The cost of the probes at one output: 20 probes on about 0.7 million particles in 3D.

Sets up (no time steps) the water of SPHERIC Test 2 (Kleefsman et al. 2005: a tank
3.22 m x 1 m x 1 m, water 1.228 m x 1 m x 0.55 m at the end x = 3.22 m) on a 0.02 m mesh
with 2 particles per cell direction (0.69 million particles), gives the particles the
hydrostatic pressure, and times ``probes.measure`` with 16 pressure probes (8 on the wall
x = 3.22 m, 8 inside the water; "fit") and 4 level gauges, after the binning that every
output does anyway (timed apart: ``cells.bin_particles``). Prints the median of 5 and the
largest pressure error against rho g (H - z) (Pa).

    python benchmarks/investigations/probes.py
"""

import statistics
import time
from pathlib import Path

import numpy as np

from mpmflow import load_case
from mpmflow.cells import bin_particles
from mpmflow.diagnostics import probes
from mpmflow.geometry.seeding import build_particles
from mpmflow.grid import Grid

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
RHO, G, DEPTH = 1000.0, 9.81, 0.55


def main():
    wall = [[3.22, 0.5, z] for z in np.linspace(0.0, 0.5, 8)]
    inside = [[2.5, y, z] for y, z in zip(np.linspace(0.1, 0.9, 8), np.linspace(0.02, 0.5, 8))]
    gauges = [[x, 0.5, 0.0] for x in (0.496, 0.992, 1.488, 2.638)]
    case = load_case(
        EXAMPLES / "hydrostatic_3d.toml",
        {
            "domain.size": [3.22, 1.0, 1.0],
            "grid.spacing": 0.02,
            "bodies.0.min": [1.992, 0.0, 0.0],
            "bodies.0.max": [3.22, 1.0, DEPTH],
            "probes": [
                {"name": f"p{k}", "quantity": "pressure", "position": p}
                for k, p in enumerate(wall + inside)
            ]
            + [{"name": f"h{k}", "quantity": "level", "position": p} for k, p in enumerate(gauges)],
        },
    )
    grid = Grid.of_case(case)
    particles = build_particles(case, grid)
    particles.pressure[:] = RHO * G * (DEPTH - particles.x[:, 2])
    bins = bin_particles(grid, particles)
    probes.measure(case, grid, particles, bins, 0.0)  # warm-up
    t_bin, t_probe = [], []
    for _ in range(5):
        t0 = time.perf_counter()
        bins = bin_particles(grid, particles, bins)
        t1 = time.perf_counter()
        row = probes.measure(case, grid, particles, bins, 0.0)
        t2 = time.perf_counter()
        t_bin.append(t1 - t0)
        t_probe.append(t2 - t1)
    err = max(
        abs(row[p.name] - RHO * G * max(DEPTH - p.position[2], 0.0))
        for p in case.probes
        if p.quantity == "pressure"
    )
    print(
        f"{particles.count} particles, {len(case.probes)} probes: probes "
        f"{statistics.median(t_probe) * 1e3:.2f} ms per output (median of 5), binning "
        f"(done by every output anyway) {statistics.median(t_bin) * 1e3:.0f} ms; largest "
        f"pressure error {err:.2e} Pa; levels "
        + ", ".join(f"{row[f'h{k}']:.4f}" for k in range(len(gauges)))
        + " m"
    )


if __name__ == "__main__":
    main()
