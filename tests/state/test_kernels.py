"""Exact properties of the compiled kernels: quadrature, transfers, binning, walls."""

import numpy as np
import pytest

from mpmflow import state
from mpmflow.cells import bin_particles
from mpmflow.geometry.lattice import lattice_in_box
from mpmflow.geometry.seeding import seed_box
from mpmflow.grid import Grid
from mpmflow.particles import Particles


def test_gauss_cell_integrals_are_the_bilinear_element_matrices():
    h = 0.3
    K, C, V = np.zeros((4, 4)), np.zeros((4, 4, 2)), np.zeros(4)
    state.gauss_cell_tensors(h, K, C, V)
    # Q1 stiffness on a square: 2/3 on the diagonal, -1/6 along edges, -1/3 across
    expected = np.array([[4, -1, -1, -2], [-1, 4, -2, -1], [-1, -2, 4, -1], [-2, -1, -1, 4]]) / 6
    np.testing.assert_allclose(K, expected, atol=1e-14)
    np.testing.assert_allclose(V, h * h / 4)
    # sum_b C[a, b, k] = int N_a d/dx_k (sum_b N_b) = 0 ; sum_a C[a, b, k] = int dN_b/dx_k
    np.testing.assert_allclose(C.sum(axis=1), 0.0, atol=1e-15)
    np.testing.assert_allclose(C.sum(axis=0)[:, 0], [-h / 2, h / 2, -h / 2, h / 2], atol=1e-15)


def test_gauss_cell_integrals_in_3d_are_those_of_the_trilinear_element():
    h = 0.2
    K, C, V = np.zeros((8, 8)), np.zeros((8, 8, 3)), np.zeros(8)
    state.gauss_cell_tensors(h, K, C, V)
    np.testing.assert_allclose(V, h**3 / 8)
    np.testing.assert_allclose(K.sum(axis=1), 0.0, atol=1e-15)  # constants have no gradient
    # Q1 stiffness of the cube: diagonal h/3, edge 0, face diagonal -h/12, body diagonal -h/12
    for a in range(8):
        for b in range(8):
            hamming = bin(a ^ b).count("1")
            assert K[a, b] == pytest.approx(
                {0: h / 3, 1: 0.0, 2: -h / 12, 3: -h / 12}[hamming], abs=1e-15
            )
    np.testing.assert_allclose(C.sum(axis=1), 0.0, atol=1e-15)
    # sum_a C[a, b, k] = int dN_b/dx_k = +-h^2/4 on the faces normal to k
    for b in range(8):
        for k in range(3):
            assert C.sum(axis=0)[b, k] == pytest.approx((1 if b >> k & 1 else -1) * h * h / 4)


def test_particle_quadrature_integrates_constants_exactly():
    # volumes sum to the cell area; sum_a V[a] = total weight, K of a constant field is 0
    h = 0.1
    pts = lattice_in_box([0, 0], [h, h], h / 4)
    K, C, V = np.zeros((1, 4, 4)), np.zeros((1, 4, 4, 2)), np.zeros((1, 4))
    order = np.arange(len(pts))
    start = np.array([0, len(pts)])
    state.particle_cell_tensors(
        pts, np.full(len(pts), (h / 4) ** 2), order, start, np.array([0]), h, (1, 1), K, C, V
    )
    assert V.sum() == pytest.approx(h * h)
    np.testing.assert_allclose(K[0].sum(axis=1), 0.0, atol=1e-12)


def test_particles_to_grid_conserves_mass_and_momentum():
    rng = np.random.default_rng(1)
    n = 500
    x = rng.uniform(0, 1, (n, 2))
    v = rng.normal(size=(n, 2))
    m = rng.uniform(0.5, 2.0, n)
    vol = m / 1000
    grid = Grid(0.1, (10, 10))
    mass, mom, nvol = np.zeros(grid.nnodes), np.zeros((grid.nnodes, 2)), np.zeros(grid.nnodes)
    v_old, v_star = np.zeros((grid.nnodes, 2)), np.zeros((grid.nnodes, 2))
    bins = bin_particles(grid, Particles(x, v, np.zeros(n), m, vol))
    g, dt = np.array([0.5, -9.81]), 0.01
    cvol = np.empty(grid.ncells)
    state.particles_to_grid(
        grid, x, v, m, vol, bins.order, bins.start, g, dt, mass, mom, nvol, v_old, v_star, cvol
    )
    assert mass.sum() == pytest.approx(m.sum(), rel=1e-13)
    # the volume on the cell centres (walls mirror): all of it, as the serial kernel has it
    assert cvol.sum() == pytest.approx(vol.sum(), rel=1e-13)
    serial = np.empty(grid.ncells)
    state.cell_volume(grid, x, vol, serial)
    np.testing.assert_allclose(cvol, serial, rtol=1e-12, atol=1e-18)
    np.testing.assert_allclose(mom.sum(axis=0), (m[:, None] * v).sum(axis=0), rtol=1e-12)
    assert nvol.sum() == pytest.approx(vol.sum(), rel=1e-13)
    # nodal velocity and predictor: momentum / mass, + dt g where there is mass, else 0
    has = mass > 0
    np.testing.assert_allclose(v_old[has], mom[has] / mass[has, None], rtol=1e-14)
    np.testing.assert_allclose(v_star[has], v_old[has] + dt * g, rtol=1e-14)
    assert not v_old[~has].any() and not v_star[~has].any()


