"""mpmflow against OpenFOAM's interFoam on SPHERIC Test 2 (the MARIN 3D dam break on a box).

Installs nothing. Where OpenFOAM is installed (Debian: `apt install openfoam`, whose
environment is /usr/share/openfoam/etc/bashrc), this script writes the same case as
examples/spheric_test2.toml (Kleefsman et al. 2005) for interFoam:

- the tank 3.22 m x 1 m x 1 m (x along it, y across, z up; gravity -9.81 m/s^2 along z),
  closed, no-slip walls everywhere (U noSlip, p_rgh fixedFluxPressure, alpha zeroGradient);
- the water column x 1.992-3.22 m, the full width, z 0-0.55 m, at rest, air above;
- the box x 0.6635-0.8245 m, y 0.2955-0.6985 m, z 0-0.161 m, cut out of the mesh;
- laminar, water rho 1000 kg/m^3 nu 1e-6 m^2/s, air rho 1 kg/m^3 nu 1.48e-5 m^2/s, no
  surface tension; adaptive time steps at maxCo = maxAlphaCo = 1 (maxDeltaT 0.01 s);
  6 s of flow by default (--end), the fields written at the end only.

The mesh: blockMesh of the whole tank, uniform, the nearest whole number of cells per axis
to the side over --spacing (half up: 3.22 / 0.04 = 80.5 gives 81 cells of 0.03975 m;
1 / 0.04 gives 25), then topoSet (a cellSet of the cells whose centres lie outside the box:
boxToCell, inverted) and `subsetMesh -overwrite -patch box`, which puts the faces the cut
exposes into the wall patch `box` (declared empty in blockMeshDict). The box is thus
staircased to the cell faces nearest its own (at 0.04 m: 4 x 10 x 4 cells, 0.159 x 0.3975
x 0.16 m). setFields fills the water by cell centres, with the cells its surface and its
side at x = 1.992 m cut given the fraction of them that lies in the column, so the water's
volume is exact (checked from checkMesh's total volume and interFoam's first "Phase-1
volume fraction").

Function objects record what mpmflow's probes record, every 0.005 s of flow (at the step
nearest each): p at P1-P8 (`probes`; each sensor moved half a cell off the box face it
sits on, into the water, as the face of the staircased box is not at the sensor), and
alpha.water at the cell centres along the vertical line through each level gauge H1-H4
(`probes` again: v1912 has no interfaceHeight), in the case's postProcessing/ folder; the
script sums the latter into levels (sum of alpha times the cell height) and writes
probes.csv in the case (time, P1-P8 in Pa, H1-H4 in m), as mpmflow's probes.csv. The tank
is closed, so p is fixed by a reference: 0 at the centre of the top row of cells (pRefPoint,
always air), which puts the air at the floor about 10 Pa above 0. p_rgh is solved by GAMG
(--solver pcg: PCG-DIC, as the 2D dam break's script).

Times the whole of blockMesh, topoSet, subsetMesh, setFields and interFoam (serial) as one:
wall (perf_counter) and CPU (user + system of the children, resource.getrusage). Prints the
cell count and the number of time steps interFoam took (checkMesh runs after the timing,
on the first case: cells, the box patch's faces, the mesh's volume). With --pairs N it also runs

    python -m mpmflow.cli run examples/spheric_test2.toml --out DIR --quiet --overwrite \
        --set grid.spacing=S --set time.end=E

(the example's outputs, threads as users run it; mpmflow puts the end wall on the grid at
3.24 m where 3.22 m is not whole cells) as a whole process, after interFoam in each pair,
after one short warm-up run (the page cache), and prints the medians and the ratio. Appends a
record to benchmarks/results.jsonl.

    python benchmarks/peers/interfoam_spheric.py [--spacing 0.04] [--end 6] [--pairs N]
        [--keep DIR]
"""

import argparse
import json
import math
import os
import re
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benchmarks"))
sys.path.insert(0, str(Path(__file__).resolve().parent))
from history import append, machine, save  # noqa: E402
from interfoam_dam_break import FV_SCHEMES, HEADER, openfoam_command  # noqa: E402

