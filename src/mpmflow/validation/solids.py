"""Solids (issue 43): the cantilever of incompressible elastic material under its own weight.

The beam of examples/cantilever.toml: L = 1 m, H = 0.1 m (L / H = 10), G = 3.68e7 Pa,
rho = 1000 kg/m^3, clamped to a bonded wall and released in gravity. Beam theory in plane
strain with Poisson's ratio 0.5 (E' = E / (1 - nu^2) = 4 G) and Timoshenko's shear term
(kappa = 5/6): delta = 3 rho g L^4 / (8 G H^2) + rho g L^2 / (2 kappa G) = 0.01016 m. Released
suddenly, an undamped beam swings about that deflection; its mean over the first mode's
period (T = 2 pi / (1.875^2 sqrt(G H^2 / (3 rho L^4))) = 0.16 s) is the static deflection
(the higher modes average out over it to within a few per cent). Measured at three meshes,
h = H / 4, H / 8, H / 16, and in 3D at H / 4 (the beam 4 cells across, periodic there:
plane strain, as the 2D beam).

The step each scheme takes for this beam (computed, not run: the explicit comparator does
not take solids): time.dt = "auto" takes 0.5 h / c_s, c_s = sqrt(G / rho) = 192 m/s, to
follow the waves, and a longer fixed step takes the coupled step, which has no limit
(docs/method.md, "Solids"); no bulk modulus enters either. An explicit compressible
solid's stable step is 0.5 h / c_p, c_p = sqrt((K + 4 G / 3) / rho), with K = 2 G (1 + nu)
/ (3 (1 - 2 nu)): c_p = 7.2 c_s at nu = 0.49 and 22.4 c_s at nu = 0.499, and unbounded at
the incompressible 0.5 the projection runs.
"""

import math
from pathlib import Path

import numpy as np

from ..case import load_case
from ..simulation import Simulation
from .common import EXAMPLES, CaseResult, Row, fmt, markdown_table
from .types import Context

L, H, RHO, G_MOD, G = 1.0, 0.1, 1000.0, 3.68e7, 9.81
KAPPA = 5.0 / 6.0
DELTA = 3 * RHO * G * L**4 / (8 * G_MOD * H**2) + RHO * G * L**2 / (2 * KAPPA * G_MOD)
PERIOD = 2 * math.pi / (1.875**2 * math.sqrt(G_MOD * H**2 / (3 * RHO * L**4)))
SPACINGS = (H / 4, H / 8, H / 16)

# tolerance, fixed before the run (the issue's)
TOL_TIP = 0.03
WHY_TIP = (
    "the issue's 3% of beam theory at the finest mesh; Timoshenko's shear term is 1.6% of "
    "the deflection at L / H = 10, so the bending-only formula would not do"
)

WHY_TIP_3D = (
    "the issue's 3D cantilever, within the same 3% at a coarser mesh; 4 cells across and "
    "periodic there, so plane strain and the same theory (a beam of free sides has none "
    "as clean: its width sets where it lies between plane stress and plane strain)"
)


def explicit_ratio(nu: float) -> float:
    """c_p / c_s of a compressible elastic solid of Poisson's ratio nu."""
    k_over_g = 2 * (1 + nu) / (3 * (1 - 2 * nu))
    return math.sqrt(k_over_g + 4.0 / 3.0)


