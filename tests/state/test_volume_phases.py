"""The volume correction in phases (issue 28, docs/design/mpi.md, section 2): volume_system,
a solve of its cell-centred system from Python and volume_apply are finish's volume
correction; Options.pockets false leaves the volume system's sealed pockets to the caller."""

import numpy as np
import pytest
import scipy.sparse as sp
from conftest import EXAMPLES
from scipy.sparse import csgraph
from scipy.sparse.linalg import spsolve
from test_phases import DT, POCKET_2D, arrays

from mpmflow import Simulation, load_case, state

# the volume solve of the twins compared: the core's multigrid PCG to this relative residual,
# Python's a direct solve (round-off)
TIGHT = 1e-12
# the particles of the two agree to this (m): with both residuals <= 1e-12 the solutions
# differ by at most cond(A) 1e-12 |q| (cond(A) ~ the rows, a few hundred: ~1e-9 |q|, |q| ~
# 0.01), and the displacement is volume_rate h grad q (0.5 x 0.01 m x 2 |dq|): ~1e-13 m
POSITION = 1e-12
# the sealed pool as stepped is at rest and at its volume: the volume system's right-hand
# side there (a cell's volume fraction - 1, dimensionless) is 0 while every wall holds the
# water. A wall's reaction at rest is 0 +- round-off, so whether it lets go is decided by
# the last bits of the direct pressure solve, which follow the BLAS kernels (OpenBLAS's
# SkylakeX and Nehalem kernels release a node at the second step, its Haswell, Zen and
# Prescott kernels none): released, the water moves by mm/s and its cells read up to 1.5e-4.
# The test compresses cells by 10% and more; 1e-3 (0.1% of a cell) tells the two apart
UNCOMPRESSED = 1e-3


def simulation(path, settings=(), steps=30):
    """The case stepped ``steps`` steps of DT with the pressure solved from Python (direct),
    so that a test can run the pressure phases of the next step as the scheme does."""
    case = load_case(path, ["output.snapshots=false", "solver.linear_solver=direct", *settings])
    sim = Simulation(case)
    if steps:
        sim.scheme.advance(DT, steps)
    return sim


def dam_break(settings=(), steps=30):
    """The dam break on a 0.01 m grid after ``steps`` steps (the column falling)."""
    return simulation(EXAMPLES / "dam_break.toml", ["grid.spacing=0.01", *settings], steps)


def pool(tmp_path, steps=5):
    """Water trapped between a disc and two walls (tests/state/test_phases.py)."""
    path = tmp_path / "pocket.toml"
    path.write_text(POCKET_2D)
    return simulation(path, steps=steps)


def predicted(sim, O):
    """The next step up to its volume correction: predict (with the cells' volume), the
    pressure step (solved by SciPy's direct solver, plugged into the core's step)."""
    core = sim.scheme.core
    core.predict(*arrays(sim), O, True)
    assert core.pressure_solve(O, state.Report()) == state.OK
    return core


def matrix(core):
    """The last volume_system's matrix as a CSR matrix (from its ELL views)."""
    cols, vals = core.volume_cols, core.volume_vals
    n = cols.shape[0]
    row = np.repeat(np.arange(n), cols.shape[1])
    used = cols.ravel() >= 0
    return sp.csr_matrix((vals.ravel()[used], (row[used], cols.ravel()[used])), shape=(n, n))


def finished(sim, O):
    """The step finished by the core (finish with the volume correction); its report."""
    core = predicted(sim, O)
    report = state.Report()
    assert core.finish(*arrays(sim), O, True, report) == state.OK
    return report