EXAMPLE = ROOT / "examples" / "spheric_test2.toml"
TANK = (3.22, 1.0, 1.0)  # m
WATER = ((1.992, 0.0, 0.0), (3.22, 1.0, 0.55))  # m
BOX = ((0.6635, 0.2955, 0.0), (0.8245, 0.6985, 0.161))  # m
# MARIN's sensors (as examples/spheric_test2.toml's [[probes]]) and the side of the box each
# pressure sensor sits on: +x is the face the water hits, +z the top
PRESSURE = {
    "P1": ((0.8245, 0.471, 0.021), 0),
    "P2": ((0.8245, 0.471, 0.061), 0),
    "P3": ((0.8245, 0.471, 0.101), 0),
    "P4": ((0.8245, 0.471, 0.141), 0),
    "P5": ((0.8035, 0.471, 0.161), 2),
    "P6": ((0.7635, 0.471, 0.161), 2),
    "P7": ((0.7235, 0.471, 0.161), 2),
    "P8": ((0.6835, 0.471, 0.161), 2),
}
LEVEL = {
    "H1": (0.496, 0.5, 0.0),
    "H2": (0.992, 0.5, 0.0),
    "H3": (1.488, 0.5, 0.0),
    "H4": (2.638, 0.5, 0.0),
}
NUMBER = r"([-+]?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?)"
APPS = ("blockMesh", "topoSet", "subsetMesh", "setFields", "interFoam")


def cells(spacing):
    """Cells per axis: the nearest whole number to side / spacing (half up)."""
    return tuple(max(1, math.floor(side / spacing + 0.5)) for side in TANK)


def runs(lo, hi, n, side):
    """Along one axis: (box_lo, box_hi, fraction) for the runs of cells that the interval
    [lo, hi] covers by the same fraction; the box bounds catch those cells' centres only."""
    h = side / n
    frac = [min(max((min(hi, (i + 1) * h) - max(lo, i * h)) / h, 0.0), 1.0) for i in range(n)]
    out, i = [], 0
    while i < n:
        j = i
        while j + 1 < n and abs(frac[j + 1] - frac[i]) < 1e-9:
            j += 1
        if frac[i] > 1e-9:
            out.append(((i + 0.25) * h, (j + 0.75) * h, frac[i]))
        i = j + 1
    return out


