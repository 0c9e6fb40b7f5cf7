"""Standing-wave sloshing in the linear regime: period and amplitude decay.

examples/sloshing.toml: a tank L = 0.4 m long, water h = 0.2 m deep, released at rest with
the surface eta = A cos(pi x / L), A = 8 mm (A/h = 0.04, k A = 0.06). Linear theory:
omega^2 = g k tanh(k h), k = pi / L. The first mode moves the water's centre of mass
sideways: x_c - L/2 = -(2 L / (pi^2 h)) eta_wall(t), so x_c is a modal projection that
uses every particle and needs no surface tracking. Period: twice the mean spacing of the
zero crossings of x_c - L/2 (linear interpolation between outputs every 10 ms; a
least-squares line through the crossing times). Decay: a line through log |x_c - L/2| at
the extrema (a parabola through the three outputs around each), as the amplitude lost per
period, 1 - exp(-rate T). Energy: the change of kinetic plus potential energy of the
particles over the run, in units of the first mode's energy rho g A^2 L / 4 (an inviscid
wave keeps it at 0).
"""

import math
from pathlib import Path

import numpy as np

from ..simulation import Simulation
from .common import (
    CaseResult,
    Row,
    box,
    fmt,
    markdown_table,
    observed_order,
    parabola_extremum,
    pyplot,
    run_example,
    save,
)
from .types import Context, FloatArray
from .volume import Recorder

SPACINGS, SPACINGS_QUICK = (0.02, 0.01, 0.005), (0.01,)
END, END_QUICK = 5.0, 3.0  # s
G = 9.81

# tolerances, fixed before the results were looked at
TOL_PERIOD_FINEST = 0.02
WHY_PERIOD_FINEST = (
    "the issue's criterion; the nonlinear shift of the period at k A = 0.06 "
    "is below 0.1%, so 2% is all discretisation"
)
TOL_PERIOD = 0.03
WHY_PERIOD = (
    "coarser grids (10 and 20 cells across the depth): 3%, the resolution a "
    "practical sloshing run uses"
)
TOL_DECAY = 0.02
WHY_DECAY = (
    "water's own viscous decay is 2 nu k^2 T = 1e-4 per period, so all decay is "
    "numerical; 2% per period keeps (or doubles) the amplitude within a factor 2 over "
    "35 periods"
)


def theory(L: float, h: float) -> float:
    k = math.pi / L
    return 2 * math.pi / math.sqrt(G * k * math.tanh(k * h))


def period_and_decay(t: FloatArray, s: FloatArray) -> tuple[float, float, FloatArray, FloatArray]:
    """(period, amplitude decay per period, crossing times, extrema) of the signal s(t)."""
    sign = np.sign(s)
    idx = np.flatnonzero(sign[:-1] * sign[1:] < 0)
    cross = t[idx] - s[idx] * (t[idx + 1] - t[idx]) / (s[idx + 1] - s[idx])
    if cross.size < 3:
        return float("nan"), float("nan"), cross, np.empty((0, 2))
    half = np.polyfit(np.arange(cross.size), cross, 1)[0]
    period = 2 * half
    found: list[tuple[float, float]] = []
    for a, b in zip(np.r_[0, idx + 1], np.r_[idx + 1, t.size]):
        if b - a < 3:
            continue
        k = a + int(np.argmax(np.abs(s[a:b])))
        if 0 < k < t.size - 1 and a < k < b - 1:
            at, value = parabola_extremum(t, s, k)
            found.append((at, abs(value)))
        elif k == 0:
            found.append((t[0], abs(s[0])))
    ext = np.array(found).reshape(-1, 2)
    if ext.shape[0] < 2:
        return period, float("nan"), cross, ext
    rate = -np.polyfit(ext[:, 0], np.log(ext[:, 1]), 1)[0]
    return period, float(1 - math.exp(-rate * period)), cross, ext


