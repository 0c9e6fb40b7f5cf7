"""The CUDA backend against the host: the check program's phases side by side.

`make check-cuda` (on a machine with nvcc and an NVIDIA GPU) builds src/core/cuda and runs
`build-cuda/mpmflow_cuda_check`, which moves the dam break's column (2D and 3D, up to
1.04 M particles; 66 M with MPMFLOW_CHECK_BIG=1) through the host's transfers and the
device's, checks that they agree and writes one JSON line per case. This script reads
those lines and prints, per case, each phase's milliseconds on both and the ratio, and
appends the 3D cases' figures to benchmarks/history.csv:

    python benchmarks/cuda.py [--from build-cuda/check.jsonl ...] [--host HOST.jsonl]
        [--commit C] [--no-history]

--host: the same program's lines from a machine without a GPU (it then times the host's
phases only), e.g. the 2-core machine the other benchmarks run on: the ratio is then
against that machine. --commit names the commit the lines were measured at (default:
this checkout's).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from history import append, machine  # noqa: E402

PHASES = ("binning", "p2g", "g2p")


def read(paths: list[Path]) -> list[dict]:
    rows = []
    for path in paths:
        for line in path.read_text().splitlines():
            if line.startswith("{"):
                rows.append(json.loads(line))
    return rows


def key(r: dict) -> tuple:
    return (r["dim"], r["particles"], r["apic"])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--from",
        dest="paths",
        type=Path,
        nargs="+",
        default=[HERE.parent / "build-cuda" / "check.jsonl"],
    )
    ap.add_argument("--host", type=Path, help="host-only lines of another machine")
    ap.add_argument("--commit", help="the commit the lines were measured at")
    ap.add_argument("--no-history", action="store_true")
    args = ap.parse_args(argv)
    for p in [*args.paths, *([args.host] if args.host else [])]:
        if not p.is_file():
            print(f"no {p}: run `make check-cuda` on a machine with a GPU first", file=sys.stderr)
            return 2
    lines = [r for r in read(args.paths) if "device_ms" in r]
    dev = [r for r in lines if "particles" in r]
    solves = [r for r in lines if r.get("solve") == "pcg"]
    other = {key(r): r for r in read([args.host])} if args.host else {}
    print(
        "| dim | particles | APIC | device | device ms (bin, p2g, g2p) | host ms "
        "(threads) | ratio |"
    )
    print("|---|---|---|---|---|---|---|")
    start = machine()
    if args.commit:
        start["commit"] = args.commit
    for r in dev:
        host = other.get(key(r), r)
        d = sum(r["device_ms"][p] for p in PHASES)
        h = sum(host["host_ms"][p] for p in PHASES)
        where = "this host" if host is r else str(args.host)
        parts = ", ".join(f"{r['device_ms'][p]:.3f}" for p in PHASES)
        print(
            f"| {r['dim']} | {r['particles']:,} | {r['apic']} | {r['device']} | "
            f"{d:.3f} ({parts}) | "
            f"{h:.2f} ({host['host_threads']} threads, {where}) | {h / d:.1f} |"
        )
        if args.no_history or r["dim"] != 3 or r["particles"] < 10**6:
            continue
        name = f"cuda transfers 3D {r['particles']} particles{' APIC' if r['apic'] else ''}"
        dm = dict(start, cpu=r["device"], cores=r["host_threads"])
        append(
            name,
            [(f"device {p}", r["device_ms"][p], "ms") for p in PHASES]
            + [("device particle-steps per second", r["particles"] / (d * 1e-3), "1/s")],
            note="make check-cuda; binning, particle-to-grid, grid-to-particle",
            start=dm,
            threads="GPU",
        )
        # the host's figures: the GPU machine's own CPU, or the --host machine (this one)
        hm = dict(
            start,
            cpu=f"host of {r['device']}" if host is r else start["cpu"],
            cores=host["host_threads"],
        )
        append(
            name,
            [(f"host {p}", host["host_ms"][p], "ms") for p in PHASES]
            + [("device against host", h / d, "x")],
            note=f"the same program's host phases ({where})",
            start=hm,
            threads=host["host_threads"],
        )
    print()
    print(
        "| dim | unknowns | iterations (host, device) | device ms (upload, pcg) | host ms "
        "(setup, pcg; threads) | pcg ratio |"
    )
    print("|---|---|---|---|---|---|")
    for r in solves:
        d, h = r["device_ms"], r["host_ms"]
        print(
            f"| {r['dim']} | {r['unknowns']:,} | {r['iterations']} | {d['upload']:.1f}, "
            f"{d['pcg']:.1f} | {h['setup']:.1f}, {h['pcg']:.1f}; {r['host_threads']} | "
            f"{h['pcg'] / d['pcg']:.1f} |"
        )
        if args.no_history or r["dim"] != 3 or r["unknowns"] < 10**5:
            continue
        append(
            f"cuda pcg 3D {r['unknowns']} unknowns",
            [
                ("device pcg", d["pcg"], "ms"),
                ("device upload", d["upload"], "ms"),
                ("host pcg", h["pcg"], "ms"),
                ("host setup", h["setup"], "ms"),
            ],
            note=f"make check-cuda; host: the GPU machine's {r['host_threads']} threads",
            start=dict(start, cpu=r["device"]),
            threads="GPU",
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
