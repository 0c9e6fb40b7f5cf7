"""Free-surface detection: which grid nodes carry a pressure unknown.

``node``   (the paper): every node of the cells in the system is an unknown unless it
           borders a cell left out of the system (empty or sparse); those get p = 0.
``subcell``: the surface is the level f = 1/2 of the nodal volume fraction f (mean theta
           of the node's cells, each clipped to 1). Unknowns are the nodes with f > 1/2
           all of whose cells are in the system; the others are ghost nodes whose pressure
           extrapolates linearly to p = 0 at the surface (see ``kernels.pressure2d``).
           For a flat surface at any height this places p = 0 exactly at the surface, not
           at the nearest node row. A cell all of whose nodes lie inside the fluid stays in
           the system even when few particles are left in it: a gap that opens between
           particle lines inside the water is not a free surface (see ``quadrature``).
"""

from dataclasses import dataclass

import numpy as np

from .kernels import pressure2d


@dataclass
class NodeSets:
    """The unknown set of one step; ``f`` and ``row`` are buffers overwritten next step."""

    f: np.ndarray  # (nnodes,) nodal volume fraction
    row: np.ndarray  # (nnodes,) equation number of each unknown node, -1 otherwise
    nrows: int
    subcell: bool

    def row_nodes(self):
        return np.flatnonzero(self.row >= 0)


class FreeSurface:
    def __init__(self, grid, mode):
        if grid.dim != 2:
            raise NotImplementedError("only 2D grids are implemented")
        self.grid = grid
        self.subcell = mode == "subcell"
        self._f = np.empty(grid.nnodes)
        self._row = np.empty(grid.nnodes, dtype=np.int64)

    def nodal_fraction(self, theta):
        """The nodal volume fraction f from the cell fractions theta."""
        nx, ny = self.grid.cells
        pressure2d.nodal_fraction_2d(nx, ny, theta, self._f)
        return self._f

    def enclosed_cells(self, node_f):
        """Cells inside the fluid by the nodal fraction (all nodes f > 1/2); None for ``node``."""
        if not self.subcell:
            return None
        nx, ny = self.grid.cells
        enclosed = np.empty(self.grid.ncells, dtype=np.bool_)
        pressure2d.enclosed_cells_2d(nx, ny, node_f, enclosed)
        return enclosed

    def classify(self, integrals, node_f):
        nx, ny = self.grid.cells
        nrows = pressure2d.classify_nodes_2d(nx, ny, integrals.slot, node_f, self.subcell,
                                            self._row)
        return NodeSets(node_f, self._row, int(nrows), self.subcell)
