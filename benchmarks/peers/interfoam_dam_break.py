"""mpmflow against OpenFOAM's interFoam on the paper's dam break, at equal accuracy.

Installs nothing. Where OpenFOAM is installed (Debian: `apt install openfoam`, whose
environment is /usr/share/openfoam/etc/bashrc), this script writes the
same dam break as examples/dam_break.toml for interFoam: the 0.42 m x 0.44 m tank closed by
slip walls, the 0.114 m x 0.228 m water column at rest, air above, a 0.004 m mesh (105 x 110
cells, one cell thick), adaptive time steps at Courant 1 (maxCo = maxAlphaCo = 1), water
nu = 1e-6 m^2/s, air nu = 1.48e-5 m^2/s and rho = 1 kg/m^3, no surface tension, 1.0 s of
flow with the fields written every 0.01 s (as mpmflow's time series). It then runs both in
pairs, back to back, as whole processes:

    mpmflow run examples/dam_break.toml        (2 threads, as users run it)
    blockMesh; setFields; interFoam             (serial, as users run a case this small)

and reports the ratio of the wall times, and both solutions' surge front (t <= 0.2 s) and
column height (t <= 0.4 s) against the VOF reference in ../shared/data/reference/ (front:
the alpha = 0.5 crossing, the largest over the rows of cells; height: the crossing along the
column of cells at the left wall; mpmflow's `front` and `height` columns use the same rule
on its cell volume fractions). The reference was computed with this set-up (OpenFOAM v1912,
0.004 m), so interFoam's deviation checks that the case here is the same.

    python benchmarks/peers/interfoam_dam_break.py [--pairs 3] [--keep DIR]
"""

import argparse
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benchmarks"))
from history import append, machine, save  # noqa: E402

REFERENCE = ROOT.parent / "shared" / "data" / "reference" / "vof_interfoam_ar2_dx0.004_slip.csv"
A = 0.114  # m, the column width
TANK = (0.42, 0.44)  # m
H = 0.004  # m
CELLS = (105, 110)
HEADER = """FoamFile
{{
    version 2.0;
    format ascii;
    class {cls};
    object {obj};
}}
"""

# the discretisation of both interFoam cases (this one and interfoam_spheric.py)
FV_SCHEMES = """
ddtSchemes { default Euler; }
gradSchemes { default Gauss linear; }
divSchemes
{
    div(rhoPhi,U) Gauss linearUpwind grad(U);
    div(phi,alpha) Gauss vanLeer;
    div(phirb,alpha) Gauss linear;
    div(((rho*nuEff)*dev2(T(grad(U))))) Gauss linear;
}
laplacianSchemes { default Gauss linear corrected; }
interpolationSchemes { default linear; }
snGradSchemes { default corrected; }
"""

