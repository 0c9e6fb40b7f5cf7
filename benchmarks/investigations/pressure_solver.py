"""The pressure solvers on the same systems: multigrid (the default), AMG and SuperLU.

Runs the dam break (examples/dam_break.toml, 0.004 m) and captures the pressure system of
the step at t = 0.1, 0.3 and 0.5 s (matrix and right-hand side, as the compiled step builds
them), then times on each: the set-up (multigrid hierarchy, AMG hierarchy, LU factors) and
one solve from zero to the run's tolerance (1e-8 relative), median of --repeat, and checks
that the three solutions agree.

    python benchmarks/investigations/pressure_solver.py [--repeat 50]
"""

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benchmarks"))
from history import machine, save  # noqa: E402

TIMES = (0.1, 0.3, 0.5)


def capture():
    from mpmflow import Simulation, load_case

    case = load_case(
        ROOT / "examples" / "dam_break.toml", ["time.end=0.5", "output.snapshots=false"]
    )
    sim = Simulation(case)
    systems = []

    def grab(s):
        if any(abs(s.time - t) < 1e-9 for t in TIMES):
            sc, P = s.scheme, s.particles
            core = sc.core  # the next step recomputes everything these phases write
            O = sc.options(case.time.dt)
            core.predict(P.x.copy(), P.v.copy(), P.mass, P.volume, P.pressure.copy(), O, False)
            core.pressure_matrix(O)
            core.pressure_rhs(O)
            systems.append(
                (
                    s.time,
                    core.matrix_cols.copy(),
                    core.matrix_vals.copy(),
                    core.rows.copy(),
                    core.rhs.copy(),
                    tuple(c + 1 for c in s.grid.cells),
                )
            )

    sim.on_output = grab
    sim.run()
    return systems


def median_time(f, repeat):
    f()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=50)
    args = ap.parse_args()
    from mpmflow.linalg.solvers import LinearSolver, PressureMatrix

    rows_out = []
    print("| t [s] | unknowns | solver | set-up [ms] | solve [ms] | iterations |")
    print("|---|---|---|---|---|---|")
    for t, cols, vals, rows, rhs, dims in capture():
        matrix = PressureMatrix(cols, vals, rows, dims)
        solutions = {}
        for method in ("multigrid", "amg", "direct"):
            solver = LinearSolver(method, 1e-8, 500)
            setup = median_time(lambda s=solver, m=matrix: s.prepare(m), args.repeat)
            result = solver.solve(rhs)
            solve = median_time(lambda s=solver, b=rhs: s.solve(b), args.repeat)
            solutions[method] = result.x
            rows_out.append(
                {
                    "t": t,
                    "unknowns": int(rows.size),
                    "solver": method,
                    "setup_ms": 1e3 * setup,
                    "solve_ms": 1e3 * solve,
                    "iterations": result.iterations,
                }
            )
            print(
                f"| {t:.1f} | {rows.size} | {method} | {1e3 * setup:.3f} | "
                f"{1e3 * solve:.3f} | {result.iterations} |",
                flush=True,
            )
        ref = solutions["direct"]
        for method in ("multigrid", "amg"):
            err = np.linalg.norm(solutions[method] - ref) / np.linalg.norm(ref)
            assert err < 1e-6, (method, err)
    save(
        {
            "label": "pressure_solver",
            "repeat": args.repeat,
            "rows": rows_out,
            "machine": machine(),
            "date": time.strftime("%Y-%m-%d"),
        }
    )


if __name__ == "__main__":
    main()
