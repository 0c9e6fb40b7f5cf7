"""Front and column height follow the VOF definition exactly; the particles' totals at an
output time are NumPy's sums and extremes."""

import numpy as np
import pytest

from mpmflow import state
from mpmflow.diagnostics.measures import front_and_height, last_crossing
from mpmflow.grid import Grid


def test_last_crossing_interpolates_between_cell_centres():
    centres = np.array([0.5, 1.5, 2.5, 3.5])
    assert last_crossing(np.array([1.0, 0.75, 0.25, 0.0]), centres, 4.0) == pytest.approx(2.0)
    assert last_crossing(np.array([1.0, 1.0, 1.0, 0.6]), centres, 4.0) == 4.0  # last cell full
    assert np.isnan(last_crossing(np.array([0.4, 0.1, 0.0, 0.0]), centres, 4.0))
    # a detached blob further right counts: the *last* crossing
    assert last_crossing(np.array([1.0, 0.0, 1.0, 0.0]), centres, 4.0) == pytest.approx(3.0)


def test_front_is_the_largest_over_rows_and_height_uses_the_wall_column():
    grid = Grid(1.0, (4, 3))
    f = np.zeros((4, 3))  # [cx, cy]
    f[:, 0] = [1.0, 1.0, 0.8, 0.0]  # bottom row: crossing at 2.5 + 0.3/0.8
    f[:, 1] = [1.0, 0.5, 0.0, 0.0]  # middle row: crossing at 1.5
    f[0, 2] = 0.25  # wall column: 1.0, 1.0, 0.25 -> crossing at 1.5 + 0.5/0.75
    theta = f.T.ravel()  # flat cell order, x fastest
    front, height = front_and_height(grid, theta)
    assert front == pytest.approx(2.5 + 0.3 / 0.8)
    assert height == pytest.approx(1.5 + 0.5 / 0.75)
    f[0, 2] = 0.6  # top cell at least half full: the height is the top wall
    assert front_and_height(grid, f.T.ravel())[1] == 3.0


def _particles(n, dim, seed=0):
    rng = np.random.default_rng(seed)
    x = rng.uniform(0.0, 2.0, (n, dim))
    v = rng.normal(0.0, 1.5, (n, dim))
    mass = rng.uniform(0.5, 2.0, n)
    pressure = rng.normal(1e3, 3e2, n)
    return x, v, mass, pressure


@pytest.mark.parametrize("dim", [2, 3])
def test_the_totals_are_numpys_sums_and_extremes(dim):
    x, v, mass, pressure = _particles(50_000, dim)
    g = [0.0] * (dim - 1) + [-9.81]
    t = state.particle_totals(x, v, mass, pressure, g)
    assert t.kinetic == pytest.approx(0.5 * np.sum(mass * np.sum(v**2, axis=1)), rel=1e-12)
    assert t.potential == pytest.approx(-np.sum(mass * (x @ np.asarray(g))), rel=1e-12)
    speed = np.sqrt(np.sum(v**2, axis=1))
    assert t.fastest == int(np.argmax(speed)) and t.max_speed == speed.max()  # exact
    assert t.max_pressure == pressure.max()
    assert (t.nonfinite, t.first_nonfinite) == (0, -1)


def test_the_totals_count_and_leave_out_the_particles_that_are_not_finite():
    x, v, mass, pressure = _particles(20_000, 2, seed=1)
    v[[0, 1]] = 3.0 * np.abs(v).max()  # two equally fastest: the first is named
    v[17_000, 1], x[9_000, 0], v[19_999, 0] = np.nan, np.inf, -np.inf
    bad = np.zeros(20_000, dtype=bool)
    bad[[9_000, 17_000, 19_999]] = True
    t = state.particle_totals(x, v, mass, pressure, [0.0, -9.81])
    assert (t.nonfinite, t.first_nonfinite, t.fastest) == (3, 9_000, 0)
    kinetic = 0.5 * np.sum((mass * np.sum(v**2, axis=1))[~bad])
    assert t.kinetic == pytest.approx(kinetic, rel=1e-12)
    empty = state.particle_totals(
        np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0), np.zeros(0), [0.0, 0.0, -9.81]
    )
    assert (empty.kinetic, empty.potential, empty.fastest) == (0.0, 0.0, -1)
    assert np.isnan(empty.max_speed) and np.isnan(empty.max_pressure)


def test_the_totals_have_the_same_bits_on_one_and_two_threads():
    x, v, mass, pressure = _particles(200_000, 3, seed=2)
    before = state.max_threads()
    try:
        state.set_threads(1)
        one = state.particle_totals(x, v, mass, pressure, [0.0, 0.0, -9.81])
        state.set_threads(2)
        two = state.particle_totals(x, v, mass, pressure, [0.0, 0.0, -9.81])
    finally:
        state.set_threads(before)
    assert one == two
