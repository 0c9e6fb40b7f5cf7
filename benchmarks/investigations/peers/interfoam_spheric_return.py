"""interFoam on SPHERIC Test 2 with the columns of spheric_return.py (issue 25, P5/P7): the
case of interfoam_spheric.py (same mesh, schemes, sensors) to --end, with alpha.water and U
on vertical lines of cell centres at y = 0.1, 0.471 and 0.9 m for x from the end wall to
1.6 m, written every 0.01 s. Writes DIR/return.npz (t, x, z, alpha[t, line, x, z],
u[t, line, x, z]; NaN inside the box) and DIR/probes.csv (P1-P8, H1-H4).

    python benchmarks/investigations/peers/interfoam_spheric_return.py [--spacing 0.04] [--end 1.3] --keep DIR
"""

import argparse
import re
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "peers"))
import interfoam_spheric as F  # noqa: E402

LINES = (0.1, 0.471, 0.9)
ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
ap.add_argument("--spacing", type=float, default=0.04)
ap.add_argument("--end", type=float, default=1.3)
ap.add_argument("--keep", required=True, help="the case folder (kept)")
ap.add_argument("--show", action="store_true", help="only read a kept case")
args = ap.parse_args()
case = Path(args.keep)
n = F.cells(args.spacing)
h = [side / k for side, k in zip(F.TANK, n)]
xc = np.array([(i + 0.5) * h[0] for i in range(n[0]) if (i + 0.5) * h[0] < 1.6])
zc = (np.arange(n[2]) + 0.5) * h[2]
(bx0, by0, _), (bx1, by1, bz1) = F.BOX


def inside(x, y, z):
    return bx0 < x < bx1 and by0 < y < by1 and z < bz1


points = [(x, y, z) for y in LINES for x in xc for z in zc if not inside(x, y, z)]
if not args.show:
    locs = " ".join(f"({x:.9g} {y:.9g} {z:.9g})" for x, y, z in points)
    extra = f"""
    lines
    {{
        type probes; libs ("libsampling.so"); writeControl runTime; writeInterval 0.01;
        fields (alpha.water U);
        probeLocations ( {locs} );
    }}
"""
    F.run_with_functions(case, args.spacing, args.end, extra)

ta, a = F.read_probes(case / "postProcessing" / "lines" / "0" / "alpha.water")
rows = [
    line
    for line in (case / "postProcessing" / "lines" / "0" / "U").read_text().splitlines()
    if line.strip() and not line.startswith("#")
]
U = np.array([[float(v.split()[0]) for v in re.findall(r"\(([^)]*)\)", r)] for r in rows])
alpha = np.full((len(ta), len(LINES), len(xc), len(zc)), np.nan)
u = np.full_like(alpha, np.nan)
k = 0
for j, y in enumerate(LINES):
    for i, x in enumerate(xc):
        for m, z in enumerate(zc):
            if inside(x, y, z):
                continue
            alpha[:, j, i, m] = np.array(a)[:, k]
            u[:, j, i, m] = U[:, k]
            k += 1
np.savez(case / "return.npz", t=np.array(ta), x=xc, z=zc, hz=h[2], alpha=alpha, u=u)
print(f"{case / 'return.npz'}: {len(ta)} times, {len(points)} points")
