"""Slamming: a wedge entering still water at constant speed, against the similarity solution
of Zhao & Faltinsen (1993).

examples/wedge_entry.toml: a wedge of deadrise angle beta = 20 degrees pushed down at V = 2
m/s into water 0.3 m deep from its apex on the surface, without gravity; half the wedge and
half the tank, the left wall (slip) the plane of symmetry.

Reference: Zhao & Faltinsen (1993, J. Fluid Mech. 246, 593), the similarity solution of the
gravity-free entry of a wedge at constant speed (potential flow, the jet's dynamics kept):
at beta = 20 degrees the pressure coefficient Cp = p / (rho V^2 / 2) peaks at 17.77, at a
height z_max = 0.5087 V t above the undisturbed surface (their Table 1, as tabulated by
Faltinsen 2005, Table 8.3, and Iafrati 2012, Table 1).

Measure: the pressure the water's own nodes carry beside the face (nodes with mass within
one cell of the face, on its water side, below 0.9 of its length), each placed at its foot
on the face, at every step of the second half of the run (V t = 0.012-0.024 m); the
heights in z / (V t) with t and the face of the step's pressure solve (the body is moved at
the step's end, so the solve at the step ending at t saw it at t - dt), binned by 0.025, the
mean Cp of each bin, the peak the parabola through the largest bin and its neighbours. The
nodes inside the wedge are left out: a node behind the face whose cells hold only a sliver
of the jet has a row of the pressure system as small as 0.003 of a full one, and its pressure
is the extension of the water's, whose noise an interpolation at the face would read.
Beside it the table gives that interpolation (the nodal pressure interpolated 0.75 h into
the water along the face's normal). Three meshes, each with V dt = h / 10.
"""

import math
from pathlib import Path

import numpy as np

from ..case import load_case
from ..simulation import Simulation
from .common import (
    EXAMPLES,
    CaseResult,
    Row,
    fmt,
    markdown_table,
    parabola_extremum,
    pyplot,
    run_example,
    save,
)
from .types import Context

# the quick report's (the test suite's) is the middle mesh: at 4 mm (V t up to 6 h) the
# peak's height moved from 0.486 to 0.606 V t when the slivers' couplings at the surface
# were folded (6d500d5), where 2 and 1 mm moved by 0.1-0.2%
SPACINGS, SPACINGS_QUICK = (0.004, 0.002, 0.001), (0.002,)  # m
CELLS_PER_STEP = 0.1  # V dt / h
ZF_CP, ZF_Z = 17.77, 0.5087  # Zhao & Faltinsen (1993), beta = 20 degrees
BINS = np.arange(-0.25, 1.0 + 1e-9, 0.025)  # z / (V t)

# tolerances, fixed before the report's run
TOL_CP = 0.10
TOL_Z = 0.10
WHY_CP = (
    "the issue's criterion: the peak pressure coefficient within 10% of the similarity "
    "solution at the finest mesh"
)
WHY_Z = "the issue's criterion: the peak's position on the wedge within 10% at the finest mesh"