def files(spacing, end, solver):
    n = cells(spacing)
    h = [side / k for side, k in zip(TANK, n)]
    lx, ly, lz = TANK
    regions = []
    for x0, x1, fx in runs(WATER[0][0], WATER[1][0], n[0], lx):
        for y0, y1, fy in runs(WATER[0][1], WATER[1][1], n[1], ly):
            for z0, z1, fz in runs(WATER[0][2], WATER[1][2], n[2], lz):
                regions.append(
                    f"    boxToCell {{ box ({x0:.9g} {y0:.9g} {z0:.9g}) "
                    f"({x1:.9g} {y1:.9g} {z1:.9g}); fieldValues "
                    f"( volScalarFieldValue alpha.water {fx * fy * fz:.12g} ); }}"
                )
    probes = []
    for (x, y, z), axis in PRESSURE.values():
        p = [x, y, z]
        p[axis] += h[axis] / 2
        probes.append(f"({p[0]:.9g} {p[1]:.9g} {p[2]:.9g})")
    # the level gauges: alpha along the vertical line through each, at the cell centres
    columns = [
        f"({x} {y} {(k + 0.5) * h[2]:.9g})" for x, y, _ in LEVEL.values() for k in range(n[2])
    ]
    (bx0, by0, bz0), (bx1, by1, bz1) = BOX
    linear = (
        "p_rgh { solver PCG; preconditioner DIC; tolerance 1e-07; relTol 0.05; }"
        if solver == "pcg"
        else "p_rgh { solver GAMG; smoother DIC; tolerance 1e-07; relTol 0.05; }"
    )
    pcorr = (
        '"pcorr.*" { solver PCG; preconditioner DIC; tolerance 1e-5; relTol 0; }'
        if solver == "pcg"
        else '"pcorr.*" { solver GAMG; smoother DIC; tolerance 1e-5; relTol 0; }'
    )
    walls = "walls { type %s; } box { type %s; }"
    return {
        ("system", "controlDict", "dictionary"): f"""
application interFoam;
startFrom startTime;
startTime 0;
stopAt endTime;
endTime {end};
deltaT 1e-4;
writeControl adjustableRunTime;
writeInterval {end};
purgeWrite 0;
writeFormat binary;
writePrecision 8;
writeCompression off;
timeFormat general;
timePrecision 6;
runTimeModifiable false;
adjustTimeStep yes;
maxCo 1;
maxAlphaCo 1;
maxDeltaT 0.01;
functions
{{
    pressure
    {{
        type probes;
        libs ("libsampling.so");
        writeControl runTime;
        writeInterval 0.005;
        fields (p);
        probeLocations ( {" ".join(probes)} );
    }}
    level
    {{
        type probes;
        libs ("libsampling.so");
        writeControl runTime;
        writeInterval 0.005;
        fields (alpha.water);
        probeLocations ( {" ".join(columns)} );
    }}
}}
""",
        ("system", "blockMeshDict", "dictionary"): f"""
scale 1;
vertices
(
    (0 0 0) ({lx} 0 0) ({lx} {ly} 0) (0 {ly} 0)
    (0 0 {lz}) ({lx} 0 {lz}) ({lx} {ly} {lz}) (0 {ly} {lz})
);
blocks ( hex (0 1 2 3 4 5 6 7) ({n[0]} {n[1]} {n[2]}) simpleGrading (1 1 1) );
boundary
(
    walls {{ type wall; faces ( (0 4 7 3) (1 2 6 5) (0 1 5 4) (3 7 6 2) (0 3 2 1)
                               (4 5 6 7) ); }}
    box {{ type wall; faces ( ); }}
);
""",
        # the fluid: the cells whose centres lie outside the box
        ("system", "topoSetDict", "dictionary"): f"""
actions
(
    {{ name fluid; type cellSet; action new; source boxToCell;
       sourceInfo {{ box ({bx0} {by0} {bz0}) ({bx1} {by1} {bz1}); }} }}
    {{ name fluid; type cellSet; action invert; }}
);
""",
        ("system", "setFieldsDict", "dictionary"): """
defaultFieldValues ( volScalarFieldValue alpha.water 0 );
regions
(
"""
        + "\n".join(regions)
        + "\n);\n",
        ("system", "fvSchemes", "dictionary"): FV_SCHEMES,
        ("system", "fvSolution", "dictionary"): f"""
solvers
{{
    "alpha.water.*" {{ nAlphaCorr 2; nAlphaSubCycles 1; cAlpha 1; MULESCorr yes;
                      nLimiterIter 3; solver smoothSolver; smoother symGaussSeidel;
                      tolerance 1e-8; relTol 0; }}
    {pcorr}
    {linear}
    p_rghFinal {{ $p_rgh; relTol 0; }}
    U {{ solver smoothSolver; smoother symGaussSeidel; tolerance 1e-06; relTol 0; }}
}}
PIMPLE
{{
    momentumPredictor no; nOuterCorrectors 1; nCorrectors 3; nNonOrthogonalCorrectors 0;
    pRefPoint ({lx / 2} {ly / 2} {lz - h[2] / 2}); pRefValue 0;
}}
relaxationFactors {{ equations {{ ".*" 1; }} }}
""",
        ("constant", "transportProperties", "dictionary"): """
phases (water air);
water { transportModel Newtonian; nu 1e-06; rho 1000; }
air { transportModel Newtonian; nu 1.48e-05; rho 1; }
sigma 0;
""",
        ("constant", "turbulenceProperties", "dictionary"): "simulationType laminar;\n",
        ("constant", "g", "uniformDimensionedVectorField"): """
dimensions [0 1 -2 0 0 0 0];
value (0 0 -9.81);
""",
        ("0", "alpha.water", "volScalarField"): f"""
dimensions [0 0 0 0 0 0 0];
internalField uniform 0;
boundaryField {{ {walls % ("zeroGradient", "zeroGradient")} }}
""",
        ("0", "U", "volVectorField"): f"""
dimensions [0 1 -1 0 0 0 0];
internalField uniform (0 0 0);
boundaryField {{ {walls % ("noSlip", "noSlip")} }}
""",
        ("0", "p_rgh", "volScalarField"): """
dimensions [1 -1 -2 0 0 0 0];
internalField uniform 0;
boundaryField
{
    walls { type fixedFluxPressure; value uniform 0; }
    box { type fixedFluxPressure; value uniform 0; }
}
""",
        ("0", "p", "volScalarField"): """
dimensions [1 -1 -2 0 0 0 0];
internalField uniform 0;
boundaryField
{
    walls { type calculated; value uniform 0; }
    box { type calculated; value uniform 0; }
}
""",
    }


