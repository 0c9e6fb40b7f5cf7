"""A frictional soil (``material.model = "drucker_prager"``): the elastic solid
(``elastic``) whose deviatoric stress is returned to sqrt(J2) <= p sin(phi) + c cos(phi),
p the projection's pressure, with zero dilatancy (the plastic flow keeps the volume, as the
projection does). In plane strain at zero dilatancy the out-of-plane stress is the mean of
the in-plane ones, so this cone is Mohr-Coulomb's criterion exactly ((sigma_1 - sigma_3)/2 <=
p sin(phi) + c cos(phi)); in 3D it is the cone matched to Mohr-Coulomb in plane strain. Where
the pressure falls below -tension_cutoff the material has parted and carries no deviatoric
stress (src/core/plasticity.hpp; docs/method.md, "Solids")."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from .elastic import check_shear_modulus

if TYPE_CHECKING:
    from ..case.sections import Material

NAME = "drucker_prager"
KEYS: tuple[str, ...] = ("shear_modulus", "friction_angle", "cohesion", "tension_cutoff")
MODEL = 6  # src/core/plasticity.hpp's DRUCKER_PRAGER


def check(m: Material) -> None:
    check_shear_modulus(m)
    if not 0.0 <= m.friction_angle < 90.0:
        raise ValueError(
            f"material.friction_angle = {m.friction_angle:g} degrees must be from 0 to "
            "below 90 (dry sand: about 30; the aluminium bars of Bui et al. 2008: 19.8)"
        )
    if not m.cohesion >= 0.0:
        raise ValueError(f"material.cohesion = {m.cohesion:g} Pa must be >= 0")
    if not m.tension_cutoff >= 0.0:
        raise ValueError(
            f"material.tension_cutoff = {m.tension_cutoff:g} Pa must be >= 0 (the tension "
            "the soil bears before it parts; 0 for a cohesionless soil)"
        )
    if m.friction_angle == 0.0 and m.cohesion == 0.0:
        raise ValueError(
            'material.model = "drucker_prager" with friction_angle = 0 and cohesion = 0 has '
            "no strength at all: give a friction angle (degrees) or a cohesion (Pa)"
        )


def parameters(m: Material) -> list[float]:
    phi = math.radians(m.friction_angle)
    return [m.shear_modulus, math.sin(phi), m.cohesion * math.cos(phi), m.tension_cutoff]
