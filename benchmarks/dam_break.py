"""Whole-process wall time of `mpmflow run examples/dam_break.toml` (1.0 s of flow, 0.004 m,
26k particles, 1000 steps, outputs at the example's intervals).

One warm-up run first (it fills the page cache), then --repeat timed runs; prints the
median, min and max and the machine, appends the medians to benchmarks/history.csv and the
whole record to benchmarks/results.jsonl (not tracked). `make bench` runs it.

    python benchmarks/dam_break.py [--repeat 5] [--set key=value ...]
"""

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from history import append, machine, save  # noqa: E402


def run_once(case, out, overrides):
    cmd = [
        sys.executable,
        "-m",
        "mpmflow.cli",
        "run",
        str(case),
        "--out",
        str(out),
        "--quiet",
        "--overwrite",
    ]
    for o in overrides:
        cmd += ["--set", o]
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True)
    wall = time.perf_counter() - t0
    summary = json.loads((Path(out) / "summary.json").read_text())
    return wall, summary


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", default=str(ROOT / "examples" / "dam_break.toml"))
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--set", action="append", default=[], dest="overrides")
    ap.add_argument("--label", default="")
    args = ap.parse_args()
    start = machine()
    with tempfile.TemporaryDirectory() as tmp:
        run_once(args.case, tmp, args.overrides)  # warm-up: JIT cache
        walls, loops = [], []
        for _ in range(args.repeat):
            wall, summary = run_once(args.case, tmp, args.overrides)
            walls.append(wall)
            loops.append(summary["wall_seconds"])
    record = {
        "label": args.label,
        "case": Path(args.case).name,
        "overrides": args.overrides,
        "repeat": args.repeat,
        "process_median_s": statistics.median(walls),
        "process_min_s": min(walls),
        "process_max_s": max(walls),
        "time_loop_median_s": statistics.median(loops),
        "steps": summary["steps"],
        "particles": summary["particles"],
        "machine": start,
        "date": time.strftime("%Y-%m-%d"),
    }
    print(
        f"{record['case']} {' '.join(args.overrides)}: whole process median "
        f"{record['process_median_s']:.2f} s (min {record['process_min_s']:.2f}, max "
        f"{record['process_max_s']:.2f}; {args.repeat} runs after a warm-up), time loop "
        f"{record['time_loop_median_s']:.2f} s, {record['steps']} steps, "
        f"{record['particles']} particles"
    )
    save(record)
    # the case and its overrides name the benchmark: rows of one name measure one thing
    append(
        " ".join([Path(args.case).stem, *args.overrides]),
        [
            ("whole process (median)", record["process_median_s"], "s"),
            ("time loop (median)", record["time_loop_median_s"], "s"),
        ],
        note="; ".join(
            [f"{args.repeat} runs after a warm-up", *([args.label] if args.label else [])]
        ),
        start=start,
    )


if __name__ == "__main__":
    main()
