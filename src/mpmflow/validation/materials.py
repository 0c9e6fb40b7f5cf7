"""Viscous, viscoplastic and granular materials (``material.model``) against theory and
experiment.

``viscous_wave``: the first sloshing mode of examples/sloshing.toml (L = 0.4 m, depth
0.2 m, slip walls) in a Newtonian liquid of kinematic viscosity nu = 1e-3 m^2/s. Linear
theory (Lamb, section 348): the amplitude decays as exp(-2 nu k^2 t), k = pi / L, at any
depth over a slip bed. The rate is fitted as in the sloshing case (a line through the log of
the centre of mass's extrema); the inviscid scheme's own rate at the same mesh is reported
beside it.

``granular_collapse``: examples/granular_collapse.toml (glass beads, mu(I) with the
parameters of Jop et al. 2006; solid fraction 0.6, bulk density 1470 kg/m^3) at aspect
ratios a = H0 / L0 from 0.5 to 10, L0 = 0.05 m the half-width (the column spreads both
ways), 12.5 cells across L0, rough (no-slip) floor, PIC transfer. Run-out: the furthest
particle on each side at the end, mean of both, (L_inf - L0) / L0, against Lube et al.
(2005): 1.2 a for a < 2.3, 1.9 a^(2/3) above. Final height H_inf / H0 (Lube: 1 for
a < 1.15) is reported, with the flow's duration t_f (the last output, every 0.05 s, at
which the front was more than a particle spacing short of where it ends) and the final
deposits' surfaces (the figure).

``bingham_slump``: examples/bingham_slump.toml (yield stress 50 Pa, plastic viscosity
20 Pa s, APIC transfers, 30 s). At rest the shallow deposit satisfies h |dh/dx| = tau_y /
(rho g), so h^2 falls linearly to the front: h^2 = 2 (tau_y / rho g) (x_f - x). That shape
is the limit of a slow slump (inertia negligible): the mud's Reynolds number rho sqrt(g H)
H / K is about 5 (at K = 1 Pa s, about 100, the slump over-runs and stops flatter; PIC's
transfer drag, about 0.19 rho h^2 / dt = 9 Pa s, would stop it steep). Measured on each
half of the deposit: the surface as the top particle of each column one particle spacing
wide plus half a spacing, and the mean of h |dh/dx| = -(1/2) d(h^2)/dx as the least-squares
slope of h^2 over the middle half of the half-deposit (a quarter to three quarters of the
way to the front), against tau_y / (rho g), read each second over the run's last 5 s and
averaged (a single reading moves by up to 0.1 as the top particle columns rearrange); and
the largest particle speed at the end (the deposit has stopped when it is a creep, below
1 mm/s). On particles filling the exact
arrested shape the measure reads 0.98 (0.95-1.01 with the particles displaced by a fifth
of their spacing at random); the earlier measure (the largest height in bins one cell wide,
np.gradient, the mean of the products over the middle 60%) read 0.91 and 1.0-1.21, and on
the simulated deposits, whose particles stand in columns with gaps, 1.4 times the fit.
"""

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..simulation import Simulation
from .common import CaseResult, Row, fmt, markdown_table, pyplot, run_example, save
from .sloshing import period_and_decay
from .types import Context, FloatArray, Measures

G = 9.81

# tolerances, fixed before the results were looked at (those of the issue)
TOL_WAVE = 0.05
WHY_WAVE = "the issue's criterion for the decay rate of a standing wave"
WAVE_SPACINGS, WAVE_SPACINGS_QUICK = (0.01, 0.005), (0.02,)
NU = 1e-3  # m^2/s

TOL_RUNOUT = 0.15
WHY_RUNOUT = "the issue's criterion; Lube et al.'s data scatter about their laws by about 10%"
TOL_REST = 5e-3  # m/s
WHY_REST = "the issue's criterion: each deposit at rest when its run-out is read"
ASPECTS, ASPECTS_QUICK = (0.5, 1.0, 2.0, 4.0, 7.0, 10.0), (0.5, 2.0)
L0 = 0.05  # m, half-width of the column
SPLIT = 2.3  # aspect ratio between Lube's two laws

