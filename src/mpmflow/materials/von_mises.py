"""Undrained clay (``material.model = "von_mises"``): the elastic solid (``elastic``) whose
deviatoric stress is returned to sqrt(J2) <= s_u + strength_gradient x (depth below
strength_datum), with zero plastic volume change. In plane strain this is Tresca's criterion
with the undrained shear strength s_u ((sigma_1 - sigma_3) / 2 <= s_u), so Prandtl's
(2 + pi) s_u holds; in 3D the von Mises cylinder through Tresca's in pure shear
(src/core/plasticity.hpp; docs/method.md, "Solids")."""

from __future__ import annotations

from typing import TYPE_CHECKING

from .elastic import check_shear_modulus

if TYPE_CHECKING:
    from ..case.sections import Material

NAME = "von_mises"
KEYS: tuple[str, ...] = (
    "shear_modulus",
    "undrained_strength",
    "strength_gradient",
    "strength_datum",
)
MODEL = 5  # src/core/plasticity.hpp's VON_MISES


def check(m: Material) -> None:
    check_shear_modulus(m)
    if not m.undrained_strength >= 0.0:
        raise ValueError(
            f"material.undrained_strength = {m.undrained_strength:g} Pa must be >= 0 (the "
            "undrained shear strength s_u of the clay at strength_datum), e.g. "
            "material.undrained_strength = 20e3"
        )
    if not m.strength_gradient >= 0.0:
        raise ValueError(
            f"material.strength_gradient = {m.strength_gradient:g} Pa/m must be >= 0 (how "
            "fast s_u grows with depth below material.strength_datum)"
        )


def parameters(m: Material) -> list[float]:
    return [m.shear_modulus, m.undrained_strength, m.strength_gradient, m.strength_datum]
