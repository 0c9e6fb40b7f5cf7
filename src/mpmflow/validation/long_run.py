"""Long runs: the water keeps its volume and its energy for tens of seconds.

Standing-wave sloshing (examples/sloshing.toml, about 27 periods) for 20 s at h = 0.01 m and
0.005 m, and the aspect-ratio-2 dam break (examples/dam_break.toml) for 10 s at 0.008 m and
0.004 m, where the water hits the far wall, overturns, sloshes and settles. dt = 1 ms and
the default settings throughout. Measured at every output (10 ms), from the cell volume
fractions f (particle volume in the cell over the cell's volume):

* **wetted region**: V(f >= 1/2) / V_water - 1, the largest magnitude over the run (the dam
  break: from 3 s on, after the impact and the overturning jet). Loosening shows as > 0,
  packing as < 0. The same f = 1/2 rule defines the front, the height and the surface;
* **packed share**: the largest share of the cells holding material with f > 1.2. A count
  per cell steps by a row of particles (1/4 of a cell with 16 per cell), so a lattice of
  particles strained by a few percent already reads 1.25 in some cells; the row **packed
  share, hat measure** applies the same threshold to the volume correction's density (the
  bilinear hat of the cell grid, which a strained lattice does not trip);
* **energy**: kinetic plus potential energy (from the floor, y = 0) of the particles; the
  largest rise above its initial value, relative to it (the issue's measure), and in units of
  the wave's own energy rho g A^2 L / 4 (reported in the table);
* **period**: from the zero crossings of the water's centre of mass over the whole run (see
  the sloshing case), against linear theory;
* **settled level**: the mean over the last second of the mean over the cell columns of the
  height where f drops below 1/2, against the level the water's volume gives in the tank
  (volume / tank width).
"""

from pathlib import Path

import numpy as np

from .. import state
from ..cells import bin_particles
from ..diagnostics.measures import last_crossings, volume_measures
from ..simulation import Simulation
from .common import CaseResult, Row, box, fmt, markdown_table, pyplot, run_example, save
from .sloshing import period_and_decay, theory
from .types import Context, FloatArray

G = 9.81
SLOSH = (0.01, 0.005)  # m
SLOSH_END = 20.0  # s
DAM = (0.008, 0.004)  # m
DAM_END = 10.0  # s
QUICK = {"sloshing": ((0.01,), 10.0), "dam break": ((0.008,), 6.0)}
SETTLED_FROM = 3.0  # s, the dam break's wetted region counts from here
LAST = 1.0  # s, the settled level is averaged over the last second

# tolerances, fixed before the results were looked at (the acceptance)
TOL_REGION = {"sloshing": 0.01, "dam break": 0.03}
WHY_REGION = {
    "sloshing": "1% of the water is 2 mm of depth, a quarter of the wave amplitude: the issue's "
    "criterion",
    "dam break": "3% of the water is 1.9 mm of settled depth, half a cell of the finer mesh: "
    "the issue's criterion",
}
TOL_PACKED = {"sloshing": 0.01, "dam break": 0.05}
WHY_PACKED = {
    "sloshing": "the issue's criterion: at most 1 cell in 100 with 4 particles more than 16",
    "dam break": "the volume case's tolerance for the dam break (impact and overturning pack "
    "the particles for a moment)",
}
TOL_ENERGY = 0.005
WHY_ENERGY = (
    "the issue's criterion: an inviscid flow in closed walls may lose energy but must "
    "not gain it; 0.5% of the initial energy"
)
TOL_PERIOD = 0.02
WHY_PERIOD = "the issue's criterion; the sloshing case's tolerance at the finest grid"
TOL_LEVEL = 0.03
WHY_LEVEL = "the issue's criterion: 3% of 0.0619 m is 1.9 mm, half a cell of the finer mesh"


