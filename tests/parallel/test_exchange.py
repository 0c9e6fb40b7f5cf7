"""The exchanges between ranks, on one process and under ``mpirun -n 2`` (make test-mpi):
node values reach the ranks that hold a node without owning it, and particles are neither
lost nor doubled when they migrate."""

import numpy as np

from mpmflow.grid import Grid
from mpmflow.parallel.boxes import Boxes, bisect
from mpmflow.parallel.comm import world
from mpmflow.parallel.exchange import Halo, NodeExchange, migrate, owners
from mpmflow.parallel.subgrid import extended, neighbours, subgrid

GRID = Grid(0.1, (12, 8))


def test_every_local_node_gets_its_owners_value():
    comm = world()
    boxes = bisect(np.ones(GRID.cells), comm.size)
    sub = subgrid(GRID, boxes, comm.rank)
    exchange = NodeExchange(comm, sub)
    scalar = np.where(sub.owned_nodes, sub.node_global * 1.5, np.nan)
    vector = np.where(sub.owned_nodes[:, None], sub.node_global[:, None] * [1.0, -2.0], np.nan)
    rows = np.where(sub.owned_nodes, sub.node_global, -7)
    exchange.fill(scalar, vector, rows)
    assert np.array_equal(scalar, sub.node_global * 1.5)
    assert np.array_equal(vector, sub.node_global[:, None] * np.array([1.0, -2.0]))
    assert np.array_equal(rows, sub.node_global)


def test_every_local_cell_gets_its_owners_value():
    comm = world()
    boxes = bisect(np.ones(GRID.cells), comm.size)
    sub = subgrid(GRID, boxes, comm.rank)
    exchange = NodeExchange(comm, sub, cells=True)
    value = np.where(sub.owned_cells, sub.cell_global * 0.5, np.nan)
    exchange.fill(value)
    assert np.array_equal(value, sub.cell_global * 0.5)


def test_particles_migrate_to_their_owners_once():
    comm = world()
    boxes = bisect(np.ones(GRID.cells), comm.size)
    rng = np.random.default_rng(7)
    n = 500
    everyone = rng.uniform(0, 1, (n, 2)) * GRID.size
    ids = np.arange(n)
    # each rank starts with the particles it owned a step before, when each lay up to 0.9
    # of a cell away from where it is now (a step moves a particle less than a cell)
    before = np.clip(everyone + rng.uniform(-0.9, 0.9, (n, 2)) * GRID.spacing, 0, GRID.size)
    mine = boxes.owner_of_points(before, GRID.spacing) == comm.rank
    sub = subgrid(GRID, boxes, comm.rank)
    x = everyone[mine]
    near = neighbours(boxes, comm.rank)
    assert comm.rank not in near
    moved = migrate(comm, owners(boxes, sub, x), {"x": x, "id": ids[mine]}, near)
    owner = boxes.owner_of_points(moved["x"], GRID.spacing)
    assert np.all(owner == comm.rank)
    got = np.sort(np.concatenate(comm.allgather(moved["id"])))
    assert np.array_equal(got, ids)  # none lost, none doubled
    assert np.array_equal(moved["x"], everyone[moved["id"]])


def test_the_halo_is_every_neighbour_particle_in_the_ghost_layer():
    comm = world()
    boxes = bisect(np.ones(GRID.cells), comm.size)
    rng = np.random.default_rng(8)
    everyone = rng.uniform(0, 1, (400, 2)) * GRID.size
    owner = boxes.owner_of_points(everyone, GRID.spacing)
    mine = owner == comm.rank
    ids = np.arange(400)
    sub = subgrid(GRID, boxes, comm.rank)
    halo = Halo(comm, boxes, sub, neighbours(boxes, comm.rank))
    got = halo({"x": everyone[mine], "id": ids[mine]})
    lo, hi = extended(boxes, comm.rank)
    ijk = np.floor(everyone / GRID.spacing).astype(int)
    expected = np.flatnonzero(~mine & np.all((ijk >= lo) & (ijk < hi), axis=1))
    assert np.array_equal(np.sort(got["id"]), expected)


def test_the_neighbours_of_a_box_are_those_its_ghost_layer_meets():
    """Four boxes in a row, 3 cells wide (the ghost layer is GHOST cells): each box's
    neighbours are the boxes beside it and no others, and the relation is symmetric; the
    particles and the halo go to them only."""
    from mpmflow.parallel.subgrid import GHOST

    width = 3
    assert GHOST < width  # the boxes beyond the next lie outside the ghost layer
    boxes = Boxes(
        lo=np.array([[k * width, 0] for k in range(4)]),
        hi=np.array([[(k + 1) * width, 8] for k in range(4)]),
        cells=(4 * width, 8),
    )
    assert [neighbours(boxes, r) for r in range(4)] == [[1], [0, 2], [1, 3], [2]]
