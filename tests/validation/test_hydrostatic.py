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


@pytest.mark.parametrize("shallow", ["auto", 0.3])
@pytest.mark.parametrize(
    "depth, ppc", [(0.1913, 4), (0.1926, 4), (0.1955, 4), (0.1987, 4), (0.2081, 4), (0.1938, 8)]
)
def test_subcell_surface_makes_one_step_exactly_hydrostatic(depth, ppc, shallow):
    """For a flat surface at any height inside a cell, one projection step from rest gives
    the exact linear pressure and zero velocity (ghost-fluid extrapolation + wall term). The
    surface lies 0.125, 0.25, 0.5, 0.75, 0.75 and 0.375 of a cell above the top node row;
    with solver.shallow_fraction = 0.3 the first two rows lie within it and are interpolated
    between the row below and p = 0 at the surface instead of being unknowns ("auto" takes
    no shallow nodes at this step of 1 ms: 0.24 cells of free fall a step)."""
    spacing = 0.01
    # fill to the nearest particle row below `depth`, then the true surface is there
    dp = spacing / ppc
    top = np.floor(depth / dp) * dp
    case = make_case(
        body=((0, 0), (0.1, top)), spacing=spacing, ppc=ppc, solver={"shallow_fraction": shallow}
    )
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


def test_a_row_of_nodes_near_the_surface_is_interpolated_not_solved():
    """A surface a quarter of a cell above a node row: with solver.shallow_fraction = 0.3 that
    row of 11 nodes is not among the unknowns, with 0 it is; the pressure is the same linear
    field either way (test above)."""
    top = 0.1925  # a quarter of a cell above the node row at 0.19 m (particle rows 2.5 mm apart)
    rows = {}
    for shallow in (0.0, 0.3):
        case = make_case(body=((0, 0), (0.1, top)), solver={"shallow_fraction": shallow})
        grid = Grid.of_case(case)
        P = build_particles(case, grid)
        scheme = make_scheme(case, grid, P)
        scheme.advance(1e-3, 1)
        rows[shallow] = scheme.core.rows.size
        assert np.abs(P.v).max() < 1e-10
    assert rows[0.0] - rows[0.3] == 11


def test_no_slip_walls_keep_the_column_at_rest_too():
    case = load_case(
        EXAMPLES / "hydrostatic.toml",
        ["domain.walls=no_slip", "time.end=0.2", "output.snapshots=false"],
    )
    sim = Simulation(case)
    sim.run()
    assert np.nanmax(sim.series("max_speed")) < 1e-8
