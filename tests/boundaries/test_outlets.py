"""Outlets (domain.walls = "outlet", ``mpmflow.boundaries.outlets``): an open side whose
velocity is free and whose pressure takes the weak form's natural condition; the material
that crosses it leaves the run, counted, with the mass kept plus the outflow equal to the
start's."""

import json

import numpy as np
import pytest
from conftest import EXAMPLES

import mpmflow
from mpmflow import Simulation, load_case
from mpmflow.cli import main
from mpmflow.errors import CaseError
from mpmflow.simulation.schedules import TimeInterval

H, L, U, DX = 0.05, 0.4, 0.5, 0.005  # a slab H deep moving at U towards the outlet at x = L


SLAB = [
    f"domain.size=[{L}, {3 * H}]",
    'domain.walls={x_max="outlet"}',
    f"grid.spacing={DX}",
    f"bodies.0.max=[{L}, {H}]",
    f"bodies.0.velocity=[{U}, 0.0]",
    "bodies.0.particles_per_cell=2",
    "output.snapshots=false",
]


def _slab(*more):
    return load_case(
        EXAMPLES / "dam_break.toml",
        [*SLAB, "time.end=0.2", "time.dt=0.001", "output.interval=0.01", *more],
    )


def _run(case):
    sim = Simulation(case)
    start = (sim.particles.volume.sum(), sim.particles.mass.sum())
    rows = []

    def record(s):
        P = s.particles
        out = s.scheme.outflow
        rows.append((s.time, out.volume, out.mass, P.volume.sum(), P.mass.sum(), P.v.copy()))

    sim.add_writer(record, TimeInterval(0.01))
    sim.run()
    return start, rows


def test_a_slab_leaves_through_an_outlet_at_its_own_speed():
    """Without gravity (and without the volume correction, which acts at the slab's back
    surface) the slab is a uniform flow: the outlet lets it go at U, untouched (a wall would
    stop it), so the outflow is U H t to one column of particles (2 per cell: a column is
    H DX / 2), and every particle still in the domain moves at U exactly."""
    (V0, M0), rows = _run(_slab("physics.gravity=[0.0, 0.0]", "solver.volume_correction=0"))
    assert rows[-1][1] > 0.9 * U * H * 0.2  # most of 0.2 s of flow has left
    for t, out_v, out_m, v, m, vel in rows:
        assert abs(out_v - U * H * t) <= H * DX / 2 + 1e-12, t
        assert np.all(vel[:, 0] == U) and np.all(vel[:, 1] == 0.0), t
        assert v + out_v == pytest.approx(V0, rel=1e-12) and m + out_m == pytest.approx(
            M0, rel=1e-12
        )


def test_with_gravity_the_outflow_keeps_the_mass_and_the_summary_says_so(tmp_path):
    """The slab under gravity with every default: what stays plus what left is the start's
    mass and volume to rounding at each output, and summary.json counts the outflow."""
    (V0, M0), rows = _run(_slab())
    for _t, out_v, out_m, v, m, _vel in rows:
        assert v + out_v == pytest.approx(V0, rel=1e-12) and m + out_m == pytest.approx(
            M0, rel=1e-12
        )
    # while the rarefaction from the slab's back has not reached the outlet (U + sqrt(g H)
    # = 1.2 m/s over 0.4 m: 0.33 s), the slab leaves at about U: within 5%
    t, out_v = rows[-1][0], rows[-1][1]
    assert out_v == pytest.approx(U * H * t, rel=0.05)
    out = tmp_path / "o"
    overrides = [*SLAB, "time.end=0.1"]
    args = ["run", str(EXAMPLES / "dam_break.toml"), "--out", str(out), "-q"]
    assert main(args + [a for o in overrides for a in ("--set", o)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["outflow"]["particles"] > 0 and summary["particles_lost"] == 0
    assert abs(summary["mass_relative_change"]) < 1e-12
    # 2 particles per cell axis: 20 rows of 160
    assert summary["particles"] + summary["outflow"]["particles"] == 20 * 160


def test_outlets_are_refused_where_they_cannot_act():
    with pytest.raises(CaseError, match='does not support outlets .domain.walls = "outlet".'):
        _slab("solver.scheme=explicit", "material.bulk_modulus=4e5")
    with pytest.raises(CaseError, match="x is periodic"):
        _slab("domain.periodic=[true, false]")
    with pytest.raises(CaseError, match='"slip", "no_slip", "bonded" or "outlet"'):
        _slab('domain.walls={x_max="open"}')


def test_an_obstacle_takes_the_walls_condition_beside_an_outlet():
    """obstacles.N.walls = "domain" takes the walls' one condition; an outlet is no wall."""
    case = _slab(
        'domain.walls={x_max="outlet", y="no_slip", x_min="no_slip"}',
        "obstacles=[{type='box', min=[0.2, 0.1], max=[0.25, 0.12]}]",
    )
    assert case.domain.uniform_walls() == "no_slip"
    assert case.domain.outlet_sides() == [False, True, False, False]


@pytest.mark.parametrize("step", ["time.dt=0.001", "time.dt=auto"])
def test_an_outlet_that_drains_every_particle_ends_the_run_normally(tmp_path, capsys, step):
    """The column at rest over an outlet floor falls out of the tank in about 0.2 s: the run
    ends there, "completed", with a notice, the outflow holding the initial mass to
    rounding; every writer (time series, snapshots, centre of mass, probes) and the summary
    take the empty state, and the results read back (an empty snapshot too)."""
    out = tmp_path / "o"
    overrides = [
        "domain.walls.y_min=outlet",
        "bodies.0.particles_per_cell=2",
        step,
        "output.snapshot_interval=0.01",
        "output.centre_of_mass=true",
        "probes=[{name='p', quantity='pressure', position=[0.05, 0.01]}]",
    ]
    args = ["run", str(EXAMPLES / "hydrostatic.toml"), "--out", str(out), "-q"]
    code = main(args + [a for o in overrides for a in ("--set", o)])
    err = capsys.readouterr().err
    assert code == 0 and "Traceback" not in err, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "completed", summary["message"]
    assert summary["message"].startswith("every particle left through the outlets by t = ")
    assert (
        f"mpmflow: note: {summary['message']}" in err and summary["message"] in summary["notices"]
    )
    assert 0.1 < summary["time"] < 0.5 and summary["particles"] == 0  # time.end is 1 s
    # 2 particles a cell along each axis: 20 columns of 39 (0.195 m deep)
    assert summary["outflow"]["particles"] == 20 * 39 and summary["particles_lost"] == 0
    assert summary["outflow"]["mass"] == pytest.approx(summary["mass_initial"], rel=1e-12, abs=0)
    assert summary["mass_final"] == 0.0 and abs(summary["mass_relative_change"]) < 1e-12
    run = mpmflow.open_run(out)
    assert run.timeseries["time"][-1] == pytest.approx(summary["time"])
    assert run.timeseries["kinetic_energy"][-1] == 0.0 and np.isnan(run.timeseries["max_speed"][-1])
    last = run.snapshots[-1]
    assert last.time == pytest.approx(summary["time"]) and last.read()["x"].shape == (0, 2)
    centre = np.loadtxt(out / "centre_of_mass.csv", delimiter=",", skiprows=1)[:, 2]  # y
    assert np.isnan(centre[-1]) and np.isfinite(centre[:-1]).all()