class FaceReader:
    """Reads the pressure beside the wedge's lower face at every output of a run."""

    def __init__(self, spacing: float):
        self.h = spacing
        self.samples: list[tuple[float, np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = []
        self.nodes = np.zeros((0, 2))

    def _start(self, sim: Simulation) -> None:
        obstacle = sim.case.obstacles[0]
        (x0, y0), (x1, y1) = obstacle.vertices[0], obstacle.vertices[1]  # type: ignore[union-attr]
        self.apex0, self.length = float(y0), float(x1 - x0)
        self.beta = math.atan2(y1 - y0, x1 - x0)
        self.V = -float(obstacle.motion.velocity[1])  # type: ignore[union-attr, index]
        self.dt = float(sim.case.time.dt)
        self.q = 0.5 * float(sim.case.material.density) * self.V**2
        self.nodes = sim.grid.node_coordinates()

    def __call__(self, sim: Simulation) -> None:
        if not self.nodes.size:
            self._start(sim)
        t = sim.time - self.dt  # the face the step's pressure solve saw
        if t <= 0:
            return
        p = np.asarray(sim.scheme.p_node)  # type: ignore[attr-defined]
        mass = np.asarray(sim.scheme.core.node_mass)  # type: ignore[attr-defined]
        apex = self.apex0 - self.V * t
        tb, cb = math.tan(self.beta), math.cos(self.beta)
        x, y = self.nodes[:, 0], self.nodes[:, 1]
        d = (apex + x * tb - y) * cb  # distance below the face's line
        on = (mass > 0) & (d > 0) & (d <= self.h) & (x < 0.9 * self.length)
        z_nodes = (y[on] + d[on] * cb - self.apex0) / (self.V * t)
        # the interpolation 0.75 h into the water along the normal
        xs = np.linspace(0.0, 0.9 * self.length, 400)
        pts = np.c_[xs, apex + xs * tb] + 0.75 * self.h * np.array([math.sin(self.beta), -cb])
        inner = sim.grid.interpolate(p, pts)
        z_face = (xs * tb + apex - self.apex0) / (self.V * t)
        self.samples.append((t, z_nodes, p[on] / self.q, z_face, inner / self.q))

    def peak(self, start: float, nodes: bool = True) -> tuple[float, float, np.ndarray]:
        """The time-mean profile over the samples from ``start`` (s): its peak (z / (V t),
        Cp) and the profile itself (the bins' mean Cp, nan where empty)."""
        total = np.zeros(BINS.size - 1)
        count = np.zeros(BINS.size - 1)
        for t, zn, cn, zf, cf in self.samples:
            if t < start:
                continue
            heights, cps = (zn, cn) if nodes else (zf, cf)
            bins = np.digitize(heights, BINS) - 1
            ok = (bins >= 0) & (bins < total.size)
            np.add.at(total, bins[ok], cps[ok])
            np.add.at(count, bins[ok], 1)
        mean = np.where(count > 0, total / np.maximum(count, 1), np.nan)
        k = int(np.nanargmax(mean))
        centres = 0.5 * (BINS[1:] + BINS[:-1])
        if 0 < k < mean.size - 1 and np.all(np.isfinite(mean[k - 1 : k + 2])):
            z, cp = parabola_extremum(centres, mean, k)
            return z, cp, mean
        return float(centres[k]), float(mean[k]), mean

    def spread(self, start: float) -> tuple[float, float]:
        """The least and largest single-step peak Cp of the nodes from ``start`` (s)."""
        peaks = [float(cn.max()) for t, _, cn, _, _ in self.samples if t >= start and cn.size]
        return min(peaks), max(peaks)


def run_wedge_entry(out: Path, quick: bool = False, context: Context | None = None) -> CaseResult:
    res = CaseResult("wedge_entry", "Slamming: a wedge entering still water (Zhao & Faltinsen)")
    runs = []
    wedge = load_case(EXAMPLES / "wedge_entry.toml").obstacles[0]
    speed = float(np.linalg.norm(wedge.motion.velocity))  # type: ignore[union-attr, arg-type]
    for h in SPACINGS_QUICK if quick else SPACINGS:
        reader = FaceReader(h)
        dt = CELLS_PER_STEP * h / speed  # V dt = h / 10: the example's dt at its 0.002 m
        sim = run_example(
            "wedge_entry.toml",
            [f"grid.spacing={h}", f"time.dt={dt}", f"output.interval={dt}"],
            on_output=reader,
        )
        start = 0.5 * float(sim.case.time.end)
        z, cp, profile = reader.peak(start)
        zi, cpi, _ = reader.peak(start, nodes=False)
        low, high = reader.spread(start)
        runs.append(
            {
                "h": h,
                "dt": dt,
                "z": z,
                "cp": cp,
                "zi": zi,
                "cpi": cpi,
                "low": low,
                "high": high,
                "profile": profile,
                "particles": sim.particles.count,
                "steps": sim.steps,
                "wall": sim.summary["wall_seconds"],
            }
        )
    fine = runs[-1]
    label = f"h = {fmt(fine['h'])} m"
    res.rows.append(
        Row(
            "wedge_entry",
            f"peak pressure coefficient, {label}",
            "(Cp_max - 17.77) / 17.77, time-mean profile of the water's nodes at the face, "
            "V t = 0.012-0.024 m",
            (fine["cp"] - ZF_CP) / ZF_CP,
            TOL_CP,
            WHY_CP,
            sense="|<=|",
            miss="the spray root is a few cells thick at this mesh: its peak is smeared "
            "over them (see the text)",
        )
    )
    res.rows.append(
        Row(
            "wedge_entry",
            f"peak's height on the wedge, {label}",
            "(z_max / (V t) - 0.5087) / 0.5087, the same profile",
            (fine["z"] - ZF_Z) / ZF_Z,
            TOL_Z,
            WHY_Z,
            sense="|<=|",
            miss="the peak sits within a cell or two of the spray root, which the mesh "
            "places to a cell (see the text)",
        )
    )
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7, 4))
    centres = 0.5 * (BINS[1:] + BINS[:-1])
    for r in runs:
        ax.plot(centres, r["profile"], lw=1.0, label=f"h = {fmt(r['h'])} m")
    ax.plot([ZF_Z], [ZF_CP], "k*", ms=10, label="Zhao & Faltinsen (1993): the peak")
    ax.set_xlabel("z / (V t)")
    ax.set_ylabel("Cp = p / (rho V^2 / 2)")
    ax.set_xlim(-0.25, 1.0)
    ax.legend(loc="upper left")
    fig.tight_layout()
    save(fig, out / "wedge_entry.png")
    res.figures.append(
        (
            "wedge_entry.png",
            "The pressure on the wedge's face (the water's nodes beside it), the mean over "
            "V t = 0.012-0.024 m in similarity coordinates; the star: the similarity "
            "solution's peak.",
        )
    )
    table = markdown_table(
        [
            "h (m)",
            "dt (s)",
            "particles",
            "steps",
            "Cp_max (nodes)",
            "z_max / (V t)",
            "single steps' Cp_max",
            "Cp_max (0.75 h in)",
            "z_max / (V t) (0.75 h in)",
            "wall (s)",
        ],
        [
            [
                fmt(r["h"]),
                fmt(r["dt"]),
                str(r["particles"]),
                str(r["steps"]),
                f"{r['cp']:.2f}",
                f"{r['z']:.3f}",
                f"{r['low']:.1f}-{r['high']:.1f}",
                f"{r['cpi']:.2f}",
                f"{r['zi']:.3f}",
                f"{r['wall']:.0f}",
            ]
            for r in runs
        ]
        + [["Zhao & Faltinsen", "", "", "", f"{ZF_CP}", f"{ZF_Z}", "", "", "", ""]],
    )
    res.text = "\n\n".join([*__doc__.split("\n\n")[1:4], table])
    return res
