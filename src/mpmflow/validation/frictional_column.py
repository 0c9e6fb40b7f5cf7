"""Solids (issue 43): the collapse of a frictional column against Bui et al. (2008)'s
experiment.

Bui, Fukagawa, Sako & Ohno (2008, Int. J. Numer. Anal. Meth. Geomech. 32, 1537) stacked
aluminium bars (5 cm long, plane strain) 0.2 m long and 0.1 m high against the wall of a
flume and released them at once; the bars failed along a line from the column's foot and
came to rest as a deposit. examples/bui_column.toml is the set-up: Mohr-Coulomb in plane
strain (the Drucker-Prager cone matched to it, zero dilatancy), friction angle 19.8 degrees,
no cohesion, no tension, a rough floor and a slip wall behind the column, bulk density
2650 kg/m^3 and E = 0.84 MPa, nu = 0.3, as the peers that compare with this experiment take
them (fMPMM-solver, HydraxMPM; the deposit depends on the stiffness only through G / (rho g
H) = 124, a column that barely compresses). The measured final surface and failure line are
the digitisation Wyser et al. (2020, Geosci. Model Dev. 13, 6265) made of Bui's figure
(data/validation/README.md): the toe at 0.442 m (a spread of 0.242 m), the wall's height
unchanged, and the failure line from the foot at 0.179 m up to the top at 0.021 m from the
wall, 33.0 degrees to the horizontal (the least-squares line x(y) through its 9 points).

The measures. Run-out: the spread of the toe, (L_f - L0) with L_f the furthest particle
plus half a particle spacing, against the measured 0.242 m. Failure line: the boundary of
the particles that did not move, as the experiment saw it from the bars that stayed put:
for each band of initial height 2.5 mm thick, the furthest initial x of a particle whose
final displacement is under 2 mm (13 times the column's elastic settlement rho g H^2 /
(2 E) = 0.15 mm; with 1 or 5 mm the angle moves by about half a degree), and the least-squares line x(y) through those
points (its angle to the horizontal and its foot, x at y = 0), as for the measured line. At
rest: the largest particle speed at the end, 2 s after the release (the measured deposit is
final; the computed front stops by 0.8 s).
"""

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..simulation import Simulation
from .common import ROOT, CaseResult, Row, fmt, markdown_table, pyplot, run_example, save
from .materials import deposit_profile
from .types import Context, FloatArray

DATA = ROOT / "data" / "validation"
SURFACE = DATA / "bui_2008_final_surface_digitised_fmpmm.csv"
FAILURE = DATA / "bui_2008_failure_line_digitised_fmpmm.csv"
L0, H0 = 0.2, 0.1  # m: the column
END = 2.0  # s
END_QUICK = 1.0  # s: the quick report's (the front stops by 0.8 s)
STILL = 2e-3  # m: a particle that moved less stayed put
BAND = 0.0025  # m: the initial-height bands of the failure line
SPACINGS = (0.005, 0.0025)  # m: 20 and 40 cells through the column's height

# tolerances, fixed before the run (the issue's)
TOL_RUNOUT = 0.10
WHY_RUNOUT = (
    "the issue's 10% of the measurement, on the spread (L_f - L0) rather than the toe's "
    "distance from the wall (the stricter of the two)"
)
TOL_ANGLE = 0.10
WHY_ANGLE = "the issue's 10% of the measurement (33.0 deg, the digitised line's fit)"
TOL_FOOT = 0.10
WHY_FOOT = "the issue's 10% of the measurement (0.179 m from the wall, the fit's foot)"
TOL_REST = 1e-3
WHY_REST = "the issue's criterion: every particle slower than 1 mm/s at the end"


def measured() -> tuple[FloatArray, FloatArray]:
    """The digitised final surface and failure line, (n, 2) arrays of (x, y) in m."""
    surface = np.loadtxt(SURFACE, delimiter=",", skiprows=1)
    failure = np.loadtxt(FAILURE, delimiter=",", skiprows=1)
    return surface, failure


def line_fit(points: FloatArray) -> tuple[float, float]:
    """The least-squares line x = foot + slope y through (x, y) points: (angle to the
    horizontal in degrees, foot: x at y = 0)."""
    slope, foot = np.polyfit(points[:, 1], points[:, 0], 1)
    return math.degrees(math.atan2(1.0, abs(slope))), float(foot)


def failure_points(x0: FloatArray, x: FloatArray, still: float = STILL) -> FloatArray:
    """For each band of initial height, the furthest initial place of a particle that
    moved less than ``still``: (x, y) rows, y the band's middle."""
    moved = np.linalg.norm(x - x0, axis=1)
    rows = []
    for lo in np.arange(0.0, H0 - 0.5 * BAND, BAND):
        band = (x0[:, 1] >= lo) & (x0[:, 1] < lo + BAND) & (moved < still)
        if band.any():
            rows.append((float(x0[band, 0].max()), lo + 0.5 * BAND))
    return np.array(rows)


def surface_error(profile: tuple[FloatArray, FloatArray], surface: FloatArray) -> float:
    """The RMS over the measured surface's points of the computed surface's height there
    (linear between its columns, 0 past the toe) minus the measured, over H0."""
    px, top = profile
    y = np.interp(surface[:, 0], px, top, left=top[0], right=0.0)
    return float(np.sqrt(np.mean((y - surface[:, 1]) ** 2)) / H0)