def write_case(case, spacing, end, solver, functions=""):
    """The case's files in ``case``; ``functions``: more function objects (OpenFOAM
    dictionary text) put inside controlDict's functions dictionary."""
    fs = files(spacing, end, solver)
    if functions:
        key = ("system", "controlDict", "dictionary")
        body = fs[key]
        fs[key] = body[: body.rstrip().rfind("}")] + functions + "}\n"
    for (folder, name, cls), body in fs.items():
        path = case / folder / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(HEADER.format(cls=cls, obj=name) + body)


def run_with_functions(case, spacing, end, functions):
    """write_case with the extra function objects (GAMG), interFoam run in it, the probes'
    CSV written (the peer scripts that sample more than the case's probes)."""
    write_case(case, spacing, end, "gamg", functions)
    prefix = openfoam_command()
    if prefix is None:
        raise SystemExit("OpenFOAM not found")
    wall, cpu = run_interfoam(case, prefix)
    print(f"interFoam: {wall:.0f} s wall, {cpu:.0f} s CPU")
    write_probes_csv(case, spacing)


def children_cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run_apps(case, prefix, apps, args=None):
    for app in apps:
        extra = (args or {}).get(app, [])
        with open(case / f"log.{app}", "w") as log:
            done = subprocess.run(
                [*prefix, app, "-case", str(case), *extra], stdout=log, stderr=subprocess.STDOUT
            )
        if done.returncode:
            raise SystemExit(f"{app} failed (exit {done.returncode}); see {case}/log.{app}")


def run_interfoam(case, prefix):
    """The five applications in the case folder: (wall s, CPU s of the children)."""
    c0, t0 = children_cpu(), time.perf_counter()
    run_apps(case, prefix, APPS, {"subsetMesh": ["fluid", "-overwrite", "-patch", "box"]})
    return time.perf_counter() - t0, children_cpu() - c0


def interfoam_facts(case, prefix):
    """From the logs (and checkMesh, run after the timing): cells, time steps, water volume."""
    run_apps(case, prefix, ("checkMesh",))
    check = (case / "log.checkMesh").read_text()
    log = (case / "log.interFoam").read_text()
    facts = {
        "cells": int(re.search(r"^\s*cells:\s+(\d+)", check, re.M).group(1)),
        "mesh_ok": "Mesh OK." in check,
        "steps": len(re.findall(r"^Time = ", log, re.M)),
    }
    volume = float(re.search(r"Total volume = " + NUMBER, check).group(1))
    box = re.search(r"^\s*box\s+(\d+)\s+\d+", check, re.M)
    facts["box_faces"] = int(box.group(1)) if box else None
    first = re.search(r"Phase-1 volume fraction = " + NUMBER, log)
    if first:
        facts["water_volume"] = float(first.group(1)) * volume
    facts["mesh_volume"] = volume
    clock = re.findall(r"ExecutionTime = " + NUMBER + r" s\s+ClockTime = " + NUMBER + " s", log)
    if clock:
        facts["interfoam_execution_s"] = float(clock[-1][0])
    return facts


