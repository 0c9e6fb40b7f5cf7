"""The energy check (``mpmflow.simulation.energy``): KE + PE above its start by more than
0.5% of the initial energy measured from the floor is told at the end of the run and in
summary.json; the blow-up guard names the settings that likely caused a blow-up."""

import json
from types import SimpleNamespace

import numpy as np
import pytest
from conftest import EXAMPLES

from mpmflow import Simulation, load_case
from mpmflow.errors import SimulationError
from mpmflow.grid import Grid
from mpmflow.simulation import callbacks, energy

G = 9.81


def _sim(ke, pe, overrides=(), mass=19.5, dt=None):
    """A stand-in for a Simulation whose time series holds the energies ke and pe, one row
    per 0.01 s (the record reads only the series, the case, the grid and the mass)."""
    case = load_case(EXAMPLES / "hydrostatic.toml", list(overrides))
    columns = {
        "time": 0.01 * np.arange(len(ke)),
        "kinetic_energy": np.asarray(ke, dtype=float),
        "potential_energy": np.asarray(pe, dtype=float),
        "body_energy": np.zeros(len(ke)),  # no free body
    }
    grid = Grid.of_case(case)
    return SimpleNamespace(
        case=case,
        grid=grid,
        mass0=mass,
        dt=dt or case.time.dt,
        series=columns.__getitem__,
        scheme=SimpleNamespace(movers=[]),  # no free body
    )


def test_the_rise_is_measured_against_the_initial_energy_from_the_floor():
    # the column of examples/hydrostatic.toml: 19.5 kg/m, its centre 0.0975 m above the
    # floor: E_floor = 18.65 J/m
    e0 = 19.5 * G * 0.0975
    falls = _sim([0.0, 1.0, 2.0, 0.5], [e0, e0 - 1.5, e0 - 2.5, e0 - 1.0])
    r = energy.record(falls)
    assert r["initial_energy"] == pytest.approx(e0, rel=1e-12)
    assert r["largest_rise"] == 0.0 and r["at_time"] == 0.0 and r["exceeded"] is False
    assert r["threshold"] == 0.005 and r["not_checked"] is None
    # 0.6% of E_floor gained at 0.02 s, 0.4% at 0.03 s: the largest counts
    rises = _sim([0.0, 0.0, 0.006 * e0, 0.004 * e0], [e0] * 4)
    r = energy.record(rises)
    assert r["largest_rise"] == pytest.approx(0.006) and r["at_time"] == pytest.approx(0.02)
    assert r["exceeded"] is True
    below = _sim([0.0, 0.0049 * e0], [e0, e0])
    assert energy.record(below)["exceeded"] is False and not energy.notices(below)
    [notice] = energy.notices(rises)
    assert notice.startswith("KE + PE rose 0.6% above its start (largest at t = 0.02 s;")
    assert "18.65 J/m" in notice and "time.dt" in notice


def test_the_floor_is_where_gravity_points_whatever_the_origin():
    """PE is -sum m g.x from the origin; the floor is the corner of the domain lowest along
    gravity: with g along +x in a 0.1 m wide tank, 0.1 m from the origin."""
    assert energy.initial_energy(1.0, 5.0, 2.0, [0.0, -G], [0.1, 0.3]) == pytest.approx(6.0)
    # a particle of 2 kg at x = 0.04: pe = -2 g 0.04; above the floor x = 0.1 by 0.06 m
    pe = -2.0 * G * 0.04
    assert energy.initial_energy(0.0, pe, 2.0, [G, 0.0], [0.1, 0.3]) == pytest.approx(
        2.0 * G * 0.06
    )
    # no gravity and at rest: the scale is the kinetic energy of the mass at 1 mm/s
    still = _sim([0.0, 0.005 * 0.5 * 19.5e-6 * 1.01], [0.0, 0.0], ["physics.gravity=[0, 0]"])
    r = energy.record(still)
    assert r["initial_energy"] == 0.0 and r["largest_rise"] == pytest.approx(0.00505)