NONE = (np.zeros(0), np.zeros(0))  # no volume-correction displacement


def test_grid_to_particles_reproduces_linear_fields_and_flip_increments():
    grid = Grid(0.1, (10, 10))
    nodes = grid.node_coordinates()
    v_old = np.zeros((grid.nnodes, 2))
    v_new = np.stack([1 + 2 * nodes[:, 0] - nodes[:, 1], 3 * nodes[:, 1]], axis=1)
    p_node = 5 - 4 * nodes[:, 0] + 7 * nodes[:, 1]
    rng = np.random.default_rng(2)
    x = rng.uniform(0.05, 0.95, (200, 2))
    x0 = x.copy()
    v = np.ones((200, 2))
    p = np.zeros(200)
    dt = 0.01
    exact = np.stack([1 + 2 * x0[:, 0] - x0[:, 1], 3 * x0[:, 1]], axis=1)
    moved = state.grid_to_particles(
        grid, x, v, p, v_old, v_new, p_node, dt, 1.0, np.array([1.0, 1.0]), 1e-9, NONE
    )
    assert moved == 0
    np.testing.assert_allclose(v, 1 + exact, atol=1e-12)  # FLIP: old velocity + increment
    np.testing.assert_allclose(x, x0 + dt * exact, atol=1e-12)  # eq. 21 moves with v^{t+1}
    np.testing.assert_allclose(p, 5 - 4 * x0[:, 0] + 7 * x0[:, 1], atol=1e-12)


def test_grid_to_particles_puts_particles_back_inside_and_counts_them():
    x = np.array([[-0.01, 0.5], [0.5, 1.02], [0.5, 0.5], [1.5, -2.0]])
    v = np.array([[-1.0, 0.0], [0.0, 2.0], [1.0, 1.0], [3.0, -3.0]])
    still = np.zeros((121, 2))  # no grid velocity: FLIP keeps v, particles do not move
    moved = state.grid_to_particles(
        Grid(0.1, (10, 10)),
        x,
        v,
        np.zeros(4),
        still,
        still,
        np.zeros(121),
        0.01,
        1.0,
        np.array([1.0, 1.0]),
        1e-9,
        NONE,
    )
    assert moved == 3
    assert np.all((x >= 0) & (x <= 1))
    np.testing.assert_allclose(x[0], [0.01, 0.5])  # mirrored back across the wall
    np.testing.assert_allclose(x[2], [0.5, 0.5])  # untouched
    assert v[0, 0] == 0.0 and v[1, 1] == 0.0 and v[3, 0] == 0.0 and v[3, 1] == 0.0
    assert v[2, 0] == 1.0


def test_binning_and_volume_fraction():
    grid = Grid(0.01, (10, 30))
    P = seed_box([0, 0], [0.1, 0.195], 0.0025, 1000.0, [0, 0])
    bins = bin_particles(grid, P)
    theta = bins.theta.reshape(30, 10)
    np.testing.assert_allclose(theta[:19], 1.0)
    np.testing.assert_allclose(theta[19], 0.5)
    np.testing.assert_allclose(theta[20:], 0.0)
    counts = bins.counts()
    assert counts.sum() == P.count
    for c in (0, 191, 199):
        members = bins.order[bins.start[c] : bins.start[c + 1]]
        assert np.all(bins.cell[members] == c)


def test_walls_are_one_sided_unless_in_contact():
    ncx, ncy = 2, 2
    n = (ncx + 1) * (ncy + 1)
    v = np.tile([[-1.0, 1.0]], (n, 1))  # moving into the left and top walls
    released = np.zeros((n, 2), dtype=np.bool_)
    pairs = state.wall_pairs((ncx, ncy))
    state.apply_walls(*pairs, False, v, released)
    left = [0, 3, 6]
    top = [6, 7, 8]
    assert np.all(v[left, 0] == 0.0) and np.all(v[top, 1] == 0.0)
    bottom_mid = 1  # leaving the bottom wall upwards: kept
    assert v[bottom_mid, 1] == 1.0
    # every node carries a pressure unknown: every wall node starts in contact
    contact = np.zeros((n, 2), dtype=np.bool_)
    state.start_contact(*pairs, np.zeros((n, 2)), np.zeros(n, dtype=np.int64), contact)
    ix, iy = np.arange(n) % (ncx + 1), np.arange(n) // (ncx + 1)
    np.testing.assert_array_equal(
        contact, np.stack([(ix == 0) | (ix == ncx), (iy == 0) | (iy == ncy)], axis=1)
    )
    v = np.tile([[1.0, 1.0]], (n, 1))
    state.apply_walls(*pairs, True, v, contact)  # in contact, no-slip: all zero
    assert np.all(v[bottom_mid] == 0.0)
    assert np.all(v[4] == 1.0)  # interior node untouched


