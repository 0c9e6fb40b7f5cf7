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

With ``divergence="particles"`` (and Gauss partial cells) the divergence of the predicted
velocity (eq. 15, the right-hand side) is integrated over the material points in the
partial cells that are not enclosed, the cells the free surface passes through: the
velocity the grid carries in the air part of such a cell is an extrapolation that no
equation constrains, and its divergence, integrated over the whole cell, did work against
the extrapolated (ghost) pressure that nothing balanced (a standing wave gained energy;
docs/method.md). The Laplacian and the corrector keep the Gauss integrals.
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
    # the divergence of the right-hand side: slots and C (V: the cell's, as in V above)
    div_slot: np.ndarray = None
    C_div: np.ndarray = None
    V_div: np.ndarray = None

    def divergence(self):
        """(slot, C, V) for the right-hand side's divergence."""
        if self.div_slot is None:
            return self.slot, self.C, self.V
        return self.div_slot, self.C_div, self.V_div


class Quadrature:
    """Builds the cell integrals each step from the particle bins."""

    def __init__(self, grid, full_threshold, sparse_threshold, partial, divergence="gauss"):
        if grid.dim != 2:
            raise NotImplementedError("only 2D grids are implemented")
        self.grid = grid
        self.full_threshold = full_threshold
        self.sparse_threshold = sparse_threshold
        self.partial = partial
        self.divergence = divergence
        self._div_slot = np.empty(grid.ncells, dtype=np.int64)
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
        result = CellIntegrals(slot, K, C, V)
        if self.divergence == "particles" and self.partial == "gauss":
            self._surface_divergence(result, particles, bins, counted, enclosed)
        return result

    def _surface_divergence(self, result, particles, bins, counted, enclosed):
        """The divergence tensors of the cells the free surface passes through (partial and
        not enclosed) from their material points; slot 0: the Gauss tensors."""
        theta = bins.theta
        surface = counted & (theta < self.full_threshold)
        if enclosed is not None:
            surface &= ~enclosed
        cells = np.flatnonzero(surface)
        n = cells.size + 1
        nv = self._V_ref.size
        K = np.empty((n, nv, nv))
        C = np.empty((n, nv, nv, self.grid.dim))
        V = np.empty((n, nv))
        C[0] = self._C_ref
        div_slot = self._div_slot
        np.minimum(result.slot, 0, out=div_slot)  # -1 left out, 0 Gauss
        if cells.size:
            div_slot[cells] = np.arange(1, n)
            quadrature2d.particle_cell_tensors_2d(
                particles.x, particles.volume, bins.order, bins.start, cells,
                self.grid.spacing, self.grid.cells[0], K[1:], C[1:], V[1:])
        V[:] = self._V_ref  # the node volumes of the density correction stay the cells'
        result.div_slot, result.C_div, result.V_div = div_slot, C, V