def test_cases_whose_energy_may_rise_are_not_checked():
    e0 = 19.5 * G * 0.0975
    explicit = _sim(
        [0.0, e0], [e0, e0], ["solver.scheme=explicit", "material.bulk_modulus=4e5", "time.dt=5e-4"]
    )
    r = energy.record(explicit)
    assert r["exceeded"] is None and r["largest_rise"] is None
    assert "compression" in r["not_checked"] and not energy.notices(explicit)
    slope = _sim(
        [0.0, e0],
        [e0, e0],
        ["domain.periodic=[true, false]", "domain.size=[0.2, 0.3]", "physics.gravity=[1, -9.81]"],
    )
    assert "periodic x axis" in energy.record(slope)["not_checked"]


def test_the_advice_names_the_step_for_the_grid():
    e0 = 19.5 * G * 0.0975
    grows = [0.0, 0.1 * e0]
    # the tank is 0.3 m tall: free fall 2.43 m/s, 0.024 cells a step of 1e-4 s at 0.01 m
    small = energy.notices(_sim(grows, [e0, e0], ["time.dt=1e-4"]))[0]
    assert (
        "too small for this grid" in small and "Try a larger time.dt (0.00082 s or more)" in small
    )
    assert 'solver.free_surface = "node"' in small and "solver.flip" in small
    large = energy.advice(_sim(grows, [e0, e0], ["time.dt=0.01"]))
    assert (
        "too large for this grid" in large and "Try a smaller time.dt (0.0041 s or less)" in large
    )
    # settings already taken are not offered again
    taken = energy.advice(_sim(grows, [e0, e0], ["solver.free_surface=node", "solver.flip=0.9"]))
    assert "free_surface" not in taken and "flip" not in taken and "another time.dt" in taken
    # the shallow nodes, when a run turned them off
    assert "shallow_fraction" not in small
    unbounded = energy.advice(_sim(grows, [e0, e0], ["solver.shallow_fraction=0"]))
    assert "solver.shallow_fraction = 0.3 (the nodes nearest the surface" in unbounded
    outlet = energy.advice(_sim(grows, [e0, e0], ["domain.walls.y_min=outlet"]))
    assert "solver.volume_correction = 0" in outlet
    auto = energy.advice(_sim(grows, [e0, e0], ["time.dt=auto", "time.courant=0.05"]))
    assert "larger time.courant" in auto


def test_the_blow_up_guard_names_the_likely_setting_and_the_rise_so_far():
    case = load_case(
        EXAMPLES / "hydrostatic.toml", ["time.dt=1e-4", "time.end=0.02", "output.snapshots=false"]
    )
    sim = Simulation(case)
    sim.run()
    sim.particles.v[7] = [0.0, 150.0]  # as if the step had blown up
    with pytest.raises(SimulationError) as err:
        callbacks.blow_up_guard(sim)
    text = str(err.value)
    assert "moves at 150 m/s, above solver.max_speed = 100 m/s" in text
    assert "The step is likely too small for this grid" in text and "larger time.dt" in text
    assert "KE + PE had risen" not in text  # the column at rest did not gain energy
    assert text.endswith("Raise solver.max_speed only if such speeds are real.")


def test_a_column_at_rest_reports_no_energy_rise(tmp_path, capsys):
    """The run's summary.json carries the check: the column at rest keeps its energy."""
    from mpmflow.cli import main

    out = tmp_path / "o"
    args = ["run", str(EXAMPLES / "hydrostatic.toml"), "--out", str(out), "-q"]
    assert main(args + ["--set", "time.end=0.1", "--set", "output.snapshots=false"]) == 0
    assert "KE + PE rose" not in capsys.readouterr().err
    summary = json.loads((out / "summary.json").read_text())
    r = summary["energy"]
    assert r["exceeded"] is False and r["not_checked"] is None and r["threshold"] == 0.005
    assert r["initial_energy"] == pytest.approx(19.5 * G * 0.0975, rel=1e-9)
    assert 0.0 <= r["largest_rise"] < 1e-6
    assert summary["units"]["initial_energy"] == "J/m" and summary["units"]["at_time"] == "s"
