"""SPHERIC Test 2 (Kleefsman et al. 2005): a 3D dam break hitting a box, against MARIN's data.

examples/spheric_test2.toml at two meshes (0.04 m and 0.025 m, 8 particles per cell; quick:
0.05 m to t = 0.75 s, the first impact at the front face). Where the tank's 3.22 m is not a whole number of
cells, the domain is lengthened to a whole number and the end wall at x = 3.22 m is an
obstacle filling the rest (at least two cells thick): its face lies at 3.22 m, off the grid.
Measured data: ../shared/data/validation/, section E, with the H1/H3 columns as that README
explains (the example's gauges are named by their position).

* **water levels** H1-H4: RMS over the outputs with t <= 6 s of (h - h_exp) / H0, H0 = 0.55 m
  the initial depth, h_exp interpolated to the output times;
* **first-impact time** at P1, P3 (front face) and P5, P7 (top face): the first time the
  pressure exceeds 500 Pa (the measured signal's noise is about +-70 Pa, every first impact
  rises above 1000 Pa);
* **pressure impulse** of the first impact at the same sensors: the integral of p over
  [t_exp - 0.05 s, t_exp + 0.3 s], t_exp the measured first-impact time, relative to the
  measured impulse;
* **peak pressures** P1-P8 in that window: reported only (peaks do not converge with the mesh
  in any code: they depend on the air cushion, compressibility and the sampling).

The 3D pictures (spheric_3d.png) show the finest mesh's water at the times of the
experiment's photographs (PHOTOS: 0.4, 0.6, 1.0 and 1.5 s; the quick run, which ends at
0.75 s, the first two): the surface where the particles' volume fraction is 1/2, as
`mpmflow plot` draws it (``plotting.surface``), taken from the particles in memory at those
output times (no snapshot files).
"""

import math
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TypedDict

import numpy as np
from numpy.typing import ArrayLike

from ..simulation import Simulation
from .common import ROOT, CaseResult, Row, fmt, markdown_table, pyplot, run_example, save
from .types import Context, FloatArray

H0 = 0.55  # m
LENGTH = 3.22  # m, the tank
DATA = (
    ROOT.parent
    / "shared"
    / "data"
    / "validation"
    / "spheric_test2_kleefsman2005_marin_exp_P1-P8_H1-H4.csv"
)
GAUGES = {
    "H1": "H3 as labelled in source [m]",
    "H2": "H2 as labelled in source [m]",
    "H3": "H1 as labelled in source [m]",
    "H4": "H4 as labelled in source [m]",
}
IMPACT = ("P1", "P3", "P5", "P7")
THRESHOLD = 500.0  # Pa
WINDOW = (-0.05, 0.3)  # s around the measured first impact

