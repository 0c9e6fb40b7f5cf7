"""The measured references of the frictional and granular columns (data/validation/) and
the measures read from a run: exact on made-up particles, and the data's own numbers as
data/validation/README.md states them."""

import math

import numpy as np
import pytest

from mpmflow.validation import frictional_column as bui
from mpmflow.validation import granular_cd


def test_bui_measured_line_and_deposit():
    surface, failure = bui.measured()
    assert surface.shape == (23, 2) and failure.shape == (9, 2)
    angle, foot = bui.line_fit(failure)
    assert angle == pytest.approx(33.0, abs=0.05)
    assert foot == pytest.approx(0.179, abs=5e-4)
    assert surface[:, 0].max() == pytest.approx(0.4423, abs=1e-4)  # the toe
    # the digitisation keeps the column's area (0.2 m x 0.1 m): 0.0203 m^2, 1.5% more
    assert np.trapezoid(surface[:, 1], surface[:, 0]) == pytest.approx(0.0203, abs=5e-5)


def test_failure_line_is_the_edge_of_the_particles_that_stayed():
    """Particles left of a line at 40 degrees from a foot at 0.15 m do not move, those
    right of it move by 3 cm: the measure finds that line to within a particle spacing."""
    s = 0.00125
    g = np.arange(0.5 * s, 0.2, s)
    x0 = np.array([(x, y) for y in np.arange(0.5 * s, 0.1, s) for x in g])
    edge = 0.15 - x0[:, 1] / math.tan(math.radians(40.0))
    x = x0.copy()
    x[x0[:, 0] > edge] += (0.03, -0.01)
    x[x0[:, 0] <= edge] += (1e-4, 0.0)  # an elastic settlement, well under 2 mm
    angle, foot = bui.line_fit(bui.failure_points(x0, x))
    assert angle == pytest.approx(40.0, abs=0.5)
    assert foot == pytest.approx(0.15, abs=s)


def test_contact_dynamics_runouts_as_the_data_readme_states():
    runouts = [granular_cd.contact_runout(c) for c in granular_cd.COLUMNS]
    assert runouts == pytest.approx([0.94, 3.48, 12.43], abs=0.01)
    for c in granular_cd.COLUMNS:
        first = granular_cd.profiles(c)[0]
        # the first profile is the column: its half-width and height as the case takes them
        assert 0.5 * np.ptp(first[:, 0]) == pytest.approx(c.L0, abs=0.6 * granular_cd.D)
        assert first[:, 1].max() == pytest.approx(c.H0, rel=0.01)


@pytest.mark.slow
def test_mu_i_column_runs_out_short_of_the_grains():
    """Lagrée et al. found their plane-strain mu(I) continuum's final run-out short of the
    contact dynamics': so is mpmflow's at a = 0.5 (12.5 cells across L0, 2 s), by less than
    the report's 15% plus the coarse mesh's (the shortfall halves from 12.5 to 25 cells)."""
    column = granular_cd.COLUMNS[0]
    r = granular_cd.collapse(column, 12.5)
    assert 0.75 < r.runout / granular_cd.contact_runout(column) < 1.0
