"""Solids (issue 43): rigid footings pushed into weightless undrained clay (Prandtl's strip,
and a square one in 3D).

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
work the footing does over it per unit settlement). The footing's edge lies midway between
two planes of nodes at every mesh (B / 2 = 7.5, 15.5 and 31.5 cells at h = B / 15, B / 31
and B / 63): a tool holds the nodes on and in it, and the clay feels it to half a cell past
its last held node, so that the footing modelled is B wide. With its edge on a plane of
nodes (B / 16, 32, 64) it was B + h wide: 1.082, 1.030 and 1.023 of Prandtl's load.

In 3D (examples/footing_3d.toml) a square footing B x B, its quarter beside the planes x =
0 and y = 0, on the same clay 3 B from the centre each way and 2 B deep (a box 4 B wide
and 3 B deep bore the same load to 0.1%), 27 particles a cell, its edges midway between
planes of nodes (h = B / 9, B / 11, B / 13); q = F / (B^2 / 4). No exact solution exists
for a square footing; Gourvenec, Randolph & Kingsnorth (2006, Int. J. Geomech. 6(3) 147,
finite elements calibrated against the exact strip and circle) find a rough square
footing's capacity on Tresca clay about 5% below Skempton's shape factor of 1.2 on
Prandtl's, N_c = 0.95 x 1.2 x (2 + pi) = 5.86 (the rough circle's exact value is 6.05,
Cox et al. 1961). The clay here is von Mises, sqrt(J2) <= s_u: Tresca's in plane strain,
weaker off it (in triaxial compression (sigma_1 - sigma_3) / 2 <= 0.87 s_u), so its
capacity lies at or below Tresca's: a load above N_c s_u is an error of the mesh (or of
the reference's "about 5%").
"""

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.optimize import brentq

from ..case import load_case
from ..simulation import Simulation
from .common import EXAMPLES, CaseResult, Row, fmt, markdown_table
from .types import Context

B, S_U, G_MOD, RHO, SPEED = 1.0, 1.0e4, 5.0e6, 1000.0, 0.1
PRANDTL = 2.0 + math.pi
NC_SQUARE = 0.95 * 1.2 * PRANDTL  # Gourvenec, Randolph & Kingsnorth (2006): 5.86
WINDOW = (0.02, 0.03)  # settlement / B over which the limit pressure is the mean
CURVE = tuple(round(0.005 * k, 3) for k in range(1, 7))  # settlements / B of the table

# tolerance, fixed before the run (the issue's)
TOL = 0.03
WHY = (
    "the issue's 3% of Prandtl's (2 + pi) s_u at the finest mesh; the plateau's mean over "
    "0.02-0.03 B, past the rise (over by 0.015 B at G = 500 s_u) and before the heave"
)
WHY_3D = (
    "the issue's 3D footing within the same 3% at a coarser mesh, of a rough square "
    "footing's N_c = 5.86 (Gourvenec et al. 2006); the same window"
)


@dataclass(frozen=True)
class Footing:
    """One footing of the report: its example, dimension and reference capacity."""

    example: str
    dim: int
    reference: float  # the limit pressure / s_u it is measured against
    area: float  # the modelled part of the footing's face (m^(D-1)): half or a quarter
    spacings: tuple[float, ...]  # each puts the footing's edge midway between two nodes
    label: str  # the reference's name in the table's header
    named: str  # and in a sentence
    formula: str  # and in the row's error measure (times s_u)
    which: str  # the row's quantity after "limit pressure"
    why: str  # the row's tolerance, why
    about: int  # the docstring's paragraph on it, before its tables (0: none)


STRIP = Footing(
    example="footing.toml",
    dim=2,
    reference=PRANDTL,
    area=0.5 * B,
    spacings=(B / 15, B / 31, B / 63),
    label="Prandtl",
    named="Prandtl's load",
    formula="(2 + pi)",
    which="",
    why=WHY,
    about=0,  # the strip's paragraph opens the section
)
SQUARE = Footing(
    example="footing_3d.toml",
    dim=3,
    reference=NC_SQUARE,
    area=0.25 * B * B,
    spacings=(B / 9, B / 11, B / 13),
    label="N_c",
    named="Gourvenec et al.'s N_c s_u",
    formula="N_c",
    which=", square footing (3D)",
    why=WHY_3D,
    about=2,
)


def load_curve(
    h: float, end: float = WINDOW[1] * B / SPEED, footing: Footing = STRIP
) -> tuple[Simulation, np.ndarray]:
    """Run the footing at spacing h to time ``end`` (s; 0.1 m of settlement a second; the
    window's end by default); returns the run and its curve, rows (settlement / B,
    q / s_u) at every step."""
    # one output a step: the auto step, 0.5 h / c_s, a hair shorter (a longer one would be
    # past the shear wave's, where plastic flow is refused)
    dt = 0.5 * h / math.sqrt(G_MOD / RHO) * (1 - 1e-6)
    sets = [
        "output.snapshots=false",
        f"grid.spacing={h!r}",
        f"time.end={end}",
        f"output.interval={dt!r}",
        # the cell pressure's multigrid takes 65 iterations a solve at B / 32 and more at
        # B / 64, where the footing's first step needs more than the default 200
        "solver.max_iterations=2000",
    ]
    sim = Simulation(load_case(EXAMPLES / footing.example, sets))
    rows: list[tuple[float, float]] = []
    axis = footing.dim - 1

    def record(s: Simulation) -> None:
        force = float(s.scheme.core.body_force[0, axis])  # type: ignore[attr-defined]
        rows.append((SPEED * s.time / B, force / footing.area / S_U))

    sim.on_output = record
    sim.run()
    return sim, np.array(rows)


