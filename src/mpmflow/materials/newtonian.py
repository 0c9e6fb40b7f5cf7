"""A Newtonian liquid (``material.model = "newtonian"``): tau = 2 eta D with a constant
dynamic viscosity eta = ``material.viscosity`` (Pa s)."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the case's schema lists the materials (case.sections imports this package)
    from ..case.sections import Material

NAME = "newtonian"
KEYS: tuple[str, ...] = ("viscosity",)
MODEL = 1  # src/core/rheology.hpp's NEWTONIAN (tests/materials check it against the core)


def check(m: Material) -> None:
    if not m.viscosity > 0.0:
        raise ValueError(
            'material.model = "newtonian" needs material.viscosity > 0 (Pa s; water at '
            '20 C: 1.0e-3); for inviscid material use material.model = "water"'
        )


def parameters(m: Material) -> list[float]:
    return [m.viscosity]
