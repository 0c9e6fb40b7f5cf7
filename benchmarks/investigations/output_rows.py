"""The cost of a run's outputs against its length: 10,000 and 20,000 timeseries rows.

Runs the water column at rest of examples/hydrostatic.toml with 2 particles per cell
direction (780 particles, as in the issue: the outputs weigh in the step's cost, and the
steps cost the same all along, which a dam break's do not) with an output row every step
(output.interval = time.dt = 1 ms), a snapshot every second and a checkpoint every 0.1 s
(the default), each as its own `mpmflow run` process:

- N rows and 2N rows from the start (default N = 10,000): the whole process's wall time
  and the time loop's (summary.json's wall_seconds), and their ratios. Output cost linear
  in the run's length gives a ratio below 2 (the start-up is paid once); issue 17 measured
  2k/4k/8k/16k rows at 2.1/4.8/12.5/38 s when the time series was rewritten whole after
  every row and every checkpoint carried all rows (ratio 3 from 8k to 16k).
- the second N rows as a restart of the N-row run (--restart --set time.end=...): the
  same steps as the first N, with N rows already in the files; linear outputs make it cost
  what the first N cost.
- the whole process's CPU time (os.wait4), steadier than its wall time beside other
  programs;
- the bytes: timeseries.csv, and the largest checkpoint (fixed size when checkpoints hold
  state, not history).

    python benchmarks/investigations/output_rows.py [--rows 10000] [--src OTHER_CHECKOUT/src]

--src runs another checkout (e.g. the commit before issue 17) with this environment.
Run it with OMP_NUM_THREADS=1 on a shared machine. Appends a JSON record to
benchmarks/results.jsonl (not tracked).
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benchmarks"))
from history import machine, save  # noqa: E402

CASE = ROOT / "examples" / "hydrostatic.toml"
SETTINGS = [
    "bodies.0.particles_per_cell=2",
    "time.dt=1e-3",
    "output.interval=1e-3",
    "output.snapshot_interval=1.0",
]


def run(out, rows, src=None, restart=False):
    """(whole-process wall s, summary) of one run of ``rows`` rows after t = 0."""
    cmd = [sys.executable, "-m", "mpmflow.cli", "run", str(CASE), "--out", str(out), "-q"]
    for item in SETTINGS + [f"time.end={rows * 1e-3:g}"]:
        cmd += ["--set", item]
    if restart:
        cmd.append("--restart")
    env = dict(os.environ)
    if src:
        env["PYTHONPATH"] = str(Path(src).resolve())
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stderr=subprocess.PIPE, text=True, env=env)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    err = proc.stderr.read()
    if os.waitstatus_to_exitcode(status) != 0:
        raise SystemExit(f"{' '.join(cmd)} failed:\n{err}")
    summary = json.loads((Path(out) / "summary.json").read_text())
    summary["cpu_s"] = usage.ru_utime + usage.ru_stime  # steadier than wall on a busy machine
    return wall, summary


def sizes(out):
    checkpoints = [p.stat().st_size for p in Path(out).glob("checkpoint_*.npz")]
    return {
        "timeseries_bytes": (Path(out) / "timeseries.csv").stat().st_size,
        "largest_checkpoint_bytes": max(checkpoints, default=0),
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=10_000, help="N: runs of N and 2N rows")
    ap.add_argument("--src", default=None, help="the src folder of another checkout to run")
    args = ap.parse_args()
    n = args.rows
    record = {
        "label": "output_rows",
        "rows": n,
        "src": args.src or "this checkout",
        "machine": machine(),
        "date": time.strftime("%Y-%m-%d"),
    }
    with tempfile.TemporaryDirectory() as tmp:
        run(Path(tmp) / "warm", 10, args.src)  # the page cache
        for label, rows in (("short", n), ("long", 2 * n)):
            out = Path(tmp) / label
            wall, summary = run(out, rows, args.src)
            record[label] = {
                "rows": rows,
                "wall_s": wall,
                "loop_s": summary["wall_seconds"],
                "cpu_s": summary["cpu_s"],
                "particles": summary["particles"],
                **sizes(out),
            }
            print(
                f"{rows:,} rows: {wall:.2f} s whole process ({summary['cpu_s']:.2f} s CPU), "
                f"{summary['wall_seconds']:.2f} s time loop ({summary['particles']} "
                "particles); timeseries.csv "
                f"{record[label]['timeseries_bytes']:,} B, largest checkpoint "
                f"{record[label]['largest_checkpoint_bytes']:,} B",
                flush=True,
            )
        wall, summary = run(Path(tmp) / "short", 2 * n, args.src, restart=True)
        first = record["short"]["loop_s"]
        second = summary["wall_seconds"] - first  # wall_seconds counts the whole run
        record["second_half"] = {"wall_s": wall, "loop_s": second, "cpu_s": summary["cpu_s"]}
        print(
            f"rows {n:,} to {2 * n:,} as a restart: {wall:.2f} s whole process "
            f"({summary['cpu_s']:.2f} s CPU), {second:.2f} s time loop"
        )
    short, long = record["short"], record["long"]
    record["ratio_wall"] = long["wall_s"] / short["wall_s"]
    record["ratio_cpu"] = long["cpu_s"] / short["cpu_s"]
    record["ratio_loop"] = long["loop_s"] / short["loop_s"]
    record["ratio_halves"] = record["second_half"]["loop_s"] / short["loop_s"]
    record["ratio_halves_cpu"] = record["second_half"]["cpu_s"] / short["cpu_s"]
    print(
        f"{2 * n:,} rows / {n:,} rows: {record['ratio_wall']:.2f} (whole process), "
        f"{record['ratio_cpu']:.2f} (its CPU time), {record['ratio_loop']:.2f} (time loop); "
        f"second {n:,} / first {n:,}: "
        f"{record['ratio_halves']:.2f} (time loop), {record['ratio_halves_cpu']:.2f} (CPU) "
        f"(issue 17 asks for a whole-run ratio below 2)"
    )
    save(record)


if __name__ == "__main__":
    main()
