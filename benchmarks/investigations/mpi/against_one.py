"""The split step against one process (issue 28): a case stepped by the one-process scheme
and by the split scheme side by side, every 10 steps the surge front and column height
compared, at the end the largest particle difference.

    mpirun -n N .venv-mpi/bin/python benchmarks/investigations/mpi/against_one.py STEPS TOL [CASE]
    .venv-mpi/bin/python benchmarks/investigations/mpi/against_one.py STEPS TOL [CASE] --self TOL2

TOL: ``solver.tolerance`` on both sides, the relative residual of every linear solve of the
step (the pressure and the volume correction; its default is 1e-8; the volume correction
was solved to 1e-2 before it followed solver.tolerance). ``--self TOL2``: no split; one process at TOL against one process at TOL2
(what the tolerance alone moves). Prints the worst front and height differences in units of
the column width a = 0.114 m and the largest particle distance (m).
"""

import argparse

import numpy as np

from mpmflow import load_case
from mpmflow.parallel.comm import world
from mpmflow.parallel.scheme import DistributedProjection
from mpmflow.schemes.projection import ProjectionScheme
from mpmflow.simulation import Simulation

A = 0.114  # m


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("steps", type=int)
    parser.add_argument("tolerance", type=float)
    parser.add_argument("case", nargs="?", default="examples/dam_break.toml")
    parser.add_argument("--self", dest="other", type=float, default=None)
    args = parser.parse_args()
    comm = world()

    def simulation(tol: float) -> Simulation:
        return Simulation(load_case(args.case, ["time.end=10", f"solver.tolerance={tol}"]))

    one = simulation(args.tolerance)
    if type(one.scheme) is not ProjectionScheme:
        one.scheme = ProjectionScheme(one.case, one.grid, one.particles)
    two = simulation(args.other if args.other is not None else args.tolerance)
    if args.other is None and not isinstance(two.scheme, DistributedProjection):
        two.scheme = DistributedProjection(two.case, two.grid, two.particles)
    worst = [0.0, 0.0]
    for _ in range(args.steps // 10):
        one.scheme.advance(one.dt, 10)
        two.scheme.advance(two.dt, 10)
        one.forget_bins()
        two.forget_bins()
        a, b = one.measure(), two.measure()
        worst = [
            max(worst[0], abs(a["front"] - b["front"])),
            max(worst[1], abs(a["height"] - b["height"])),
        ]
    if comm.rank == 0:
        what = f"one process at {args.other:g}" if args.other is not None else f"{comm.size} ranks"
        print(
            f"{args.case}, {args.steps} steps, tolerance {args.tolerance:g}, against {what}: "
            f"front {worst[0] / A:.4f} a, height {worst[1] / A:.4f} a, largest particle "
            f"distance {np.abs(two.particles.x - one.particles.x).max():.3g} m"
        )


if __name__ == "__main__":
    main()
