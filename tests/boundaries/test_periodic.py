"""Periodic axes (domain.periodic): material that leaves through one end comes back through
the other, and the step sees no wall there. The states that stay exact with walls stay
exact across a periodic axis: the column at rest, and a layer sliding down a slip incline
(gravity tilted, x periodic), which accelerates as a rigid body at g sin(theta), flat, with
the hydrostatic pressure of g cos(theta)."""

import math
import shutil

import numpy as np
import pytest
from conftest import EXAMPLES, make_case

from mpmflow import Simulation, load_case
from mpmflow.cells import bin_particles
from mpmflow.diagnostics import probes
from mpmflow.errors import CaseError

RHO, G = 1000.0, 9.81


def _run(case):
    sim = Simulation(case)
    sim.run()
    return sim


def test_column_at_rest_is_exact_across_a_periodic_axis():
    """The 2D column at rest with x periodic: no particle moves faster than 1e-8 m/s over
    0.3 s, the pressure is the one of the same column between walls to the pressure
    solver's tolerance (solver.tolerance = 1e-8 relative; the two hierarchies differ) and
    rho g (H - y) to 1e-6, as the hydrostatic tests check it."""
    common = dict(
        size=(0.1, 0.3), body=((0.0, 0.0), (0.1, 0.195)), end=0.3, output=dict(snapshots=False)
    )
    walls = _run(make_case(**common))
    wraps = _run(make_case(**common, domain=dict(periodic=[True, False])))
    assert wraps.case.domain.periodic == [True, False]
    assert np.nanmax(wraps.series("max_speed")) <= 1e-8
    scale = RHO * G * 0.195
    assert np.max(np.abs(wraps.particles.pressure - walls.particles.pressure)) <= 1e-8 * scale
    exact = RHO * G * (0.195 - wraps.particles.x[:, 1])
    assert np.max(np.abs(wraps.particles.pressure - exact)) <= 1e-6 * scale
    assert np.max(np.abs(wraps.particles.x - walls.particles.x)) <= 1e-10


def test_column_at_rest_in_3d_with_two_periodic_axes_is_exact():
    case = load_case(
        EXAMPLES / "hydrostatic_3d.toml",
        [
            "domain.size=[0.1, 0.04, 0.3]",
            "bodies.0.max=[0.1, 0.04, 0.1]",
            "time.end=0.1",
            "domain.periodic=[true, true, false]",
            "output.snapshots=false",
        ],
    )
    sim = _run(case)
    P = sim.particles
    assert np.nanmax(sim.series("max_speed")) <= 1e-8
    exact = RHO * G * (0.1 - P.x[:, 2])
    assert np.max(np.abs(P.pressure - exact)) <= 1e-6 * exact.max()


