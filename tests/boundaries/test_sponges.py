"""Damping zones along the domain's sides ([[sponges]], ``mpmflow.boundaries.sponges``,
src/core/sponges.hpp): the water's velocity relaxed towards rest there, gravity's increment
left alone, so that still water stays still and a wave running in dies out."""

import numpy as np
import pytest
from conftest import EXAMPLES

from mpmflow import Simulation, load_case
from mpmflow.boundaries import sponges
from mpmflow.errors import CaseError
from mpmflow.grid import Grid
from mpmflow.parallel.support import refusals
from mpmflow.simulation.schedules import TimeInterval

TANK = [
    "domain.size=[1.0, 0.4]",
    "grid.spacing=0.01",
    "bodies.0.max=[1.0, 0.2]",
    "bodies.0.particles_per_cell=2",
    'bodies.0.initial_pressure="hydrostatic"',
    "output.snapshots=false",
    "output.interval=0.05",
]


def test_the_rates_rise_as_the_square_of_the_depth_into_the_zone():
    case = load_case(
        EXAMPLES / "dam_break.toml", [*TANK, 'sponges=[{side="x_max", length=0.4, strength=8.0}]']
    )
    grid = Grid.of_case(case)
    rate = sponges.rates(case, grid)
    x = grid.node_coordinates()
    expected = 8.0 * np.clip((x[:, 0] - 0.6) / 0.4, 0.0, 1.0) ** 2
    assert rate == pytest.approx(expected, abs=1e-12)
    assert sponges.rates(load_case(EXAMPLES / "dam_break.toml", TANK), grid) is None


def test_still_water_in_a_sponge_stays_still():
    """The zone damps the velocity but not gravity's increment: water at rest over a zone of
    strength 50/s stays at rest (damping v + g dt would lower the pressure gradient there and
    the zone's water would rise)."""
    case = load_case(
        EXAMPLES / "dam_break.toml",
        [
            *TANK,
            "time.end=0.5",
            "time.dt=0.005",
            'sponges=[{side="x_max", length=0.5, strength=50.0}]',
        ],
    )
    sim = Simulation(case)
    sim.run()
    assert np.abs(sim.particles.v).max() < 1e-9


def _sloshing(more):
    """A tank whose water starts with a standing wave's velocity field (the first mode's
    potential flow at its largest velocity): its kinetic energy after 3 s."""
    case = load_case(EXAMPLES / "dam_break.toml", [*TANK, "time.end=3.0", "time.dt=auto", *more])
    sim = Simulation(case)
    k, U = np.pi / 1.0, 0.05
    x, z = sim.particles.x[:, 0], sim.particles.x[:, 1]
    scale = U / np.cosh(k * 0.2)
    sim.particles.v[:, 0] = -scale * np.sin(k * x) * np.cosh(k * z)
    sim.particles.v[:, 1] = scale * np.cos(k * x) * np.sinh(k * z)
    ke = []
    sim.add_writer(
        lambda s: ke.append(0.5 * (s.particles.mass * (s.particles.v**2).sum(1)).sum()),
        TimeInterval(0.05),
    )
    sim.run()
    return ke


def test_a_sloshing_wave_dies_out_in_sponges():
    """The tank's first sloshing mode, started with 0.05 m/s at the surface: in a closed
    tank it keeps most of its energy over 3 s (the step's own dissipation); with sponges
    0.3 m wide at both ends (the default 10/s) it loses it: the kinetic energy of the last
    half second under 10% of the start's (6% measured; the mode's period is 1.5 s, so the
    zones act over two periods), against more than 30% without."""
    free = _sloshing([])
    damped = _sloshing(['sponges=[{side="x_min", length=0.3}, {side="x_max", length=0.3}]'])
    assert max(free[-10:]) > 0.3 * free[0]
    assert max(damped[-10:]) < 0.1 * damped[0]


def test_bad_sponges_are_refused():
    with pytest.raises(CaseError, match="floor or the ceiling"):
        load_case(EXAMPLES / "dam_break.toml", [*TANK, 'sponges=[{side="y_max", length=0.1}]'])
    with pytest.raises(CaseError, match="longer than the domain"):
        load_case(EXAMPLES / "dam_break.toml", [*TANK, 'sponges=[{side="x_min", length=2.0}]'])
    case = load_case(EXAMPLES / "dam_break.toml", [*TANK, 'sponges=[{side="x_min", length=0.2}]'])
    assert any("damping zones" in p for p in refusals(case))
