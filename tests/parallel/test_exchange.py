"""The exchanges between ranks, on one process and under ``mpirun -n 2`` (make test-mpi):
node values reach the ranks that hold a node without owning it, and particles are neither
lost nor doubled when they migrate."""

import numpy as np

from mpmflow.grid import Grid
from mpmflow.parallel.boxes import bisect
from mpmflow.parallel.comm import world
from mpmflow.parallel.exchange import Halo, NodeExchange, migrate, owners
from mpmflow.parallel.subgrid import extended, subgrid

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
    # each rank starts with every comm.size-th particle, wherever it lies
    mine = ids % comm.size == comm.rank
    sub = subgrid(GRID, boxes, comm.rank)
    x = everyone[mine]
    moved = migrate(comm, owners(boxes, sub, x), {"x": x, "id": ids[mine]})
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
    got = Halo(comm, boxes, subgrid(GRID, boxes, comm.rank))({"x": everyone[mine], "id": ids[mine]})
    lo, hi = extended(boxes, comm.rank)
    ijk = np.floor(everyone / GRID.spacing).astype(int)
    expected = np.flatnonzero(~mine & np.all((ijk >= lo) & (ijk < hi), axis=1))
    assert np.array_equal(np.sort(got["id"]), expected)