def run(out: Path, quick: bool = False, context: Context | None = None) -> CaseResult:
    spacings = SPACINGS_QUICK if quick else SPACINGS
    end = END_QUICK if quick else END
    res = CaseResult("sloshing", "Standing-wave sloshing")
    runs = []
    for h in spacings:
        xc: list[tuple[float, float]] = []

        def centre(sim: Simulation, xc: list[tuple[float, float]] = xc) -> None:
            P = sim.particles
            xc.append((sim.time, float(np.sum(P.mass * P.x[:, 0]) / np.sum(P.mass))))

        finest = h == spacings[-1]
        recorder = Recorder(then=centre) if finest else None
        sim = run_example(
            "sloshing.toml", [f"grid.spacing={h}", f"time.end={end}"], on_output=recorder or centre
        )
        body = box(sim.case.bodies[0])
        L, depth, A = body.max[0] - body.min[0], body.max[1], body.surface_amplitude
        T0 = theory(L, depth)
        a = np.array(xc)
        t, s = a[:, 0], a[:, 1] - L / 2
        period, decay, cross, ext = period_and_decay(t, s)
        energy = sim.series("kinetic_energy") + sim.series("potential_energy")
        wave = 0.25 * sim.case.material.density * G * A**2 * L  # J/m, the mode's energy
        runs.append(
            {
                "h": h,
                "particles": sim.particles.count,
                "T": period,
                "err": abs(period - T0) / T0,
                "decay": decay,
                "t": t,
                "s": s,
                "ext": ext,
                "periods": (cross[-1] - cross[0]) / T0 * 1.0 if cross.size else 0,
                "wall": sim.summary["wall_seconds"],
                "T0": T0,
                "energy": (energy[-1] - energy[0]) / wave,
                "L": L,
                "depth": depth,
                "A": A,
            }
        )
        if recorder is not None and context is not None:
            context.setdefault("volume", {})["sloshing"] = (f"h = {h} m", recorder)
    name = "sloshing"
    for r in runs:
        finest = r is runs[-1]
        res.rows.append(
            Row(
                name,
                f"period, h = {r['h']} m",
                "|T - T_linear| / T_linear (zero crossings of the centre of mass)",
                r["err"],
                TOL_PERIOD_FINEST if finest else TOL_PERIOD,
                WHY_PERIOD_FINEST if finest else WHY_PERIOD,
                miss="too few cells across the wave to carry its pressure field: at 10 "
                "cells over the depth 1% PIC per millisecond damps the wave "
                "(2.3% per period) and slows it",
            )
        )
    r = runs[-1]
    res.rows.append(
        Row(
            name,
            f"amplitude change, h = {r['h']} m",
            f"amplitude lost per period (fit over {r['periods']:.1f} periods; < 0: the wave grows)",
            r["decay"],
            TOL_DECAY,
            WHY_DECAY,
            sense="|<=|",
            miss="loss: numerical damping (1% PIC per millisecond, solver.flip = "
            "0.99); growth: energy put in by the pressure at the free surface "
            "(docs/method.md, Energy)",
        )
    )
    T0 = runs[0]["T0"]
    if len(runs) >= 3:
        order = observed_order([r["h"] for r in runs], [r["err"] for r in runs])
        conv = f" Observed order of the period error over the three grids: {order:.2f}."
    else:
        conv = ""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(10, 4))
    scale = -(math.pi**2) * runs[0]["depth"] / (2 * runs[0]["L"])  # x_c - L/2 -> eta at x = 0
    for r in runs:
        ax.plot(r["t"], r["s"] * scale * 1e3, label=f"h = {r['h']} m")
    tt = np.linspace(0, runs[0]["t"][-1], 2000)
    ax.plot(
        tt,
        runs[0]["A"] * np.cos(2 * np.pi * tt / T0) * 1e3,
        "k:",
        lw=1,
        label=f"linear theory, T = {T0:.4f} s",
    )
    ax.set_xlabel("t [s]")
    ax.set_ylabel("first-mode elevation at x = 0 [mm]\n(from the centre of mass)")
    ax.legend(loc="lower left")
    fig.tight_layout()
    save(fig, out / "sloshing.png")
    res.figures.append(
        (
            "sloshing.png",
            "First-mode surface elevation at the left wall, from "
            "the centre of mass, against undamped linear theory.",
        )
    )
    table = markdown_table(
        [
            "grid spacing h (m)",
            "cells over the depth",
            "particles",
            "period T (s)",
            "T_linear (s)",
            "period error",
            "amplitude lost per period",
            "energy gained by the end / wave energy",
            "wall (s)",
        ],
        [
            [
                r["h"],
                round(r["depth"] / r["h"]),
                r["particles"],
                fmt(r["T"], 5),
                fmt(T0, 5),
                fmt(r["err"]),
                fmt(r["decay"]),
                fmt(r["energy"]),
                fmt(r["wall"]),
            ]
            for r in runs
        ],
    )
    res.text = (
        __doc__.split("\n", 2)[2].strip() + f" Run to {end:g} s with dt = 1 ms and "
        "the default solver settings, slip walls.\n\n" + table + "\n\n" + conv.strip()
    )
    return res