def test_a_solve_from_python_between_volume_system_and_volume_apply_is_finish():
    one, two = dam_break(), dam_break()
    O = one.scheme.options(DT)
    O.volume_tol = TIGHT
    report = finished(one, O)
    core = predicted(two, O)
    core.correct(O)
    n = core.volume_system(O)
    assert n == core.volume_rows.size > 0 and core.volume_anchored
    A, rhs = matrix(core), core.volume_rhs.copy()
    assert abs(A - A.T).max() == 0.0
    q = spsolve(A.tocsc(), rhs)
    assert np.linalg.norm(A @ q - rhs) <= TIGHT * np.linalg.norm(rhs)
    assert core.volume_apply(O, q) == report.clamped
    undisplaced = [a.copy() for a in arrays(two)]
    assert core.to_particles(*arrays(two), O, True) == report.moved
    assert np.abs(two.particles.x - one.particles.x).max() <= POSITION
    # the correction moves positions only: velocities, pressure, mass and volume are exact
    for name in ("v", "mass", "volume", "pressure"):
        assert np.array_equal(getattr(two.particles, name), getattr(one.particles, name)), name
    Q = one.scheme.core.volume_q
    assert np.abs(core.volume_q - Q).max() <= 1e-9 * np.abs(Q).max()
    # and it did move them: by far more than the bound
    core.to_particles(*undisplaced, O, False)
    assert np.abs(undisplaced[0] - two.particles.x).max() > 1e6 * POSITION


def test_volume_apply_of_the_cores_own_solution_is_finish_bit_for_bit():
    """At the case's own tolerance: the core's solution (volume_q on the rows) put back
    through volume_apply moves the particles exactly as finish did."""
    one, two = dam_break(), dam_break()
    O = one.scheme.options(DT)
    report = finished(one, O)
    core = predicted(two, O)
    core.correct(O)
    n = core.volume_system(O)
    rows = core.volume_rows
    cell_row = np.full(core.cell_row.size, -1)
    cell_row[rows] = np.arange(n)
    assert np.array_equal(core.cell_row, cell_row)
    Q = one.scheme.core.volume_q.copy()
    assert core.volume_apply(O, Q[rows]) == report.clamped
    assert core.to_particles(*arrays(two), O, True) == report.moved
    for a, b in zip(arrays(one), arrays(two)):
        assert np.array_equal(a, b)
    assert np.array_equal(core.volume_q, Q)


@pytest.mark.parametrize("steps", [0, 30], ids=["at rest", "falling"])
def test_volume_air_marks_the_rows_next_to_an_empty_cell(steps):
    """volume_air: the rows with a face neighbour inside the domain that holds no row (the
    dam break has no obstacle: every such neighbour is an empty cell)."""
    sim = dam_break(steps=steps)
    O = sim.scheme.options(DT)
    core = predicted(sim, O)
    n = core.volume_system(O)
    nx, ny = (int(c) for c in sim.grid.cells)
    cell_row = core.cell_row.reshape(ny, nx)
    empty = np.pad(cell_row < 0, 1, constant_values=False)  # outside: a wall, no air
    touches = empty[:-2, 1:-1] | empty[2:, 1:-1] | empty[1:-1, :-2] | empty[1:-1, 2:]
    air = core.volume_air
    assert air.shape == (n,) and air.dtype == np.bool_
    assert np.array_equal(air, touches.ravel()[core.volume_rows])
    assert air.any() and not air.all() and core.volume_anchored
    if steps == 0:  # the column at rest: its top row touches air, its inside does not
        j, i = divmod(int(core.volume_rows[0]), nx)  # the corner cell at the floor, x = 0
        full = cell_row[j : j + 20, i : i + 11] >= 0
        assert full.all()
        inside = cell_row[j + 1 : j + 19, i : i + 10]
        assert not air[inside.ravel()].any()
        top = cell_row[j + 22, i : i + 10]
        assert (top >= 0).all() and air[top].all()


def pockets_of(core):
    """The volume system's parts with no row touching air (their rows, ascending)."""
    _, label = csgraph.connected_components(matrix(core), directed=False)
    air = core.volume_air
    return [np.flatnonzero(label == k) for k in np.unique(label) if not air[label == k].any()]


def pockets_on_and_off(core, O):
    """The volume system with O.pockets, then without; checks what stays and returns the
    first's (cols, vals, rhs) and the second's, and its pockets."""
    O.pockets = True
    core.volume_system(O)
    names = ("volume_cols", "volume_vals", "volume_rhs")
    on = tuple(getattr(core, k).copy() for k in names)
    same = ("volume_rows", "volume_air", "cell_row")
    kept = {k: getattr(core, k).copy() for k in same}
    O.pockets = False
    core.volume_system(O)
    assert core.volume_anchored
    for k in same:
        assert np.array_equal(getattr(core, k), kept[k]), k
    return on, tuple(getattr(core, k).copy() for k in names), pockets_of(core)


