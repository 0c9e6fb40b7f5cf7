"""The cost of a run's outputs against its length: 10,000 and 20,000 timeseries rows.

Runs the dam break of examples/dam_break.toml on a coarse mesh (grid.spacing = 0.02 m:
about 1,200 particles, so that the outputs weigh in the step's cost) with an output row
every step (output.interval = time.dt = 1 ms), a snapshot every second and a checkpoint
every 0.1 s (the default), each as its own `mpmflow run` process:

- N rows and 2N rows from the start (default N = 10,000): the whole process's wall time
  and the time loop's (summary.json's wall_seconds), and their ratios. Output cost linear
  in the run's length gives a ratio below 2 (the start-up is paid once); issue 17 measured
  2k/4k/8k/16k rows at 2.1/4.8/12.5/38 s when the time series was rewritten whole after
  every row and every checkpoint carried all rows (ratio 3 from 8k to 16k).
- the second N rows as a restart of the N-row run (--restart --set time.end=...): the
  same steps as the first N, with N rows already in the files; linear outputs make it cost
  what the first N cost.
- the bytes: timeseries.csv, and the largest checkpoint (fixed size when checkpoints hold
  state, not history).

    python benchmarks/output_rows.py [--rows 10000] [--src OTHER_CHECKOUT/src]

--src runs another checkout (e.g. the commit before issue 17) with this environment.
Run it with NUMBA_NUM_THREADS=1 on a shared machine. Appends a JSON record to
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

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from dam_break import machine, save  # noqa: E402

CASE = ROOT / "examples" / "dam_break.toml"
SETTINGS = ["grid.spacing=0.02", "time.dt=1e-3", "output.interval=1e-3",
            "output.snapshot_interval=1.0"]


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
    res = subprocess.run(cmd, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t0
    if res.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({res.returncode}):\n{res.stderr}")
    return wall, json.loads((Path(out) / "summary.json").read_text())


def sizes(out):
    checkpoints = [p.stat().st_size for p in Path(out).glob("checkpoint_*.npz")]
    return {"timeseries_bytes": (Path(out) / "timeseries.csv").stat().st_size,
            "largest_checkpoint_bytes": max(checkpoints, default=0)}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=10_000, help="N: runs of N and 2N rows")
    ap.add_argument("--src", default=None, help="the src folder of another checkout to run")
    args = ap.parse_args()
    n = args.rows
    record = {"label": "output_rows", "rows": n, "src": args.src or "this checkout",
              "machine": machine(), "date": time.strftime("%Y-%m-%d")}
    with tempfile.TemporaryDirectory() as tmp:
        run(Path(tmp) / "warm", 10, args.src)  # Numba's cache
        for label, rows in (("short", n), ("long", 2 * n)):
            out = Path(tmp) / label
            wall, summary = run(out, rows, args.src)
            record[label] = {"rows": rows, "wall_s": wall, "loop_s": summary["wall_seconds"],
                             "particles": summary["particles"], **sizes(out)}
            print(f"{rows:,} rows: {wall:.2f} s whole process, {summary['wall_seconds']:.2f} s "
                  f"time loop ({summary['particles']} particles); timeseries.csv "
                  f"{record[label]['timeseries_bytes']:,} B, largest checkpoint "
                  f"{record[label]['largest_checkpoint_bytes']:,} B", flush=True)
        wall, summary = run(Path(tmp) / "short", 2 * n, args.src, restart=True)
        first = record["short"]["loop_s"]
        second = summary["wall_seconds"] - first  # wall_seconds counts the whole run
        record["second_half"] = {"wall_s": wall, "loop_s": second}
        print(f"rows {n:,} to {2 * n:,} as a restart: {wall:.2f} s whole process, "
              f"{second:.2f} s time loop")
    short, long = record["short"], record["long"]
    record["ratio_wall"] = long["wall_s"] / short["wall_s"]
    record["ratio_loop"] = long["loop_s"] / short["loop_s"]
    record["ratio_halves"] = record["second_half"]["loop_s"] / short["loop_s"]
    print(f"{2 * n:,} rows / {n:,} rows: {record['ratio_wall']:.2f} (whole process), "
          f"{record['ratio_loop']:.2f} (time loop); second {n:,} / first {n:,}: "
          f"{record['ratio_halves']:.2f} (issue 17 asks for a whole-run ratio below 2)")
    save(record)


if __name__ == "__main__":
    main()