TOL_ARREST = 0.2
WHY_ARREST = (
    "the arrest condition is the shallow-layer limit; the deposit is 0.05 m deep "
    "over 0.3 m (aspect 1/6), whose corrections are of that order"
)
WINDOW = 5.0  # s: the arrest measure is the mean of its readings each second over the last 5 s
TOL_STOPPED = 1e-3
WHY_STOPPED = (
    "a creep of the capped viscosity is far below 1 mm/s (|tau| / cap ~ 5e-4 1/s); "
    "the split of the viscous and pressure steps allows up to 0.6 |g| dt = 2.9 "
    "mm/s at this step (materials/stiffness.py): a miss may be the split's"
)


def lube(a: float) -> float:
    return 1.2 * a if a < SPLIT else 1.9 * a ** (2 / 3)


def run_wave(out: Path, quick: bool = False, context: Context | None = None) -> CaseResult:
    res = CaseResult("viscous_wave", "Viscous standing wave: decay against linear theory")
    k = math.pi / 0.4
    theory = 2 * NU * k * k
    runs = []
    for h in WAVE_SPACINGS_QUICK if quick else WAVE_SPACINGS:
        rates = []
        for nu in (NU, 0.0):
            xc: list[tuple[float, float]] = []

            def centre(sim: Simulation, xc: list[tuple[float, float]] = xc) -> None:
                xc.append((sim.time, float(sim.particles.x[:, 0].mean()) - 0.2))

            model = (
                ["material.model='newtonian'", f"material.viscosity={nu * 1000.0}"]
                if nu > 0
                else []
            )
            sim = run_example(
                "sloshing.toml",
                [f"grid.spacing={h}", f"time.end={2.0 if quick else 5.0}", *model],
                on_output=centre,
            )
            a = np.array(xc)
            period, decay = period_and_decay(a[:, 0], a[:, 1])[:2]
            rates.append(-math.log(1 - decay) / period)
            if nu > 0:
                wall = sim.summary["wall_seconds"]
                iters = sim.counters.viscous_iterations / max(sim.steps, 1)
        runs.append({"h": h, "rate": rates[0], "inviscid": rates[1], "wall": wall, "iters": iters})
    r = runs[-1]
    res.rows.append(
        Row(
            "viscous_wave",
            f"decay rate, h = {r['h']} m",
            "|rate - 2 nu k^2| / (2 nu k^2), nu = 1e-3 m^2/s",
            abs(r["rate"] - theory) / theory,
            TOL_WAVE,
            WHY_WAVE,
            miss="too few cells across the wave: the decay converges from above (see the table)",
        )
    )
    table = markdown_table(
        [
            "h (m)",
            "decay rate (1/s)",
            "2 nu k^2 (1/s)",
            "error",
            "inviscid rate, same mesh",
            "viscous iterations per step",
            "wall (s)",
        ],
        [
            [
                x["h"],
                fmt(x["rate"], 4),
                fmt(theory, 4),
                fmt((x["rate"] - theory) / theory),
                fmt(x["inviscid"], 3),
                fmt(x["iters"]),
                fmt(x["wall"]),
            ]
            for x in runs
        ],
    )
    res.text = __doc__.split("\n\n")[1] + "\n\n" + table
    return res


# the transfers the collapse studies compare (benchmarks/investigations/collapse_energy.py,
# granular_mesh.py)
TRANSFERS = {
    "pic": ["solver.flip=0"],
    "flip": ["solver.flip=0.99"],
    "apic": ["solver.transfer=apic"],
}