def check_pockets(on, off, pockets):
    """Pockets on, the volume system differs from pockets off only in the sealed pockets'
    rows: there the right-hand side loses its mean over the pocket (summed in row order, as
    the core sums it), the held row (the pocket's first: every height is 0) is 0 and loses
    its couplings, both ways."""
    cols, vals, rhs = (a.copy() for a in off)
    expected = rhs.copy()
    for rows in pockets:
        total = 0.0
        for r in rows:
            total += float(rhs[r])
        expected[rows] = rhs[rows] - total / len(rows)
        expected[rows[0]] = 0.0
    assert np.array_equal(on[2], expected)
    outside = np.ones(rhs.size, bool)
    outside[np.concatenate(pockets)] = False
    assert np.array_equal(on[2][outside], rhs[outside])
    centre = cols.shape[1] // 2
    for rows in pockets:
        r = rows[0]
        for s in range(cols.shape[1]):
            j = cols[r, s]
            if s == centre or j < 0:
                continue
            back = cols[j] == r
            cols[r, s], vals[r, s] = -1, 0.0
            cols[j, back], vals[j, back] = -1, 0.0
    assert np.array_equal(on[0], cols) and np.array_equal(on[1], vals)
    assert not np.array_equal(on[1], off[1])  # a held row lost its couplings


def test_options_pockets_false_leaves_the_volume_systems_sealed_pockets(tmp_path):
    sim = pool(tmp_path)
    O = sim.scheme.options(DT)
    assert O.pockets
    core = predicted(sim, O)
    core.correct(O)
    on, off, pockets = pockets_on_and_off(core, O)
    assert [len(rows) for rows in pockets] == [8]  # the water between the disc and the walls
    check_pockets(on, off, pockets)
    # as stepped, every cell of the pocket lies next to the disc, where only an excess
    # counts, and the trapped water is not compressed: its right-hand side is 0 either way
    # (to UNCOMPRESSED: on some BLAS kernels the pool has started to move)
    assert np.abs(off[2][pockets[0]]).max() <= UNCOMPRESSED
    assert np.abs(on[2] - off[2]).max() <= UNCOMPRESSED
    # compressed (the cells' volume is a view a caller may write before volume_system, as
    # a rank writes its ring's): an excess that differs from cell to cell, moved about
    cells = core.volume_rows[pockets[0]]
    core.cell_vol[cells] *= 1.1 + 0.05 * np.arange(cells.size)
    on, off, again = pockets_on_and_off(core, O)
    assert [list(rows) for rows in again] == [list(pockets[0])]
    assert (off[2][pockets[0]] > 0).sum() >= 2  # an excess where the cells were full
    check_pockets(on, off, again)
    assert np.abs(on[2] - off[2]).max() > 10 * UNCOMPRESSED  # the pocket's mean taken off


def test_volume_apply_ignores_q_without_a_system_and_refuses_one_of_another_size():
    sim = dam_break(steps=0)  # a fresh state: no volume_system yet
    core, O = sim.scheme.core, sim.scheme.options(DT)
    assert core.volume_rows.size == 0 and core.volume_cols.shape == (0, 9)
    assert core.volume_apply(O, np.zeros(3)) == 0
    predicted(sim, O)
    n = core.volume_system(O)
    with pytest.raises(ValueError, match="one value per row"):
        core.volume_apply(O, np.zeros(n + 1))


def test_the_volume_phases_need_the_volume_correction():
    sim = dam_break(["solver.volume_correction=0"], steps=2)
    core, O = sim.scheme.core, sim.scheme.options(DT)
    core.predict(*arrays(sim), O, False)
    for name in ("volume_rows", "volume_rhs", "volume_air", "cell_row"):
        assert getattr(core, name).size == 0, name
    assert core.volume_cols.shape == core.volume_vals.shape == (0, 9)
    assert not core.volume_anchored
    with pytest.raises(RuntimeError, match="without the volume correction"):
        core.volume_system(O)
    with pytest.raises(RuntimeError, match="without the volume correction"):
        core.volume_apply(O, np.zeros(0))