def read_probes(path):
    """(times, rows of values) from a probes function object's file of a scalar field."""
    rows = [
        line.split()
        for line in path.read_text().splitlines()
        if line.strip() and not line.lstrip().startswith("#")
    ]
    return [float(r[0]) for r in rows], [[float(v) for v in r[1:]] for r in rows]


def write_probes_csv(case, spacing):
    """case/probes.csv: time, P1-P8 (p, Pa) and H1-H4 (level, m) from the function objects'
    output; the number of rows (0 where the output is missing)."""
    pressure = case / "postProcessing" / "pressure" / "0" / "p"
    alpha = case / "postProcessing" / "level" / "0" / "alpha.water"
    if not (pressure.exists() and alpha.exists()):
        return 0
    nz = cells(spacing)[2]
    dz = TANK[2] / nz
    tp, p = read_probes(pressure)
    ta, a = read_probes(alpha)
    levels = {
        round(t, 9): [sum(r[g * nz : (g + 1) * nz]) * dz for g in range(len(LEVEL))]
        for t, r in zip(ta, a)
    }
    lines = ["time," + ",".join([*PRESSURE, *LEVEL])]
    for t, r in zip(tp, p):
        h = levels.get(round(t, 9))
        if h is not None:
            lines.append(",".join(f"{v:.8g}" for v in (t, *r, *h)))
    (case / "probes.csv").write_text("\n".join(lines) + "\n")
    return len(lines) - 1


def run_mpmflow(out, spacing, end):
    """The example as a whole process: (wall s, CPU s of the child)."""
    c0, t0 = children_cpu(), time.perf_counter()
    subprocess.run(
        [
            sys.executable,
            "-m",
            "mpmflow.cli",
            "run",
            str(EXAMPLE),
            "--out",
            str(out),
            "--quiet",
            "--overwrite",
            "--set",
            f"grid.spacing={spacing}",
            "--set",
            f"time.end={end}",
        ],
        check=True,
    )
    return time.perf_counter() - t0, children_cpu() - c0


