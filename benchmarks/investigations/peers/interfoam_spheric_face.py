"""interFoam on SPHERIC Test 2 with extra probes at the box's front face and above its top
(issue 25): the case of interfoam_spheric.py (same mesh, schemes, sensors), to --end, with
p, alpha.water and U on the vertical line through the cell centres next to the staircased
front face (y = 0.471 m) and one cell further, and alpha above P5 and P7. Prints the face's
water column (sum of alpha times the cell height, the highest cell above alpha 0.5 and
0.05), its pressure and vertical velocity, the rows of the validation (first p > 500 Pa,
impulse over [t_exp - 0.05, t_exp + 0.3] s) and the level gauges.

    python benchmarks/investigations/peers/interfoam_spheric_face.py [--spacing 0.04] [--end 1.5] --keep DIR
"""

import argparse
import csv
import re
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "peers"))
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
import interfoam_spheric as F  # noqa: E402

from mpmflow.validation import spheric  # noqa: E402

ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
ap.add_argument("--spacing", type=float, default=0.04)
ap.add_argument("--end", type=float, default=1.5)
ap.add_argument("--keep", required=True, help="the case folder (kept)")
ap.add_argument("--show", action="store_true", help="only print the tables of a kept case")
args = ap.parse_args()
case = Path(args.keep)
n = F.cells(args.spacing)
h = [side / k for side, k in zip(F.TANK, n)]
zc = (np.arange(n[2]) + 0.5) * h[2]
x1 = min((i + 0.5) * h[0] for i in range(n[0]) if (i + 0.5) * h[0] > F.BOX[1][0])
ztop = [z for z in zc if z > F.BOX[1][2]]

if not args.show:
    points = (
        [f"({x1:.9g} 0.471 {z:.9g})" for z in zc]
        + [f"({x1 + h[0]:.9g} 0.471 {z:.9g})" for z in zc]
        + [f"({x} 0.471 {z:.9g})" for x in (0.8035, 0.7235) for z in ztop]
    )
    extra = f"""
    face
    {{
        type probes; libs ("libsampling.so"); writeControl runTime; writeInterval 0.005;
        fields (p alpha.water U);
        probeLocations ( {" ".join(points)} );
    }}
"""
    F.run_with_functions(case, args.spacing, args.end, extra)

nz = n[2]
tp, p = F.read_probes(case / "postProcessing" / "face" / "0" / "p")
_, a = F.read_probes(case / "postProcessing" / "face" / "0" / "alpha.water")
tp, p, a = np.array(tp), np.array(p), np.array(a)
rows_u = [
    line
    for line in (case / "postProcessing" / "face" / "0" / "U").read_text().splitlines()
    if not line.startswith("#")
]
print(
    f"face line x = {x1:.4f} m: t, water column (m), highest alpha > 0.5 / 0.05 (m), "
    "p (Pa) and w (m/s) at z = 0.02-0.22 m"
)
for t in (0.45, 0.5, 0.55, 0.6, 0.65, 0.7, 0.8, 0.9, 1.0):
    i = int(np.argmin(abs(tp - t)))
    col = a[i, :nz]
    top5 = zc[col > 0.5].max() if (col > 0.5).any() else 0.0
    top05 = zc[col > 0.05].max() if (col > 0.05).any() else 0.0
    vec = np.array([[float(v) for v in m.split()] for m in re.findall(r"\(([^)]*)\)", rows_u[i])])
    print(
        f"{tp[i]:.3f} {col.sum() * h[2]:.3f} {top5:.2f} {top05:.2f} | "
        + " ".join(f"{v:6.0f}" for v in p[i, :6])
        + " | "
        + " ".join(f"{v:5.2f}" for v in vec[:6, 2])
    )
rows = list(csv.DictReader(open(case / "probes.csv")))
t = np.array([float(r["time"]) for r in rows])
exp = spheric.data()
te = exp["time [s]"]
for name in ("P1", "P3", "P5", "P6", "P7", "P8"):
    y = np.array([float(r[name]) for r in rows])
    ye = exp[f"{name} [Pa]"]
    t_exp = spheric.first_above(te, ye)
    line = (
        f"{name}: first > 500 Pa {spheric.first_above(t, y):.3f} s (MARIN {t_exp:.3f}), "
        f"> 200 Pa {spheric.first_above(t, y, 200):.3f} (MARIN "
        f"{spheric.first_above(te, ye, 200):.3f})"
    )
    if t[-1] >= t_exp + 0.3:
        line += (
            f", impulse {spheric.impulse(t, y, t_exp - 0.05, t_exp + 0.3):.0f} Pa s "
            f"(MARIN {spheric.impulse(te, ye, t_exp - 0.05, t_exp + 0.3):.0f})"
        )
    w = (t >= 0.45) & (t <= 0.7)
    line += f", mean 0.45-0.7 s {y[w].mean():.0f} Pa"
    print(line)
for gauge in ("H1", "H2"):
    y = np.array([float(r[gauge]) for r in rows])
    w = (t >= 0.45) & (t <= 0.7)
    print(
        f"{gauge}: mean 0.45-0.7 s {y[w].mean():.3f} m (MARIN "
        f"{np.interp(t[w], te, exp[spheric.GAUGES[gauge]]).mean():.3f})"
    )
