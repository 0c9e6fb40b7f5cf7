"""Time per step and peak memory against particle count, and the speed-up from threads.

Runs the dam break of examples/dam_break.toml at 0.004, 0.002 and 0.001 m (26k, 104k and
416k particles; dt scaled with the mesh: 1e-3, 5e-4, 2.5e-4 s) from rest for the same
simulated time (default 0.1 s), each in its own process (after one short warm-up run), and
reports the time-loop seconds per step (median over --repeat
runs), the fitted exponent of time per step against particle count, the peak resident
memory of each process, and the speed-up from 1 to 2 threads on the largest case.

    python benchmarks/scaling.py [--end 0.1] [--repeat 3] [--threads 1 2] [--dim 3]

With --dim 3: examples/dam_break_3d.toml at 0.008, 0.004 and 0.002 m (16k, 128k, 1M
particles; use a short --end, e.g. 0.01).

Appends a JSON record to benchmarks/results.jsonl (not tracked) and the time per step and
peak memory of each run to benchmarks/history.csv. The suite's 3D step: `python
benchmarks/scaling.py --dim 3 --end 0.005` (the time per step at 0.002 m, 1.04M particles).
"""

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from history import append, machine, save  # noqa: E402

MESHES = {
    2: [(0.004, 1e-3), (0.002, 5e-4), (0.001, 2.5e-4)],
    3: [(0.008, 1e-3), (0.004, 5e-4), (0.002, 2.5e-4)],
}
EXAMPLE = {2: "dam_break.toml", 3: "dam_break_3d.toml"}


def child(spacing, dt, end, dim):
    """Run one case in this process; print a JSON line with its numbers."""
    from mpmflow import Simulation, load_case

    example = ROOT / "examples" / EXAMPLE[int(dim)]
    # load every kernel into this process first, so the timed loop holds no start-up cost
    Simulation(
        load_case(
            example,
            [
                "grid.spacing=0.02" if dim == 3 else "grid.spacing=0.01",
                "time.end=0.003",
                "output.snapshots=false",
            ],
        )
    ).run()
    case = load_case(
        example,
        [
            f"grid.spacing={spacing}",
            f"time.dt={dt}",
            f"time.end={end}",
            "output.snapshots=false",
            "checkpoint.interval=1000",
        ],
    )
    sim = Simulation(case)
    t0 = time.perf_counter()
    summary = sim.run()
    loop = time.perf_counter() - t0
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # Linux: KiB
    print(
        json.dumps(
            {
                "particles": summary["particles"],
                "steps": summary["steps"],
                "loop_s": loop,
                "s_per_step": loop / summary["steps"],
                "peak_mb": peak_mb,
                "status": summary["status"],
                "unknowns": summary["pressure_solver"]["max_unknowns"],
            }
        )
    )


def run_child(spacing, dt, end, threads, dim):
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), MPMFLOW_THREADS=str(threads))
    out = subprocess.run(
        [sys.executable, __file__, "--child", str(spacing), str(dt), str(end), str(dim)],
        check=True,
        capture_output=True,
        text=True,
        env=env,
    ).stdout
    return json.loads(out.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--end", type=float, default=0.1, help="simulated seconds per run")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument(
        "--dim",
        type=int,
        choices=(2, 3),
        default=2,
        help="3: the 3D dam break (examples/dam_break_3d.toml) at 0.008, 0.004 and "
        "0.002 m, 16k to 1M particles",
    )
    ap.add_argument("--child", nargs=4, type=float, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(*args.child)
        return
    meshes = MESHES[args.dim]
    start = machine()
    run_child(meshes[0][0], 1e-3, 0.003, max(args.threads), args.dim)  # warm-up: the cache
    results = {}
    for threads in args.threads:
        for spacing, dt in meshes:
            if threads != max(args.threads) and spacing != meshes[-1][0]:
                continue  # fewer threads: only the largest case, for the speed-up
            runs = [run_child(spacing, dt, args.end, threads, args.dim) for _ in range(args.repeat)]
            r = dict(
                runs[0],
                s_per_step=statistics.median(x["s_per_step"] for x in runs),
                s_per_step_all=[x["s_per_step"] for x in runs],
                peak_mb=max(x["peak_mb"] for x in runs),
            )
            results[(threads, spacing)] = r
            print(
                f"{threads} thread(s), {spacing} m: {r['particles']} particles, "
                f"{r['steps']} steps, {1e3 * r['s_per_step']:.2f} ms per step (median of "
                f"{args.repeat}), peak memory {r['peak_mb']:.0f} MB",
                flush=True,
            )
    top = max(args.threads)
    n = np.array([results[(top, s)]["particles"] for s, _ in meshes], dtype=float)
    t = np.array([results[(top, s)]["s_per_step"] for s, _ in meshes])
    exponent = float(np.polyfit(np.log(n), np.log(t), 1)[0])
    print(f"time per step ~ particles^{exponent:.2f} ({top} threads, fit over 3 sizes)")
    record = {
        "label": f"scaling {args.dim}D",
        "end": args.end,
        "repeat": args.repeat,
        "exponent": exponent,
        "runs": {f"{k[0]}threads_{k[1]}m": v for k, v in results.items()},
        "machine": start,
        "date": time.strftime("%Y-%m-%d"),
    }
    if len(args.threads) > 1:
        largest = meshes[-1][0]
        speedup = (
            results[(min(args.threads), largest)]["s_per_step"]
            / results[(top, largest)]["s_per_step"]
        )
        record["speedup"] = speedup
        print(f"speed-up from {min(args.threads)} to {top} threads at {largest} m: {speedup:.2f}x")
    save(record)
    for threads in args.threads:
        append(
            f"scaling {args.dim}D",
            [
                (f"{what}, {spacing:g} m", r[key], unit)
                for spacing, _ in meshes
                if (r := results.get((threads, spacing)))
                for what, key, unit in (
                    ("time per step", "s_per_step", "s"),
                    ("peak memory", "peak_mb", "MiB"),
                )
            ],
            note=f"median of {args.repeat}, {args.end:g} s of flow from rest",
            start=start,
            threads=threads,
        )


if __name__ == "__main__":
    main()
