"""Surface loads (``[[loads]]``): each grid node's share of the tractions, built once; the
core adds them to the predictor (src/core/step.hpp, GridTables::load).

A traction t on a face of constant x_k = at between lower and upper along the other axes is,
in the weak form, the force f_i = t int_face N_i dA on each node i of that node plane: the
product over the face's axes of the integral of the node's hat function over the face's
extent (exact for any extent, the ends of a face included)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..arrays import Floats
from ..case.domain import AXES
from ..grid import Grid

if TYPE_CHECKING:
    from ..case import Case


def _hat_integral(t: Floats) -> Floats:
    """int_{-1}^{t} (1 - |s|) ds for the hat function of half-width 1."""
    t = np.clip(t, -1.0, 1.0)
    return np.where(t <= 0.0, 0.5 * (t + 1.0) ** 2, 1.0 - 0.5 * (1.0 - t) ** 2)


def nodal(case: Case, grid: Grid) -> Floats | None:
    """Each node's force (nnodes x D, N; 2D N/m) of the case's loads (None: none)."""
    if not case.loads:
        return None
    D = grid.dim
    h = float(grid.spacing)
    x = grid.node_coordinates()
    force = np.zeros((grid.nnodes, D))
    for load in case.loads:
        k = AXES.index(load.axis)
        on = np.abs(x[:, k] - load.at) < 1e-6 * h
        share = np.ones(grid.nnodes)
        for i, m in enumerate(m for m in range(D) if m != k):
            c = x[:, m]
            share *= h * (
                _hat_integral((load.upper[i] - c) / h) - _hat_integral((load.lower[i] - c) / h)
            )
        share[~on] = 0.0
        force += share[:, None] * np.asarray(load.traction, dtype=float)[None, :]
    return force
