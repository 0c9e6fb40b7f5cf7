"""Damping zones along the domain's sides (``[[sponges]]``): each grid node's damping rate,
built once; the core relaxes the predictor's velocity by it (src/core/sponges.hpp).

The rate rises from 0 at a zone's inner edge to its ``strength`` at the side as the square of
the distance into the zone, c(d) = strength (d / length)^2 (d: from the inner edge towards
the side), the usual profile of a numerical beach (a gradual rise reflects least); where
zones overlap, the larger rate."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..arrays import Floats
from ..case.sponges import AXIS
from ..grid import Grid

if TYPE_CHECKING:
    from ..case import Case


def rates(case: Case, grid: Grid) -> Floats | None:
    """Each node's damping rate (1/s; None: the case has no sponge)."""
    if not case.sponges:
        return None
    x = grid.node_coordinates()
    size = np.asarray(grid.size, dtype=float)
    rate = np.zeros(grid.nnodes)
    for sponge in case.sponges:
        k = AXIS[sponge.side]
        into = x[:, k] if sponge.side.endswith("min") else size[k] - x[:, k]
        d = np.clip((sponge.length - into) / sponge.length, 0.0, 1.0)
        rate = np.maximum(rate, sponge.strength * d * d)
    return rate
