"""What a benchmark run records, shared by the scripts under benchmarks/.

- ``append(benchmark, figures)``: the run's headline figures, one row each, appended to
  benchmarks/history.csv (tracked: commit the rows with the change they measure, so that the
  file is the suite's history): date, commit, machine, cores, threads, benchmark, figure,
  value, unit, note.
- ``save(record)``: the whole record (every run, every setting) as a JSON line appended to
  benchmarks/results.jsonl (not tracked), as the investigations under
  benchmarks/investigations/ write theirs.
- ``machine()``: the CPU model (/proc/cpuinfo), cores, Python, NumPy, the commit and the
  thread setting, as both record them.

Standard library only (NumPy's version is read if it imports), so that it runs in the MPI
environment too.
"""

from __future__ import annotations

import csv
import datetime
import json
import os
import platform
import subprocess
from collections.abc import Iterable
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
HISTORY = HERE / "history.csv"
RESULTS = HERE / "results.jsonl"
COLUMNS = (
    "date",
    "commit",
    "machine",
    "cores",
    "threads",
    "benchmark",
    "figure",
    "value",
    "unit",
    "note",
)


def cpu_model() -> str:
    """The CPU's model name from /proc/cpuinfo (platform.processor() elsewhere)."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def commit() -> str:
    """The checkout's short commit; '+dirty' when tracked files differ from it (the numbers
    then measure more than the commit)."""

    def git(*args: str) -> str:
        try:
            return subprocess.run(
                ["git", "-C", str(ROOT), *args], capture_output=True, text=True
            ).stdout.strip()
        except OSError:
            return ""

    head = git("rev-parse", "--short", "HEAD") or "?"
    return head + ("+dirty" if git("status", "--porcelain", "--untracked-files=no") else "")


def threads() -> str:
    """The thread setting the run inherits (MPMFLOW_THREADS, else OMP_NUM_THREADS)."""
    return os.environ.get("MPMFLOW_THREADS") or os.environ.get("OMP_NUM_THREADS") or "default"


def machine() -> dict[str, Any]:
    try:
        import numpy

        numpy_version = numpy.__version__
    except ImportError:
        numpy_version = "-"
    return {
        "cpu": cpu_model(),
        "cores": os.cpu_count(),
        "python": platform.python_version(),
        "numpy": numpy_version,
        "commit": commit(),
        "threads": threads(),
    }


def save(record: dict[str, Any]) -> None:
    """Print the machine and append the whole record to benchmarks/results.jsonl."""
    print(f"machine: {record.get('machine', machine())}")
    with open(RESULTS, "a") as f:
        f.write(json.dumps(record) + "\n")


def append(
    benchmark: str,
    figures: Iterable[tuple[str, float, str]],
    note: str = "",
    start: dict[str, Any] | None = None,
    threads: int | str | None = None,
) -> None:
    """Append one row per (figure, value, unit) to benchmarks/history.csv. ``start``: the
    machine() taken when the run started (a long run outlives commits made meanwhile);
    ``threads``: the threads the figures ran on, where the script set them itself."""
    m = dict(start or machine())
    if threads is not None:
        m["threads"] = threads
    date = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d")
    new = not HISTORY.exists()
    with open(HISTORY, "a", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        if new:
            w.writerow(COLUMNS)
        for figure, value, unit in figures:
            w.writerow(
                [
                    date,
                    m["commit"],
                    m["cpu"],
                    m["cores"],
                    m["threads"],
                    benchmark,
                    figure,
                    f"{value:.6g}",
                    unit,
                    note,
                ]
            )
    print(f"appended to {HISTORY}: {benchmark}")
