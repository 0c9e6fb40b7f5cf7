"""The split of the cells into boxes: every cell and node has one owner, and the particles
are shared as evenly as whole planes of cells allow."""

import numpy as np
import pytest

from mpmflow.grid import Grid
from mpmflow.parallel.boxes import bisect, cell_weights
from mpmflow.parallel.subgrid import subgrid


def corner_column(cells=(60, 40), width=15, height=30, ppc=16):
    """Particle counts of water standing in the lower-left corner (the dam break's start)."""
    w = np.zeros(cells)
    w[:width, :height] = ppc
    return w


@pytest.mark.parametrize("ranks", [1, 2, 3, 4, 7])
def test_every_cell_has_one_owner_and_the_water_is_shared(ranks):
    w = corner_column()
    boxes = bisect(w, ranks)
    ijk = np.stack(np.meshgrid(*[np.arange(c) for c in w.shape], indexing="ij"), -1)
    owner = boxes.owner_of_cells(ijk.reshape(-1, 2))
    assert owner.min() == 0 and np.all(owner < ranks)
    assert np.all(boxes.hi - boxes.lo >= 1)
    load = np.bincount(owner, weights=w.reshape(-1), minlength=ranks)
    # whole planes of cells: each cut misses its share by at most one plane of water (30
    # cells of 16 particles across the column, 15 along it), each rank by its two cuts
    assert np.abs(load - w.sum() / ranks).max() <= 2 * 30 * 16


def test_a_midpoint_split_would_starve_a_rank_but_bisection_does_not():
    w = corner_column()
    boxes = bisect(w, 2)
    assert boxes.hi[0, 0] <= 15  # the cut goes through the water, not the middle of the tank


def test_nodes_are_owned_by_their_lower_cell():
    grid = Grid(0.1, (6, 4))
    boxes = bisect(np.ones(grid.cells), 2)
    subs = [subgrid(grid, boxes, r) for r in range(2)]
    owners = np.full(grid.nnodes, -1)
    for s in subs:
        mine = s.owned_nodes
        assert np.all(owners[s.node_global[mine]] == -1)  # owned once
        owners[s.node_global[mine]] = s.rank
        # a local node is a real node of the whole grid, and its owner agrees
        assert np.all(
            boxes.owner_of_nodes(
                np.stack(np.unravel_index(s.node_global, grid.nodes, order="F"), 1)
            )
            == s.node_owner
        )
    assert np.all(owners >= 0)
    # the ghost layer: one cell past the cut on each side, none past the walls
    assert subs[0].grid.cells == (4, 4) and subs[1].grid.cells == (4, 4)
    assert list(subs[1].origin) == [2, 0]


def test_cell_weights_count_particles():
    x = np.array([[0.05, 0.05], [0.05, 0.06], [0.55, 0.35], [0.61, 0.39]])
    w = cell_weights(x, 0.1, (6, 4))
    assert w[0, 0] == 2 and w[5, 3] == 2 and w.sum() == 4


def test_more_ranks_than_cells_is_refused():
    with pytest.raises(ValueError, match="ranks"):
        bisect(np.ones((2, 1)), 3)