def window_mean(curve: np.ndarray, lo: float, hi: float) -> float:
    k = (curve[:, 0] > lo) & (curve[:, 0] <= hi)
    return float(np.mean(curve[k, 1]))


def convergence(limits: list[float], spacings: tuple[float, ...], footing: Footing) -> str:
    """The observed order of the limit pressure's error over three meshes (measured against
    the reference, and from the three alone), as a sentence."""
    if len(limits) < 3:
        return ""
    e = [q / footing.reference - 1 for q in limits]
    orders = [
        math.log(a / b) / math.log(ha / hb) if a > 0 and b > 0 else float("nan")
        for a, b, ha, hb in zip(e, e[1:], spacings, spacings[1:])
    ]
    # from the limits alone: q(h) = q0 + c h^p through the three
    h0, h1, h2 = spacings
    d = (limits[0] - limits[1]) / (limits[1] - limits[2])

    def gap(p: float) -> float:
        return float((h0**p - h1**p) / (h1**p - h2**p) - d)

    solvable = d > 0 and gap(0.05) * gap(8.0) < 0
    alone = (
        fmt(brentq(gap, 0.05, 8.0))
        if solvable
        else "none (their differences do not fall as a power of h)"
    )
    return (
        f"\n\nThe error against {footing.named} at the three meshes: "
        f"{', '.join(fmt(x) for x in e)}; its observed order from mesh to mesh "
        f"{' and '.join(fmt(p) for p in orders)}, and from the three limits alone (no "
        f"reference, q = q_0 + c h^p) {alone}."
    )


Line = tuple[str, str, int, int, str, str, str]


def _series(
    out: Path, footing: Footing, spacings: tuple[float, ...]
) -> tuple[list[Line], list[np.ndarray], list[float]]:
    """Each mesh's run: the table's lines, the curves and the limit pressures."""
    lines: list[Line] = []
    curves: list[np.ndarray] = []
    limits: list[float] = []
    tag = "" if footing.dim == 2 else "_3d"
    for h in spacings:
        sim, curve = load_curve(h, footing=footing)
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
                fmt(limit / footing.reference),
                fmt(sim.summary["wall_seconds"]),
            )
        )
        np.savetxt(
            out / f"footing{tag}_h{B / h:.0f}.csv",
            curve,
            delimiter=",",
            header="settlement / B, q / s_u",
            comments="",
        )
    return lines, curves, limits


def _section(
    footing: Footing,
    spacings: tuple[float, ...],
    lines: list[Line],
    curves: list[np.ndarray],
    limits: list[float],
) -> str:
    curve_rows = []
    for k, s in enumerate(CURVE):
        lo = CURVE[k - 1] if k > 0 else 0.0
        curve_rows.append((f"{lo:.3f}-{s:.3f}", *(fmt(window_mean(c, lo, s)) for c in curves)))
    return (
        markdown_table(
            ["h (m)", "mesh", "particles", "steps", "q / s_u", f"/ {footing.label}", "wall (s)"],
            lines,
        )
        + convergence(limits, spacings, footing)
        + "\n\nThe load-settlement curve: q / s_u, the mean over each settlement interval.\n\n"
        + markdown_table(["s / B", *(f"B / {B / h:.0f}" for h in spacings)], curve_rows)
    )


def run_footing(out: Path, quick: bool = False, context: Context | None = None) -> CaseResult:
    res = CaseResult("prandtl_footing", "Rigid footings on weightless Tresca clay (Prandtl)")
    text = [__doc__.split("\n\n")[1], f"Prandtl's limit pressure {fmt(PRANDTL)} s_u."]
    # the quick report (the test suite's) runs the strip's coarsest mesh only: the square's
    # takes 42 s at its coarsest
    for footing in (STRIP,) if quick else (STRIP, SQUARE):
        spacings = footing.spacings[:1] if quick else footing.spacings
        lines, curves, limits = _series(out, footing, spacings)
        res.rows.append(
            Row(
                "prandtl_footing",
                f"limit pressure{footing.which}, h = B / {B / spacings[-1]:.0f}",
                f"|mean q over s = 0.02-0.03 B / ({footing.formula} s_u) - 1|",
                abs(limits[-1] / footing.reference - 1),
                TOL,
                footing.why,
                miss=(
                    "the error falls with h (its order in the text): the mesh is coarse "
                    'for the footing\'s edge, where the clay is held: docs/method.md, "Solids"'
                ),
            )
        )
        if footing.about:
            text.append(__doc__.split("\n\n")[footing.about])
        text.append(_section(footing, spacings, lines, curves, limits))
    res.text = "\n\n".join(text)
    return res
