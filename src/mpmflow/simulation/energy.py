"""The energy check: a closed tank may lose energy but must not gain it (issue 39).

Nothing in a run without inlets or obstacles on prescribed paths puts energy into the water:
walls and fixed obstacles stand still, gravity is constant, outlets only let energy leave,
viscosity only dissipates, and a free body only trades energy with the water (and loses it
in its contacts). So the mechanical energy E = KE + PE of the particles and the free bodies
(``kinetic_energy`` + ``potential_energy`` + ``body_energy``, the time series' columns) can
only fall; a rise is the step's doing. At the end of a run (``record``, in summary.json's
``energy``) the largest rise over the output times,

    (E(t) - E(0)) / E_floor(0),

is compared with ``THRESHOLD``. E_floor(0) is the initial energy measured from the domain's
floor: KE + sum m |g| (height above the lowest point of the domain along gravity), the
energy the water and the free bodies could give up falling to the bottom of the tank at
rest. It is positive for any water above the floor or moving, does not depend on where the
coordinates' origin lies, and is the measure of the validation report's long runs
(docs/validation). With no
gravity and no motion it would be 0: the scale is then the kinetic energy of the whole
mass at ``FLOOR_SPEED``.

``THRESHOLD`` = 0.5%: issue 39's criterion for a good run. Correct runs stay far below it:
the validation's long runs rise by at most 0.023% over 20 s of sloshing (0.005 m), 20 times
less, and the dam break never above its start; the defects the issue measured rise by
7.5% to 15 times the start. A rise above it is told at the end of the run (a notice, with
the settings that likely caused it: ``advice``) and in summary.json.

``sources`` names what may legitimately raise KE + PE in a case; the check is off when
there is any: an inlet is one, an obstacle on a prescribed path (obstacles.N.motion, but
a free one) another.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from .. import materials
from ..boundaries import moving, outlets
from ..stability import SHALLOW_FRACTION, SMALL_FALL_COURANT, fall_speed, shallow_nodes

if TYPE_CHECKING:
    from ..case import Case
    from ..grid import Grid
    from .loop import Simulation

THRESHOLD = 0.005  # largest (E - E0) / E_floor(0) of a run without a notice
FLOOR_SPEED = 1e-3  # m/s: the scale of a case with no gravity and no motion
AXES = "xyz"


def sources(case: Case, grid: Grid) -> list[str]:
    """Why KE + PE may rise in this case without a fault of the step (empty: it may not)."""
    why = []
    if case.solver.scheme == "explicit":
        why.append(
            "the explicit scheme stores energy in the water's compression (p^2 / 2K), which "
            "KE + PE leaves out and the pressure waves give back"
        )
    g = case.physics.gravity
    for k, periodic in enumerate(grid.periodic):
        if periodic and g[k] != 0.0:
            why.append(
                f"gravity along the periodic {AXES[k]} axis drives the flow down an endless "
                "slope (and the potential energy jumps where a particle wraps round)"
            )
    if case.inlets:
        why.append("the inlets ([[inlets]]) bring water, and its energy, into the domain")
    moved = [
        o.name or f"obstacles.{k}"
        for k, o in enumerate(case.obstacles)
        if o.motion and o.motion.type != "free"
    ]
    if moved:
        why.append(
            f"the obstacles on prescribed paths ({', '.join(moved)}: obstacles.N.motion) do "
            "work on the water"
        )
    return why


def initial_energy(ke: float, pe: float, mass: float, gravity: Any, size: Any) -> float:
    """KE + PE at the start with PE measured from the domain's floor: ``pe`` is
    -sum m g . x (from the origin), and the floor is the corner of [0, size] lowest along
    gravity (size along an axis where g points to +, 0 where it points to -)."""
    g = np.asarray(gravity, dtype=float)
    corner = np.where(g > 0.0, np.asarray(size, dtype=float), 0.0)
    return float(ke + pe + mass * float(g @ corner))


def rise(time: Any, energy: Any, scale: float) -> tuple[float, float]:
    """The largest (E - E[0]) / scale over the series and when (s): (0, time[0]) when E
    never rises above its start."""
    e = np.asarray(energy, dtype=float)
    k = int(np.argmax(e - e[0]))
    return float((e[k] - e[0]) / scale), float(np.asarray(time)[k])


def record(sim: Simulation) -> dict[str, Any]:
    """summary.json's ``energy``: the largest rise of KE + PE above its start over the
    output times so far, relative to the initial energy from the floor, against the
    threshold; ``not_checked`` says why a case is not checked (None when it is)."""
    why = sources(sim.case, sim.grid)
    out: dict[str, Any] = {
        "initial_energy": None,
        "largest_rise": None,
        "at_time": None,
        "threshold": THRESHOLD,
        "exceeded": None,
        "not_checked": "; ".join(why) or None,
    }
    t = sim.series("time")
    if why or t.size == 0:
        if t.size == 0 and not why:
            out["not_checked"] = "no output was written"
        return out
    ke, pe = sim.series("kinetic_energy"), sim.series("potential_energy")
    body = sim.series("body_energy")  # the free bodies' KE + PE (0: none)
    mass = sim.mass0 + moving.free_mass(getattr(sim.scheme, "movers", []))
    e0 = initial_energy(ke[0], pe[0] + body[0], mass, sim.case.physics.gravity, sim.grid.size)
    scale = max(e0, 0.5 * mass * FLOOR_SPEED**2)
    largest, when = rise(t, ke + pe + body, scale)
    out.update(initial_energy=e0, largest_rise=largest, at_time=when, exceeded=largest > THRESHOLD)
    return out


def notices(sim: Simulation) -> list[str]:
    """The end-of-run notice of an energy rise above the threshold (none otherwise). Never
    raises: it runs as the run ends, also after a failure."""
    try:
        r = record(sim)
    except Exception:  # a failure before the first output: nothing to tell
        return []
    if not r["exceeded"]:
        return []
    return [
        f"KE + PE rose {100 * r['largest_rise']:.3g}% above its start (largest at t = "
        f"{r['at_time']:.6g} s; the threshold is {100 * THRESHOLD:g}% of the initial energy "
        f"measured from the floor, {r['initial_energy']:.4g} {_unit(sim)}): nothing in "
        f"this case puts energy into the water, so the step did. {advice(sim)} (docs/method.md, "
        '"Energy"; summary.json\'s energy)'
    ]


def _unit(sim: Simulation) -> str:
    return "J/m" if sim.grid.dim == 2 else "J"


def so_far(sim: Simulation) -> str:
    """' KE + PE had risen X% above its start by t = ... s.' when it rose above the
    threshold by the last output, else ''."""
    try:
        r = record(sim)
    except Exception:
        return ""
    if not r["exceeded"]:
        return ""
    return (
        f" KE + PE had risen {100 * r['largest_rise']:.3g}% above its start by t = "
        f"{r['at_time']:.6g} s (timeseries.csv)."
    )


def fixes(case: Case) -> str:
    """The settings, not taken already, that keep the projection step's energy gain down,
    as "A, B or C" ('' when none is left). Measured: issue 39, one setting at a time at
    0.008 m, dt = 1e-4 s, the largest (KE + PE) / start 2.9-3.8 with every node with
    f > 1/2 an unknown (solver.shallow_fraction = 0; chaotic), 1.0006 with the shallow nodes
    (0.3; at most 1.0037 at every step from 2 to 0.05 ms) and 1.0000 with the node surface,
    since the walls' contact is a complementarity problem (docs/method.md; before it: 15.1
    and 1.04); a column draining through an outlet in its floor (examples/hydrostatic.toml,
    y_min an outlet) gains 1% with the volume correction and nothing without: it holds the
    falling water back (half the free fall's displacement in the first 10 ms) while the
    velocities fall freely."""
    s = case.solver
    out = []
    fraction, longest = shallow_nodes(case)
    every_step = fraction >= SHALLOW_FRACTION and (
        longest == math.inf or (case.time.dt != "auto" and case.time.dt < longest)
    )
    if s.free_surface != "node" and not every_step:
        out.append(
            f"solver.shallow_fraction = {SHALLOW_FRACTION:g} (the nodes nearest the surface "
            "interpolated at every step, which bounds the ghost extrapolation; the default "
            "takes them at steps small for the grid only)"
        )
    if outlets.sides(case).any() and (s.volume_correction or 0.0) > 0.0:
        out.append(
            "solver.volume_correction = 0 (it holds back water that falls through an outlet)"
        )
    if s.free_surface != "node":
        out.append(
            'solver.free_surface = "node" (the sub-cell surface is where the step gains '
            "energy; the node surface gains none at any step, but places the surface up to "
            "half a cell off)"
        )
    if (s.flip or 0.0) > 0.9:
        out.append("a lower solver.flip (e.g. 0.9)")
    return ", ".join(out[:-1]) + (" or " if len(out) > 1 else "") + (out[-1] if out else "")


def advice(sim: Simulation) -> str:
    """The settings that likely put energy into the step (issue 39's measurements), as one
    or two sentences. For a fixed step, the fall Courant number C = sqrt(2 |g| H) dt / h (H:
    the domain's extent along gravity) is how many cells water falling the whole tank
    crosses in one step: the issue measured gains of 7.5% to 15 times the start at C = 0.026
    to 0.092 (0.004 to 0.0114 m, dt = 1e-4 to 2.5e-4 s) and none at C = 0.18 and above."""
    case = sim.case
    if materials.is_solid(case.material):
        return (
            "A solid's step is measured stable at any time.dt (the split step up to "
            f"{materials.SHEAR_COURANT:g} grid.spacing / sqrt(material.shear_modulus / "
            "material.density), the coupled step past it): a blow-up is not a known limit "
            'of the method (docs/method.md, "Solids"): please report the case.'
        )
    if case.solver.scheme == "explicit":
        return (
            'Try a smaller time.dt (or time.dt = "auto"): the explicit step must stay below '
            "the sound-speed limit."
        )
    fix = fixes(case)
    also = f", or {fix}" if fix else ""
    if case.time.dt == "auto":
        c = case.time.courant
        if c < SMALL_FALL_COURANT:
            return (
                f"time.courant = {c:g} takes many short steps, and the step gains a little "
                f"energy at the free surface each time: try a larger time.courant{also}."
            )
        return f"Try {fix}." if fix else "Try another time.courant."
    fall, height = fall_speed(case.physics.gravity, [float(L) for L in sim.grid.size])
    if fall == 0.0:
        return f"Try another time.dt{also}."
    h = sim.grid.spacing
    courant = fall * sim.dt / h
    where = (
        f"water falling the tank's {height:.3g} m ({fall:.3g} m/s) crosses {courant:.2g} "
        f"cells of {h:g} m in a step of time.dt = {sim.dt:g} s"
    )
    if courant < SMALL_FALL_COURANT:
        return (
            f"The step is likely too small for this grid: {where}, and the step gains a "
            "little energy at the free surface each time, so more steps gain more (issue "
            f"39). Try a larger time.dt ({2 * SMALL_FALL_COURANT * h / fall:.2g} s or more) or "
            f'time.dt = "auto"{also}.'
        )
    if courant > 1.0:
        return (
            f"The step is likely too large for this grid: {where}. Try a smaller time.dt "
            f'({h / fall:.2g} s or less) or time.dt = "auto"{also}.'
        )
    return f"With {where}, try {fix or 'another time.dt'}."
