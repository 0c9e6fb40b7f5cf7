"""The per-rank memory estimate (src/mpmflow/parallel/memory.py) against each rank's
measured peak resident memory (issue 42, item 4).

Runs the 3D dam break (examples/dam_break_3d.toml) at each mesh under
``mpirun -n R .venv-mpi/bin/python`` for 20 steps of 1 ms with two output times, each with
a snapshot (the gather of every particle on every rank, and rank 0 writing them), and reads
each rank's peak resident memory (``ru_maxrss`` of getrusage in the rank itself, at its
exit: what /usr/bin/time -v reports as "Maximum resident set size") against the estimate
the run printed (summary.json, ``memory_estimate_bytes.per_rank``; on one rank the
one-process estimate, ``memory_estimate_bytes.total``).

    python benchmarks/investigations/mpi/memory_ranks.py [--spacing 0.004 0.003] [--ranks 1 2 4]
    python benchmarks/investigations/mpi/memory_ranks.py --case examples/dam_break.toml \
        --spacing 0.002 0.001 --ranks 2

Needs `make setup-mpi`. Run it on a quiet machine (it starts R processes at a time).
Prints one row per rank and run.
"""

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
CASE = ROOT / "examples" / "dam_break_3d.toml"
PYTHON = ROOT / ".venv-mpi" / "bin" / "python"
MPIRUN = ["mpirun", "--oversubscribe"]
ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1", "OMP_NUM_THREADS": "1"}


def child(peaks: str, argv: list[str]) -> int:
    """One rank: mpmflow's command line, then this rank's peak into the file ``peaks``."""
    from mpmflow.cli import main

    code = main(argv)
    rank = int(os.environ.get("OMPI_COMM_WORLD_RANK", "0"))
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # Linux: KiB
    with open(f"{peaks}.{rank}", "w") as f:
        json.dump({"rank": rank, "peak": peak}, f)
    return code


def measure(case: Path, spacing: float, ranks: int, folder: Path) -> list[dict]:
    out = folder / f"run_{spacing:g}_{ranks}"
    peaks = folder / f"peaks_{spacing:g}_{ranks}"
    run = [
        "run",
        str(case),
        "--out",
        str(out),
        "-q",
        "--overwrite",
        "--set",
        f"grid.spacing={spacing}",
        "--set",
        "time.end=0.02",
        "--set",
        "output.interval=0.01",
        "--set",
        "output.snapshot_interval=0.01",
    ]
    cmd = [*MPIRUN, "-n", str(ranks), str(PYTHON), __file__, "--child", str(peaks), *run]
    subprocess.run(cmd, check=True, env=dict(os.environ, **ENV), cwd=ROOT)
    summary = json.loads((out / "summary.json").read_text())
    est = summary["memory_estimate_bytes"]
    rows = []
    for r in range(ranks):
        peak = json.loads(Path(f"{peaks}.{r}").read_text())["peak"]
        if "per_rank" in est:
            mine = est["per_rank"]["per_rank"][r]
            total, terms = mine["total"], mine["terms"]
        else:
            total, terms = est["total"], {}
        rows.append(
            {
                "case": case.name,
                "spacing": spacing,
                "ranks": ranks,
                "rank": r,
                "particles": summary["particles"],
                "estimate_MiB": round(total / 2**20, 1),
                "peak_MiB": round(peak / 2**20, 1),
                "estimate/peak": round(total / peak, 3),
                "terms_MiB": {k: round(v / 2**20, 1) for k, v in terms.items()},
            }
        )
    return rows


def main() -> None:
    if len(sys.argv) > 2 and sys.argv[1] == "--child":
        sys.exit(child(sys.argv[2], sys.argv[3:]))
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", type=Path, default=CASE, help="default: the 3D dam break")
    ap.add_argument("--spacing", type=float, nargs="+", default=[0.004])
    ap.add_argument("--ranks", type=int, nargs="+", default=[1, 2])
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        for spacing in args.spacing:
            for ranks in args.ranks:
                for row in measure(args.case, spacing, ranks, Path(tmp)):
                    print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main()
