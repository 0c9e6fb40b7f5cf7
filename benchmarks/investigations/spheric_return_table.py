"""Tables of docs/notes/benchmarks-diary.md, "Why the water returns late behind the box": mpmflow's
runs/spheric_return_TAG.npz (spheric_return.py) beside interFoam's DIR/return.npz
(peers/interfoam_spheric_return.py) on the same column lines.

    python benchmarks/investigations/spheric_return_table.py TAG [TAG ...] [--foam DIR]

Depth = particle volume (low: of the water below z = 0.2 m) / h^2 (mpmflow) or the sum of alpha times the cell height (interFoam)
in the column; front = the smallest x of a column deeper than 1 cm; u = mean u of the
column (mass- or alpha-weighted).
"""

import argparse
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
ap = argparse.ArgumentParser()
ap.add_argument("tags", nargs="+")
ap.add_argument("--foam", default=None)
cli = ap.parse_args()
LINES = (0.1, 0.471, 0.9)
XS = (0.02, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6)


def mpm(tag):
    d = np.load(ROOT / "runs" / f"spheric_return_{tag}.npz")
    h = float(d["h"])
    x = (np.arange(d["depth"].shape[2]) + 0.5) * h
    low = d["depth_low"] if "depth_low" in d else np.full_like(d["depth"], np.nan)
    return dict(t=d["t"], x=x, depth=d["depth"], low=low, u=d["u"], ztop=d["ztop"], extra=d)


def foam(path):
    d = np.load(Path(path) / "return.npz")
    a = np.nan_to_num(d["alpha"])
    depth = a.sum(3) * float(d["hz"])
    u = np.nansum(a * np.nan_to_num(d["u"]), 3) / np.maximum(a.sum(3), 1e-9)
    u[a.sum(3) < 1e-3] = np.nan
    zt = np.where(a > 0.5, d["z"][None, None, None, :], 0).max(3)
    low = a[..., d["z"] < 0.2].sum(3) * float(d["hz"])
    return dict(
        t=d["t"], x=d["x"], depth=depth, low=low, u=u, ztop=zt, extra=None, alpha=a, z=d["z"]
    )


runs = {tag: mpm(tag) for tag in cli.tags}
if cli.foam:
    runs["interFoam"] = foam(cli.foam)


def at(r, tt):
    return int(np.argmin(abs(r["t"] - tt)))


def front(r, i, j, xmax=1.6):
    wet = (r["depth"][i, j] > 0.01) & (r["x"] < xmax)
    return float(r["x"][wet].min()) if wet.any() else np.nan


def col(r, xx):
    return int(np.argmin(abs(r["x"] - xx)))


print("(a) front (smallest x of a column deeper than 1 cm), m, y = 0.1 / 0.471 / 0.9 m")
print("t | " + " | ".join(runs))
for tt in np.arange(0.3, 0.81, 0.05):
    cells = []
    for r in runs.values():
        i = at(r, tt)
        cells.append(" / ".join(f"{front(r, i, j):.2f}" for j in range(3)))
    print(f"{tt:.2f} | " + " | ".join(cells))
print("(a') depth (m) and u (m/s) beside the box, y = 0.1 m, x = 0.74 m (the box's middle)")
for tt in np.arange(0.4, 1.21, 0.05):
    cells = []
    for r in runs.values():
        i, k = at(r, tt), col(r, 0.74)
        cells.append(f"{r['depth'][i, 0, k]:.3f} {r['u'][i, 0, k]:+.2f}")
    print(f"{tt:.2f} | " + " | ".join(cells))
print("(b) at the end wall (first column, x ~ 0.02 m): depth / top (m), y = 0.1 / 0.471 / 0.9")
for tt in np.arange(0.5, 1.21, 0.05):
    cells = []
    for r in runs.values():
        i = at(r, tt)
        cells.append(
            "  ".join(f"{r['depth'][i, j, 0]:.3f}/{r['ztop'][i, j, 0]:.2f}" for j in range(3))
        )
    print(f"{tt:.2f} | " + " | ".join(cells))
print("(c) centre line y = 0.471 behind the box: depth (m) [u m/s] at x = " + str(XS))
for tt in np.arange(0.7, 1.21, 0.05):
    for name, r in runs.items():
        i = at(r, tt)
        cells = [
            f"{r['depth'][i, 1, col(r, xx)]:.3f}[{r['u'][i, 1, col(r, xx)]:+.1f}]" for xx in XS
        ]
        print(f"{tt:.2f} {name:10s} | " + " ".join(cells))
