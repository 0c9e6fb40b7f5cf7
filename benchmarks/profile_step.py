"""Where the time of a step goes: a case timed phase by phase.

The step runs in the core (``State.advance``, src/core/step.cpp), which times its own phases
with a steady clock (``State.phase_seconds``: a few clock reads per step, nothing else). This
script runs the case in-process once after a short warm-up and prints the phases' share of
the run's wall time; what is left is the outputs, checkpoints and Python between chunks.

    python benchmarks/profile_step.py [--case examples/dam_break.toml] [--set key=value ...]

Prints a Markdown table of milliseconds per step and appends each phase's to
benchmarks/history.csv.
"""

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from history import append, machine  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", default=str(ROOT / "examples" / "dam_break.toml"))
    ap.add_argument("--set", action="append", default=[], dest="overrides")
    args = ap.parse_args()
    from mpmflow import Simulation, load_case, state

    start = machine()
    Simulation(
        # a few fixed steps (time.dt = "auto" would take one of up to time.max_dt)
        load_case(
            args.case, [*args.overrides, "time.dt=0.001", "time.end=0.003", "output.interval=0.001"]
        )
    ).run()
    sim = Simulation(load_case(args.case, args.overrides))
    t0 = time.perf_counter()
    sim.run()
    wall = time.perf_counter() - t0
    steps = sim.steps
    totals = dict(zip(state.PHASES, sim.scheme.core.phase_seconds))
    print(
        f"{Path(args.case).name} {' '.join(args.overrides)}: {sim.particles.count} "
        f"particles, {steps} steps, {state.max_threads()} threads; the run takes "
        f"{wall:.2f} s"
    )
    print()
    print("| phase | ms per step | share |")
    print("|---|---|---|")
    rest = wall - sum(totals.values())
    for phase, t in [*totals.items(), ("outputs, checkpoints, Python between chunks", rest)]:
        print(f"| {phase} | {1e3 * t / steps:.3f} | {100 * t / wall:.0f}% |")
    print(f"| total | {1e3 * wall / steps:.3f} | 100% |")
    append(
        " ".join(["profile_step", Path(args.case).name, *args.overrides]),
        [
            *((phase, 1e3 * t / steps, "ms") for phase, t in totals.items()),
            ("outputs and Python", 1e3 * rest / steps, "ms"),
            ("total", 1e3 * wall / steps, "ms"),
        ],
        note=f"per step, {steps} steps, {sim.particles.count} particles",
        start=start,
        threads=state.max_threads(),
    )


if __name__ == "__main__":
    main()