@dataclass(frozen=True)
class Collapse:
    """The collapse of a column of aspect ratio ``a`` as granular_collapse.toml's overrides:
    ``cells`` across L0, a tank of half-width L0 + ``width`` x Lube's run-out + 0.02 m, dt =
    min(5e-4, 0.35 h / sqrt(2 g H0)) times ``dt_factor``, to 0.6 s + 6 sqrt(H0 / g) (or
    ``end``)."""

    a: float
    cells: float
    width: float = 1.6
    dt_factor: float = 1.0
    end: float | None = None
    interval: float = 0.05

    @property
    def H0(self) -> float:
        return self.a * L0

    @property
    def half(self) -> float:
        return L0 + self.width * (lube(self.a) * L0) + 0.02

    @property
    def h(self) -> float:
        return L0 / self.cells

    @property
    def dt(self) -> float:
        return min(5e-4, 0.35 * self.h / math.sqrt(2 * G * self.H0)) * self.dt_factor

    def overrides(self) -> list[str]:
        H0, half, h, dt = self.H0, self.half, self.h, self.dt
        end = self.end if self.end is not None else 0.6 + 6 * math.sqrt(H0 / G)
        return [
            *column_in_tank(L0, H0, half, h),
            f"time.dt={dt:.4g}",
            f"time.end={end:.3f}",
            f"output.interval={self.interval}",
        ]


def column_in_tank(L0: float, H0: float, half: float, h: float) -> list[str]:
    """The overrides that put a column of half-width L0 and height H0 (m) on the floor in
    the middle of a tank of half-width ``half``, 1.15 H0 + 2 h high, at spacing h."""
    return [
        f"domain.size=[{2 * half:.4f}, {H0 * 1.15 + 2 * h:.4f}]",
        f"grid.spacing={h!r}",
        f"bodies.0.min=[{half - L0:.4f}, 0.0]",
        f"bodies.0.max=[{half + L0:.4f}, {H0:.4f}]",
    ]


def front_reach(x: FloatArray, half: float) -> float:
    """The mean distance of the two fronts' outermost particles from the axis at x = half
    (m; x the particles' positions)."""
    return 0.5 * float((x[:, 0].max() - half) + (half - x[:, 0].min()))


def reached_side_wall(x: FloatArray, half: float, h: float) -> bool:
    """Whether a particle came within 1.5 cells of the side walls of a tank 2 half wide."""
    return bool(x[:, 0].max() > 2 * half - 1.5 * h or x[:, 0].min() < 1.5 * h)


def _collapse(a: float, quick: bool, width: float = 1.6) -> Measures:
    """The column of aspect ratio a (quick: 6.25 cells across L0, else 12.5) in a tank of
    half-width L0 + width x Lube's run-out + 0.02 m. "walled": the deposit reached a side
    wall, so its run-out is the tank's, not its own (measured: APIC at a = 2 and 7 reach it
    at width 1.6)."""
    c = Collapse(a, 6.25 if quick else 12.5, width)
    H0, half, h = c.H0, c.half, c.h
    fronts: list[tuple[float, float]] = []  # (t, mean reach of the two fronts, m)

    def front(sim: Simulation) -> None:
        fronts.append((sim.time, front_reach(sim.particles.x, half)))

    sim = run_example("granular_collapse.toml", c.overrides(), front)
    x = sim.particles.x
    reach = front_reach(x, half)
    walled = reached_side_wall(x, half, h)
    spacing = h / sim.case.bodies[0].particles_per_cell
    # the flow's duration: from the release to the last output at which the front was
    # still more than a particle spacing short of where it ends
    moving = [t for t, r in fronts if reach - r > spacing]
    return {
        "a": a,
        "duration": moving[-1] if moving else 0.0,
        "profile": deposit_profile(x, half, spacing),
        "runout": (reach - L0) / L0,
        "law": lube(a),
        "height": x[:, 1].max() / H0,
        "walled": walled,
        "speed": float(np.linalg.norm(sim.particles.v, axis=1).max()),
        "wall": sim.summary["wall_seconds"],
        "h": h,
        "particles": sim.particles.count,
    }


def deposit_profile(x: FloatArray, centre: float, spacing: float) -> tuple[FloatArray, FloatArray]:
    """The deposit's surface against the distance from the column's axis (m): the top of
    each column of particles one ``spacing`` wide (plus half a spacing), both sides
    folded together (the higher of the two). Returns (distance, height)."""
    d = np.abs(x[:, 0] - centre)
    k = (d / spacing).astype(int)
    top = np.zeros(int(k.max()) + 1)
    np.maximum.at(top, k, x[:, 1] + 0.5 * spacing)
    return (np.arange(top.size, dtype=np.float64) + 0.5) * spacing, top


