"""Velocity inlets ([[inlets]], ``mpmflow.boundaries.inlets``, src/core/inlets.hpp): the side's
nodes in the opening held to the inflow, a layer of particles each time the inflow has
travelled one particle spacing; what entered counted, and the mass kept plus what left
equal to the start's plus what entered."""

import copy
import json

import numpy as np
import pytest
from conftest import EXAMPLES
from scipy.optimize import brentq

from mpmflow import Simulation, load_case
from mpmflow.cli import main
from mpmflow.errors import CaseError
from mpmflow.simulation.schedules import TimeInterval

H, L, U, DX = 0.05, 0.5, 1.0, 0.01  # a stream H deep at U from the inlet at x = 0
S = DX / 2  # the particles' spacing (2 per cell)

STREAM = [
    f"domain.size=[{L}, {4 * H}]",
    'domain.walls={x_max="outlet"}',
    f"grid.spacing={DX}",
    f"bodies.0.max=[{L}, {H}]",
    f"bodies.0.velocity=[{U}, 0.0]",
    "bodies.0.particles_per_cell=2",
    'bodies.0.initial_pressure="hydrostatic"',
    f'inlets=[{{side="x_min", speed={U}, level={H}}}]',
    "output.snapshots=false",
    "output.interval=0.05",
]


def _stream(*more):
    return load_case(EXAMPLES / "dam_break.toml", [*STREAM, "time.end=0.5", *more])


def _run(case, every=0.05):
    sim = Simulation(case)
    start = (sim.particles.volume.sum(), sim.particles.mass.sum())
    rows = []

    def record(s):
        P = s.particles
        rows.append(
            (
                s.time,
                copy.copy(s.scheme.inflow),
                copy.copy(s.scheme.outflow),
                P.volume.sum(),
                P.mass.sum(),
                P.x.copy(),
                P.v.copy(),
            )
        )

    sim.add_writer(lambda s: record(s) if s.time > 0 else None, TimeInterval(every))
    summary = sim.run()
    return summary, start, rows


@pytest.mark.parametrize("gravity", [0.0, -9.81])
def test_a_uniform_stream_through_an_inlet_and_an_outlet_stays_uniform(gravity):
    """A stream H deep at U, from an inlet at x = 0 to an outlet at x = L, with its
    hydrostatic pressure: an exact steady state of the flow (the outlet's natural condition
    continues it). At a step that moves the stream one particle spacing (0.005 s) the inlet's
    layers continue the lattice exactly: every particle moves at U and the depth is H, to
    rounding, with and without gravity; the volume in the domain stays L H while U H t
    enters and leaves."""
    _summary, (V0, M0), rows = _run(_stream(f"physics.gravity=[0.0, {gravity}]", "time.dt=0.005"))
    for t, into, out, v, m, x, vel in rows:
        assert np.abs(vel[:, 0] - U).max() < 1e-9 and np.abs(vel[:, 1]).max() < 1e-9, t
        assert x[:, 1].max() == pytest.approx(H - S / 2, abs=1e-9), t
        assert v == pytest.approx(L * H, rel=1e-12), t
        # whole layers of H / S particles: what entered is U H t to one layer
        assert abs(into.volume - U * H * t) <= H * S + 1e-12, t
        assert v + out.volume - into.volume == pytest.approx(V0, rel=1e-12), t
        assert m + out.mass - into.mass == pytest.approx(M0, rel=1e-12), t


def test_a_viscous_stream_holds_the_inflow_in_its_viscous_solve():
    """A Newtonian stream (1 Pa s, a thousand times water's) without gravity: uniform, it
    has no shear, so the implicit viscous solve must leave it as it is; it can only if the
    inlet's nodes are held there to the inflow, not at rest as a wall's (at rest they sheared
    the water beside them)."""
    _summary, (V0, M0), rows = _run(
        _stream(
            "physics.gravity=[0.0, 0.0]",
            "time.dt=0.005",
            'material.model="newtonian"',
            "material.viscosity=1.0",
        )
    )
    for t, _into, _out, v, _m, _x, vel in rows:
        assert np.abs(vel[:, 0] - U).max() < 1e-9 and np.abs(vel[:, 1]).max() < 1e-9, t
        assert v == pytest.approx(L * H, rel=1e-12), t


def test_at_any_step_the_stream_stays_within_a_fraction_of_a_percent():
    """At a step that is not a whole number of spacings (4 ms: 0.8 of one) the first layer
    lies anywhere within a spacing of the side and the cells along it hold their share of
    water only on average: the stream keeps U within 0.5% and H within a particle row, and
    time.dt = "auto" likewise."""
    for dt in ("0.004", '"auto"'):
        _sim, _start, rows = _run(_stream(f"time.dt={dt}"))
        t, into, out, v, m, x, vel = rows[-1]
        assert np.abs(vel[:, 0].mean() - U) < 0.005 * U, dt
        assert np.abs(vel[:, 1]).max() < 0.05 * U, dt
        assert v == pytest.approx(L * H, abs=H * S), dt


