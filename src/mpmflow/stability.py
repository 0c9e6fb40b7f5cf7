"""The explicit scheme's time-step limit: the sound speed sqrt(K / rho) crossing one cell;
the longest step the projection scheme's adaptive steps take for a solid, at which its
shear waves sqrt(G / rho) are followed (``longest_projection_step``); and the fall Courant
number, which says when a projection step is small for its grid (``fall_speed``).

A signal travels at the sound speed c plus the flow speed |v|; an explicit step must not let
it cross more than one cell: dt <= h / (c + |v|max) (the CFL condition of explicit MPM).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

from . import materials

if TYPE_CHECKING:  # the case's model imports this module
    from .case import Case


# A step is small for its grid when water falling the whole tank crosses fewer cells than
# this in one step (the fall Courant number C = sqrt(2 |g| H) dt / h): issue 39 measured the
# sub-cell surface's ghost extrapolation gaining energy at C = 0.026 to 0.092 (0.004 to
# 0.0114 m, dt = 1e-4 to 2.5e-4 s) and never at C = 0.18 and above.
SMALL_FALL_COURANT = 0.1


def fall_speed(gravity: Sequence[float], size: Sequence[float]) -> tuple[float, float]:
    """(sqrt(2 |g| H) in m/s, H in m): the speed of water falling the domain's extent H
    along gravity; (0, 0) without gravity."""
    g = [float(x) for x in gravity]
    gn = math.sqrt(sum(x * x for x in g))
    if gn == 0.0:
        return 0.0, 0.0
    height = sum(abs(x) / gn * float(L) for x, L in zip(g, size))
    return math.sqrt(2.0 * gn * height), height


def small_step_limit(gravity: Sequence[float], size: Sequence[float], spacing: float) -> float:
    """The step (s) below which a step is small for its grid (C < SMALL_FALL_COURANT); 0
    without gravity (no step is then known to be small)."""
    fall, _ = fall_speed(gravity, size)
    return SMALL_FALL_COURANT * spacing / fall if fall > 0.0 else 0.0


# solver.shallow_fraction = "auto": this fraction at steps small for the grid (issue 39)
SHALLOW_FRACTION = 0.3


def shallow_nodes(case: Case) -> tuple[float, float]:
    """The sub-cell surface's shallow nodes (docs/method.md, item 3) as (fraction, longest
    step in s they are used at): solver.shallow_fraction as given at every step, or for
    "auto" SHALLOW_FRACTION at the steps small for the grid (small_step_limit) and none at
    larger ones, where they would damp waves and the ghost extrapolation gains nothing."""
    x = case.solver.shallow_fraction
    if x != "auto":
        return float(x), math.inf
    return SHALLOW_FRACTION, small_step_limit(
        case.physics.gravity, case.domain.size, case.grid.spacing
    )


def sound_speed(bulk_modulus: float, density: float) -> float:
    """c = sqrt(K / rho) (m/s)."""
    return math.sqrt(bulk_modulus / density)


def stable_time_step(
    spacing: float, bulk_modulus: float, density: float, speed: float = 0.0
) -> float:
    """The largest stable explicit step h / (c + |v|) (s)."""
    return spacing / (sound_speed(bulk_modulus, density) + speed)


def initial_speed(case: Case) -> float:
    """The largest initial body speed (m/s)."""
    return max(math.hypot(*body.velocity) for body in case.bodies)


def case_stable_time_step(case: Case) -> float:
    """The stable explicit step of a case at its initial speeds (s)."""
    return stable_time_step(
        case.grid.spacing, case.material.bulk_modulus, case.material.density, initial_speed(case)
    )


def time_step(case: Case) -> float:
    """The time step a run uses (s): time.dt; for time.dt = "auto", the stable explicit step
    times time.safety_factor (explicit scheme), or the longest step time.max_dt (projection
    scheme, which then sets each step from the flow within it)."""
    if case.time.dt == "auto":
        if case.solver.scheme == "explicit":
            return case.time.safety_factor * case_stable_time_step(case)
        return longest_projection_step(case)
    return case.time.dt


def longest_projection_step(case: Case) -> float:
    """The longest step the projection scheme takes with time.dt = "auto" (s): time.max_dt,
    and for a solid at most its shear wave's step (``materials.shear_wave_step``, past which
    a fixed time.dt takes the coupled step)."""
    return min(case.time.max_dt, materials.shear_wave_step(case.material, case.grid.spacing))