def run_collapse(out: Path, quick: bool = False, context: Context | None = None) -> CaseResult:
    res = CaseResult("granular_collapse", "Granular column collapse against Lube et al. (2005)")
    runs = [_collapse(a, quick) for a in (ASPECTS_QUICK if quick else ASPECTS)]
    for r in runs:
        res.rows.append(
            Row(
                "granular_collapse",
                f"run-out, a = {r['a']:g}",
                "|run-out - law| / law, (L_inf - L0) / L0",
                abs(r["runout"] - r["law"]) / r["law"],
                TOL_RUNOUT,
                WHY_RUNOUT,
                miss="the deposit spreads short of the law with PIC transfer (and "
                "past it with FLIP); see the text",
            )
        )
        res.rows.append(
            Row(
                "granular_collapse",
                f"at rest, a = {r['a']:g}",
                "largest particle speed when the run-out is read",
                r["speed"],
                TOL_REST,
                WHY_REST,
                unit="m/s",
                miss="PIC's deposit creeps at its toe and surface (a shear PIC drags but "
                "does not stop)",
            )
        )
    plt = pyplot()
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 4.5))
    for r in runs:
        dist, top = r["profile"]
        bx.plot(dist / L0, top / L0, "-", label=f"a = {r['a']:g}")
    bx.set_xlabel("distance from the axis / L0")
    bx.set_ylabel("deposit surface / L0")
    bx.set_title("final deposits (top particle of each column)")
    bx.legend(fontsize=8)
    aa = np.linspace(0.4, 11, 200)
    ax.plot(aa[aa < SPLIT], 1.2 * aa[aa < SPLIT], "k-", label="Lube et al. 2005: 1.2 a")
    ax.plot(
        aa[aa >= SPLIT],
        1.9 * aa[aa >= SPLIT] ** (2 / 3),
        "k--",
        label="Lube et al. 2005: 1.9 a^(2/3)",
    )
    ax.fill_between(
        aa,
        [lube(v) * (1 - TOL_RUNOUT) for v in aa],
        [lube(v) * (1 + TOL_RUNOUT) for v in aa],
        color="0.9",
        label="+-15%",
    )
    ax.plot([r["a"] for r in runs], [r["runout"] for r in runs], "o", label="mpmflow (2D, mu(I))")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("aspect ratio a = H0 / L0")
    ax.set_ylabel("run-out (L_inf - L0) / L0")
    ax.legend()
    fig.tight_layout()
    save(fig, out / "granular_collapse.png")
    res.figures.append(
        (
            "granular_collapse.png",
            "Left: run-out of the granular columns against "
            "Lube et al. (2005)'s laws (the grey band: the tolerance). Right: the final "
            "deposits' surfaces.",
        )
    )
    table = markdown_table(
        [
            "a",
            "h (m)",
            "particles",
            "run-out (L_inf - L0)/L0",
            "Lube's law",
            "H_inf / H0",
            "largest speed at the end (m/s)",
            "flow duration t_f (s)",
            "t_f sqrt(g / H0)",
            "reached a side wall",
            "wall (s)",
        ],
        [
            [
                r["a"],
                r["h"],
                r["particles"],
                fmt(r["runout"]),
                fmt(r["law"]),
                fmt(r["height"]),
                fmt(r["speed"]),
                fmt(r["duration"]),
                fmt(r["duration"] * math.sqrt(G / (r["a"] * L0))),
                "yes" if r["walled"] else "no",
                fmt(r["wall"]),
            ]
            for r in runs
        ],
    )
    res.text = __doc__.split("\n\n")[2] + "\n\n" + table
    return res


