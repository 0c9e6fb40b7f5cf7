"""Mixed quadrature of the pressure system (paper, section 2.2).

Cells are classified by their volume fraction theta:
* theta >= full threshold (0.9): full cell, 2x2 Gauss points;
* sparse threshold (0.2) <= theta < full threshold: partial cell, integrated with its
  material points (``partial="particles"``, the paper) or, like a full cell, with Gauss
  points (``partial="gauss"``: the free surface is then placed inside the cell by the
  sub-cell free-surface treatment, see ``free_surface``);
* theta < sparse threshold: left out of the pressure system, unless the free-surface
  treatment says the cell lies inside the fluid (``enclosed``): then it is a gap between
  particle lines in continuous material, integrated like a full cell.
The element integrals of every cell in the system are returned as stacked arrays; slot 0
holds the Gauss-point integrals shared by all Gauss cells.
"""

from dataclasses import dataclass

import numpy as np

from .kernels import quadrature2d

LEFT_OUT = -1
GAUSS = 0


@dataclass
class CellIntegrals:
    """Per-cell element integrals; ``slot[c]`` indexes K, C, V (-1: cell left out).

    ``slot`` is the builder's buffer, overwritten at the next step: use it within the step."""

    slot: np.ndarray  # (ncells,) int64
    K: np.ndarray  # (nslots, 2^d, 2^d)       grad N_a . grad N_b
    C: np.ndarray  # (nslots, 2^d, 2^d, d)    N_a dN_b/dx_k
    V: np.ndarray  # (nslots, 2^d)            N_a


class Quadrature:
    """Builds the cell integrals each step from the particle bins."""

    def __init__(self, grid, full_threshold, sparse_threshold, partial):
        if grid.dim != 2:
            raise NotImplementedError("only 2D grids are implemented")
        self.grid = grid
        self.full_threshold = full_threshold
        self.sparse_threshold = sparse_threshold
        self.partial = partial
        nv = 2**grid.dim
        self._K_ref = np.zeros((nv, nv))
        self._C_ref = np.zeros((nv, nv, grid.dim))
        self._V_ref = np.zeros(nv)
        quadrature2d.gauss_cell_tensors_2d(grid.spacing, self._K_ref, self._C_ref, self._V_ref)
        self._slot = np.empty(grid.ncells, dtype=np.int64)

    def integrals(self, particles, bins, enclosed=None):
        theta = bins.theta
        slot = self._slot
        slot[:] = LEFT_OUT
        counted = theta >= self.sparse_threshold
        slot[counted] = GAUSS
        if enclosed is not None:
            slot[enclosed] = GAUSS
        if self.partial == "particles":
            partial = np.flatnonzero(counted & (theta < self.full_threshold))
        else:
            partial = np.empty(0, dtype=np.int64)
        n = partial.size + 1
        nv = self._V_ref.size
        K = np.empty((n, nv, nv))
        C = np.empty((n, nv, nv, self.grid.dim))
        V = np.empty((n, nv))
        K[0], C[0], V[0] = self._K_ref, self._C_ref, self._V_ref
        if partial.size:
            slot[partial] = np.arange(1, n)
            quadrature2d.particle_cell_tensors_2d(
                particles.x, particles.volume, bins.order, bins.start, partial,
                self.grid.spacing, self.grid.cells[0], K[1:], C[1:], V[1:])
        return CellIntegrals(slot, K, C, V)