def test_each_wall_pair_keeps_its_own_condition():
    """A no-slip floor (y_min) under slip walls, every wall node in contact, moving (1, 1):
    the floor's nodes, its corners included, stop; the other walls hold only their normal."""
    n = 9  # 2 x 2 cells
    node, axis, sign = state.wall_pairs((2, 2))
    contact = np.zeros((n, 2), dtype=np.bool_)
    state.start_contact(node, axis, sign, np.zeros((n, 2)), np.zeros(n, dtype=np.int64), contact)
    v = np.ones((n, 2))
    state.apply_walls(node, axis, sign, (axis == 1) & (sign < 0), v, contact)
    np.testing.assert_array_equal(
        v,
        [
            [0, 0],
            [0, 0],
            [0, 0],  # the floor
            [0, 1],
            [1, 1],
            [0, 1],  # the side walls' normal
            [0, 0],
            [1, 0],
            [0, 0],
        ],
    )  # the top's normal, corners


def test_contact_starts_where_material_presses_and_releases_under_tension():
    ncx, ncy = 2, 2
    n = (ncx + 1) * (ncy + 1)
    row = -np.ones(n, dtype=np.int64)
    row[[0, 1]] = [0, 1]  # two bottom nodes carry unknowns
    vstar = np.zeros((n, 2))
    vstar[3, 0] = -1.0  # left wall node without unknown pressing into the wall
    vstar[5, 0] = -1.0  # right wall node without unknown leaving the wall
    vstar[1, 1] = 2.0  # bottom node with unknown leaving the floor
    contact = np.ones((n, 2), dtype=np.bool_)
    pairs = state.wall_pairs((ncx, ncy))
    state.start_contact(*pairs, vstar, row, contact)
    assert contact[0].tolist() == [True, True] and contact[1].tolist() == [False, True]
    assert contact[3, 0] and not contact[5, 0] and not contact[4].any()
    p_node = np.zeros(n)
    p_node[1] = -5.0  # tension at the node that leaves the floor: released
    p_node[0] = -5.0  # tension, but v* does not leave the walls: kept
    assert state.release_contact(*pairs, vstar, row, p_node, contact) == 1
    assert not contact[1, 1] and contact[0].all()


@pytest.mark.parametrize("min_rows", [1, 2])
def test_strips_cover_the_rows_with_room_between_and_balance_the_work(min_rows):
    strips = state.strips

    rng = np.random.default_rng(5)
    for nrows in (1, 2, 3, 7, 40, 111):
        work = rng.integers(0, 50, nrows)
        work[: nrows // 3] = 0  # empty rows at the bottom
        row_cum = np.concatenate(([0], np.cumsum(work)))
        bounds = np.empty(17, dtype=np.int64)
        k = strips(row_cum, 16, min_rows, bounds)
        b = bounds[: k + 1]
        assert k >= 1 and b[0] == 0 and b[-1] == nrows
        if nrows >= min_rows:
            assert np.all(np.diff(b) >= min_rows)  # strips two apart never touch
        if nrows >= 16 * min_rows and row_cum[-1] > 0:
            # no strip holds much more than its share plus the largest row
            share = row_cum[-1] / k
            assert np.all(np.diff(row_cum[b]) <= share + work.max())


def test_particle_divergence_tensors_match_the_full_particle_tensors():
    """The surface cells' C and V (the quadrature called without K) equal those of the full
    material-point quadrature, cell for cell."""
    rng = np.random.default_rng(1)
    x = rng.uniform(0, 1, (500, 2))
    vol = rng.uniform(0.5, 1.0, 500)
    grid = Grid(0.1, (10, 10))
    bins = bin_particles(grid, Particles(x, 0 * x, 0 * vol, vol, vol))
    cells = np.array([0, 5, 23, 99])
    K, C, V = np.zeros((4, 4, 4)), np.zeros((4, 4, 4, 2)), np.zeros((4, 4))
    state.particle_cell_tensors(x, vol, bins.order, bins.start, cells, 0.1, (10, 10), K, C, V)
    C2, V2 = np.zeros((4, 4, 4, 2)), np.zeros((4, 4))
    state.particle_cell_tensors(
        x, vol, bins.order, bins.start, cells, 0.1, (10, 10), np.zeros((0, 4, 4)), C2, V2
    )
    np.testing.assert_allclose(C2, C, rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(V2, V, rtol=1e-13, atol=1e-15)
    assert V.sum() > 0


def test_reach_walks_the_couplings_from_the_seeds_and_no_further():
    """Two chains, 0-1-2 and 3-4 (ELL rows: the diagonal slot, then the neighbours): a
    seed at 0 reaches its chain only; seeds in both reach every row; none reaches none."""
    cols = np.array([[0, 1, -1], [1, 0, 2], [2, 1, -1], [3, 4, -1], [4, 3, -1]])
    seed = np.zeros(5, dtype=bool)
    np.testing.assert_array_equal(state.reach(cols, seed), [False] * 5)
    seed[0] = True
    np.testing.assert_array_equal(state.reach(cols, seed), [True, True, True, False, False])
    seed[4] = True
    np.testing.assert_array_equal(state.reach(cols, seed), [True] * 5)
