"""The native core against the last Numba commit: particle positions after the first steps
of the paper's dam break (issue 23: agree to 1e-10 m over 20 steps).

Runs each code in its own process on the same case and compares the particles:

    python benchmarks/against_numba.py --baseline /path/to/checkout-of-9b87813 \
        [--python /path/to/python-with-numba] [--case CASE] [--steps 20] [--set key=value ...]

The baseline is a checkout of the last Numba commit (`git worktree add /tmp/numba 9b87813`)
run with an interpreter that has its dependencies (numba); this checkout runs with the
interpreter running the script. Prints the largest position, velocity and pressure
differences and exits 1 when the positions differ by more than --tolerance (m).
"""

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
CASE = ROOT / "examples" / "dam_break.toml"

RUN = """
import sys, numpy as np
from mpmflow import Simulation, load_case
case = load_case(sys.argv[1], sys.argv[3:])
sim = Simulation(case)
sim.run()
P = sim.particles
np.savez(sys.argv[2], x=P.x, v=P.v, pressure=P.pressure)
"""


def run(python, src, case, out, overrides):
    env = dict(os.environ)
    if src is not None:
        env["PYTHONPATH"] = str(src)
    subprocess.run(
        [python, "-c", RUN, str(case), str(out), *overrides],
        check=True,
        env=env,
        cwd=tempfile.gettempdir(),
    )
    return np.load(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--baseline", required=True, type=Path, help="checkout of the Numba commit")
    ap.add_argument("--python", default=sys.executable, help="interpreter for the baseline")
    ap.add_argument("--case", type=Path, default=CASE, help="case file (default: the dam break)")
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--dt", type=float, default=1e-3)
    ap.add_argument("--tolerance", type=float, default=1e-10)
    ap.add_argument("--set", action="append", default=[])
    a = ap.parse_args()
    overrides = [f"time.dt={a.dt}", f"time.end={a.steps * a.dt}", "output.snapshots=false", *a.set]
    with tempfile.TemporaryDirectory() as tmp:
        new = run(sys.executable, None, a.case.resolve(), Path(tmp) / "core.npz", overrides)
        old = run(
            a.python, a.baseline / "src", a.case.resolve(), Path(tmp) / "numba.npz", overrides
        )
    dx = float(np.abs(new["x"] - old["x"]).max())
    dv = float(np.abs(new["v"] - old["v"]).max())
    dp = float(np.abs(new["pressure"] - old["pressure"]).max())
    print(
        f"{new['x'].shape[0]} particles, {a.steps} steps of {a.dt:g} s: "
        f"max |dx| = {dx:.3e} m, max |dv| = {dv:.3e} m/s, max |dp| = {dp:.3e} Pa "
        f"(tolerance on x: {a.tolerance:g} m)"
    )
    sys.exit(0 if dx <= a.tolerance else 1)


if __name__ == "__main__":
    main()