print("(c'') centre line: depth of the water below z = 0.2 m at the same x")
for tt in np.arange(0.7, 1.21, 0.05):
    for name, r in runs.items():
        i = at(r, tt)
        cells = [f"{r['low'][i, 1, col(r, xx)]:.3f}" for xx in XS]
        print(f"{tt:.2f} {name:10s} | " + " ".join(cells))
print("(c') y = 0.1 (beside) depth [u] at the same x")
for tt in np.arange(0.7, 1.21, 0.05):
    for name, r in runs.items():
        i = at(r, tt)
        cells = [
            f"{r['depth'][i, 0, col(r, xx)]:.3f}[{r['u'][i, 0, col(r, xx)]:+.1f}]" for xx in XS
        ]
        print(f"{tt:.2f} {name:10s} | " + " ".join(cells))
print("(d) water over x = 0.3-0.66 m on the centre line above z = 0.2 m (m of depth)")
for tt in np.arange(0.6, 1.21, 0.05):
    cells = []
    for r in runs.values():
        i = at(r, tt)
        sel = (r["x"] > 0.3) & (r["x"] < 0.6635)
        if r["extra"] is None:
            hz = r["z"][1] - r["z"][0]
            v = r["alpha"][i, 1][sel][:, r["z"] > 0.2].sum() * hz * (r["x"][1] - r["x"][0])
            cells.append(f"{v:.4f} m2")
        else:
            e = r["extra"]
            cells.append(
                f"arched {e['arched_m'][i]:.1f} kg, behind in air {e['arched_air'][i]:.1f}, "
                f"floor {e['arched_floor'][i]:.1f} (x {e['arched_floor_x'][i]:.2f}, "
                f"u {e['arched_floor_u'][i]:+.2f})"
            )
    print(f"{tt:.2f} | " + " | ".join(cells))


def first(r, xx, thr, key="low", j=1):
    k = col(r, xx)
    w = np.nonzero(r[key][:, j, k] > thr)[0]
    w = w[r["t"][w] > 0.6]
    return float(r["t"][w[0]]) if w.size else np.nan


print(
    "(e) per run: centre-line depth at the wall x ~ 0.02 m at 0.75 / 0.8 s; first time the "
    "water below z = 0.2 m is deeper than 0.1 m at x = 0.3 m and 0.15 m at x = 0.62 m "
    "(the back face's column); water arched over the box: total / in the air behind it at "
    "1.0 s (kg); H1 at 1.0 / 1.05 / 1.1 s; first p > 500 Pa at P8 / P7 / P5"
)
for name, r in runs.items():
    i75, i80, i1 = at(r, 0.75), at(r, 0.8), at(r, 1.0)
    cells = [
        f"{r['depth'][i75, 1, 0]:.3f} / {r['depth'][i80, 1, 0]:.3f}",
        f"{first(r, 0.3, 0.1):.2f}",
        f"{first(r, 0.62, 0.15):.2f}",
    ]
    e = r["extra"]
    if e is not None:
        from mpmflow.validation import spheric

        cells.append(f"{e['arched_m'][i1]:.1f} / {e['arched_air'][i1]:.1f}")
        cells.append(" / ".join(f"{np.interp(tt, r['t'], e['H1']):.3f}" for tt in (1.0, 1.05, 1.1)))
        cells.append(
            " / ".join(f"{spheric.first_above(r['t'], e[p]):.3f}" for p in ("P8", "P7", "P5"))
        )
    print(f"| {name} | " + " | ".join(cells) + " |")
print(
    "(f) over P7 (x = 0.7235 m, the centre line): water in the column z = 0.161-0.461 m (m) / "
    "volume fraction of the lowest cell above the top / P7 (Pa, mpmflow)"
)
for tt in np.arange(0.8, 1.46, 0.05):
    cells = []
    for r in runs.values():
        if tt > r["t"][-1] + 1e-9:
            cells.append("")
            continue
        i = at(r, tt)
        if r["extra"] is None:
            k = col(r, 0.7235)
            a = r["alpha"][i, 1, k]
            sel = (r["z"] > 0.161) & (r["z"] < 0.461)
            low = a[np.nonzero(r["z"] > 0.161)[0][0]]
            cells.append(f"{a[sel].sum() * (r['z'][1] - r['z'][0]):.3f} / {low:.2f}")
        elif "p7_low" in r["extra"]:
            e = r["extra"]
            cells.append(f"{e['p7_layer'][i]:.3f} / {e['p7_low'][i]:.2f} / {e['P7'][i]:.0f}")
        else:
            cells.append("")
    print(f"{tt:.2f} | " + " | ".join(cells))
