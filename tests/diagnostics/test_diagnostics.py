"""Front and column height follow the VOF definition exactly."""

import numpy as np
import pytest

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