def mpmflow_steps(out):
    try:
        summary = json.loads((Path(out) / "summary.json").read_text())
    except (OSError, ValueError):
        return None
    for key in ("steps", "n_steps", "time_steps"):
        if key in summary:
            return summary[key]
    return None


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spacing", type=float, default=0.04, help="mesh spacing, m (0.04)")
    ap.add_argument("--end", type=float, default=6.0, help="seconds of flow (6)")
    ap.add_argument(
        "--pairs",
        type=int,
        default=0,
        help="also run mpmflow, alternating with interFoam, N times each (0)",
    )
    ap.add_argument(
        "--solver",
        choices=("gamg", "pcg"),
        default="gamg",
        help="interFoam's p_rgh solver (GAMG, as 3D cases use; or PCG-DIC)",
    )
    ap.add_argument("--keep", metavar="DIR", help="keep the cases and runs in DIR")
    args = ap.parse_args()
    prefix = openfoam_command()
    if prefix is None:
        raise SystemExit(
            "OpenFOAM is not installed (no interFoam on the PATH and no "
            "/usr/bin/openfoamNNNN launcher). On Debian: apt install openfoam."
        )
    base = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="peers_spheric_"))
    base.mkdir(parents=True, exist_ok=True)
    start = machine()
    n = cells(args.spacing)
    h = [side / k for side, k in zip(TANK, n)]
    print(
        f"interFoam mesh: {n[0]} x {n[1]} x {n[2]} cells of "
        f"{h[0]:.5g} x {h[1]:.5g} x {h[2]:.5g} m (the nearest whole numbers to the sides "
        f"over {args.spacing} m), less the box's",
        flush=True,
    )
    if args.pairs:
        run_mpmflow(base / "mpmflow_warmup", args.spacing, min(args.end, 0.01))
    ours, theirs, facts = [], [], None
    for k in range(max(args.pairs, 1)):
        case = base / f"interfoam_{k}"
        shutil.rmtree(case, ignore_errors=True)
        write_case(case, args.spacing, args.end, args.solver)
        theirs.append(run_interfoam(case, prefix))
        if facts is None:
            facts = interfoam_facts(case, prefix)
            facts["probe_rows"] = write_probes_csv(case, args.spacing)
            water = (WATER[1][0] - WATER[0][0]) * (WATER[1][1] - WATER[0][1]) * WATER[1][2]
            print(
                f"interFoam: {facts['cells']} cells (checkMesh: "
                f"{'Mesh OK' if facts['mesh_ok'] else 'FAILED, see log.checkMesh'}; "
                f"box patch {facts['box_faces']} faces; volume {facts['mesh_volume']:.6g} "
                f"m^3), water {facts.get('water_volume', float('nan')):.6g} m^3 "
                f"(column {water:.6g} m^3), {facts['steps']} time steps to {args.end} s; "
                f"probes.csv {facts['probe_rows']} rows",
                flush=True,
            )
        line = f"interFoam {theirs[-1][0]:.2f} s wall, {theirs[-1][1]:.2f} s CPU"
        if args.pairs:
            ours.append(run_mpmflow(base / "mpmflow", args.spacing, args.end))
            line = (
                f"pair {k + 1}: {line}; mpmflow {ours[-1][0]:.2f} s wall, "
                f"{ours[-1][1]:.2f} s CPU; ratio {theirs[-1][0] / ours[-1][0]:.2f}"
            )
        print(line, flush=True)
    record = {
        "label": "peers/interfoam_spheric",
        "spacing": args.spacing,
        "end": args.end,
        "cells": n,
        "solver": args.solver,
        "interfoam": facts,
        "interfoam_s": [w for w, _ in theirs],
        "interfoam_cpu_s": [c for _, c in theirs],
    }
    print()
    print(
        f"interFoam (serial): median {statistics.median(w for w, _ in theirs):.2f} s wall, "
        f"{statistics.median(c for _, c in theirs):.2f} s CPU"
    )
    if args.pairs:
        ratios = [b[0] / a[0] for a, b in zip(ours, theirs)]
        steps = mpmflow_steps(base / "mpmflow")
        print(
            f"mpmflow: median {statistics.median(w for w, _ in ours):.2f} s wall, "
            f"{statistics.median(c for _, c in ours):.2f} s CPU"
            + (f", {steps} time steps" if steps is not None else "")
        )
        print(
            f"interFoam / mpmflow (wall): median of {args.pairs} pairs "
            f"{statistics.median(ratios):.2f}x (pairs: {', '.join(f'{r:.2f}' for r in ratios)})"
        )
        record.update(
            {
                "pairs": args.pairs,
                "mpmflow_s": [w for w, _ in ours],
                "mpmflow_cpu_s": [c for _, c in ours],
                "mpmflow_steps": steps,
                "ratio_median": statistics.median(ratios),
            }
        )
    record.update(
        {"machine": start, "openfoam": shutil.which("interFoam"), "date": time.strftime("%Y-%m-%d")}
    )
    save(record)
    figures = [
        (
            f"interFoam whole process, {args.spacing:g} m",
            statistics.median(record["interfoam_s"]),
            "s",
        )
    ]
    if args.pairs:
        figures += [
            (
                f"mpmflow whole process, {args.spacing:g} m",
                statistics.median(record["mpmflow_s"]),
                "s",
            ),
            (f"interFoam / mpmflow, {args.spacing:g} m", record["ratio_median"], "x"),
        ]
    append(
        "peers/interfoam_spheric",
        figures,
        note=f"{args.end:g} s of flow; {max(args.pairs, 1)} run(s); interFoam serial, {args.solver}",
        start=start,
    )
    if not args.keep:
        shutil.rmtree(base, ignore_errors=True)


if __name__ == "__main__":
    os.environ.setdefault("OMPI_MCA_btl_vader_single_copy_mechanism", "none")
    main()
