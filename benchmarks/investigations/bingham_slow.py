"""The Bingham slump (examples/bingham_slump.toml) at another plastic viscosity and transfer,
run long: the validation's arrest measure h |dh/dx| rho g / tau_y (``arrest_ratios``, the
middle half of each side), the half-length, the top and the largest speed every second.

    python benchmarks/investigations/bingham_slow.py --consistency 20 --transfer apic --end 30

``--transfer``: apic (the example's), or a FLIP fraction (0: PIC). Prints one line a second.
"""

import argparse
from pathlib import Path

import numpy as np

from mpmflow import Simulation, load_case
from mpmflow.simulation.schedules import TimeInterval
from mpmflow.validation.materials import arrest_ratios

ROOT = Path(__file__).resolve().parents[2]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--consistency", type=float, default=20.0, help="Pa s")
    ap.add_argument("--transfer", default="apic", help='"apic" or a FLIP fraction')
    ap.add_argument("--end", type=float, default=30.0, help="s")
    args = ap.parse_args()
    over = [
        f"material.consistency={args.consistency}",
        f"time.end={args.end}",
        "output.snapshots=false",
        "output.interval=0.1",
    ]
    over += (
        ["solver.transfer=apic"]
        if args.transfer == "apic"
        else ["solver.transfer=flip", f"solver.flip={args.transfer}"]
    )
    case = load_case(ROOT / "examples" / "bingham_slump.toml", over)
    m = case.material
    scale = m.yield_stress / (m.density * 9.81)
    spacing = case.grid.spacing / case.bodies[0].particles_per_cell
    centre = 0.5 * case.domain.size[0]

    def report(sim: Simulation) -> None:
        if sim.time == 0 or abs(sim.time - round(sim.time)) > 1e-6:
            return
        P = sim.particles
        right, left = arrest_ratios(P.x, centre, spacing, scale)
        print(
            f"t = {sim.time:4.1f} s  ratio {(right + left) / 2:.3f} (left {left:.3f}, right "
            f"{right:.3f})  half-length {np.abs(P.x[:, 0] - centre).max():.4f} m  top "
            f"{P.x[:, 1].max():.4f} m  largest speed {np.linalg.norm(P.v, axis=1).max():.2e} m/s",
            flush=True,
        )

    sim = Simulation(case)
    sim.add_writer(report, TimeInterval(0.1))
    sim.run()


if __name__ == "__main__":
    main()
