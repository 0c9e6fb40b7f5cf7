"""The volume correction: an exact density measure, a displacement that works both ways, and
nothing else moved (velocities, walls, the column at rest)."""

import numpy as np
import pytest
from conftest import EXAMPLES, make_case

from mpmflow import Simulation, load_case, state
from mpmflow.case import validate
from mpmflow.cells import bin_particles
from mpmflow.geometry.seeding import seed_box
from mpmflow.grid import Grid


@pytest.mark.parametrize("shift", [0.0, 0.13, 0.5, 0.77])
def test_dual_density_reads_one_for_a_shifted_lattice(shift):
    """The hat of the cell-centred grid sums a lattice of 4 x 4 particles per cell to exactly
    1 wherever it is shifted (cells away from the walls); the seeded lattice, symmetric about
    the walls, reads 1 up to the walls through the mirror."""
    grid = Grid(0.1, (6, 5))
    dp = 0.1 / 4
    P = seed_box((0.0, 0.0), (0.6, 0.5), dp, 1000.0, (0.0, 0.0))
    P.x[:] = np.mod(P.x + shift * dp, [0.6, 0.5])  # a lattice shifted, wrapped into the box
    rho = np.empty(grid.ncells)
    state.cell_volume(grid, P.x, P.volume, rho)
    rho /= grid.cell_volume
    inner = rho.reshape(5, 6)[1:-1, 1:-1]
    np.testing.assert_allclose(inner, 1.0, atol=1e-12)
    if shift == 0.0:
        np.testing.assert_allclose(rho, 1.0, atol=1e-12)


def test_dual_density_sees_a_strained_lattice_as_its_volume_not_its_rows():
    """A lattice compressed by 5% vertically and stretched by 1/0.95 horizontally keeps its
    area: the hat measure reads 1 within 3%, where counting particles per cell reads rows (a
    5th row of 4 particles in some cells: 1.25)."""
    grid = Grid(0.1, (8, 8))
    P = seed_box((0.0, 0.0), (0.8, 0.8), 0.025, 1000.0, (0.0, 0.0))
    P.x[:, 0] = 0.1 + (P.x[:, 0] - 0.1) / 0.95
    P.x[:, 1] = 0.1 + (P.x[:, 1] - 0.1) * 0.95
    inside = np.all((P.x > 0.2) & (P.x < 0.6), axis=1)
    bins = bin_particles(grid, P)
    rho = np.empty(grid.ncells)
    state.cell_volume(grid, P.x, P.volume, rho)
    rho /= grid.cell_volume
    core = np.zeros((8, 8), dtype=bool)
    core[3:5, 3:5] = True
    assert np.abs(rho.reshape(8, 8)[core] - 1).max() < 0.03
    assert bins.theta.reshape(8, 8)[core].max() >= 1.25  # what a count would call packed
    assert inside.any()


def _block(spacing_factor, end=0.3, solver=None):
    """A square of water, particles spaced by spacing_factor times the normal spacing, at
    rest in zero gravity in the middle of a box."""
    case = make_case(
        size=(0.4, 0.4),
        spacing=0.01,
        body=((0.14, 0.14), (0.26, 0.26)),
        end=end,
        physics={"gravity": [0.0, 0.0]},
        output={"snapshots": False},
        **({"solver": solver} if solver else {}),
    )
    sim = Simulation(case)
    P = sim.particles
    c = P.x.mean(axis=0)
    P.x[:] = c + (P.x - c) * spacing_factor
    return sim


def _wetted_over_volume(sim):
    bins = bin_particles(sim.grid, sim.particles)
    return np.count_nonzero(bins.theta >= 0.5) * sim.grid.cell_volume / sim.volume0


@pytest.mark.parametrize("factor", [0.85, 1.2])
def test_packed_and_loosened_blocks_return_to_their_volume_without_moving(factor):
    """Both ways: a block packed to 0.85^2 = 72% of its area spreads out, a block loosened to
    1.2^2 = 144% closes up; the particles' velocities stay exactly zero (the correction moves
    positions only) and the centre of mass stays where it was."""
    sim = _block(factor)
    before = _wetted_over_volume(sim)
    centre = sim.particles.x.mean(axis=0)
    assert abs(before - factor**2) < 0.1  # it starts far from its volume
    sim.run()
    after = _wetted_over_volume(sim)
    assert abs(after - 1.0) < 0.05, (before, after)
    assert np.all(sim.particles.v == 0.0)
    np.testing.assert_allclose(sim.particles.x.mean(axis=0), centre, atol=1e-3)


@pytest.mark.parametrize("factor", [0.85, 1.2])
def test_a_looser_correction_solve_moves_the_particles_by_a_fraction_of_its_residual(factor):
    """solver.volume_correction_tolerance reaches the correction's solve: at 1e-3 the runs
    differ from the default 1e-8's (so the setting took), the blocks still come back to their
    volume, and no particle ends more than 1% of a cell from where the tight solve puts it
    (each correction is off by about its residual's share of the volume error, and the next
    one takes that up)."""
    tight, loose = _block(factor), _block(factor, solver={"volume_correction_tolerance": 1e-3})
    assert loose.scheme.options(loose.dt).volume_tol == 1e-3
    tight.run()
    loose.run()
    assert abs(_wetted_over_volume(loose) - 1.0) < 0.05
    apart = np.abs(loose.particles.x - tight.particles.x).max()
    assert 0.0 < apart < 0.01 * loose.grid.spacing, apart


def test_correction_off_leaves_the_loosened_block_loose():
    """The same loosened block with solver.volume_correction = 0 stays loose: the previous
    test measures the correction, not something else."""
    case = make_case(
        size=(0.4, 0.4),
        spacing=0.01,
        body=((0.14, 0.14), (0.26, 0.26)),
        end=0.3,
        physics={"gravity": [0.0, 0.0]},
        output={"snapshots": False},
        solver={"volume_correction": 0.0},
    )
    sim = Simulation(case)
    P = sim.particles
    c = P.x.mean(axis=0)
    P.x[:] = c + (P.x - c) * 1.2
    sim.run()
    assert _wetted_over_volume(sim) > 1.3


def test_nothing_is_pushed_into_a_wall_and_the_column_at_rest_does_not_move():
    case = load_case(EXAMPLES / "hydrostatic.toml", ["output.snapshots=false", "time.end=0.2"])
    sim = Simulation(case)
    x0 = sim.particles.x.copy()
    sim.run()
    assert np.abs(sim.particles.x - x0).max() < 1e-10
    assert sim.summary["particles_moved_inside"] == 0


def test_packed_layer_on_the_floor_spreads_up_not_into_the_floor():
    """A layer packed against the floor (0.8 of its spacing vertically) under gravity: the
    correction lifts it to its volume and puts no particle through the floor."""
    data = make_case(
        size=(0.2, 0.2),
        spacing=0.01,
        body=((0.0, 0.0), (0.2, 0.06)),
        end=0.3,
        output={"snapshots": False},
    ).model_dump()
    sim = Simulation(validate(data))
    sim.particles.x[:, 1] *= 0.8
    sim.run()
    s = sim.summary
    assert s["particles_moved_inside"] == 0
    assert abs(_wetted_over_volume(sim) - 1.0) < 0.05