TOL_LEVEL = 0.1
WHY_LEVEL = (
    "0.1 H0 = 5.5 cm RMS: 1.4 cells of the 0.04 m mesh, 2.2 of the 0.025 m one; a "
    "level that follows the measured wave's arrival, height and return"
)
PHOTOS = (0.4, 0.6, 1.0, 1.5)  # s, the experiment's photographs (Kleefsman et al. 2005)
TOL_TIME = 0.04
WHY_TIME = "10% of the 0.39 s the front takes to reach the box; 8 outputs of 5 ms"
# why rows miss, written after the runs (the tolerances above were fixed before)
MISS_TOP = (
    "the first water on the top face comes from the jet that climbs the front face at "
    "the first impact: it reaches the tank's roof (0.6-0.8 s) and arches back over "
    "the box, and the top stays dry under it until its landing walks onto the box "
    "from behind (P8 first, as measured, but at 1.39-1.42 s at 0.04 and 0.025 m "
    "against MARIN's 1.03-1.07 s at 200 Pa; interFoam at 0.04 m: P5 1.40 s, P7 "
    "1.19 s); no thin water lies on the top before (P7's window holds no particle): "
    "where and when the jet lands is not converged at these meshes "
    '(docs/notes/benchmarks-diary.md, "The box\'s front face and top face")'
)
MISS_FRONT = (
    "after the impact peak the face pressure falls off towards the box's top faster "
    "than measured (0.45-0.7 s: MARIN's P1-P4 differ by about rho g dz, P4 2 cm "
    "below the top edge 4.5 kPa at 0.55 s, where mpmflow reads 1.4-1.8 and "
    "interFoam 2.1-2.3 kPa at 0.04 m): the jet up the face is thin and fast and the "
    "water piles up lower at the face (0.20-0.26 m at 0.04 m, interFoam "
    "0.24-0.31 m); the mean also falls with the time step (P3 3.4, 3.0, 2.5 kPa at "
    "5, 2.5, 1 ms at 0.04 m; docs/notes/benchmarks-diary.md, \"The box's front face and top "
    'face")'
)
_RETURN = (
    "the RMS comes from 1-3 s, the bore that reflects from the wall behind the box "
    "(x = 0) and runs back: at 0.04 m H1 (integral gauge) averages 0.241 m over 1-2 s "
    "against the measured 0.293 m (0.227 m while the gauge clipped the volume fraction at "
    "1; the first-drop gauge read 0.130 m there: its drop-outs were 0.10 m of the "
    "deficit; benchmarks/investigations/spheric_gauges.py)"
)
MISS_LEVEL = {"H1": _RETURN, "H2": _RETURN, "H3": _RETURN, "H4": _RETURN}
TOL_IMPULSE = 0.3
WHY_IMPULSE = (
    "the impulse converges where the peak does not; 30% with the 0.16 m box "
    "resolved by 4 to 6 cells"
)


class Measured(TypedDict):
    """``measures``: by gauge the level's RMS / H0; by sensor (simulated, measured) impact
    time (s), impulse (Pa s) and peak (Pa)."""

    levels: dict[str, float]
    times: dict[str, tuple[float, float]]
    impulses: dict[str, tuple[float, float]]
    peaks: dict[str, tuple[float, float]]


Photo = tuple[float, FloatArray, FloatArray]  # (t, x, volume) of the particles


def data() -> dict[str, FloatArray]:
    """The measured series: {column name: array}."""
    with open(DATA) as f:
        names = f.readline().strip().split(",")
    values = np.loadtxt(DATA, delimiter=",", skiprows=1)
    return {n: values[:, k] for k, n in enumerate(names)}


def first_above(t: FloatArray, p: ArrayLike, threshold: float = THRESHOLD) -> float:
    """The first time p exceeds the threshold (nan if never)."""
    above = np.flatnonzero(np.asarray(p) > threshold)
    return float(t[above[0]]) if above.size else math.nan


def impulse(t: FloatArray, p: ArrayLike, lo: float, hi: float) -> float:
    """int p dt over [lo, hi] (Pa s), trapezoidal on the samples inside."""
    w = (t >= lo) & (t <= hi)
    return float(np.trapezoid(np.asarray(p)[w], np.asarray(t)[w])) if w.sum() > 1 else math.nan


def overrides(spacing: float, end: float) -> list[str]:
    """The example at ``spacing``: the domain lengthened to whole cells with the end wall as
    an obstacle where 3.22 m is not a whole number of cells."""
    out = [f"grid.spacing={spacing}", f"time.end={end}", "output.snapshots=false"]
    cells = LENGTH / spacing
    if abs(cells - round(cells)) > 1e-6:
        length = (math.ceil(cells) + 2) * spacing
        out += [
            f"domain.size=[{length:.10g}, 1.0, 1.0]",
            "obstacles=[{name = 'box', type = 'box', min = [0.6635, 0.2955, 0.0], "
            "max = [0.8245, 0.6985, 0.161]}, {name = 'end_wall', type = 'box', "
            f"min = [{LENGTH}, 0.0, 0.0], max = [{length:.10g}, 1.0, 1.0]}}]",
        ]
    return out


