"""interFoam on the 2D dam break (interfoam_dam_break.py's case), fields every 5 ms to 0.6 s,
then the run-up at the right wall and the water's energy as benchmarks/investigations/runup_2d.py measures
them for mpmflow (alpha-weighted cell sums; run-up: the highest cell with alpha > 0.5 in the
last two columns).

    python benchmarks/investigations/peers/interfoam_runup_2d.py DIR [run]   (without "run": a kept case)
"""

import re
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "peers"))
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
import interfoam_dam_break as F  # noqa: E402

case = Path(sys.argv[1])
run = len(sys.argv) > 2 and sys.argv[2] == "run"
nx, ny = F.CELLS
H = F.H
if run:
    key = ("system", "controlDict", "dictionary")
    F.FILES[key] = (
        F.FILES[key]
        .replace("endTime 1.0;", "endTime 0.6;")
        .replace("writeInterval 0.01;", "writeInterval 0.005;")
    )
    F.write_case(case)
    print(F.run_interfoam(case, F.openfoam_command()))


def field(path, vec=False):
    text = path.read_text()
    if vec:
        m = re.search(
            r"internalField\s+nonuniform\s+List<vector>\s*(\d+)\s*\((.*?)\)\s*;", text, re.S
        )
        vals = re.findall(r"\(([^()]*)\)", m.group(2))
        return np.array([v.split() for v in vals], float)
    m = re.search(r"internalField\s+nonuniform\s+List<scalar>\s*(\d+)\s*\((.*?)\)\s*;", text, re.S)
    return np.array(m.group(2).split(), float)


xc = (np.arange(nx) + 0.5) * H
yc = (np.arange(ny) + 0.5) * H
X, Y = np.meshgrid(xc, yc)  # (ny, nx) x fastest
rows = []
for d in sorted(
    case.iterdir(), key=lambda p: float(p.name) if re.fullmatch(r"[0-9.e-]+", p.name) else -1
):
    try:
        t = float(d.name)
    except ValueError:
        continue
    if not (d / "U").exists() or not (d / "alpha.water").exists():
        continue
    a = field(d / "alpha.water").reshape(ny, nx)
    if t == 0:
        U = np.zeros((ny, nx, 3))
    else:
        U = field(d / "U", True).reshape(ny, nx, 3)
    m = 1000 * a * H * H  # per m of thickness
    ke = 0.5 * (m * (U[..., 0] ** 2 + U[..., 1] ** 2)).sum()
    pe = 9.81 * (m * Y).sum()
    e = 0.5 * (U[..., 0] ** 2 + U[..., 1] ** 2) + 9.81 * Y
    # run-up: highest wet cell (alpha > 0.5) in the last two columns
    col = a[:, -2:].max(1)
    wet = np.nonzero(col > 0.5)[0]
    top = yc[wet[-1]] if wet.size else np.nan
    j = wet[-1] if wet.size else 0
    v_top = U[j, -2:, 1].mean() if wet.size else np.nan
    wet05 = np.nonzero(col > 0.05)[0]
    top05 = yc[wet05[-1]] if wet05.size else np.nan
    # highest specific energy among cells with alpha > 0.5
    emax = e[a > 0.5].max()
    # incoming: front region before the wall: max |u| with alpha>0.5
    umax = np.sqrt(U[..., 0] ** 2 + U[..., 1] ** 2)[a > 0.5].max()
    rows.append((t, ke, pe, ke + pe, top, v_top, top05, emax, umax))
    print(
        f"{t:.3f} KE {ke:7.3f} PE {pe:7.3f} E {ke + pe:7.3f} runup {top:.3f} w {v_top:5.2f} runup(a>.05) {top05:.3f} emax {emax:5.2f} umax {umax:5.2f}"
    )
np.save(case / "series.npy", np.array(rows))