@pytest.mark.parametrize("dim", [2, 3])
def test_a_layer_slides_down_a_slip_incline_as_a_rigid_body(dim):
    """x periodic, gravity tilted by 10 degrees: after 0.3 s every particle moves at
    g sin(theta) t along x to 1e-9 relative, nothing moves across the slope, the surface
    stays flat, the volume is kept, the particles crossed the periodic end (each travels
    0.077 m, 1.9 box lengths) and all lie inside [0, L)."""
    theta = math.radians(10.0)
    down = [G * math.sin(theta)] + [0.0] * (dim - 2) + [-G * math.cos(theta)]
    if dim == 2:
        case = make_case(
            size=(0.04, 0.2),
            body=((0.0, 0.0), (0.04, 0.1)),
            end=0.3,
            domain=dict(periodic=[True, False]),
            physics=dict(gravity=down),
            output=dict(snapshots=False),
        )
    else:
        case = load_case(
            EXAMPLES / "hydrostatic_3d.toml",
            [
                "domain.size=[0.04, 0.04, 0.1]",
                "grid.spacing=0.01",
                "bodies.0.max=[0.04, 0.04, 0.05]",
                "time.end=0.3",
                "domain.periodic=[true, false, false]",
                f"physics.gravity={down}",
                "output.snapshots=false",
            ],
        )
    sim = Simulation(case)
    x0 = sim.particles.x.copy()
    sim.run()
    P = sim.particles
    speed = G * math.sin(theta) * sim.time
    assert np.max(np.abs(P.v[:, 0] - speed)) <= 1e-9 * speed
    assert np.max(np.abs(P.v[:, 1:])) <= 1e-9 * speed
    # the scheme moves particles with the step's new velocity (eq. 20): after n steps of dt
    # a rigid body has travelled a dt^2 n (n + 1) / 2 = a t^2 / 2 + a t dt / 2
    n, dt = sim.steps, case.time.dt
    travelled = G * math.sin(theta) * dt * dt * n * (n + 1) / 2
    L = case.domain.size[0]
    assert travelled > L
    assert np.all((P.x[:, 0] >= 0.0) & (P.x[:, 0] < L))
    # positions: the start moved by the travel, modulo the period
    moved = np.mod(x0[:, 0] + travelled, L)
    gap = np.abs(P.x[:, 0] - moved)
    assert np.max(np.minimum(gap, L - gap)) <= 1e-9
    assert np.max(np.abs(P.x[:, -1] - x0[:, -1])) <= 1e-10
    assert sim.series("volume_ratio")[-1] == pytest.approx(1.0, abs=1e-12)
    depth = case.bodies[0].max[-1]
    exact = RHO * G * math.cos(theta) * (depth - P.x[:, -1])
    assert np.max(np.abs(P.pressure - exact)) <= 1e-6 * exact.max()


def test_a_probe_on_a_periodic_end_reads_across_it():
    """A floor sensor at x = 0 of the periodic column: its window is centred on the end and
    takes the particles of both ends (a fit over one side's particles only would read the
    same here; the window holding twice the particles of a half window shows it wraps), and
    it reads rho g H."""
    case = load_case(
        EXAMPLES / "hydrostatic.toml",
        [
            "domain.periodic=[true, false]",
            "time.end=0.02",
            "output.snapshots=false",
            "probes.0={name='end', quantity='pressure', position=[0.0, 0.0]}",
            "probes.1={name='middle', quantity='pressure', position=[0.05, 0.0]}",
        ],
    )
    sim = _run(case)
    bins = bin_particles(sim.grid, sim.particles)
    side = probes.window(sim.case.probes[0], sim.grid, sim.case)
    lo, hi = probes.window_box([0.0, 0.0], side, sim.grid.size, periodic=sim.grid.periodic)
    idx, x = probes.window_particles(sim.grid, sim.particles, bins, lo, hi)
    lo2, hi2 = probes.window_box([0.05, 0.0], side, sim.grid.size, periodic=sim.grid.periodic)
    idx2, _ = probes.window_particles(sim.grid, sim.particles, bins, lo2, hi2)
    assert idx.size == idx2.size > 0
    assert x[:, 0].min() < 0.0 < x[:, 0].max()
    for name in ("end", "middle"):
        assert sim.probe_series(name)[-1] == pytest.approx(RHO * G * 0.195, rel=1e-6)


@pytest.mark.parametrize(
    "override, message",
    [
        (["domain.periodic=[true]"], "domain.periodic has 1 entries and domain.size 2"),
        (
            [
                "domain.size=[0.105, 0.3]",
                "bodies.0.max=[0.105, 0.195]",
                "domain.periodic=[true, false]",
            ],
            r"needs a whole, even number of cells",
        ),
        (
            [
                "domain.size=[0.11, 0.3]",
                "bodies.0.max=[0.11, 0.195]",
                "domain.periodic=[true, false]",
            ],
            r"make domain.size\[0\] = 0.1[02]",
        ),
        (
            [
                "domain.size=[1.3, 0.3]",
                "bodies.0.max=[1.3, 0.195]",
                "domain.periodic=[true, false]",
            ],
            r"130 cells halve down to no fewer than 130 points.*e.g. 1.28 m \(128 cells\)",
        ),
        (
            [
                "domain.periodic=[true, false]",
                "solver.scheme=explicit",
                "time.dt=auto",
                "material.bulk_modulus=4e5",
            ],
            r'solver.scheme = "explicit" does not support periodic axes \(domain.periodic\); set '
            r'solver.scheme = "projection", or remove domain.periodic',
        ),
    ],
)
def test_bad_periodic_settings_are_refused_with_the_fix(override, message):
    with pytest.raises(CaseError, match=message):
        load_case(EXAMPLES / "hydrostatic.toml", override)


