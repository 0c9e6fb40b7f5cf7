"""SPHERIC Test 2 (examples/spheric_test2.toml) at a given mesh: whole-process wall time and
peak memory of `mpmflow run`, as a user runs it, with the validation's measures of its probes.

    python benchmarks/spheric.py [--spacing 0.02] [--end 6.0] [--out runs/spheric_bench] [--set time.dt=auto]

The run is a child process (`mpmflow run ... -q`, snapshots off), timed from the outside;
the peak resident memory is that child's (``ru_maxrss`` of RUSAGE_CHILDREN). Where 3.22 m
is not a whole number of cells the end wall is an obstacle (``validation.spheric.overrides``).
Prints one JSON line and appends it to benchmarks/results.jsonl (not tracked); the wall
time, steps and peak memory to benchmarks/history.csv. The suite's run is SPHERIC at 0.04 m:
`python benchmarks/spheric.py --spacing 0.04 --set time.dt=auto` (about 2 minutes on 2 cores).
"""

import argparse
import json
import resource
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from history import append, machine, save  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--spacing", type=float, default=0.02)
    ap.add_argument("--end", type=float, default=6.0)
    ap.add_argument("--out", default=str(ROOT / "runs" / "spheric_bench"))
    ap.add_argument(
        "--set", action="append", default=[], help="more overrides, e.g. --set time.dt=auto"
    )
    args = ap.parse_args()
    from mpmflow import open_run
    from mpmflow.validation import spheric

    sets = []
    for o in spheric.overrides(args.spacing, args.end) + args.set:
        sets += ["--set", o]
    cmd = [
        sys.executable,
        "-m",
        "mpmflow.cli",
        "run",
        str(ROOT / "examples" / "spheric_test2.toml"),
        "--out",
        args.out,
        "--overwrite",
        "-q",
        *sets,
    ]
    # the machine and commit the run starts from (a long run outlives commits made meanwhile)
    start = machine()
    t0 = time.perf_counter()
    res = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024  # MiB (Linux: KiB)
    if res.returncode != 0:
        sys.exit(f"the run failed ({res.returncode}):\n{res.stderr}")
    run = open_run(args.out)

    class Series:  # what spheric.measures reads from a Simulation
        summary = run.summary

        @staticmethod
        def series(name):
            return run.timeseries[name]

        @staticmethod
        def probe_series(name):
            return run.probes[name]

    m = spheric.measures(Series, spheric.data(), args.end)
    record = {
        "benchmark": "spheric",
        "commit": start["commit"],
        "spacing": args.spacing,
        "end": args.end,
        "overrides": args.set,
        "particles": run.summary["particles"],
        "steps": run.summary["steps"],
        "wall_s": wall,
        "loop_s": run.summary["wall_seconds"],
        "peak_mb": peak,
        "measures": m,
        "machine": start,
    }
    print(json.dumps(record))
    save(record)
    append(
        " ".join([f"spheric {args.spacing:g} m", *args.set]),
        [
            ("whole process", wall, "s"),
            ("time loop", run.summary["wall_seconds"], "s"),
            ("steps", run.summary["steps"], ""),
            ("peak memory", peak, "MiB"),
        ],
        note=f"{args.end:g} s of flow, {run.summary['particles']} particles",
        start=start,
    )


if __name__ == "__main__":
    main()
