"""The pressure solvers agree with each other and report failure."""

import numpy as np
import pytest
import scipy.sparse.linalg as spla

from mpmflow.linalg.solvers import LinearSolver, PressureMatrix


def poisson_ell(nnx, nny, mask):
    """Q1 9-point Laplacian on the masked nodes, Dirichlet outside, in ELL form."""
    row = -np.ones(nnx * nny, dtype=np.int64)
    nodes = np.flatnonzero(mask.ravel())
    row[nodes] = np.arange(nodes.size)
    cols = -np.ones((nodes.size, 9), dtype=np.int64)
    vals = np.zeros((nodes.size, 9))
    for r, i in enumerate(nodes):
        ix, iy = i % nnx, i // nnx
        for dy in range(3):
            for dx in range(3):
                jx, jy = ix + dx - 1, iy + dy - 1
                s = 3 * dy + dx
                if dx == 1 and dy == 1:
                    cols[r, s], vals[r, s] = r, 8 / 3
                elif 0 <= jx < nnx and 0 <= jy < nny and row[jy * nnx + jx] >= 0:
                    cols[r, s], vals[r, s] = row[jy * nnx + jx], -1 / 3
    return PressureMatrix(cols, vals, nodes, (nnx, nny))


@pytest.fixture(scope="module")
def system():
    nnx, nny = 41, 37
    yy, xx = np.mgrid[0:nny, 0:nnx]
    mask = ((xx - 20) ** 2 + (yy - 18) ** 2 < 15**2) | ((xx > 3) & (xx < 10) & (yy > 2))
    m = poisson_ell(nnx, nny, mask.astype(bool))
    b = np.random.default_rng(0).normal(size=m.nodes.size)
    return m, b


def test_csr_is_symmetric(system):
    m, _ = system
    A = m.csr()
    assert abs(A - A.T).max() == 0.0
    assert A.has_sorted_indices


@pytest.mark.parametrize("method", ["multigrid", "amg", "direct"])
def test_solvers_match_sparse_lu(system, method):
    m, b = system
    exact = spla.spsolve(m.csr().tocsc(), b)
    s = LinearSolver(method, 1e-10, 200)
    s.prepare(m)
    res = s.solve(b)
    assert res.converged and res.residual <= 1e-10
    np.testing.assert_allclose(res.x, exact, rtol=0, atol=1e-8 * np.abs(exact).max())


def test_multigrid_converges_in_few_iterations(system):
    m, b = system
    s = LinearSolver("multigrid", 1e-8, 200)
    s.prepare(m)
    res = s.solve(b)
    assert res.iterations <= 20  # mesh-independent convergence of the V-cycle


def test_multigrid_warm_start_from_solution_takes_no_iterations(system):
    m, b = system
    s = LinearSolver("multigrid", 1e-8, 200)
    s.prepare(m)
    x = s.solve(b).x
    again = s.solve(b, x0=x)
    assert again.iterations == 0 and again.converged


def test_iteration_limit_is_reported_not_hidden(system):
    m, b = system
    s = LinearSolver("multigrid", 1e-14, 1)
    s.prepare(m)
    res = s.solve(b)
    assert not res.converged and res.residual > 1e-14


def test_large_multigrid_solve_is_right_and_independent_of_threads():
    # above state.PARALLEL_ROWS the row loops and dot products run on all threads:
    # the answer must match sparse LU and be bit-identical on 1 and 2 threads
    from mpmflow import state

    nnx, nny = 121, 111
    yy, xx = np.mgrid[0:nny, 0:nnx]
    mask = (yy > 0) & (xx > 0) & (xx < nnx - 1) & (yy < 0.8 * nny + 5 * np.sin(xx / 7))
    m = poisson_ell(nnx, nny, mask)
    assert m.nodes.size > state.PARALLEL_ROWS
    b = np.random.default_rng(3).normal(size=m.nodes.size)
    exact = spla.spsolve(m.csr().tocsc(), b)
    if state.max_threads() < 2:
        pytest.skip("one thread only: nothing to compare")
    answers = []
    before = state.max_threads()
    try:
        for threads in (1, 2):
            state.set_threads(threads)
            s = LinearSolver("multigrid", 1e-10, 200)
            s.prepare(m)
            res = s.solve(b)
            assert res.converged and res.iterations <= 20
            answers.append(res.x)
    finally:
        state.set_threads(before)
    np.testing.assert_allclose(answers[0], exact, rtol=0, atol=1e-8 * np.abs(exact).max())
    for x in answers[1:]:
        assert np.array_equal(x, answers[0])