@dataclass
class ColumnRun:
    """One mesh's run and its measures (m, m/s, s)."""

    h: float
    particles: int
    steps: int
    toe: float  # the furthest particle plus half a particle spacing
    angle: float  # the failure line's, degrees to the horizontal
    foot: float  # where it meets the floor
    line: FloatArray  # the still particles' edge, (x, y) rows
    profile: tuple[FloatArray, FloatArray]  # the deposit's surface
    speed: float  # the largest particle speed at the end
    moving: int  # particles faster than 1 mm/s at the end
    wall: float


def _run(h: float, end: float) -> ColumnRun:
    """The column at spacing h to ``end`` (s); its measures."""
    start: list[FloatArray] = []

    def record(sim: Simulation) -> None:
        if not start:
            start.append(sim.particles.x.copy())

    sim = run_example(
        "bui_column.toml",
        [f"grid.spacing={h!r}", f"time.end={end}", f"output.interval={end}"],
        record,
    )
    x0, x = start[0], sim.particles.x
    if x0.shape != x.shape:
        raise RuntimeError("the column lost or gained particles: no displacement to measure")
    spacing = h / sim.case.bodies[0].particles_per_cell
    line = failure_points(x0, x)
    angle, foot = line_fit(line)
    speed = np.linalg.norm(sim.particles.v, axis=1)
    return ColumnRun(
        h=h,
        particles=sim.particles.count,
        steps=sim.steps,
        toe=float(x[:, 0].max()) + 0.5 * spacing,
        angle=angle,
        foot=foot,
        line=line,
        profile=deposit_profile(x, 0.0, spacing),  # the wall at x = 0
        speed=float(speed.max()),
        moving=int(np.sum(speed > TOL_REST)),
        wall=float(sim.summary["wall_seconds"]),
    )


def run_column(out: Path, quick: bool = False, context: Context | None = None) -> CaseResult:
    res = CaseResult("bui_collapse", "Collapse of a frictional column (Bui et al. 2008)")
    surface, failure = measured()
    angle_exp, foot_exp = line_fit(failure)
    toe_exp = float(surface[:, 0].max())
    end = END_QUICK if quick else END
    runs = [_run(h, end) for h in (SPACINGS[:1] if quick else SPACINGS)]
    r = runs[-1]
    label = f"h = {fmt(r.h)} m"
    res.rows += [
        Row(
            "bui_collapse",
            f"run-out, {label}",
            "|(L_f - L0) / (L_exp - L0) - 1|, L_f: the toe",
            abs((r.toe - L0) / (toe_exp - L0) - 1),
            TOL_RUNOUT,
            WHY_RUNOUT,
            miss="the run-out depends on the transfer's damping (examples/bui_column.toml)",
        ),
        Row(
            "bui_collapse",
            f"failure line's angle, {label}",
            "|angle / angle_exp - 1|, each the least-squares line's",
            abs(r.angle / angle_exp - 1),
            TOL_ANGLE,
            WHY_ANGLE,
            miss="the computed line is flatter than the measured one, at every mesh (see the text)",
        ),
        Row(
            "bui_collapse",
            f"failure line's foot, {label}",
            "|x_foot / x_foot,exp - 1|, x at y = 0 of each line",
            abs(r.foot / foot_exp - 1),
            TOL_FOOT,
            WHY_FOOT,
            miss="the computed line meets the floor further from the wall (see the text)",
        ),
        Row(
            "bui_collapse",
            f"at rest, {label}",
            f"largest particle speed at {end:g} s",
            r.speed,
            TOL_REST,
            WHY_REST,
            unit="m/s",
            miss="the deposit's surface layer, where the pressure and with it the strength "
            "is near zero, keeps moving (see the text)",
        ),
    ]
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(10, 4.2))
    ax.plot(*surface.T, "ko", ms=4, label="Bui et al. (2008): final surface")
    ax.plot(*failure.T, "ks", mfc="none", ms=5, label="Bui et al. (2008): failure line")
    for run in runs:
        px, top = run.profile
        ax.plot(px, top, "-", label=f"mpmflow h = {fmt(run.h)} m: surface")
        line = run.line
        ax.plot(*line.T, ".", ms=3, label=f"mpmflow h = {fmt(run.h)} m: still particles' edge")
    ax.plot([L0, L0, 0], [0, H0, H0], "k:", lw=0.8, label="initial column")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_aspect("equal")
    ax.legend(fontsize=7, ncol=3, loc="upper center", bbox_to_anchor=(0.5, -0.3))
    fig.tight_layout()
    save(fig, out / "bui_collapse.png")
    res.figures.append(
        (
            "bui_collapse.png",
            "The deposit's surface and the failure line (the edge of the particles that "
            "moved less than 2 mm) against Bui et al.'s measurement.",
        )
    )
    table = markdown_table(
        [
            "h (m)",
            "particles",
            "steps",
            "toe (m)",
            "spread (m)",
            "failure angle (deg)",
            "foot (m)",
            "largest speed (m/s)",
            "faster than 1 mm/s",
            "surface RMS / H0",
            "wall (s)",
        ],
        [
            [
                fmt(run.h),
                run.particles,
                run.steps,
                fmt(run.toe, 4),
                fmt(run.toe - L0, 4),
                fmt(run.angle, 3),
                fmt(run.foot, 3),
                fmt(run.speed),
                run.moving,
                fmt(surface_error(run.profile, surface)),
                fmt(run.wall),
            ]
            for run in runs
        ]
        + [
            [
                "measured",
                "",
                "",
                fmt(toe_exp, 4),
                fmt(toe_exp - L0, 4),
                fmt(angle_exp, 3),
                fmt(foot_exp, 3),
                "",
                "",
                "",
                "",
            ]
        ],
    )
    res.text = "\n\n".join([__doc__.split("\n\n")[1], __doc__.split("\n\n")[2], table])
    return res
