"""A Newtonian liquid (``material.model = "newtonian"``): tau = 2 eta D with a constant
dynamic viscosity eta = ``material.viscosity`` (Pa s)."""

from .. import state

NAME = "newtonian"
KEYS = ("viscosity",)
MODEL = state.NEWTONIAN


def check(m):
    if not m.viscosity > 0.0:
        raise ValueError(
            'material.model = "newtonian" needs material.viscosity > 0 (Pa s; water at '
            '20 C: 1.0e-3); for inviscid material use material.model = "water"'
        )


def parameters(m):
    return [m.viscosity]
