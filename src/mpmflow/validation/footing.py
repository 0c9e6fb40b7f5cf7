"""Solids (issue 43): a rigid strip footing pushed into weightless undrained clay (Prandtl).

The footing of examples/footing.toml: B = 1 m wide, rough, its half modelled beside the
plane of symmetry (a slip wall), pushed down at 0.1 m/s (0.003 of the shear wave's speed:
quasi-static) into weightless Tresca clay (material.model = "von_mises" in plane strain:
(sigma_1 - sigma_3) / 2 <= s_u), s_u = 10 kPa, G = 1 MPa, 3 B deep and 5 B wide (half;
Prandtl's mechanism reaches 1.5 B from the centre line and 0.7 B down, but between slip
walls 1.5 B deep and 2.5 B wide the whole layer flowed, sliding on its base and up the far
wall, below Prandtl's load: with the particles held in place, 5.37, 5.19, 5.10 and 5.05 s_u
at B / 8 to B / 64, against 5.23, 5.19, 5.17 at B / 8 to B / 32 in this box), 16 particles a
cell (the report's norm). Prandtl's limit pressure is q = (2 + pi) s_u (Prandtl 1920; for a
rough footing Hill's mechanism gives the same, and it is the exact collapse load of the
rigid-plastic strip: Martin 2005). The clay's force on the footing is its nodes' reactions
(bodies.csv), pressure and shear. The limit pressure measured is the mean of q = F / (B / 2)
over a settlement s from 0.05 B to 0.1 B (chosen before the run as past the elastic rise; it
is not: the curve still rises there), read at every step (the mean over a window is the work
the footing does over it per unit settlement). Measured at h = B / 8, B / 16 and B / 32.
"""

import math
from pathlib import Path

import numpy as np

from ..case import load_case
from ..simulation import Simulation
from .common import EXAMPLES, CaseResult, Row, fmt, markdown_table
from .types import Context

B, S_U, G_MOD, RHO, SPEED = 1.0, 1.0e4, 1.0e6, 1000.0, 0.1
PRANDTL = 2.0 + math.pi
SPACINGS = (B / 8, B / 16, B / 32)
WINDOW = (0.05, 0.10)  # settlement / B over which the limit pressure is the mean
CURVE = tuple(round(0.01 * k, 2) for k in range(1, 11))  # settlements / B of the table

# tolerance, fixed before the run (the issue's)
TOL = 0.03
WHY = (
    "the issue's 3% of Prandtl's (2 + pi) s_u at the finest mesh; the plateau's mean over "
    "0.05-0.1 B, where the elastic rise is over"
)


def load_curve(h: float, end: float = 1.0) -> tuple[Simulation, np.ndarray]:
    """Run the footing at spacing h to time ``end`` (s; 0.1 m of settlement a second);
    returns the run and its curve, rows (settlement / B, q / s_u) at every step."""
    # one output a step: the auto step, 0.5 h / c_s, a hair shorter (a longer one would be
    # past the shear wave's, where the coupled step takes no tools)
    dt = 0.5 * h / math.sqrt(G_MOD / RHO) * (1 - 1e-6)
    sets = [
        "output.snapshots=false",
        f"grid.spacing={h}",
        f"time.end={end}",
        f"output.interval={dt!r}",
    ]
    sim = Simulation(load_case(EXAMPLES / "footing.toml", sets))
    rows: list[tuple[float, float]] = []

    def record(s: Simulation) -> None:
        force = float(s.scheme.core.body_force[0, 1])  # type: ignore[attr-defined]
        rows.append((SPEED * s.time / B, force / (0.5 * B) / S_U))

    sim.on_output = record
    sim.run()
    return sim, np.array(rows)


def window_mean(curve: np.ndarray, lo: float, hi: float) -> float:
    k = (curve[:, 0] > lo) & (curve[:, 0] <= hi)
    return float(np.mean(curve[k, 1]))


def run_footing(out: Path, quick: bool = False, context: Context | None = None) -> CaseResult:
    res = CaseResult("prandtl_footing", "Strip footing on weightless Tresca clay (Prandtl)")
    spacings = SPACINGS[:1] if quick else SPACINGS
    lines, curves = [], []
    limit = float("nan")
    for h in spacings:
        sim, curve = load_curve(h)
        limit = window_mean(curve, *WINDOW)
        curves.append(curve)
        lines.append(
            (
                fmt(h),
                f"B / {B / h:.0f}",
                sim.particles.count,
                sim.steps,
                fmt(limit),
                fmt(limit / PRANDTL),
                fmt(sim.summary["wall_seconds"]),
            )
        )
        np.savetxt(
            out / f"footing_h{B / h:.0f}.csv",
            curve,
            delimiter=",",
            header="settlement / B, q / s_u",
            comments="",
        )
    res.rows.append(
        Row(
            "prandtl_footing",
            f"limit pressure, h = B / {B / spacings[-1]:.0f}",
            "|mean q over s = 0.05-0.1 B / ((2 + pi) s_u) - 1|",
            abs(limit / PRANDTL - 1),
            TOL,
            WHY,
            miss=(
                "q is still rising over 0.05-0.1 B: the clay's heave beside the footing, and "
                "the plastic zone still spreading (the footing's speed does not enter; "
                'docs/method.md, "Solids")'
            ),
        )
    )
    curve_rows = []
    for k, s in enumerate(CURVE):
        lo = CURVE[k - 1] if k > 0 else 0.0
        curve_rows.append((f"{lo:.2f}-{s:.2f}", *(fmt(window_mean(c, lo, s)) for c in curves)))
    res.text = (
        __doc__.split("\n\n")[1]
        + f"\n\nPrandtl's limit pressure {fmt(PRANDTL)} s_u.\n\n"
        + markdown_table(
            ["h (m)", "mesh", "particles", "steps", "q / s_u", "/ Prandtl", "wall (s)"], lines
        )
        + "\n\nThe load-settlement curve: q / s_u, the mean over each settlement interval.\n\n"
        + markdown_table(["s / B", *(f"B / {B / h:.0f}" for h in spacings)], curve_rows)
    )
    return res