class Record:
    """An on_output callback recording the long-run measures."""

    def __init__(self) -> None:
        self.rows: list[tuple[float, ...]] = []

    def __call__(self, sim: Simulation) -> None:
        g, P = sim.grid, sim.particles
        bins = bin_particles(g, P)
        vm = volume_measures(bins.theta, g.cell_volume, sim.volume0)
        rho = np.empty(g.ncells)
        state.cell_volume(g, P.x, P.volume, rho)
        hat = np.count_nonzero(rho > 1.2 * g.cell_volume) / max(
            int(np.count_nonzero(bins.theta > 0)), 1
        )
        f = np.clip(bins.theta, 0, 1).reshape(g.cells[1], g.cells[0])  # [cy, cx]
        levels = last_crossings(f, g.cell_centres(1), g.size[1])
        ke = 0.5 * float(np.sum(P.mass * np.sum(P.v**2, axis=1)))
        pe = -float(np.sum(P.mass * (P.x @ np.asarray(sim.case.physics.gravity))))
        xc = float(np.sum(P.mass * P.x[:, 0]) / np.sum(P.mass))
        self.rows.append(
            (
                sim.time,
                vm["volume_ratio"],
                vm["packed_share"],
                hat,
                ke,
                pe,
                xc,
                float(np.nanmean(levels)),
            )
        )

    def array(self) -> FloatArray:
        return np.array(self.rows, dtype=float).reshape(-1, 8)


def _run(example: str, h: float, end: float) -> tuple[Simulation, FloatArray]:
    rec = Record()
    sim = run_example(
        example, [f"grid.spacing={h}", f"time.end={end}", "output.interval=0.01"], on_output=rec
    )
    return sim, rec.array()


