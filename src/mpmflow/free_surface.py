"""Free-surface detection: which grid nodes carry a pressure unknown.

``node``   (the paper): every node of the cells in the system is an unknown unless it
           borders a cell left out of the system (empty or sparse); those get p = 0.
``subcell``: the surface is the level f = 1/2 of the nodal volume fraction f (mean theta
           of the node's cells, each clipped to 1). Unknowns are the nodes with f > 1/2
           all of whose cells are in the system; the others are ghost nodes whose pressure
           extrapolates linearly to p = 0 at the surface (see ``kernels.pressure2d``).
           For a flat surface at any height this places p = 0 exactly at the surface, not
           at the nearest node row.
"""

from dataclasses import dataclass

import numpy as np

from .kernels import pressure2d


@dataclass
class NodeSets:
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

    def classify(self, integrals, theta):
        nx, ny = self.grid.cells
        nrows = pressure2d.classify_nodes_2d(nx, ny, integrals.slot, theta, self.subcell,
                                            self._f, self._row)
        return NodeSets(self._f, self._row, int(nrows), self.subcell)