def tip_history(h: float, dim: int = 2) -> tuple[Simulation, list[float]]:
    """Run the cantilever at spacing h over the first period; returns the run and the tip's
    deflection (m; the particle that starts nearest the end of the neutral axis, in 3D the
    mean of those across the beam) at each of the 41 outputs from t = 0. In 3D the beam is
    4 cells across and periodic there (plane strain, the 2D beam's theory)."""
    sets = [
        "output.snapshots=false",
        f"grid.spacing={h}",
        f"time.end={PERIOD:.6f}",
        f"output.interval={PERIOD / 40:.6f}",
    ]
    if dim == 3:
        sets += [
            f"domain.size=[1.2, {4 * h}, 0.6]",
            "domain.periodic=[false, true, false]",
            "bodies.0.min=[0.0, 0.0, 0.25]",
            f"bodies.0.max=[1.0, {4 * h}, 0.35]",
            "physics.gravity=[0.0, 0.0, -9.81]",
        ]
    sim = Simulation(load_case(EXAMPLES / "cantilever.toml", sets))
    x0 = sim.particles.x.copy()
    up = dim - 1
    end = np.abs(x0[:, 0] - x0[:, 0].max()) < 1e-9 * L
    mid = np.abs(x0[:, up] - 0.3)
    k = np.flatnonzero(end & (mid <= mid[end].min() + 1e-9 * H))
    tips: list[float] = []
    sim.on_output = lambda s: tips.append(float(np.mean(x0[k, up] - s.particles.x[k, up])))
    sim.run()
    return sim, tips


def run_cantilever(out: Path, quick: bool = False, context: Context | None = None) -> CaseResult:
    res = CaseResult("cantilever", "Cantilever: an incompressible elastic beam under gravity")
    spacings = SPACINGS[:1] if quick else SPACINGS
    lines = []
    ratio = float("nan")
    for h in spacings:
        sim, tips = tip_history(h)
        mean = float(np.mean(tips[:-1]))  # 40 outputs evenly over the period (t = 0 first)
        ratio = mean / DELTA
        lines.append(
            (
                fmt(h),
                fmt(H / h),
                sim.particles.count,
                sim.steps,
                fmt(mean),
                fmt(ratio),
                fmt(sim.summary["wall_seconds"]),
            )
        )
    res.rows.append(
        Row(
            "cantilever",
            f"tip deflection, h = H / {H / spacings[-1]:.0f}",
            "|mean over the first period / Timoshenko's static deflection - 1|",
            abs(ratio - 1),
            TOL_TIP,
            WHY_TIP,
            miss=(
                "the swinging beam's mean over the first period is off the static deflection; "
                'docs/method.md, "Solids", says what set it before'
            ),
        )
    )
    if not quick:
        h3 = SPACINGS[0]
        sim, tips = tip_history(h3, dim=3)
        mean = float(np.mean(tips[:-1]))
        lines.append(
            (
                fmt(h3) + " (3D)",
                fmt(H / h3),
                sim.particles.count,
                sim.steps,
                fmt(mean),
                fmt(mean / DELTA),
                fmt(sim.summary["wall_seconds"]),
            )
        )
        res.rows.append(
            Row(
                "cantilever",
                f"tip deflection in 3D, h = H / {H / h3:.0f}",
                "|mean over the first period / Timoshenko's static deflection - 1|",
                abs(mean / DELTA - 1),
                TOL_TIP,
                WHY_TIP_3D,
                miss=(
                    "the 3D kernels' beam is off the 2D one's at the same mesh; "
                    'docs/method.md, "Solids"'
                ),
            )
        )
    steps = markdown_table(
        ["scheme", "wave", "step / (h / c_s)"],
        [
            ("projection (nu = 0.5), auto", "shear, c_s", "0.5 (auto; coupled: no limit)"),
            (
                "explicit, nu = 0.49",
                f"c_p = {explicit_ratio(0.49):.1f} c_s",
                fmt(0.5 / explicit_ratio(0.49)),
            ),
            (
                "explicit, nu = 0.499",
                f"c_p = {explicit_ratio(0.499):.1f} c_s",
                fmt(0.5 / explicit_ratio(0.499)),
            ),
        ],
    )
    res.text = (
        __doc__.split("\n\n")[1]
        + f"\n\nTimoshenko's static deflection {fmt(DELTA)} m; first period {fmt(PERIOD)} s.\n\n"
        + markdown_table(
            [
                "h (m)",
                "H / h",
                "particles",
                "steps",
                "mean tip deflection (m)",
                "/ theory",
                "wall (s)",
            ],
            lines,
        )
        + "\n\n"
        + __doc__.split("\n\n")[2]
        + "\n\n"
        + steps
    )
    return res
