"""Walls push but never pull: water leaves a ceiling and a wall it moves away from."""

import numpy as np
import pytest

from mpmflow import Simulation

from conftest import make_case


def test_water_does_not_hang_from_the_ceiling():
    # a block touching the ceiling of a closed box falls freely under gravity
    case = make_case(size=(0.1, 0.2), spacing=0.01, body=((0.0, 0.12), (0.1, 0.2)), end=0.1,
                     output={"snapshots": False})
    sim = Simulation(case)
    top0 = sim.particles.x[:, 1].max()
    sim.run()
    fall = top0 - sim.particles.x[:, 1].max()
    assert fall == pytest.approx(0.5 * 9.81 * 0.1**2, rel=0.1)


def test_material_leaves_a_wall_it_moves_away_from():
    case = make_case(size=(0.3, 0.1), spacing=0.01, body=((0.0, 0.0), (0.05, 0.05)), end=0.05,
                     physics={"gravity": [0.0, 0.0]}, output={"snapshots": False})
    data = case.model_dump()
    data["bodies"][0]["velocity"] = [1.0, 0.0]
    from mpmflow.case import validate

    sim = Simulation(validate(data))
    sim.run()
    # moving right at 1 m/s without gravity: the block left the left wall by ~5 cm
    assert sim.particles.x[:, 0].min() == pytest.approx(0.05 + 0.00125, abs=0.005)
    assert np.allclose(sim.particles.v[:, 0], 1.0, atol=1e-6)
