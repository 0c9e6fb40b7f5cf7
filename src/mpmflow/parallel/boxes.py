"""The split of the grid's cells into one box per rank (docs/design/mpi.md, section 2).

A box is a range of cells [lo_k, hi_k) along each axis. The split is recursive coordinate
bisection on a weight per cell (the particles in it): the cells are cut across their
longest axis where the weight on each side is proportional to the ranks it goes to, and each
side is split again, until every rank has a box. DMDA's tensor-product split cannot balance
water standing in one corner of a tank (the dam break: a fixed midpoint split put all 1653
unknowns on one of two ranks); bisection on the weight can.

Ownership: a cell belongs to the box that holds it; a node to the box that holds its
"lower" cell (the cell whose first corner it is; on a domain's upper side, where no such
cell exists, the last cell along that axis), so every node has one owner.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..arrays import Ints


@dataclass(frozen=True)
class Boxes:
    """One box of cells per rank: ``lo[r, k]`` to ``hi[r, k]`` (exclusive) along axis k."""

    lo: Ints  # (ranks, D)
    hi: Ints  # (ranks, D)
    cells: tuple[int, ...]  # the whole grid's cells per axis

    @property
    def ranks(self) -> int:
        return int(self.lo.shape[0])

    def owner_of_cells(self, ijk: Ints) -> Ints:
        """The rank owning each cell, given its coordinates (n x D)."""
        owner = np.full(ijk.shape[0], -1, dtype=np.int64)
        if self.ranks == 1:
            owner[np.all((ijk >= 0) & (ijk < np.asarray(self.cells)), axis=1)] = 0
            return owner
        for r in range(self.ranks):
            inside = np.all((ijk >= self.lo[r]) & (ijk < self.hi[r]), axis=1)
            owner[inside] = r
        return owner

    def owner_of_nodes(self, ijk: Ints) -> Ints:
        """The rank owning each node (coordinates n x D): the owner of its lower cell."""
        top = np.asarray(self.cells, dtype=np.int64) - 1
        return self.owner_of_cells(np.minimum(ijk, top))

    def owner_of_points(self, x: NDArray[np.float64], spacing: float) -> Ints:
        """The rank owning the cell of each point (n x D, m); points beyond the grid go to
        the nearest cell, as the core bins them."""
        return self.owner_of_cells(cells_of(x, spacing, self.cells))


def bisect(weight: NDArray[Any], ranks: int) -> Boxes:
    """Recursive coordinate bisection of the cells (``weight``: one value per cell, shaped
    as the grid's cells, axis 0 first) into ``ranks`` boxes, each at least one cell wide."""
    cells = tuple(int(c) for c in weight.shape)
    D = len(cells)
    lo = np.zeros((ranks, D), dtype=np.int64)
    hi = np.zeros((ranks, D), dtype=np.int64)
    total = weight.astype(float) + 1e-9 * max(float(weight.sum()), 1.0) / weight.size

    def split(a: list[int], b: list[int], first: int, n: int) -> None:
        if n == 1:
            lo[first], hi[first] = a, b
            return
        extent = [b[k] - a[k] for k in range(D)]
        axis = int(np.argmax(extent))
        if extent[axis] < 2:
            raise ValueError(
                f"{ranks} ranks are more than the grid's {cells} cells can give a box each"
            )
        left = n // 2
        box = total[tuple(slice(a[k], b[k]) for k in range(D))]
        other = tuple(k for k in range(D) if k != axis)
        profile = np.cumsum(box.sum(axis=other))
        share = profile[-1] * left / n
        # the cut at the plane whose cumulative weight comes nearest the share, with at
        # least one cell on each side
        cut = int(np.argmin(np.abs(profile[:-1] - share))) + 1
        cut = min(max(cut, 1), extent[axis] - 1)
        mid = a[axis] + cut
        split(a, [*b[:axis], mid, *b[axis + 1 :]], first, left)
        split([*a[:axis], mid, *a[axis + 1 :]], b, first + left, n - left)

    split([0] * D, list(cells), 0, ranks)
    return Boxes(lo, hi, cells)


def cells_of(x: NDArray[np.float64], spacing: float, cells: tuple[int, ...]) -> Ints:
    """The cell (coordinates, n x D) of each point (n x D, m); points beyond the grid go to
    the nearest cell, as the core bins them."""
    top = np.asarray(cells, dtype=np.int64) - 1
    ijk: Ints = np.minimum(np.maximum(np.floor(x / spacing).astype(np.int64), 0), top)
    return ijk


def cell_weights(x: NDArray[np.float64], spacing: float, cells: tuple[int, ...]) -> Ints:
    """The particles in each cell (shaped as the cells, axis 0 first)."""
    ijk = cells_of(x, spacing, cells)
    flat = np.ravel_multi_index(tuple(ijk.T), cells, order="C")
    counts: Ints = np.bincount(flat, minlength=int(np.prod(cells))).reshape(cells)
    return counts
