"""Inviscid water (``material.model = "water"``, the default): no deviatoric stress."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the case's schema lists the materials (case.sections imports this package)
    from ..case.sections import Material

NAME = "water"
KEYS: tuple[str, ...] = ("viscosity",)
MODEL = 0  # src/core/rheology.hpp's WATER (tests/materials check it against the core)


def check(m: Material) -> None:
    if m.viscosity != 0.0:
        raise ValueError(
            f'material.viscosity = {m.viscosity:g} Pa s with material.model = "water", '
            'which is inviscid: set material.model = "newtonian" for a viscous liquid '
            "(water at 20 C: viscosity = 1.0e-3), or leave material.viscosity out"
        )


def parameters(m: Material) -> list[float]:
    return []
