"""A rank's part of the grid: its box of cells with one ghost layer round it (docs/design/
mpi.md, section 2), and the case's fixed tables (walls, obstacles) cut to it.

The local grid's cells are the box's cells and, where the box does not end at the domain's
side, one more layer: the transfer's stencil (multilinear shape functions reach the nodes of
a particle's own cell), so that the particles in the ghost layer (copies of the neighbours'
particles, the halo) complete the sums at every node of the box. The local grid starts at
global cell ``origin``; a particle's local coordinates are its global ones less
``origin * spacing`` (a whole number of cells: the cell a point falls in is the same).

Flat indices run along axis 0 fastest, as the core numbers nodes and cells (src/core/grid.hpp).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..arrays import Bools, Floats, Ints
from ..boundaries.obstacles import Tables
from ..grid import Grid
from .boxes import Boxes

GHOST = 1  # ghost cell layers round a box: the multilinear transfer's reach


def ghost_layers(moving: bool) -> int:
    """The ghost cell layers round a box: the transfer's one, and with obstacles moving two.
    A moving body's tables are rebuilt on each rank every step, and the obstacle nodes and
    normals on the ghost layer's outer face read cells past the rank's grid; through the
    face terms of the cells the nodes on the box's side share with them, that reached the
    rank's own rows (a box towed across a rank boundary: 1.3 mm and 0.13 m/s off one process
    after 150 steps with one layer, 8e-11 m with two)."""
    return 2 if moving else GHOST


def _flat(ijk: Ints, dims: tuple[int, ...]) -> Ints:
    """Flat indices (axis 0 fastest) of coordinates ijk (n x D) in a block of ``dims``."""
    flat: Ints = np.ravel_multi_index(tuple(ijk.T), dims, order="F").astype(np.int64)
    return flat


def _coords(n: int, dims: tuple[int, ...]) -> Ints:
    """The coordinates (n x D) of flat indices 0 .. n - 1 (axis 0 fastest)."""
    return np.stack(np.unravel_index(np.arange(n), dims, order="F"), axis=1).astype(np.int64)


@dataclass(frozen=True)
class Subgrid:
    """Rank ``rank``'s local grid, its place in the whole grid and what it owns."""

    rank: int
    grid: Grid  # the local grid (not periodic)
    whole: Grid  # the whole grid
    origin: Ints  # (D,) global coordinates of the local grid's first cell
    node_global: Ints  # (local nodes,) flat global index of each local node
    cell_global: Ints  # (local cells,)
    node_owner: Ints  # (local nodes,) the rank owning each local node
    cell_owner: Ints  # (local cells,)

    @property
    def offset(self) -> Floats:
        """The local grid's origin (m) in the domain's coordinates."""
        out: Floats = self.origin.astype(float) * self.grid.spacing
        return out

    @property
    def owned_nodes(self) -> Bools:
        out: Bools = self.node_owner == self.rank
        return out

    @property
    def owned_cells(self) -> Bools:
        out: Bools = self.cell_owner == self.rank
        return out

    def local_nodes(self, global_index: Ints) -> Ints:
        """The local index of global nodes (-1 where the local grid does not hold one)."""
        whole = self.whole.nodes
        ijk = _unflat(global_index, whole) - self.origin
        inside = np.all((ijk >= 0) & (ijk < np.asarray(self.grid.nodes)), axis=1)
        out = np.full(global_index.shape[0], -1, dtype=np.int64)
        out[inside] = _flat(ijk[inside], self.grid.nodes)
        return out

    def node_position(self, local: int) -> Floats:
        """The position (m) of a local node in the domain's coordinates."""
        ijk = _unflat(self.node_global[[local]], self.whole.nodes)[0]
        out: Floats = ijk * self.grid.spacing
        return out

    def cell_centre(self, local: int) -> Floats:
        """The centre (m) of a local cell in the domain's coordinates."""
        ijk = _unflat(self.cell_global[[local]], self.whole.cells)[0]
        out: Floats = (ijk + 0.5) * self.grid.spacing
        return out

    def local_cells(self, global_index: Ints) -> Ints:
        """The local index of global cells (-1 where the local grid does not hold one)."""
        ijk = _unflat(global_index, self.whole.cells) - self.origin
        inside = np.all((ijk >= 0) & (ijk < np.asarray(self.grid.cells)), axis=1)
        out = np.full(global_index.shape[0], -1, dtype=np.int64)
        out[inside] = _flat(ijk[inside], self.grid.cells)
        return out


