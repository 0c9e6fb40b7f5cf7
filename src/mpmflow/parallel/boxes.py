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

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..arrays import Ints


@dataclass(frozen=True)
class Boxes:
    """One box of cells per rank: ``lo[r, k]`` to ``hi[r, k]`` (exclusive) along axis k,
    each with ``ghost`` layers of cells round it (``subgrid``)."""

    lo: Ints  # (ranks, D)
    hi: Ints  # (ranks, D)
    cells: tuple[int, ...]  # the whole grid's cells per axis
    ghost: int = 1  # cell layers round each box (subgrid.ghost_layers)

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
    total = weight.astype(float) + 1e-9 * max(float(weight.sum()), 1.0) / weight.size

    def profile(a: list[int], b: list[int], axis: int) -> NDArray[np.float64]:
        box = total[tuple(slice(a[k], b[k]) for k in range(D))]
        out: NDArray[np.float64] = box.sum(axis=tuple(k for k in range(D) if k != axis))
        return out

    return _bisect(cells, ranks, profile)


Factors = tuple[NDArray[np.float64], ...]  # one 1D array per axis, as long as its cells
DENSE = 2**20  # cells of a box whose weight ``bisect_separable`` makes (8 MB)


def bisect_separable(layers: list[Factors], cells: tuple[int, ...], ranks: int) -> Boxes:
    """``bisect`` of the weight sum_l outer(layers[l][0], layers[l][1], ...) without making
    it: each layer is a weight per cell that is a product of one factor per axis (the
    particles of a box-shaped body: so many lattice planes per cell along each axis). The
    same cuts as ``bisect`` on the dense weight: a box of up to ``DENSE`` cells has its
    weight made and summed as ``bisect`` sums it; a larger one is summed from the factors,
    where a cut that ties in exact arithmetic (two planes equally near the share) may go
    the other way by rounding. The memory is that of the factors (a few cells' worth per
    axis) and of one box of ``DENSE`` cells, so the split of a case far too large for this
    machine is found in a second (``parallel.memory``)."""
    D = len(cells)
    whole = float(sum(np.prod([f.sum() for f in layer]) for layer in layers))
    eps = 1e-9 * max(whole, 1.0) / float(np.prod([float(c) for c in cells]))

    def profile(a: list[int], b: list[int], axis: int) -> NDArray[np.float64]:
        others = [k for k in range(D) if k != axis]
        if np.prod([float(b[k] - a[k]) for k in range(D)]) <= DENSE:
            # the box's weight made, as ``bisect`` sums it: the same floats, so a cut
            # that ties in exact arithmetic goes the same way
            box = np.zeros([b[k] - a[k] for k in range(D)])
            for layer in layers:
                box += functools.reduce(
                    np.multiply.outer, [layer[k][a[k] : b[k]] for k in range(D)]
                )
            summed: NDArray[np.float64] = (box + eps).sum(axis=tuple(others))
            return summed
        out = np.full(b[axis] - a[axis], eps * float(np.prod([b[k] - a[k] for k in others])))
        for layer in layers:
            across = float(np.prod([layer[k][a[k] : b[k]].sum() for k in others]))
            out += layer[axis][a[axis] : b[axis]] * across
        return out

    return _bisect(cells, ranks, profile)


def box_weight(layers: list[Factors], lo: NDArray[Any], hi: NDArray[Any]) -> float:
    """The weight of separable ``layers`` (``bisect_separable``) in the cells [lo, hi)."""
    return float(
        sum(
            np.prod([f[int(a) : int(b)].sum() for f, a, b in zip(layer, lo, hi)])
            for layer in layers
        )
    )


def _bisect(
    cells: tuple[int, ...],
    ranks: int,
    profile: Callable[[list[int], list[int], int], NDArray[np.float64]],
) -> Boxes:
    """The bisection itself; ``profile(a, b, axis)``: the weight of the box [a, b) summed
    over every axis but ``axis``, one value per plane of cells along it."""
    D = len(cells)
    lo = np.zeros((ranks, D), dtype=np.int64)
    hi = np.zeros((ranks, D), dtype=np.int64)

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
        cumulative = np.cumsum(profile(a, b, axis))
        share = cumulative[-1] * left / n
        # the cut at the plane whose cumulative weight comes nearest the share, with at
        # least one cell on each side
        cut = int(np.argmin(np.abs(cumulative[:-1] - share))) + 1
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
