"""A column of water at rest stays at rest with hydrostatic pressure (default settings)."""

import numpy as np
import pytest
from conftest import EXAMPLES, make_case

from mpmflow import Simulation, load_case
from mpmflow.geometry.seeding import build_particles
from mpmflow.grid import Grid
from mpmflow.simulation.setup import make_scheme

RHO, G = 1000.0, 9.81


@pytest.mark.parametrize("depth, tolerance", [(0.2, 0.02), (0.195, 0.05)])
def test_column_at_rest_for_one_second(depth, tolerance):
    """Acceptance: no particle faster than 0.01 m/s, pressure L2 error <= 2% (surface on a
    grid line) and <= 5% (half a cell off it), with the example's default settings."""
    case = load_case(
        EXAMPLES / "hydrostatic.toml", [f"bodies.0.max=[0.1, {depth}]", "output.snapshots=false"]
    )
    sim = Simulation(case)
    sim.run()
    assert sim.time == pytest.approx(1.0)
    assert np.nanmax(sim.series("max_speed")) < 0.01
    P = sim.particles
    exact = RHO * G * (depth - P.x[:, 1])
    err = np.sqrt(np.sum((P.pressure - exact) ** 2) / np.sum(exact**2))
    assert err <= tolerance
    # what the sub-cell free surface achieves is far better than the floor: the column is
    # exact up to the pressure solve's tolerance (solver.tolerance = 1e-8, relative)
    assert np.nanmax(sim.series("max_speed")) < 1e-8
    assert err < 100 * case.solver.tolerance


@pytest.mark.parametrize("depth", [0.1913, 0.1955, 0.1987, 0.2081])
def test_subcell_surface_makes_one_step_exactly_hydrostatic(depth):
    """For a flat surface at any height inside a cell, one projection step from rest gives
    the exact linear pressure and zero velocity (ghost-fluid extrapolation + wall term)."""
    spacing, ppc = 0.01, 4
    # fill to the nearest particle row below `depth`, then the true surface is there
    dp = spacing / ppc
    top = np.floor(depth / dp) * dp
    case = make_case(body=((0, 0), (0.1, top)), spacing=spacing, ppc=ppc)
    grid = Grid.of_case(case)
    P = build_particles(case, grid)
    scheme = make_scheme(case, grid, P)
    scheme.advance(1e-3, 1)
    exact = RHO * G * (top - P.x[:, 1])
    assert np.abs(P.v).max() < 1e-10
    # exact up to the pressure solve's relative tolerance
    np.testing.assert_allclose(
        P.pressure, exact, rtol=0, atol=100 * case.solver.tolerance * exact.max()
    )


def test_no_slip_walls_keep_the_column_at_rest_too():
    case = load_case(
        EXAMPLES / "hydrostatic.toml",
        ["domain.walls=no_slip", "time.end=0.2", "output.snapshots=false"],
    )
    sim = Simulation(case)
    sim.run()
    assert np.nanmax(sim.series("max_speed")) < 1e-8