def _unflat(index: Ints, dims: tuple[int, ...]) -> Ints:
    return np.stack(np.unravel_index(index, dims, order="F"), axis=1).astype(np.int64)


def extended(boxes: Boxes, rank: int) -> tuple[Ints, Ints]:
    """The cells of rank's box with its ghost layer, clipped to the grid: [lo, hi)."""
    lo = np.maximum(boxes.lo[rank] - boxes.ghost, 0)
    hi = np.minimum(boxes.hi[rank] + boxes.ghost, np.asarray(boxes.cells))
    return lo, hi


def neighbours(boxes: Boxes, rank: int) -> list[int]:
    """The ranks whose box meets rank's box with its ghost layer, or whose box with its
    ghost layer meets rank's: the only ranks it exchanges particles with (a particle moves
    less than a cell in a step, so it stays within the ghost layer of the box it left)."""
    lo, hi = extended(boxes, rank)
    out = []
    for r in range(boxes.ranks):
        if r == rank:
            continue
        rlo, rhi = extended(boxes, r)
        meets = np.all((boxes.lo[r] < hi) & (boxes.hi[r] > lo)) or np.all(
            (boxes.lo[rank] < rhi) & (boxes.hi[rank] > rlo)
        )
        if meets:
            out.append(r)
    return out


def subgrid(whole: Grid, boxes: Boxes, rank: int) -> Subgrid:
    if whole.periodic and any(whole.periodic):
        raise ValueError("periodic axes are not split over ranks yet")
    lo, hi = extended(boxes, rank)
    local = Grid(whole.spacing, tuple(int(c) for c in hi - lo))
    nodes = _coords(local.nnodes, local.nodes) + lo
    cells = _coords(local.ncells, local.cells) + lo
    return Subgrid(
        rank=rank,
        grid=local,
        whole=whole,
        origin=lo.astype(np.int64),
        node_global=_flat(nodes, whole.nodes),
        cell_global=_flat(cells, whole.cells),
        node_owner=boxes.owner_of_nodes(nodes),
        cell_owner=boxes.owner_of_cells(cells),
    )


def restrict_walls(
    walls: tuple[Ints, Ints, Floats, Bools], sub: Subgrid
) -> tuple[Ints, Ints, Floats, Bools]:
    """The domain's wall pairs (node, axis, sign, no_slip) at the local grid's nodes,
    renumbered locally."""
    node, axis, sign, no_slip = walls
    local = sub.local_nodes(np.asarray(node, dtype=np.int64))
    keep = local >= 0
    flags = np.broadcast_to(np.asarray(no_slip, dtype=np.bool_), np.shape(node))
    return local[keep], np.asarray(axis)[keep], np.asarray(sign)[keep], flags[keep].copy()


def restrict_obstacles(tables: Tables, sub: Subgrid) -> Tables:
    """The obstacles' tables on the local grid: node and cell arrays cut to it, the static
    element integrals (indexed by slot) kept whole, the obstacle nodes renumbered."""
    cut = replace(
        tables, open=tables.open[sub.cell_global], static_slot=tables.static_slot[sub.cell_global]
    )
    if not tables.present:
        return cut
    local = sub.local_nodes(tables.node)
    keep = local >= 0
    return replace(
        cut,
        phi=tables.phi[sub.node_global],
        node=local[keep],
        normal=np.reshape(tables.normal, (-1, sub.grid.dim))[keep],
        no_slip=np.asarray(tables.no_slip)[keep],
    )
