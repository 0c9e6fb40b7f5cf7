"""The validation rows with the default transfer against solver.transfer = "apic" (issue 26,
item 3): the same cases of `mpmflow validate`, run twice, the second time with every case
file loaded with ``solver.transfer=apic`` added to its overrides.

    python benchmarks/investigations/apic_validation.py [--quick] [--case dam_break --case sloshing ...]
        [--out runs/apic_validation] [--set key=value ...]

Writes the two reports (OUT/flip, OUT/apic: README.md and summary.csv, as `mpmflow
validate` writes them) and prints a Markdown table: row, value with the default transfer,
value with APIC, APIC - default. ``--set`` adds overrides to the APIC runs only (e.g.
``--set solver.volume_correction=0``). Default cases: dam_break, dam_break_ar1, sloshing.
"""

import argparse
import csv
import json
import time
from pathlib import Path

from mpmflow.validation import common, run_validation

ROOT = Path(__file__).resolve().parents[2]

ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
ap.add_argument(
    "--quick", action="store_true", help="the quick versions (mpmflow validate --quick)"
)
ap.add_argument(
    "--case",
    action="append",
    default=[],
    dest="cases",
    help="a validation case (repeatable; default dam_break, dam_break_ar1, sloshing)",
)
ap.add_argument("--out", default=str(ROOT / "runs" / "apic_validation"))
ap.add_argument("--set", action="append", default=[], help="more overrides of the APIC runs")
ap.add_argument(
    "--only",
    choices=("flip", "apic"),
    help="run one transfer only (the other's report, if there, is read)",
)
cli = ap.parse_args()
cases = cli.cases or ["dam_break", "dam_break_ar1", "sloshing"]
out = Path(cli.out)

_load = common.load_case


def run(transfer, extra):
    def load(path, overrides=()):
        return _load(path, [*overrides, *extra])

    common.load_case = load
    try:
        t0 = time.perf_counter()
        run_validation(out / transfer, quick=cli.quick, cases=cases)
        return time.perf_counter() - t0
    finally:
        common.load_case = _load


wall = {}
for transfer, extra in (("flip", []), ("apic", ["solver.transfer=apic", *cli.set])):
    if cli.only in (None, transfer):
        wall[transfer] = run(transfer, extra)


def rows(transfer):
    with open(out / transfer / "summary.csv", newline="") as f:
        return {(r["case"], r["quantity"]): r for r in csv.DictReader(f)}


a, b = rows("flip"), rows("apic")
print("| row | measure | default (FLIP 0.99) | APIC | APIC - default |")
print("|---|---|---|---|---|")
for key, r in a.items():
    s = b.get(key)
    va = float(r["value"])
    vb = float(s["value"]) if s else float("nan")
    unit = f" {r['unit']}" if r.get("unit") else ""
    print(
        f"| {key[0]}: {key[1]} | {r['measure']} | {va:.4g}{unit} ({r['status']}) | "
        f"{vb:.4g} ({s['status'] if s else '-'}) | {vb - va:+.4f} |"
    )
print(json.dumps({"quick": cli.quick, "cases": cases, "apic_overrides": cli.set, "wall_s": wall}))
