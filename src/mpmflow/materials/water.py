"""Inviscid water (``material.model = "water"``, the default): no deviatoric stress."""

from .. import state

NAME = "water"
KEYS = ("viscosity",)
MODEL = state.WATER


def check(m):
    if m.viscosity != 0.0:
        raise ValueError(
            f'material.viscosity = {m.viscosity:g} Pa s with material.model = "water", '
            'which is inviscid: set material.model = "newtonian" for a viscous liquid '
            "(water at 20 C: viscosity = 1.0e-3), or leave material.viscosity out"
        )


def parameters(m):
    return []
