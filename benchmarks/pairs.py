"""Two codes timed back to back, in alternating pairs: `mpmflow run CASE` as a whole process
with this checkout and with another one (the last Numba commit, say), so that a shared,
noisy machine treats both alike. Prints each run, the medians and their ratio.

    python benchmarks/pairs.py --baseline /path/to/other/checkout --python /path/to/its/python \
        [--case examples/dam_break.toml] [--pairs 5] [--set key=value ...]

The other checkout runs with PYTHONPATH=its src and the interpreter given (one with its
dependencies); this one with the interpreter running the script. One warm-up run of each
first (the page cache; a Numba checkout also fills its compile cache then). Appends a JSON
record to benchmarks/results.jsonl.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from dam_break import machine, save  # noqa: E402


def run(python, src, case, out, overrides):
    env = dict(os.environ)
    if src is not None:
        env["PYTHONPATH"] = str(src)
    cmd = [
        python,
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
    subprocess.run(cmd, check=True, env=env, cwd=tempfile.gettempdir())
    wall = time.perf_counter() - t0
    summary = json.loads((Path(out) / "summary.json").read_text())
    return wall, summary


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--baseline", required=True, type=Path)
    ap.add_argument("--python", default=sys.executable)
    ap.add_argument("--case", type=Path, default=ROOT / "examples" / "dam_break.toml")
    ap.add_argument("--pairs", type=int, default=5)
    ap.add_argument("--set", action="append", default=[])
    a = ap.parse_args()
    case = a.case.resolve()
    walls = {"this": [], "baseline": []}
    with tempfile.TemporaryDirectory() as tmp:
        codes = {"this": (sys.executable, None), "baseline": (a.python, a.baseline / "src")}
        for name, (py, src) in codes.items():  # warm-up
            run(py, src, case, Path(tmp) / name, a.set)
        for k in range(a.pairs):
            for name, (py, src) in codes.items():
                wall, summary = run(py, src, case, Path(tmp) / name, a.set)
                walls[name].append(wall)
                print(f"pair {k + 1} {name}: {wall:.2f} s ({summary['steps']} steps)", flush=True)
    med = {name: statistics.median(w) for name, w in walls.items()}
    ratio = med["baseline"] / med["this"]
    print(
        f"{case.name} {' '.join(a.set)}: this {med['this']:.2f} s, baseline "
        f"{med['baseline']:.2f} s (medians of {a.pairs}): {ratio:.2f}x"
    )
    save(
        {
            "script": "pairs.py",
            "case": case.name,
            "overrides": a.set,
            "walls": walls,
            "medians": med,
            "speedup": ratio,
            "baseline": str(a.baseline),
            "machine": machine(),
        }
    )


if __name__ == "__main__":
    main()