FILES = {
    ("system", "controlDict", "dictionary"): """
application interFoam;
startFrom startTime;
startTime 0;
stopAt endTime;
endTime 1.0;
deltaT 1e-4;
writeControl adjustableRunTime;
writeInterval 0.01;
purgeWrite 0;
writeFormat ascii;
writePrecision 6;
writeCompression off;
timeFormat general;
timePrecision 6;
runTimeModifiable false;
adjustTimeStep yes;
maxCo 1;
maxAlphaCo 1;
maxDeltaT 1;
""",
    ("system", "blockMeshDict", "dictionary"): f"""
scale 1;
vertices
(
    (0 0 0) ({TANK[0]} 0 0) ({TANK[0]} {TANK[1]} 0) (0 {TANK[1]} 0)
    (0 0 {H}) ({TANK[0]} 0 {H}) ({TANK[0]} {TANK[1]} {H}) (0 {TANK[1]} {H})
);
blocks ( hex (0 1 2 3 4 5 6 7) ({CELLS[0]} {CELLS[1]} 1) simpleGrading (1 1 1) );
boundary
(
    walls {{ type wall; faces ( (0 4 7 3) (1 2 6 5) (0 1 5 4) (3 7 6 2) ); }}
    frontAndBack {{ type empty; faces ( (0 3 2 1) (4 5 6 7) ); }}
);
""",
    # the column is 28.5 cells wide: the cells whose centres lie in it are water, the cell
    # its side cuts in half holds alpha = 1/2, so the water's volume is exact
    ("system", "setFieldsDict", "dictionary"): f"""
defaultFieldValues ( volScalarFieldValue alpha.water 0 );
regions
(
    boxToCell {{ box (0 0 -1) ({A - H / 4} {2 * A} 1);
                 fieldValues ( volScalarFieldValue alpha.water 1 ); }}
    boxToCell {{ box ({A - H / 4} 0 -1) ({A + H / 4} {2 * A} 1);
                 fieldValues ( volScalarFieldValue alpha.water 0.5 ); }}
);
""",
    ("system", "fvSchemes", "dictionary"): FV_SCHEMES,
    ("system", "fvSolution", "dictionary"): """
solvers
{
    "alpha.water.*" { nAlphaCorr 2; nAlphaSubCycles 1; cAlpha 1; MULESCorr yes;
                      nLimiterIter 3; solver smoothSolver; smoother symGaussSeidel;
                      tolerance 1e-8; relTol 0; }
    "pcorr.*" { solver PCG; preconditioner DIC; tolerance 1e-5; relTol 0; }
    p_rgh { solver PCG; preconditioner DIC; tolerance 1e-07; relTol 0.05; }
    p_rghFinal { $p_rgh; relTol 0; }
    U { solver smoothSolver; smoother symGaussSeidel; tolerance 1e-06; relTol 0; }
}
PIMPLE
{
    momentumPredictor no; nOuterCorrectors 1; nCorrectors 3; nNonOrthogonalCorrectors 0;
    pRefCell 0; pRefValue 0;
}
relaxationFactors { equations { ".*" 1; } }
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
value (0 -9.81 0);
""",
    ("0", "alpha.water", "volScalarField"): """
dimensions [0 0 0 0 0 0 0];
internalField uniform 0;
boundaryField { walls { type zeroGradient; } frontAndBack { type empty; } }
""",
    ("0", "U", "volVectorField"): """
dimensions [0 1 -1 0 0 0 0];
internalField uniform (0 0 0);
boundaryField { walls { type slip; } frontAndBack { type empty; } }
""",
    ("0", "p_rgh", "volScalarField"): """
dimensions [1 -1 -2 0 0 0 0];
internalField uniform 0;
boundaryField { walls { type fixedFluxPressure; value uniform 0; } frontAndBack { type empty; } }
""",
}


BASHRC = ("/usr/share/openfoam/etc/bashrc", "/usr/lib/openfoam/openfoam/etc/bashrc")


def openfoam_command():
    """How to run an OpenFOAM application here: a prefix for its command line (a shell that
    sources OpenFOAM's environment first, where the installation has one), or None."""
    for bashrc in BASHRC:
        if Path(bashrc).exists():
            return ["bash", "-c", f'source {bashrc} >/dev/null 2>&1; exec "$0" "$@"']
    if shutil.which("interFoam"):
        return []
    for launcher in sorted(Path("/usr/bin").glob("openfoam[0-9]*"), reverse=True):
        return [str(launcher)]
    return None


def write_case(case):
    for (folder, name, cls), body in FILES.items():
        path = case / folder / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(HEADER.format(cls=cls, obj=name) + body)


def run_interfoam(case, prefix):
    """blockMesh, setFields and interFoam in the case folder; the whole wall time (s)."""
    t0 = time.perf_counter()
    for app in ("blockMesh", "setFields", "interFoam"):
        with open(case / f"log.{app}", "w") as log:
            done = subprocess.run(
                [*prefix, app, "-case", str(case)], stdout=log, stderr=subprocess.STDOUT
            )
        if done.returncode:
            raise SystemExit(f"{app} failed (exit {done.returncode}); see {case}/log.{app}")
    return time.perf_counter() - t0


def crossing(values, coords):
    """Where ``values`` (cell alpha or volume fraction along a line) last falls through 1/2,
    linear between cell centres; the first cell's coordinate if it starts below."""
    wet = np.nonzero(values >= 0.5)[0]
    if wet.size == 0:
        return np.nan
    i = wet[-1]
    if i + 1 >= values.size:
        return coords[i]
    f0, f1 = values[i], values[i + 1]
    return coords[i] + (f0 - 0.5) / (f0 - f1) * (coords[i + 1] - coords[i])


def interfoam_series(case):
    """(t, front, height) from the written alpha.water fields."""
    nx, ny = CELLS
    xc = (np.arange(nx) + 0.5) * H
    yc = (np.arange(ny) + 0.5) * H
    rows = []
    for d in case.iterdir():
        try:
            t = float(d.name)
        except ValueError:
            continue
        path = d / "alpha.water"
        if not path.exists():
            continue
        text = path.read_text()
        m = re.search(
            r"internalField\s+nonuniform\s+List<scalar>\s*(\d+)\s*\((.*?)\)\s*;", text, re.S
        )
        if m is None:
            continue
        alpha = np.array(m.group(2).split(), dtype=float).reshape(ny, nx)  # x fastest
        front = max(crossing(alpha[j], xc) for j in range(ny))
        height = crossing(alpha[:, 0], yc)
        rows.append((t, front, height))
    return np.array(sorted(rows))