def test_a_tank_fills_at_the_inlets_rate():
    """An inlet into a closed tank: the water's volume grows at U times the opening's
    height, whatever the water does inside (here it piles up against the far wall), to one
    layer, and the summary counts what entered."""
    case = load_case(
        EXAMPLES / "dam_break.toml",
        [
            f"domain.size=[{L}, {4 * H}]",
            f"grid.spacing={DX}",
            "bodies.0.min=[0.0, 0.0]",
            f"bodies.0.max=[{L}, {H / 2}]",
            "bodies.0.particles_per_cell=2",
            f'inlets=[{{side="x_min", speed={U / 4}, level={H / 2}}}]',
            "output.snapshots=false",
            "output.interval=0.05",
            "time.end=0.4",
        ],
    )
    summary, (V0, _M0), rows = _run(case)
    for t, into, _out, v, _m, _x, _vel in rows:
        assert abs(v - V0 - U / 4 * H / 2 * t) <= H / 2 * S + 1e-12, t
        assert into.volume == pytest.approx(v - V0, rel=1e-12), t
    assert summary["inflow"]["volume"] == pytest.approx(rows[-1][1].volume, rel=1e-12)
    assert summary["particles_lost"] == 0
    assert abs(summary["mass_relative_change"]) < 1e-12
    assert summary["energy"]["not_checked"]  # an inlet brings energy: no energy check


def test_a_3d_stream_enters_and_keeps_its_speed():
    """The same stream in 3D (a channel 0.1 m wide, slip side walls) at a step of one
    spacing: exact as in 2D."""
    L3 = 0.24  # m: 12 cells of 0.02 m (a domain is rounded up to whole cells)
    case = load_case(
        EXAMPLES / "dam_break_3d.toml",
        [
            f"domain.size=[{L3}, 0.1, {4 * H}]",
            'domain.walls={x_max="outlet"}',
            f"grid.spacing={DX * 2}",
            "bodies.0.min=[0.0, 0.0, 0.0]",
            f"bodies.0.max=[{L3}, 0.1, {H}]",
            f"bodies.0.velocity=[{U}, 0.0, 0.0]",
            "bodies.0.particles_per_cell=2",
            'bodies.0.initial_pressure="hydrostatic"',
            f'inlets=[{{side="x_min", speed={U}, level={H}}}]',
            "output.snapshots=false",
            "output.interval=0.05",
            "time.end=0.2",
            f"time.dt={DX / U}",
        ],
    )
    _summary, (V0, _M0), rows = _run(case)
    for t, into, out, v, _m, _x, vel in rows:
        assert np.abs(vel[:, 0] - U).max() < 1e-9 and np.abs(vel[:, 1:]).max() < 1e-9, t
        assert v == pytest.approx(L3 * 0.1 * H, rel=1e-12), t
        assert v + out.volume - into.volume == pytest.approx(V0, rel=1e-12), t


@pytest.mark.parametrize(
    ("settings", "words"),
    [
        (['inlets=[{side="y_min", speed=1.0, level=0.1}]'], "floor or the ceiling"),
        (
            ['inlets=[{side="x_max", speed=1.0, level=0.1}]', 'domain.walls={x_max="outlet"}'],
            "is an outlet",
        ),
        (['inlets=[{side="x_min", speed=1.0, level=9.0}]'], "above the domain's top"),
        (['inlets=[{side="x_min", speed=-1.0, level=0.1}]'], "greater than 0"),
        (['inlets=[{side="x_min", level=0.1}]'], "either speed"),
        (['inlets=[{side="x_min", speed=1.0, profile=[[0.0, 1.0]], level=0.1}]'], "either speed"),
        (['inlets=[{side="x_min", profile=[[0.05, 1.0], [0.0, 0.5]], level=0.1}]'], "increase"),
        (['inlets=[{side="x_min", profile=[[0.0, -1.0]], level=0.1}]'], "must be >= 0"),
        (['inlets=[{side="x_min", speed=1.0, level=1e-4}]'], "below one particle spacing"),
        (['inlets=[{side="x_min", speed=1e3, level=0.1}]'], "solver.max_speed"),
        (
            [
                'inlets=[{side="x_min", speed=1.0, level=0.1}]',
                'material.model="elastic"',
                "material.shear_modulus=1e6",
            ],
            "inlets bring a fluid",
        ),
        (
            ['inlets=[{side="x_min", speed=1.0, level=0.1}]', 'solver.scheme="explicit"'],
            "does not support inlets",
        ),
        (
            ['inlets=[{side="x_min", speed=1.0, level=0.1}, {side="x_min", speed=1.0, level=0.1}]'],
            "two inlets on side",
        ),
    ],
)
def test_bad_inlets_are_refused_by_name(settings, words):
    with pytest.raises(CaseError, match=words):
        load_case(EXAMPLES / "dam_break.toml", settings)