def star_laplacian(dims, mask):
    """The (2D + 1)-point Laplacian on the masked points of a grid (Dirichlet outside) in the
    multigrid's ELL form, 3^D slots a row, the neighbour at offset d in slot sum (d_k + 1) 3^k:
    the volume correction's operator on the cells."""
    D = len(dims)
    node = np.flatnonzero(mask.ravel(order="F"))  # axis 0 fastest
    row = -np.ones(mask.size, dtype=np.int64)
    row[node] = np.arange(node.size)
    coords = np.stack(np.unravel_index(node, dims, order="F"), axis=1)
    cols = -np.ones((node.size, 3**D), dtype=np.int64)
    vals = np.zeros((node.size, 3**D))
    centre = 3**D // 2
    cols[:, centre], vals[:, centre] = np.arange(node.size), 2.0 * D
    for k in range(D):
        for d in (-1, 1):
            c = coords.copy()
            c[:, k] += d
            inside = (c[:, k] >= 0) & (c[:, k] < dims[k])
            j = np.full(node.size, -1)
            j[inside] = row[np.ravel_multi_index(c[inside].T, dims, order="F")]
            held = j >= 0
            cols[held, centre + d * 3**k], vals[held, centre + d * 3**k] = j[held], -1.0
    return cols, vals, node


@pytest.mark.parametrize("dims", [(130, 70), (30, 26, 22)], ids=["2D", "3D"])
def test_a_star_operator_iterates_on_its_star_with_the_same_bits(dims):
    """The multigrid keeps a (2D + 1)-point operator on its 2D + 1 slots as well
    (src/core/multigrid.hpp, star_slots) and iterates on those: the same sums in the same
    order as on the 3^D slots. The same operator with a corner slot filled by a zero entry
    (which changes no sum) is iterated on the 3^D slots: both must give the same bits, on
    a grid large enough for the threaded row loops."""
    from mpmflow import state
    from mpmflow.state.pressure import multigrid

    grids = np.meshgrid(*[np.linspace(-1, 1, n) for n in dims], indexing="ij")
    mask = sum(g**2 for g in grids) < 0.9
    cols, vals, node = star_laplacian(dims, mask)
    assert node.size > state.PARALLEL_ROWS
    full_cols = cols.copy()
    full_cols[:, 0] = np.arange(node.size)  # slot 0 (offset -1 on every axis): 0 * x_r
    b = np.random.default_rng(5).normal(size=node.size)
    answers = []
    for c in (cols, full_cols):
        x = np.zeros(node.size)
        iterations, residual = multigrid(c, vals, node, dims).pcg(b, x, 1e-10, 100, 1)
        assert residual <= 1e-10 and 0 < iterations <= 30
        answers.append((iterations, x))
    assert answers[0][0] == answers[1][0]
    assert np.array_equal(answers[0][1], answers[1][1])
    exact = spla.spsolve(PressureMatrix(cols, vals, node, dims).csr().tocsc(), b)
    np.testing.assert_allclose(answers[0][1], exact, rtol=0, atol=1e-8 * np.abs(exact).max())


def test_a_star_changed_in_place_is_read_again_after_refresh():
    """The pressure's contact rounds change the finest level's values in place between
    solves (complementarity.hpp, hold_at_zero) and then call refresh(): a star's iteration
    form copies its values, so without refresh the solve would answer the old matrix.
    After the change and refresh, the solution satisfies the changed system."""
    from mpmflow.state.pressure import multigrid

    dims = (40, 30)
    grids = np.meshgrid(*[np.linspace(-1, 1, n) for n in dims], indexing="ij")
    cols, vals, node = star_laplacian(dims, sum(g**2 for g in grids) < 0.9)
    b = np.random.default_rng(7).normal(size=node.size)
    mg = multigrid(cols, vals, node, dims)
    mg.pcg(b, np.zeros(node.size), 1e-10, 100, 1)
    vals[:, 3**2 // 2] *= 1.5  # the diagonal changed in place, as the held array
    mg.refresh()
    x = np.zeros(node.size)
    iterations, residual = mg.pcg(b, x, 1e-10, 100, 1)
    assert residual <= 1e-10
    r = b - PressureMatrix(cols, vals, node, dims).csr() @ x
    assert np.linalg.norm(r) <= 1e-9 * np.linalg.norm(b)
