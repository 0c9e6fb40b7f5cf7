"""The explicit scheme's time-step limit: the sound speed sqrt(K / rho) crossing one cell;
and the longest step the projection scheme's adaptive steps take for a solid, at which its
shear waves sqrt(G / rho) are followed (``longest_projection_step``).

A signal travels at the sound speed c plus the flow speed |v|; an explicit step must not let
it cross more than one cell: dt <= h / (c + |v|max) (the CFL condition of explicit MPM).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from . import materials

if TYPE_CHECKING:  # the case's model imports this module
    from .case import Case


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
