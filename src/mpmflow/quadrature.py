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

With Gauss partial cells, ``surface`` chooses how the cells the free surface passes
through (partial and not enclosed) are integrated besides the Laplacian, which keeps Gauss
points: "gauss" (all of them), "divergence" (the divergence of the predicted velocity,
eq. 15, over their material points: the velocity the grid carries in the air part of such
a cell is an extrapolation that no equation constrains, and integrated over the whole cell
its divergence did work against the extrapolated (ghost) pressure that nothing balanced, so
a standing wave gained energy) or "consistent" (the corrector's gradient and volumes, eqs.
16-18, too: divergence and gradient are then adjoint and the projection takes energy out
only, at the price of more damping). docs/method.md, "Energy".
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
    # the cells the free surface passes through, integrated over their material points:
    # slot per cell (0: the Gauss tensors, -1: left out) and the stacked tensors
    surface_slot: np.ndarray = None
    C_surface: np.ndarray = None
    V_surface: np.ndarray = None
    V_cells: np.ndarray = None  # the Gauss V in every surface slot (the nodes' cell volumes)
    surface: str = "gauss"

    def divergence(self):
        """(slot, C, V) of the right-hand side: C for the divergence of v*, V for the nodes'
        volumes (the density correction's V_i, always the cells')."""
        if self.surface == "gauss":
            return self.slot, self.C, self.V
        return self.surface_slot, self.C_surface, self.V_cells

    def corrector(self):
        """(slot, C, V) of the corrector's gradient and lumped volumes."""
        if self.surface == "consistent":
            return self.surface_slot, self.C_surface, self.V_surface
        return self.slot, self.C, self.V


class Quadrature:
    """Builds the cell integrals each step from the particle bins."""

    def __init__(self, grid, full_threshold, sparse_threshold, partial, surface="gauss"):
        if grid.dim != 2:
            raise NotImplementedError("only 2D grids are implemented")
        self.grid = grid
        self.full_threshold = full_threshold
        self.sparse_threshold = sparse_threshold
        self.partial = partial
        self.surface = surface if partial == "gauss" else "gauss"
        self._surface_slot = np.empty(grid.ncells, dtype=np.int64)
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
        if self.surface != "gauss":
            self._surface_cells(result, particles, bins, counted, enclosed)
        return result

    def _surface_cells(self, result, particles, bins, counted, enclosed):
        """C and V of the cells the free surface passes through (partial and not enclosed)
        from their material points; slot 0: the Gauss tensors."""
        theta = bins.theta
        surface = counted & (theta < self.full_threshold)
        if enclosed is not None:
            surface &= ~enclosed
        cells = np.flatnonzero(surface)
        n = cells.size + 1
        nv = self._V_ref.size
        C = np.empty((n, nv, nv, self.grid.dim))
        V = np.empty((n, nv))
        C[0], V[0] = self._C_ref, self._V_ref
        surface_slot = self._surface_slot
        np.minimum(result.slot, 0, out=surface_slot)  # -1 left out, 0 Gauss
        if cells.size:
            surface_slot[cells] = np.arange(1, n)
            quadrature2d.particle_cell_divergence_2d(
                particles.x, particles.volume, bins.order, bins.start, cells,
                self.grid.spacing, self.grid.cells[0], C[1:], V[1:])
        result.surface = self.surface
        result.surface_slot, result.C_surface, result.V_surface = surface_slot, C, V
        result.V_cells = np.broadcast_to(self._V_ref, V.shape)
