"""An incompressible linear elastic solid (``material.model = "elastic"``): the deviatoric
stress s = 2 G (deviatoric strain), carried by the particles and turned with their spin
(the Jaumann rate), the pressure from the projection; so Poisson's ratio is 0.5 exactly and
no bulk modulus enters the step (src/core/plasticity.hpp; docs/method.md, "Solids")."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the case's schema lists the materials (case.sections imports this package)
    from ..case.sections import Material

NAME = "elastic"
KEYS: tuple[str, ...] = ("shear_modulus",)
MODEL = 4  # src/core/plasticity.hpp's ELASTIC (tests/materials check it against the core)


def check_shear_modulus(m: Material) -> None:
    if not m.shear_modulus > 0.0:
        raise ValueError(
            f'material.model = "{m.model}" needs material.shear_modulus > 0 (Pa; the '
            "elastic shear stiffness G = E / 3 of an incompressible solid), e.g. "
            "material.shear_modulus = 1e6"
        )


def check(m: Material) -> None:
    check_shear_modulus(m)


def parameters(m: Material) -> list[float]:
    return [m.shear_modulus]