def measures(sim: Simulation, exp: Mapping[str, FloatArray], end: float) -> Measured:
    """Per mesh: level RMS by gauge, impact time and impulse by sensor, peaks."""
    t = sim.series("time")
    te = exp["time [s]"]
    out: Measured = {"levels": {}, "times": {}, "impulses": {}, "peaks": {}}
    for gauge, column in GAUGES.items():
        h = sim.probe_series(gauge)
        he = np.interp(t, te, exp[column])
        keep = t <= end + 1e-9
        out["levels"][gauge] = float(np.sqrt(np.mean(((h - he)[keep] / H0) ** 2)))
    for k in range(1, 9):
        name = f"P{k}"
        p, pe = sim.probe_series(name), exp[f"{name} [Pa]"]
        t_exp = first_above(te, pe)
        lo, hi = t_exp + WINDOW[0], t_exp + WINDOW[1]
        peak_sim = float(np.max(p[(t >= lo) & (t <= hi)])) if t[-1] >= lo else math.nan
        peak_exp = float(np.max(pe[(te >= lo) & (te <= hi)]))
        out["peaks"][name] = (peak_sim, peak_exp)
        if name in IMPACT:
            out["times"][name] = (first_above(t, p), t_exp)
            if t[-1] >= hi:
                out["impulses"][name] = (impulse(t, p, lo, hi), impulse(te, pe, lo, hi))
    return out


def run(out: Path, quick: bool, context: Context | None) -> CaseResult:
    exp = data()
    meshes = [(0.05, 0.75)] if quick else [(0.04, 6.0), (0.025, 6.0)]
    rows, text, runs = [], [], []
    photos: list[Photo] = []  # (t, x, volume) of the finest mesh at the PHOTOS times
    for j, (spacing, end) in enumerate(meshes):
        sim = run_example(
            "spheric_test2.toml",
            overrides(spacing, end),
            on_output=_photographer(photos) if j == len(meshes) - 1 else None,
        )
        m = measures(sim, exp, end)
        runs.append(
            (spacing, sim.series("time"), {n: sim.probe_series(n) for n in (*GAUGES, *IMPACT)})
        )
        tag = f"{spacing:g} m"
        if end >= 6.0:
            for gauge, value in m["levels"].items():
                rows.append(
                    Row(
                        "SPHERIC 2",
                        f"{tag}: water level {gauge}",
                        "RMS of (h - h_exp) / H0 over 0-6 s",
                        value,
                        TOL_LEVEL,
                        WHY_LEVEL,
                        miss=MISS_LEVEL.get(gauge, ""),
                    )
                )
        for name, (ts, te_) in m["times"].items():
            if end < te_ + WINDOW[1]:
                continue
            rows.append(
                Row(
                    "SPHERIC 2",
                    f"{tag}: first impact at {name}",
                    f"|t - t_exp|, first p > {THRESHOLD:g} Pa",
                    abs(ts - te_),
                    TOL_TIME,
                    WHY_TIME,
                    unit="s",
                    miss=MISS_TOP,
                )
            )
        for name, (js, je) in m["impulses"].items():
            rows.append(
                Row(
                    "SPHERIC 2",
                    f"{tag}: impulse of the first impact at {name}",
                    "|J - J_exp| / J_exp, J = int p dt over [t_exp - 0.05, t_exp + 0.3] s",
                    abs(js - je) / je,
                    TOL_IMPULSE,
                    WHY_IMPULSE,
                    miss=MISS_TOP if name in ("P5", "P7") else MISS_FRONT,
                )
            )
        table = [[n, fmt(ps), fmt(pe)] for n, (ps, pe) in m["peaks"].items()]
        timing = [[n, fmt(ts), fmt(te_)] for n, (ts, te_) in m["times"].items()]
        text.append(
            f"At {tag} ({sim.particles.count} particles, {fmt(sim.summary['wall_seconds'])} s "
            f"wall, to t = {end:g} s). Peak pressures in the first-impact window (Pa; "
            "reported, no tolerance):\n\n"
            + markdown_table(["sensor", "computed", "measured"], table)
            + "\n\nFirst-impact times (s):\n\n"
            + markdown_table(["sensor", "computed", "measured"], timing)
        )
    res = CaseResult(
        "spheric",
        "SPHERIC Test 2: 3D dam break on a box",
        rows,
        text=__doc__.split("\n\n", 1)[1] + "\n\n" + "\n\n".join(text),
    )
    figure(out, exp, runs, res)
    pictures(out, sim, photos, res)
    return res


