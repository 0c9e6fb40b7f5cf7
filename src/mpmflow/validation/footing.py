"""Solids (issue 43): a rigid strip footing pushed into weightless undrained clay (Prandtl).

The footing of examples/footing.toml: B = 1 m wide, rough, its half modelled beside the
plane of symmetry (a slip wall), pushed down at 0.1 m/s (0.0014 of the shear wave's speed:
quasi-static) into weightless Tresca clay (material.model = "von_mises" in plane strain:
(sigma_1 - sigma_3) / 2 <= s_u), s_u = 10 kPa, G = 5 MPa (G / s_u = 500, a stiff clay: the
elastic settlement scales with s_u / G, so the clay is at its limit within a settlement of
0.015 B, before the heave beside the footing changes the geometry Prandtl's solution is
for), 3 B deep and 5 B wide (half; Prandtl's mechanism reaches 1.5 B from the centre line
and 0.7 B down; a box 1.5 B deep and 2.5 B wide let the whole layer flow between its slip
walls below Prandtl's load), 16 particles a cell (the report's norm). Prandtl's limit
pressure is q = (2 + pi) s_u (Prandtl 1920; for a rough footing Hill's mechanism gives the
same, and it is the exact collapse load of the rigid-plastic strip: Martin 2005). The clay's
force on the footing is its nodes' reactions (bodies.csv), pressure and shear. The limit
pressure measured is the mean of q = F / (B / 2) over a settlement s from 0.02 B to 0.03 B
(chosen before the finest run, from the coarser meshes' curves: past the rise, which ends
by 0.015 B, and flat to 0.06 B at B / 16), read at every step (the mean over a window is the
work the footing does over it per unit settlement). Measured at h = B / 16, B / 32 and
B / 64; the error falls with h, at first order to B / 32 (the footing's edge node holds
the clay over half the next cell, widening the footing by about h).
"""

import math
from pathlib import Path

import numpy as np

from ..case import load_case
from ..simulation import Simulation
from .common import EXAMPLES, CaseResult, Row, fmt, markdown_table
from .types import Context

B, S_U, G_MOD, RHO, SPEED = 1.0, 1.0e4, 5.0e6, 1000.0, 0.1
PRANDTL = 2.0 + math.pi
SPACINGS = (B / 16, B / 32, B / 64)
WINDOW = (0.02, 0.03)  # settlement / B over which the limit pressure is the mean
CURVE = tuple(round(0.005 * k, 3) for k in range(1, 7))  # settlements / B of the table

# tolerance, fixed before the run (the issue's)
TOL = 0.03
WHY = (
    "the issue's 3% of Prandtl's (2 + pi) s_u at the finest mesh; the plateau's mean over "
    "0.02-0.03 B, past the rise (over by 0.015 B at G = 500 s_u) and before the heave"
)


def load_curve(h: float, end: float = WINDOW[1] * B / SPEED) -> tuple[Simulation, np.ndarray]:
    """Run the footing at spacing h to time ``end`` (s; 0.1 m of settlement a second; the
    window's end by default); returns the run and its curve, rows (settlement / B,
    q / s_u) at every step."""
    # one output a step: the auto step, 0.5 h / c_s, a hair shorter (a longer one would be
    # past the shear wave's, where plastic flow is refused)
    dt = 0.5 * h / math.sqrt(G_MOD / RHO) * (1 - 1e-6)
    sets = [
        "output.snapshots=false",
        f"grid.spacing={h}",
        f"time.end={end}",
        f"output.interval={dt!r}",
        # the cell pressure's multigrid takes 65 iterations a solve at B / 32 and more at
        # B / 64, where the footing's first step needs more than the default 200
        "solver.max_iterations=2000",
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


def convergence(limits: list[float]) -> str:
    """The observed order of the limit pressure's error over three meshes halved in turn
    (measured against Prandtl's load, and from the three alone), as a sentence."""
    if len(limits) < 3:
        return ""
    e = [q / PRANDTL - 1 for q in limits]
    orders = [math.log2(a / b) if a > 0 and b > 0 else float("nan") for a, b in zip(e, e[1:])]
    d = (limits[0] - limits[1]) / (limits[1] - limits[2])
    alone = math.log2(d) if d > 0 else float("nan")
    return (
        f"\n\nThe error against Prandtl's load at the three meshes: "
        f"{', '.join(fmt(x) for x in e)}; its observed order over each halving of h "
        f"{' and '.join(fmt(p) for p in orders)}, and from the three limits alone (no "
        f"reference) {fmt(alone)}."
    )


def run_footing(out: Path, quick: bool = False, context: Context | None = None) -> CaseResult:
    res = CaseResult("prandtl_footing", "Strip footing on weightless Tresca clay (Prandtl)")
    spacings = SPACINGS[:1] if quick else SPACINGS
    lines, curves, limits = [], [], []
    for h in spacings:
        sim, curve = load_curve(h)
        limit = window_mean(curve, *WINDOW)
        curves.append(curve)
        limits.append(limit)
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
            "|mean q over s = 0.02-0.03 B / ((2 + pi) s_u) - 1|",
            abs(limits[-1] / PRANDTL - 1),
            TOL,
            WHY,
            miss=(
                "the error falls with h, at first order to B / 32 (the footing's edge node "
                'holds the clay over half the next cell): docs/method.md, "Solids"'
            ),
        )
    )
    curve_rows = []
    for k, s in enumerate(CURVE):
        lo = CURVE[k - 1] if k > 0 else 0.0
        curve_rows.append((f"{lo:.3f}-{s:.3f}", *(fmt(window_mean(c, lo, s)) for c in curves)))
    res.text = (
        __doc__.split("\n\n")[1]
        + f"\n\nPrandtl's limit pressure {fmt(PRANDTL)} s_u.\n\n"
        + markdown_table(
            ["h (m)", "mesh", "particles", "steps", "q / s_u", "/ Prandtl", "wall (s)"], lines
        )
        + convergence(limits)
        + "\n\nThe load-settlement curve: q / s_u, the mean over each settlement interval.\n\n"
        + markdown_table(["s / B", *(f"B / {B / h:.0f}" for h in spacings)], curve_rows)
    )
    return res