def run(out: Path, quick: bool = False, context: Context | None = None) -> CaseResult:
    res = CaseResult("long_run", "Long runs: volume and energy")
    slosh_h, slosh_end = QUICK["sloshing"] if quick else (SLOSH, SLOSH_END)
    dam_h, dam_end = QUICK["dam break"] if quick else (DAM, DAM_END)
    plt = pyplot()
    fig, ax = plt.subplots(2, 2, figsize=(11, 7))
    lines = []
    for h in slosh_h:
        sim, a = _run("sloshing.toml", h, slosh_end)
        t, region, packed, hat, ke, pe, xc, _ = a.T
        body = box(sim.case.bodies[0])
        L, depth, A = body.max[0] - body.min[0], body.max[1], body.surface_amplitude
        T0 = theory(L, depth)
        period, decay, _, _ = period_and_decay(t, xc - L / 2)
        e = ke + pe
        wave = 0.25 * sim.case.material.density * G * A**2 * L
        rise = float(np.max(e) - e[0])
        name = f"sloshing, h = {h} m, {t[-1]:g} s"
        change = region - 1
        res.rows += [
            Row(
                "long_run",
                f"{name}: wetted region",
                "largest |V(f >= 1/2) / V_water - 1| (signed value shown)",
                float(change[np.argmax(np.abs(change))]),
                TOL_REGION["sloshing"],
                WHY_REGION["sloshing"],
                sense="|<=|",
                miss="the f = 1/2 count flickers by a few surface cells as the wave passes "
                "through them (one cell is 0.125% of the water at 0.01 m)",
            ),
            Row(
                "long_run",
                f"{name}: packed share",
                "largest share of the cells holding material with f > 1.2",
                float(packed.max()),
                TOL_PACKED["sloshing"],
                WHY_PACKED["sloshing"],
                miss="the count steps by a row of particles: the wave strains the lattice of "
                "particles by a few percent, and some cells hold 5 rows of 4 (1.25) "
                "while their neighbours hold 3 or 4 (see the hat-measure row)",
            ),
            Row(
                "long_run",
                f"{name}: packed share, hat measure",
                "largest share of the cells holding material whose hat-kernel density exceeds 1.2",
                float(hat.max()),
                TOL_PACKED["sloshing"],
                WHY_PACKED["sloshing"],
            ),
            Row(
                "long_run",
                f"{name}: energy rise",
                "largest (E - E0) / E0, E = kinetic + potential energy of the particles",
                rise / e[0],
                TOL_ENERGY,
                WHY_ENERGY,
                miss="energy is created where the sub-cell free surface extrapolates the "
                "pressure (docs/method.md, energy)",
            ),
            Row(
                "long_run",
                f"{name}: period",
                "|T - T_linear| / T_linear over the whole run",
                abs(period - T0) / T0,
                TOL_PERIOD,
                WHY_PERIOD,
                miss="the wave has decayed or grown too far to keep a clean period",
            ),
        ]
        lines.append(
            [
                name,
                len(sim.particles.x),
                fmt(change.min()),
                fmt(change.max()),
                fmt(packed.max()),
                fmt(hat.max()),
                fmt(rise / e[0]),
                fmt(rise / wave),
                fmt(decay),
                fmt(abs(period - T0) / T0),
                fmt(sim.summary["wall_seconds"]),
            ]
        )
        ax[0, 0].plot(t, change, label=f"sloshing h = {h} m")
        ax[0, 1].plot(t, (e - e[0]) / wave, label=f"sloshing h = {h} m")
        ax[1, 0].plot(t, packed, label=f"sloshing h = {h} m, count")
        ax[1, 0].plot(t, hat, ":", label=f"sloshing h = {h} m, hat")
    for h in dam_h:
        sim, a = _run("dam_break.toml", h, dam_end)
        t, region, packed, hat, ke, pe, xc, level = a.T
        width = float(sim.grid.size[0])
        expected = sim.volume0 / width
        settled = t >= SETTLED_FROM
        change = region - 1
        worst = float(change[settled][np.argmax(np.abs(change[settled]))])
        last = t >= t[-1] - LAST + 1e-9
        lev = float(np.mean(level[last]))
        e = ke + pe
        name = f"dam break, h = {h} m, {t[-1]:g} s"
        res.rows += [
            Row(
                "long_run",
                f"{name}: wetted region",
                f"largest |V(f >= 1/2) / V_water - 1| "
                f"from {SETTLED_FROM:g} s on (signed value shown)",
                worst,
                TOL_REGION["dam break"],
                WHY_REGION["dam break"],
                sense="|<=|",
                miss="splashes and trapped air still count as wetted cells",
            ),
            Row(
                "long_run",
                f"{name}: settled level",
                "|mean f = 1/2 level over the last "
                "second - V_water / tank width| / (V_water / tank width)",
                abs(lev - expected) / expected,
                TOL_LEVEL,
                WHY_LEVEL,
                miss="the water has not settled, or its volume has drifted",
            ),
            Row(
                "long_run",
                f"{name}: packed share",
                "largest share of the cells holding material with f > 1.2",
                float(packed.max()),
                TOL_PACKED["dam break"],
                WHY_PACKED["dam break"],
                miss="the impact and the overturning jet pack the particles faster than the "
                "correction (half the excess per step) spreads them",
            ),
        ]
        lines.append(
            [
                name,
                len(sim.particles.x),
                fmt(change[settled].min()),
                fmt(change[settled].max()),
                fmt(packed.max()),
                fmt(hat.max()),
                fmt(float(np.max(e[t >= 1.0]) - e[t >= 1.0][0]) / e[0]),
                "",
                f"level {lev:.4f} m (volume: {expected:.4f} m)",
                "",
                fmt(sim.summary["wall_seconds"]),
            ]
        )
        ax[0, 0].plot(t, change, label=f"dam break h = {h} m")
        ax[1, 1].plot(t, level, label=f"dam break h = {h} m")
        ax[1, 1].axhline(expected, color="k", lw=0.5)
    ax[0, 0].set_ylabel("V(f >= 1/2) / V_water - 1")
    ax[0, 1].set_ylabel("(E - E0) / wave energy")
    ax[1, 0].set_ylabel("share of cells with f > 1.2")
    ax[1, 1].set_ylabel("mean f = 1/2 level [m]")
    for a_ in ax.flat:
        a_.set_xlabel("t [s]")
        if a_.lines:
            a_.legend(fontsize=7)
    fig.tight_layout()
    save(fig, out / "long_run.png")
    res.figures.append(
        (
            "long_run.png",
            "Wetted region (top left), energy of the sloshing "
            "wave (top right), packed share by count and by the hat measure "
            "(bottom left) and the dam break's mean surface level with the level "
            "its volume gives (bottom right).",
        )
    )
    res.text = (
        __doc__.split("\n", 2)[2].strip()
        + "\n\n"
        + markdown_table(
            [
                "run",
                "particles",
                "wetted region - 1: smallest",
                "largest",
                "packed share (count)",
                "packed share (hat)",
                "largest energy rise / E0 (dam break: after 1 s)",
                "largest energy rise / wave energy",
                "amplitude lost per period / level",
                "period error",
                "wall (s)",
            ],
            lines,
        )
    )
    return res