def _photographer(photos: list[Photo]) -> Callable[[Simulation], None]:
    """An on_output callback that keeps (t, particle positions, volumes) at the PHOTOS
    times (outputs every 5 ms fall on them; a quarter output of slack for round-off)."""

    def keep(sim: Simulation) -> None:
        dt = sim.case.output.interval
        if any(abs(sim.time - t) <= 0.25 * dt for t in PHOTOS):
            photos.append((sim.time, sim.particles.x.copy(), sim.particles.volume.copy()))

    return keep


def pictures(out: Path, sim: Simulation, photos: Sequence[Photo], res: CaseResult) -> None:
    """spheric_3d.png: the water's surface (volume fraction 1/2, ``plotting.surface``) and
    the box at the photograph times the run reached, one panel each."""
    from ..plotting.surface import draw_surface, obstacle_triangles, volume_fraction, water_surface

    if not photos:
        return
    plt = pyplot()
    grid = sim.grid
    notes: list[str] = []
    solids = obstacle_triangles(sim.summary, notes)
    cols = min(2, len(photos))
    rows = math.ceil(len(photos) / cols)
    fig = plt.figure(figsize=(6.0 * cols, 3.2 * rows))
    for k, (t, x, volume) in enumerate(photos):
        ax = fig.add_subplot(rows, cols, k + 1, projection="3d")
        f = volume_fraction(x, volume, grid.spacing, grid.cells)
        draw_surface(ax, *water_surface(f, grid.spacing), solids, grid.size, f"t = {t:.2f} s")
    fig.subplots_adjust(0, 0.02, 1, 0.92, wspace=0.02, hspace=0.1)
    save(fig, out / "spheric_3d.png")
    times = ", ".join(f"{t:.1f}" for t, _, _ in photos)
    res.figures.append(
        (
            "spheric_3d.png",
            f"The water at {grid.spacing:g} m at {times} s (the "
            "experiment's photograph times the run reaches): the surface where "
            "the particles' volume fraction on the grid is 1/2, the box and the "
            "end wall in grey; seen from the front (y < 0), above and the side of "
            "the dam's end (x = 3.22 m).",
        )
    )


def figure(
    out: Path,
    exp: Mapping[str, FloatArray],
    runs: Sequence[tuple[float, FloatArray, Mapping[str, FloatArray]]],
    res: CaseResult,
) -> None:
    """spheric.png: the levels H1-H4 (top) and the pressures P1, P3, P5, P7 (bottom) of each
    mesh against the measured series (black)."""
    plt = pyplot()
    fig, ax = plt.subplots(2, 4, figsize=(16, 6.5))
    te = exp["time [s]"]
    for k, (gauge, column) in enumerate(GAUGES.items()):
        ax[0, k].plot(te, exp[column], "k-", lw=0.7, label="MARIN")
        ax[0, k].set(
            title=f"{gauge} (data: {column.split(' ')[0]} as labelled)",
            xlabel="t [s]",
            ylabel="level [m]",
        )
    for k, name in enumerate(IMPACT):
        ax[1, k].plot(te, exp[f"{name} [Pa]"], "k-", lw=0.5, label="MARIN")
        ax[1, k].set(title=name, xlabel="t [s]", ylabel="pressure [Pa]")
    for j, (spacing, t, series) in enumerate(runs):
        for k, gauge in enumerate(GAUGES):
            ax[0, k].plot(t, series[gauge], f"C{j}-", lw=0.9, label=f"MPM {spacing:g} m")
        for k, name in enumerate(IMPACT):
            ax[1, k].plot(t, series[name], f"C{j}-", lw=0.7, label=f"MPM {spacing:g} m")
    end = max(t[-1] for _, t, _ in runs)
    for a in ax.ravel():
        a.set_xlim(0, end)
        a.legend(fontsize=7)
    for a in ax[1]:
        a.set_xlim(0, min(end, 2.0))
    fig.tight_layout()
    save(fig, out / "spheric.png")
    res.figures.append(
        (
            "spheric.png",
            "Water levels H1-H4 (top) and pressures on the box's "
            "front (P1, P3) and top (P5, P7) face (bottom, first 2 s) against "
            "MARIN's measurements (black).",
        )
    )
