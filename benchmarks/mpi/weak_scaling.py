"""Weak scaling of the split projection step (issue 28): N dam breaks' worth of water on N
ranks, the per-rank time per step and what each rank sends per step.

The case is the paper's dam break (0.004 m, volume correction off, as every row of this
benchmark since issue 28 has it) widened N times: a column N x 0.114 m wide in a tank
N x 0.42 m wide, so each rank starts with one column's particles (26k). Run under mpirun
from the MPI environment:

    mpirun -n N .venv-mpi/bin/python benchmarks/mpi/weak_scaling.py [--steps 200] [--pc gamg]
        [--chunk 10]   # steps a chunk, as a run's output times (0.01 s) make them
    .venv-mpi/bin/python benchmarks/mpi/weak_scaling.py --alone   # one process, compiled step

Prints (rank 0) one JSON line: ranks, steps, the median and slowest rank's seconds per step
(after a 20-step warm-up), the PETSc share, and per rank and step: node-fill bytes sent,
halo particles received, particles migrated, the pressure matrix's off-rank columns (each
CG iteration exchanges them), CG iterations. Times are only comparable at N <= cores.
Rank 0 appends the slowest and median rank's seconds per step and PETSc's share to
benchmarks/history.csv (--alone: the compiled step's).
"""

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from mpmflow import load_case
from mpmflow.parallel.comm import world
from mpmflow.parallel.scheme import DistributedProjection
from mpmflow.simulation import Simulation

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from history import append, machine  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--warm", type=int, default=20)
    parser.add_argument("--pc", default="hypre", choices=["gamg", "hypre"])
    parser.add_argument(
        "--chunk",
        type=int,
        default=0,
        help="steps a chunk (as a run's output times make them: the boxes split again at a "
        "chunk's start when the load is uneven, and every rank gathers the particles at its "
        "end); 0: the whole measurement in one chunk",
    )
    parser.add_argument(
        "--alone", action="store_true", help="the one-process scheme (compiled multigrid) instead"
    )
    args = parser.parse_args()
    comm = world()
    n = comm.size
    start = machine() if comm.rank == 0 else None
    case = load_case(
        "examples/dam_break.toml",
        [
            f"domain.size=[{0.42 * n}, 0.44]",
            f"bodies.0.max=[{0.114 * n}, 0.228]",
            "solver.volume_correction=0",
            "time.end=10",
            f"solver.petsc_preconditioner={args.pc}",
        ],
    )
    sim = Simulation(case)
    if args.alone:
        sim.scheme.advance(sim.dt, args.warm)
        wall = time.perf_counter()
        sim.scheme.advance(sim.dt, args.steps)
        per_step = (time.perf_counter() - wall) / args.steps
        print(json.dumps({"ranks": 1, "alone": True, "wall_per_step": per_step}))
        append(
            "mpi/weak_scaling",
            [("1 rank, compiled step (--alone)", per_step, "s")],
            note=f"per step, {args.steps} steps after {args.warm}",
            start=start,
        )
        return
    if not isinstance(sim.scheme, DistributedProjection):
        sim.scheme = DistributedProjection(case, sim.grid, sim.particles)
    scheme = sim.scheme
    scheme.advance(sim.dt, args.warm)
    step0, solve0 = scheme.step_seconds, scheme.pressure.seconds
    traffic0 = dict(scheme.traffic)
    bytes0 = scheme.node_bytes + scheme.exchange.nodes.sent
    comm.Barrier()
    wall = time.perf_counter()
    chunk = args.chunk or args.steps
    for first in range(0, args.steps, chunk):
        scheme.advance(sim.dt, min(chunk, args.steps - first))
    wall = time.perf_counter() - wall
    mine = {
        "step": (scheme.step_seconds - step0) / args.steps,
        "solve": (scheme.pressure.seconds - solve0) / args.steps,
        "node_bytes": (scheme.node_bytes + scheme.exchange.nodes.sent - bytes0) / args.steps,
        **{k: (scheme.traffic[k] - traffic0[k]) / args.steps for k in traffic0 if k != "steps"},
        "particles": scheme.ranks_report["particles"][comm.rank],
    }
    everyone = comm.allgather(mine)
    if comm.rank == 0:
        step = [e["step"] for e in everyone]
        out = {
            "ranks": n,
            "pc": args.pc,
            "steps": args.steps,
            "chunk": chunk,
            "splits": scheme.splits,
            "particles": [e["particles"] for e in everyone],
            "seconds_per_step_median": float(np.median(step)),
            "seconds_per_step_max": float(max(step)),
            "wall_per_step": wall / args.steps,
            "petsc_share": float(np.median([e["solve"] / e["step"] for e in everyone])),
            "per_rank_per_step": {
                k: [round(e[k], 1) for e in everyone]
                for k in mine
                if k not in ("step", "solve", "particles")
            },
        }
        print(json.dumps(out))
        append(
            "mpi/weak_scaling",
            [
                (f"{n} ranks, slowest rank", out["seconds_per_step_max"], "s"),
                (f"{n} ranks, median rank", out["seconds_per_step_median"], "s"),
                (f"{n} ranks, PETSc share", out["petsc_share"], ""),
            ],
            note=f"per step, {args.pc}, {args.steps} steps after {args.warm}, chunks of {chunk}",
            start=start,
        )


if __name__ == "__main__":
    main()