def test_an_obstacle_at_a_periodic_end_is_refused():
    with pytest.raises(CaseError, match="must stay a grid cell"):
        load_case(
            EXAMPLES / "hydrostatic.toml",
            [
                "domain.periodic=[true, false]",
                "bodies.0.max=[0.1, 0.1]",
                "obstacles.0={type='box', min=[0.0, 0.15], max=[0.03, 0.2]}",
            ],
        )


def test_a_periodic_run_restarted_from_a_checkpoint_is_the_uninterrupted_run(tmp_path):
    """A viscous film on a no-slip incline, x periodic (particles crossing the end, the
    viscous and pressure systems wrapping): resumed from its checkpoint at 0.06 s, it ends
    bit for bit where the uninterrupted run ends."""
    theta = math.radians(10.0)
    more = [
        "domain.size=[0.04, 0.08]",
        "grid.spacing=0.005",
        "bodies.0.max=[0.04, 0.05]",
        "domain.periodic=[true, false]",
        "domain.walls=no_slip",
        "material.model=newtonian",
        "material.viscosity=10.0",
        f"physics.gravity=[{G * math.sin(theta)}, {-G * math.cos(theta)}]",
        "time.end=0.1",
        "checkpoint.interval=0.06",
        "output.snapshots=false",
    ]
    whole = Simulation(load_case(EXAMPLES / "hydrostatic.toml", more), tmp_path / "whole")
    whole.run()
    out = tmp_path / "parts"
    shutil.copytree(tmp_path / "whole", out)  # resuming truncates the later outputs
    rest = Simulation.resume(
        load_case(EXAMPLES / "hydrostatic.toml", more), out, out / "checkpoint_000000060.npz"
    )
    assert rest.time == pytest.approx(0.06)
    rest.run()
    assert rest.steps == whole.steps
    for name in ("x", "v", "pressure"):
        assert np.array_equal(getattr(rest.particles, name), getattr(whole.particles, name))
    assert np.max(whole.particles.v[:, 0]) > 0.01  # it flows


def test_water_flows_over_a_bump_beside_a_periodic_end_and_stays_in_the_box():
    """Periodic axes with an obstacle: a layer sliding down a slip incline over a bump one
    cell from the periodic end flows over it, every particle stays in [0, L) along x at the
    end, and the run keeps its volume (the volume correction's 1%). (The step also wraps
    particles that the obstacle's push-out moves across an end; this case does not happen to
    push any across, so it does not test that.)"""
    theta = math.radians(10.0)
    case = make_case(
        size=(0.08, 0.2),
        body=((0.0, 0.0), (0.08, 0.1)),
        end=0.3,
        domain=dict(periodic=[True, False]),
        physics=dict(gravity=[G * math.sin(theta), -G * math.cos(theta)]),
        output=dict(snapshots=False),
    )
    data = case.model_dump(exclude_none=True)
    data["obstacles"] = [dict(type="box", min=[0.01, 0.0], max=[0.03, 0.03])]
    data["bodies"][0]["around_obstacles"] = True
    from mpmflow.case import validate

    sim = _run(validate(data))
    x = sim.particles.x[:, 0]
    assert np.all((x >= 0.0) & (x < 0.08))
    assert np.max(sim.particles.v[:, 0]) > 0.1  # it flows over the bump
    assert abs(sim.series("volume_ratio")[-1] - 1.0) <= 0.01