def test_the_cli_counts_the_inflow_in_the_summary(tmp_path):
    out = tmp_path / "run"
    args = [str(EXAMPLES / "dam_break.toml"), "--out", str(out)]
    for s in [*STREAM, "time.end=0.1", "time.dt=0.005"]:
        args += ["--set", s]
    assert main(["run", *args, "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["inflow"]["particles"] == 20 * round(H / S)  # 20 layers of H / S
    assert summary["particles_lost"] == 0


def test_the_memory_estimate_counts_the_water_the_inlets_bring():
    """The estimate before a run holds the particles the inlets may bring over the whole run
    (whole layers of the opening's lattice, one more), beside the bodies'."""
    from mpmflow.memory import estimate, inflow_count

    case = _stream("time.end=0.5")
    layers = int(U * 0.5 / S) + 1
    assert inflow_count(case) == layers * round(H / S)
    assert estimate(case).particles == sum(case.particle_counts()) + inflow_count(case)


def test_a_run_over_mpi_ranks_refuses_inlets_by_name():
    from mpmflow.parallel.support import refusals

    assert any("inlets are not split over ranks" in r for r in refusals(_stream()))


@pytest.mark.slow
def test_a_channel_over_a_hump_reaches_bernoullis_critical_flow():
    """examples/hump.toml: q = 0.05 m^2/s from an inlet over a smooth hump 0.05 m high to an
    outlet. Steady, Bernoulli with a hydrostatic critical section at the crest gives the
    upstream depth 0.1385 m and the downstream 0.0338 m (critical flow theory, which neglects
    the crest's curvature: the head is 0.06 of its radius there). Over the last 2 s of 8 the
    depths (the particles' volume per length, away from the inlet, the hump and the outlet)
    are within 2% upstream and 4% downstream (measured at this mesh, 0.01 m: -0.9% and +2.1%;
    the downstream flow loses a little head), and the outflow equals the inflow within 2%."""
    g, q, bump = 9.81, 0.5 * 0.1, 0.05
    yc = (q * q / g) ** (1 / 3)
    energy = bump + 1.5 * yc

    def depth_for(lo, hi):  # Bernoulli: y + q^2 / (2 g y^2) = energy, one root in [lo, hi]
        return brentq(lambda y: y + q * q / (2 * g * y * y) - energy, lo, hi)

    upstream, downstream = depth_for(yc, 1.0), depth_for(0.005, yc)
    assert upstream == pytest.approx(0.1385, abs=1e-4) and downstream == pytest.approx(
        0.0338, abs=1e-4
    )
    sim = Simulation(load_case(EXAMPLES / "hump.toml", {"output.snapshots": False}))
    seen = []

    def measure(s):
        if s.time < 6.0 - 1e-9:
            return
        P = s.particles
        up = (P.x[:, 0] > 0.3) & (P.x[:, 0] < 1.1)
        down = (P.x[:, 0] > 2.4) & (P.x[:, 0] < 2.9)
        seen.append(
            (s.time, P.volume[up].sum() / 0.8, P.volume[down].sum() / 0.5, s.scheme.outflow.volume)
        )

    sim.add_writer(measure, TimeInterval(0.05))
    sim.run()
    t, up, down, out = np.array(seen).T
    assert np.mean(up) == pytest.approx(upstream, rel=0.02)
    assert np.mean(down) == pytest.approx(downstream, rel=0.04)
    assert (out[-1] - out[0]) / (t[-1] - t[0]) == pytest.approx(q, rel=0.02)


def test_a_profiled_inflow_brings_its_profile_in():
    """An inflow whose speed grows linearly with height, 0.5 m/s at the floor to 1 m/s at the
    top of the opening, into an empty channel without gravity (the case's body, a small
    block, leaves through the outlet first): a parallel shear flow with a free front, which
    the inviscid step keeps (each row's particles move at their own speed). What entered is
    the profile's integral x time, to a particle per row. With APIC transfers (which carry
    the profile's gradient to the grid) the particles behind the slowest row's front keep
    their row's speed within 1% (0.9% measured); with FLIP the lowest row drifts by up to 5%
    over 0.5 s, the lag of FLIP's first row at a wall (docs/method.md, "Known
    limitations")."""
    profile = "[[0.0, 0.5], [0.05, 1.0]]"
    _summary, _start, rows = _run(
        _stream(
            "physics.gravity=[0.0, 0.0]",
            "time.dt=0.002",
            f"bodies.0.min=[{L - 0.02}, 0.0]",
            f'inlets=[{{side="x_min", profile={profile}, level={H}}}]',
            'solver.transfer="apic"',
        )
    )
    heights = (np.arange(round(H / S)) + 0.5) * S
    rate = np.sum(0.5 + 0.5 * heights / H) * S  # m^2/s: the rows' speeds x their height
    for t, into, _out, _v, _m, x, vel in rows:
        assert abs(into.volume - rate * t) <= len(heights) * S * S + 1e-12, t
        came = x[:, 0] < 0.5 * t - 0.05  # behind the lowest row's front (it moves at 0.5)
        expected = 0.5 + 0.5 * x[came, 1] / H
        assert t < 0.15 or np.abs(vel[came, 0] - expected).max() < 0.01, t