def mpmflow_series(out):
    data = np.genfromtxt(out / "timeseries.csv", delimiter=",", names=True)
    return np.stack([data["time"], data["front"], data["height"]], axis=1)


def deviations(series):
    """Largest |front - VOF| / a for t <= 0.2 s and |height - VOF| / a for t <= 0.4 s, at the
    reference's times (the series interpolated to them)."""
    ref = np.loadtxt(REFERENCE, delimiter=",", skiprows=1)
    out = {}
    for col, end, key in ((1, 0.2, "front"), (2, 0.4, "height")):
        t = ref[:, 0]
        keep = t <= end + 1e-9
        sim = np.interp(t[keep], series[:, 0], series[:, col])
        out[key] = float(np.max(np.abs(sim - ref[keep, col])) / A)
    return out


def run_mpmflow(out):
    t0 = time.perf_counter()
    subprocess.run(
        [
            sys.executable,
            "-m",
            "mpmflow.cli",
            "run",
            str(ROOT / "examples" / "dam_break.toml"),
            "--out",
            str(out),
            "--quiet",
            "--overwrite",
        ],
        check=True,
    )
    return time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=3)
    ap.add_argument("--keep", metavar="DIR", help="keep the cases and runs in DIR")
    args = ap.parse_args()
    prefix = openfoam_command()
    if prefix is None:
        raise SystemExit(
            "OpenFOAM is not installed (no interFoam on the PATH and no "
            "/usr/bin/openfoamNNNN launcher). On Debian: apt install openfoam."
        )
    base = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="peers_"))
    base.mkdir(parents=True, exist_ok=True)
    start = machine()
    run_mpmflow(base / "mpmflow_warmup")  # the page cache, as any first run fills it
    ours, theirs = [], []
    for k in range(args.pairs):
        ours.append(run_mpmflow(base / "mpmflow"))
        case = base / f"interfoam_{k}"
        shutil.rmtree(case, ignore_errors=True)
        write_case(case)
        theirs.append(run_interfoam(case, prefix))
        print(
            f"pair {k + 1}: mpmflow {ours[-1]:.2f} s, interFoam {theirs[-1]:.2f} s, "
            f"ratio {theirs[-1] / ours[-1]:.1f}",
            flush=True,
        )
    dev_ours = deviations(mpmflow_series(base / "mpmflow"))
    dev_theirs = deviations(interfoam_series(base / f"interfoam_{args.pairs - 1}"))
    ratios = [b / a for a, b in zip(ours, theirs)]
    print()
    print(
        "| code | whole process (median) | front vs VOF, t <= 0.2 s | height vs VOF, t <= 0.4 s |"
    )
    print("|---|---|---|---|")
    print(
        f"| mpmflow (2 threads) | {statistics.median(ours):.2f} s | "
        f"{dev_ours['front']:.3f} a | {dev_ours['height']:.3f} a |"
    )
    print(
        f"| interFoam (serial) | {statistics.median(theirs):.2f} s | "
        f"{dev_theirs['front']:.3f} a | {dev_theirs['height']:.3f} a |"
    )
    print(
        f"\ninterFoam / mpmflow: median of {args.pairs} pairs {statistics.median(ratios):.1f}x "
        f"(pairs: {', '.join(f'{r:.1f}' for r in ratios)})"
    )
    save(
        {
            "label": "peers/interfoam",
            "pairs": args.pairs,
            "mpmflow_s": ours,
            "interfoam_s": theirs,
            "ratio_median": statistics.median(ratios),
            "deviation_mpmflow": dev_ours,
            "deviation_interfoam": dev_theirs,
            "machine": start,
            "openfoam": shutil.which("interFoam"),
            "date": time.strftime("%Y-%m-%d"),
        }
    )
    append(
        "peers/interfoam_dam_break",
        [
            ("mpmflow whole process (median)", statistics.median(ours), "s"),
            ("interFoam whole process (median)", statistics.median(theirs), "s"),
            ("interFoam / mpmflow", statistics.median(ratios), "x"),
        ],
        note=f"{args.pairs} pairs; interFoam serial",
        start=start,
    )
    if not args.keep:
        shutil.rmtree(base, ignore_errors=True)


if __name__ == "__main__":
    os.environ.setdefault("OMPI_MCA_btl_vader_single_copy_mechanism", "none")
    main()