def arrest_ratios(
    x: FloatArray, centre: float, spacing: float, scale: float, lo: float = 0.25, hi: float = 0.75
) -> list[float]:
    """h |dh/dx| / scale on each side of a deposit centred at ``centre`` (m), from the
    particles' positions x (n x 2, m; ``spacing`` their spacing, m): the least-squares slope
    of h^2 against x over [lo, hi] of the way from the centre to the front, halved (h the
    top particle of each column plus half a spacing). Returns [right, left]."""
    values = []
    for side in (1, -1):
        d = side * (x[:, 0] - centre)
        front = d.max() + 0.5 * spacing
        edges = np.arange(0.0, front, spacing)
        top = np.array(
            [
                x[(d >= a) & (d < a + spacing), 1].max() + 0.5 * spacing
                if ((d >= a) & (d < a + spacing)).any()
                else np.nan
                for a in edges
            ]
        )
        mid = edges + 0.5 * spacing
        keep = (mid > lo * front) & (mid < hi * front) & np.isfinite(top)
        if keep.sum() < 3:
            values.append(float("nan"))
            continue
        values.append(float(-0.5 * np.polyfit(mid[keep], top[keep] ** 2, 1)[0] / scale))
    return values


def run_slump(out: Path, quick: bool = False, context: Context | None = None) -> CaseResult:
    res = CaseResult("bingham_slump", "Bingham slump: arrest condition")
    readings: list[tuple[float, float, float, float]] = []  # (t, right, left, largest speed)

    def read(sim: Simulation) -> None:
        m = sim.case.material
        scale = m.yield_stress / (m.density * G)
        spacing = sim.case.grid.spacing / sim.case.bodies[0].particles_per_cell
        right, left = arrest_ratios(sim.particles.x, 0.5 * sim.case.domain.size[0], spacing, scale)
        readings.append(
            (sim.time, right, left, float(np.linalg.norm(sim.particles.v, axis=1).max()))
        )

    def each_second(sim: Simulation) -> None:
        t = sim.time
        late = t >= sim.case.time.end - WINDOW - 1e-9 and t > 0.5 * sim.dt
        if late and abs(t - round(t)) < 0.5 * sim.dt:
            read(sim)

    sim = run_example("bingham_slump.toml", ["time.end=0.6"] if quick else [], each_second)
    if not readings or readings[-1][0] < sim.time - 0.5 * sim.dt:
        read(sim)  # the end (the quick run's only reading)
    values = np.array([[r, l] for _, r, l, _ in readings])
    means = values.mean(axis=1)
    ratio = float(means.mean())
    speed = float(np.linalg.norm(sim.particles.v, axis=1).max())
    res.rows.append(
        Row(
            "bingham_slump",
            "arrest: h |dh/dx| rho g / tau_y",
            f"|mean over the deposit's middle and the last {WINDOW:g} s - 1|",
            abs(ratio - 1),
            TOL_ARREST,
            WHY_ARREST,
            miss="the deposit has not stopped, or is not shallow",
        )
    )
    res.rows.append(
        Row(
            "bingham_slump",
            "stopped",
            "largest particle speed at the end",
            speed,
            TOL_STOPPED,
            WHY_STOPPED,
            unit="m/s",
            miss="still spreading at the end of the run",
        )
    )
    each = ", ".join(f"{fmt(v)} ({r[0]:g} s)" for r, v in zip(readings, means))
    speeds = ", ".join(f"{r[3]:.2g}" for r in readings)
    half = float(np.abs(sim.particles.x[:, 0] - 0.5 * sim.case.domain.size[0]).max())
    res.text = (
        __doc__.split("\n\n")[3] + f"\n\nMeasured: h |dh/dx| rho g / tau_y = {fmt(ratio)}, "
        f"the mean of {each} (left and right sides within {fmt(np.ptp(values, axis=1).max())} "
        f"of each other); half-length {fmt(half)} m; largest speed at t = {sim.time:g} s: "
        f"{speed:.3g} m/s (at the readings: {speeds} m/s; a single surface particle's "
        f"rearrangement reads up to a few mm/s); wall {fmt(sim.summary['wall_seconds'])} s."
    )
    return res
