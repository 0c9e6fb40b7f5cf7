"""Obstacles moving along a prescribed path (``obstacles.N.motion``,
``mpmflow.boundaries.moving``, src/core/bodies.hpp): the obstacle's tables rebuilt each step at
its pose, its nodes held to its velocity, the pressure's force on it in bodies.csv."""

import math
from pathlib import Path

import numpy as np
import pytest

from mpmflow import Simulation, load_case
from mpmflow.boundaries import moving
from mpmflow.errors import CaseError
from mpmflow.parallel.support import refusals
from mpmflow.simulation.schedules import TimeInterval

RHO, G = 1000.0, 9.81

TANK = """
title = "moving obstacle"
[domain]
size = {size}
walls = "slip"
[grid]
spacing = {h}
[[bodies]]
type = "box"
min = {water_min}
max = {water_max}
particles_per_cell = {ppc}
velocity = {water_velocity}
around_obstacles = true
initial_pressure = "{pressure}"
[[obstacles]]
name = "body"
type = "box"
min = {body_min}
max = {body_max}
motion = {motion}
[material]
density = 1000.0
[physics]
gravity = {gravity}
[time]
dt = {dt}
end = {end}
[output]
interval = {interval}
snapshots = false
"""


# water 0.1 m deep and 0.4 m long beside a wall 0.1 m thick at x = 0 (a piston when it moves)
PISTON_TANK = dict(
    size="[0.5, 0.3]",
    h=0.01,
    water_min="[0.1, 0.0]",
    water_max="[0.5, 0.1]",
    water_velocity="[0.0, 0.0]",
    body_min="[0.0, 0.0]",
    body_max="[0.1, 0.3]",
    gravity="[0.0, -9.81]",
    dt=0.005,
    interval=0.1,
)


def _case(tmp_path, ppc=2, pressure="zero", **keys):
    text = TANK.format(ppc=ppc, pressure=pressure, **keys)
    path = tmp_path / "case.toml"
    path.write_text(text)
    return load_case(path)


def _run(case, every):
    sim = Simulation(case)
    rows = []
    sim.add_writer(
        lambda s: rows.append((s.time, s.particles.x.copy(), s.particles.v.copy())),
        TimeInterval(every),
    )
    sim.run()
    return sim, rows


@pytest.mark.parametrize("dim", [2, 3])
def test_a_body_moving_with_the_water_leaves_it_untouched(tmp_path, dim):
    """Without gravity, a block of water with a hole holding a box, both moving at U: an exact
    solution (uniform motion, p = 0). The box's tables are rebuilt at every step at its new
    place, its nodes held to U: every particle keeps U to rounding and moves U t. (4
    particles per cell: with 2, a free block in uniform motion is not exact even without an
    obstacle, its surface crossing a grid line: 0.6% of U here, the sparse-cell threshold.)"""
    U = [0.2, 0.1, 0.0][:dim] if dim == 2 else [0.2, 0.0, 0.1]
    vec = lambda *a: "[" + ", ".join(str(x) for x in a[:dim]) + "]"  # noqa: E731
    case = _case(
        tmp_path,
        ppc=4,
        size=vec(0.8, 0.6, 0.6) if dim == 2 else "[0.8, 0.3, 0.6]",
        h=0.02,
        water_min=vec(0.1, 0.1, 0.1) if dim == 2 else "[0.1, 0.02, 0.1]",
        water_max=vec(0.4, 0.3, 0.3) if dim == 2 else "[0.4, 0.22, 0.3]",
        water_velocity=vec(*U) if dim == 2 else "[0.2, 0.0, 0.1]",
        body_min=vec(0.2, 0.16) if dim == 2 else "[0.2, 0.08, 0.16]",
        body_max=vec(0.3, 0.24) if dim == 2 else "[0.3, 0.16, 0.24]",
        motion="{type = 'velocity', velocity = "
        + ("[0.2, 0.1]" if dim == 2 else "[0.2, 0.0, 0.1]")
        + "}",
        gravity=vec(0.0, 0.0, 0.0),
        dt=0.01,
        end=0.4,
        interval=0.1,
    )
    sim, rows = _run(case, 0.1)
    x0 = rows[0][1]
    for t, x, v in rows:
        assert np.abs(v - np.array(U)).max() < 1e-9, t
        assert np.abs(x - x0 - t * np.array(U)).max() < 1e-9, t
    assert sim.scheme.core.body_force == pytest.approx(np.zeros((1, dim)), abs=1e-9)


@pytest.mark.parametrize("velocity", [-0.02, 0.02])
def test_a_body_pushed_slowly_through_the_surface_feels_a_smooth_buoyancy(tmp_path, velocity):
    """A box 0.194 m wide, its bottom 0.093 m under the surface of a tank 0.6 m wide, pushed
    down (or pulled up) at 2 cm/s, ramped over 0.2 s: slow, so the pressure's force on it is
    the buoyancy of its draft, rho g w (level - bottom), the level moving by w / (W - w) of
    the body's travel. Every step's force stays within 3% of a smooth (quadratic) trend and
    ends within 3% of that buoyancy. Before the nodes beside a moving face counted as inside
    the water when their cells hold particles (free_surface.hpp, nodal_fraction; cut_cells.hpp,
    sliver_fractions), a node there turned into free surface for a step as the strained
    particle rows crossed a cell boundary: force spikes of 120% (down) and 570% (up) of it."""
    W, w, level, bottom, ramp, end, dt = 0.6, 0.194, 0.3, 0.207, 0.2, 0.6, 0.002
    case = _case(
        tmp_path,
        pressure="hydrostatic",
        size="[0.6, 0.4]",
        h=0.01,
        water_min="[0.0, 0.0]",
        water_max=f"[{W}, {level}]",
        water_velocity="[0.0, 0.0]",
        body_min=f"[{(W - w) / 2}, {bottom}]",
        body_max=f"[{(W + w) / 2}, 0.4]",
        motion=f"{{type = 'velocity', velocity = [0.0, {-velocity}], ramp = {ramp}}}",
        gravity="[0.0, -9.81]",
        dt=dt,
        end=end,
        interval=dt,
    )
    sim = Simulation(case)
    rows = []
    sim.add_writer(
        lambda s: rows.append((s.time, s.scheme.core.body_force[0][1])),
        TimeInterval(dt),
        name="force",
    )
    sim.run()
    t, force = np.array(rows).T
    after = t > ramp + 0.05
    trend = np.polyval(np.polyfit(t[after], force[after], 2), t[after])
    travel = velocity * (end - ramp / 2)  # down positive
    buoyancy = RHO * G * w * (level - bottom + travel * (1 + w / (W - w)))
    assert np.abs(force[after] - trend).max() < 0.03 * buoyancy
    assert force[-1] == pytest.approx(buoyancy, rel=0.03)


def test_a_body_at_rest_in_still_water_feels_the_hydrostatic_force(tmp_path):
    """A wall on the moving path's code (a motion of zero velocity) standing in still water H
    deep: the water stays at rest as against a fixed obstacle, and the pressure's force on
    the wall is rho g H^2 / 2 per metre, exactly for the hydrostatic pressure the step
    computes (linear in depth: the face term integrates it exactly)."""
    H = 0.1
    case = _case(
        tmp_path,
        **{
            **PISTON_TANK,
            "water_min": "[0.105, 0.0]",
            "body_max": "[0.105, 0.3]",  # its face between grid lines
        },
        motion="{type = 'velocity', velocity = [0.0, 0.0]}",
        end=0.3,
    )
    sim, rows = _run(case, 0.1)
    for t, _x, v in rows:
        assert np.abs(v).max() < 1e-9, t
    force = sim.scheme.core.body_force[0]
    assert force[0] == pytest.approx(-RHO * G * H**2 / 2, rel=1e-6)
    assert abs(force[1]) < 1e-9


def test_a_piston_pushed_into_a_closed_tank_raises_the_level_by_its_displacement(tmp_path):
    """A piston wall pushed 0.05 m into a tank of water 0.1 m deep and 0.4 m long (0.05 m/s
    for 1 s, ramped over 0.2 s), then held: the water is never inside the piston (its
    particles stay beyond its face), its volume is kept, so the level settles at
    H L / (L - d); the pressure's force on the piston then returns to rho g H'^2 / 2. The
    sloshing the push leaves swings that force by 5-7% at 2-3 s (a period of about 0.7 s),
    so its mean over 2-3 s is compared, within 2% (measured 0.9% off with every node with
    f > 1/2 an unknown, 0.1% with the shallow nodes interpolated)."""
    H, L, d, S = 0.1, 0.4, 0.05, 0.005
    case = _case(
        tmp_path,
        motion="{type = 'velocity', velocity = [0.05, 0.0], stop = 1.1, ramp = 0.2}",
        end=3.0,
        **PISTON_TANK,
    )
    forces = []
    sim = Simulation(case)
    sim.add_writer(
        lambda s: forces.append((s.time, s.scheme.core.body_force[0][0])),
        TimeInterval(0.05),
        name="force",
    )
    rows = []
    sim.add_writer(
        lambda s: rows.append((s.time, s.particles.x.copy(), s.particles.v.copy())),
        TimeInterval(0.1),
    )
    sim.run()
    mover = sim.scheme.movers[0]
    for t, x, _v in rows:
        face = mover.path.at(t)[0][0] + 0.05
        assert x[:, 0].min() >= face, t
    c, v, _, _ = mover.path.at(3.0)
    assert c[0] - 0.05 == pytest.approx(d, rel=1e-9) and np.abs(v).max() == 0.0
    # the mean over the tank's columns of the top particle's upper edge: the level of water
    # that keeps its volume, whatever waves are left
    x = rows[-1][1]
    column = np.floor(x[:, 0] / S).astype(int)
    tops = [x[column == c, 1].max() + S / 2 for c in np.unique(column)]
    level = H * L / (L - d)
    assert abs(np.mean(tops) - level) < S / 2, (np.mean(tops), level)
    f = np.array(forces)
    settled = f[f[:, 0] >= 2.0 - 1e-9, 1]
    assert settled.mean() == pytest.approx(-RHO * G * level**2 / 2, rel=0.02)


def test_the_sampled_paths_follow_their_motions():
    """The core's Hermite interpolation of the sampled path (Trajectory.at, as
    src/core/bodies.cpp) against the analytic motion: a ramped oscillation within 1e-6 of its
    amplitude, a ramped velocity's displacement exact where it runs at full speed."""
    from mpmflow.case.motion import Motion

    pivot = np.array([0.05, 0.2])
    m = Motion(type="oscillation", amplitude=[0.02, 0.0], period=1.0, ramp=2.0, angle_amplitude=5)
    path = moving.path_of(m, pivot, 6.0, Path("."), "motion")
    for t in np.linspace(0.0, 6.0, 997):
        r = 0.5 * (1 - math.cos(math.pi * min(t / 2.0, 1.0)))
        c, v, angle, _ = path.at(t)
        assert c[0] - pivot[0] == pytest.approx(0.02 * r * math.sin(2 * math.pi * t), abs=2e-8)
        assert angle == pytest.approx(math.radians(5) * r * math.sin(2 * math.pi * t), abs=2e-9)
        if t > 2.0:
            assert v[0] == pytest.approx(0.02 * 2 * math.pi * math.cos(2 * math.pi * t), abs=1e-6)
    m = Motion(type="velocity", velocity=[0.0, -0.01], start=0.5, ramp=0.4, stop=3.0)
    path = moving.path_of(m, pivot, 4.0, Path("."), "motion")
    for t in (1.0, 2.0, 2.9):  # after the ramp: 0.01 (t - 0.5 - 0.4 / 2) down
        c, v, _, _ = path.at(t)
        assert c[1] == pytest.approx(0.2 - 0.01 * (t - 0.7), abs=1e-12)
        assert v[1] == pytest.approx(-0.01, abs=1e-12)
    c, v, _, _ = path.at(3.5)
    assert c[1] == pytest.approx(0.2 - 0.01 * 2.3, abs=1e-12) and v[1] == 0.0


def test_a_table_path_and_bad_motions_are_told(tmp_path):
    """A table's path is read with its rates; a table that stops before time.end, an obstacle
    faster than a cell a step and a periodic domain are refused by name; several MPI ranks
    run a prescribed path (tests/parallel/test_split_bodies.py), not a free body."""
    common = PISTON_TANK
    (tmp_path / "path.csv").write_text("t,x,y\n0,0,0\n0.5,0.01,0\n1.0,0.02,0\n")
    case = _case(tmp_path, motion="{type = 'table', file = 'path.csv'}", end=1.0, **common)
    path = moving.of_case(case)[0].path
    c, v, _, _ = path.at(0.75)
    assert c[0] - 0.05 == pytest.approx(0.015, abs=1e-12) and v[0] == pytest.approx(0.02)
    case = _case(tmp_path, motion="{type = 'table', file = 'path.csv'}", end=2.0, **common)
    with pytest.raises(CaseError, match="at least time.end"):
        Simulation(case)
    case = _case(tmp_path, motion="{type = 'velocity', velocity = [3.0, 0.0]}", end=0.1, **common)
    with pytest.raises(CaseError, match=r"give time.dt <= 0.00333 s"):
        Simulation(case)
    case = _case(tmp_path, motion="{type = 'velocity', velocity = [0.1, 0.0]}", end=0.1, **common)
    assert refusals(case) == []
    case = _case(tmp_path, motion="{type = 'free', density = 500.0}", end=0.1, **common)
    assert refusals(case) == []  # free bodies run on ranks (tests/parallel/test_split_bodies.py)
    with pytest.raises(CaseError, match="needs its period"):
        _case(tmp_path, motion="{type = 'oscillation', amplitude = [0.01, 0.0]}", end=0.1, **common)


def _float(tmp_path, density, locked, **keys):
    """The tank with a free box of that density (``locked``: its held degrees of freedom),
    the water at rest with its hydrostatic pressure."""
    dim = keys["gravity"].count(",") + 1
    return _case(
        tmp_path,
        pressure="hydrostatic",
        water_velocity="[" + ", ".join(["0.0"] * dim) + "]",
        motion=f"{{type = 'free', density = {density}, locked = {locked}}}",
        **keys,
    )


def _body_rows(sim, every):
    rows = []
    sim.add_writer(
        lambda s: rows.append((s.time, s.scheme.core.body_state.copy())), TimeInterval(every)
    )
    return rows


def test_a_free_body_in_the_air_falls_freely(tmp_path):
    """A box of density 500 far above the water: nothing but gravity acts on it, and its
    pivot follows the step's integration exactly: v_n = -g n dt, y_n = y_0 - g dt^2 n (n +
    1) / 2 (the velocity first, then the position: symplectic Euler), x and the angle kept.
    The time series' body_energy is its 1/2 m v^2 + m g y, which that integration lowers
    by 1/2 m g^2 dt^2 a step: E_n = E_0 - n m g^2 dt^2 / 2."""
    dt = 0.005
    case = _float(
        tmp_path,
        size="[1.0, 2.0]",
        h=0.02,
        water_min="[0.0, 0.0]",
        water_max="[1.0, 0.1]",
        body_min="[0.4, 1.5]",
        body_max="[0.6, 1.7]",
        density=500.0,
        locked="[]",
        gravity="[0.0, -9.81]",
        dt=dt,
        end=0.2,
        interval=0.05,
    )
    sim = Simulation(case)
    rows = _body_rows(sim, 0.05)
    sim.run()
    for t, state in rows:
        n = round(t / dt)
        assert state[0, 1] == pytest.approx(1.6 - G * dt**2 * n * (n + 1) / 2, abs=1e-12), t
        assert state[0, 4] == pytest.approx(-G * dt * n, abs=1e-12), t
        assert state[0, 0] == pytest.approx(0.5, abs=1e-12) and state[0, 12] == 0.0, t
    mass = 500.0 * 0.2 * 0.2  # kg/m
    steps = np.round(sim.series("time") / dt)
    expected = mass * G * 1.6 - steps * mass * G**2 * dt**2 / 2  # J/m
    assert np.allclose(sim.series("body_energy"), expected, rtol=0, atol=1e-9)


def test_a_body_dropped_into_still_water_never_gains_energy_over_its_start(tmp_path):
    """A box of density 500 dropped from 5 cm above still water: the free body's kinetic and
    potential energy is in the time series (body_energy), so the run's energy check counts
    the water and the body together (a free body does no work of its own: the check is on)
    and the pair never rises above its start over 2 s (summary.json's energy).

    Not monotone between outputs (issue 44 asks for that): measured over these 2 s at
    0.01 s outputs, with the defaults the total rises above its running minimum by up to
    16% of the drop's energy (m g 5 cm), FLIP's particle kinetic energy and the volume
    correction's moves of the particles; with PIC and no volume correction (solver.flip = 0,
    solver.volume_correction = 0) and 5 ms steps by 0.4% at h = 0.02 m and never at 0.01 m,
    but at 10 ms steps by 7.6% at 0.01 m, near the top of the body's heave."""
    from mpmflow.simulation import energy

    case = _float(
        tmp_path,
        size="[1.0, 0.6]",
        h=0.02,
        water_min="[0.0, 0.0]",
        water_max="[1.0, 0.3]",
        body_min="[0.43, 0.35]",
        body_max="[0.57, 0.45]",
        density=500.0,
        locked="[]",
        gravity="[0.0, -9.81]",
        dt="'auto'",
        end=2.0,
        interval=0.01,
    )
    sim = Simulation(case)
    sim.run()
    body = sim.series("body_energy")
    mass = 500.0 * 0.14 * 0.1  # kg/m
    assert body[0] == pytest.approx(mass * G * 0.4, rel=1e-12)  # J/m: at rest, 0.4 m up
    total = sim.series("kinetic_energy") + sim.series("potential_energy") + body
    assert total[0] - total[-1] > 0.5 * mass * G * 0.05  # J/m: it lost energy settling
    record = energy.record(sim)
    assert record["not_checked"] is None
    assert record["largest_rise"] == 0.0


@pytest.mark.parametrize("dim", [2, 3])
def test_a_box_floating_at_its_draft_stays_there_and_the_water_at_rest(tmp_path, dim):
    """A box of density 500 and 0.1 m high floating at its draft, 0.05 m (weight = the water
    it displaces), its faces on grid lines: the implicit coupling of the body's velocity to
    the pressure (src/core/step.cpp, couple_bodies) holds it and the water at rest (to 1e-9
    m/s), and the pressure's force on it is its weight."""
    two = dim == 2
    case = _float(
        tmp_path,
        size="[1.0, 0.6]" if two else "[0.48, 0.4, 0.48]",
        h=0.01 if two else 0.04,
        water_min="[0.0, 0.0]" if two else "[0.0, 0.0, 0.0]",
        water_max="[1.0, 0.3]" if two else "[0.48, 0.4, 0.28]",
        body_min="[0.4, 0.25]" if two else "[0.16, 0.12, 0.24]",
        body_max="[0.6, 0.35]" if two else "[0.32, 0.28, 0.32]",
        density=500.0,
        locked="[]",
        gravity="[0.0, -9.81]" if two else "[0.0, 0.0, -9.81]",
        dt="'auto'",
        end=0.5 if two else 0.2,
        interval=0.1,
    )
    sim = Simulation(case)
    rows = _body_rows(sim, 0.1)
    start = sim.scheme.core.body_state.copy()
    sim.run()
    weight = 500.0 * (0.2 * 0.1 if two else 0.16 * 0.16 * 0.08) * G
    for t, state in rows:
        assert np.abs(state[0, :3] - start[0, :3]).max() < 1e-9, t
        assert np.abs(state[0, 3:9]).max() < 1e-9, t
    assert np.abs(sim.particles.v).max() < 1e-9
    assert sim.scheme.core.body_force[0, dim - 1] == pytest.approx(weight, rel=1e-9)


def test_a_free_box_with_its_corners_on_nodes_sinks_without_turning(tmp_path):
    """A box of density 1500 kg/m^3 sinking in a tank symmetric about its axis, its faces
    and corners on planes of nodes: nothing turns it. Its distance at its corner nodes
    comes out +-1e-15 m from its pose and lattice; read with that sign, one corner's cells
    were solid and the other's cut, and the box turned at 0.05 rad/s within 40 steps (4
    particles a cell). Such a node is on its surface (BodyTables::ON_SURFACE), and the box
    keeps its angle to rounding, its pivot on the axis."""
    case = _float(
        tmp_path,
        size="[0.2, 0.15]",
        h=0.01,
        water_min="[0.0, 0.0]",
        water_max="[0.2, 0.1]",
        body_min="[0.08, 0.05]",
        body_max="[0.12, 0.07]",
        density=1500.0,
        locked="[]",
        gravity="[0.0, -9.81]",
        dt=0.001,
        end=0.04,
        interval=0.01,
    )
    sim = Simulation(case)
    rows = _body_rows(sim, 0.01)
    sim.run()
    assert rows[-1][1][0, 1] < 0.06 - 1e-4  # m: it sank
    for t, state in rows:
        assert abs(state[0, 8]) < 1e-10, t  # rad/s
        assert state[0, 0] == pytest.approx(0.1, abs=1e-12), t  # m


def test_a_box_released_off_its_draft_heaves_about_it(tmp_path):
    """The box released 0.02 m high (draft 0.02 m of its equilibrium 0.05 m), held to heave
    only: it oscillates about the level its weight gives, H_eq = the water's level (its
    volume and the box's displacement over the tank) less the draft, within 1% of its
    height (the mean from 2 to 10 s; the closed tank keeps the energy the release gave, in
    the heave and the sloshing it beats with: 1 s means wander by 3 mm), its oscillation
    dies down, and the water's volume is kept."""
    case = _float(
        tmp_path,
        size="[1.0, 0.6]",
        h=0.01,
        water_min="[0.0, 0.0]",
        water_max="[1.0, 0.3]",
        body_min="[0.4, 0.28]",
        body_max="[0.6, 0.38]",
        density=500.0,
        locked='["x", "rotation"]',
        gravity="[0.0, -9.81]",
        dt="'auto'",
        end=10.0,
        interval=0.02,
    )
    sim = Simulation(case)
    rows = _body_rows(sim, 0.02)
    water = sim.particles.volume.sum()
    sim.run()
    level = (water + 0.2 * 0.05) / 1.0
    centre = level - 0.05 + 0.05  # the box's centre: its bottom at level - draft, 0.05 up
    y = np.array([s[0, 1] for t, s in rows])
    t = np.array([t for t, s in rows])
    late = y[t >= 2.0]
    assert abs(late.mean() - centre) < 0.01 * 0.1, (late.mean(), centre)
    first, last = np.ptp(y[t < 1.0]), np.ptp(y[t >= 9.0])
    assert last < 0.6 * first, (first, last)
    assert sim.particles.volume.sum() == pytest.approx(water, rel=1e-12)


# a dry tank 2 m wide for the bodies' contacts: a little water in its far corner (a run needs
# particles), which does not reach them within the runs' time
DRY_TANK = """
title = "{title}"
[domain]
size = [2.0, {height}]
walls = "slip"
[grid]
spacing = 0.02
[[bodies]]
type = "box"
min = [1.95, 0.0]
max = [2.0, 0.05]
particles_per_cell = 2
"""
DRY_END = """
[material]
density = 1000.0
[physics]
gravity = [0.0, -9.81]
[time]
dt = 0.005
end = {end}
[output]
interval = 0.1
snapshots = false
"""

DROP = (
    DRY_TANK.format(title="box dropped", height=0.6)
    + """
[[obstacles]]
name = "box"
type = "box"
min = {body_min}
max = {body_max}
motion = {{type = "free", density = 500.0, rate = {rate}}}
[[obstacles]]
name = "step"
type = "box"
min = [0.5, 0.0]
max = [0.8, 0.2]
"""
    + DRY_END
)


@pytest.mark.parametrize(
    ("body_min", "body_max", "rate", "rest"),
    [
        ("[0.2, 0.3]", "[0.4, 0.4]", 0.0, 0.05),  # flat onto the floor
        ("[0.55, 0.35]", "[0.75, 0.45]", 0.0, 0.25),  # onto the fixed step (top 0.2 m)
        ("[0.2, 0.3]", "[0.4, 0.4]", 60.0, 0.05),  # turning: a corner first, then flat
    ],
)
def test_a_free_body_lands_and_rests_on_the_floor_or_an_obstacle(
    tmp_path, body_min, body_max, rate, rest
):
    """Contact (src/core/bodies.hpp, BodyTables::contact): rigid, frictionless, inelastic, by
    projected Gauss-Seidel over the body's surface points touching a wall or a fixed
    obstacle. A box of density 500 dropped from 0.3 m lands and comes to rest, flat, on the
    floor or on a fixed step, its centre half its height (0.05 m) above what it rests on; no
    sideways motion (frictionless: no sideways impulse); turning as it falls, it lands on a
    corner and settles flat."""
    path = tmp_path / "drop.toml"
    path.write_text(
        DROP.format(body_min=body_min, body_max=body_max, rate=rate, end=2.0 if rate else 0.8)
    )
    sim = Simulation(load_case(path))
    sim.run()
    state = sim.scheme.core.body_state[0]
    centre_x = 0.5 * (float(body_min[1:-1].split(",")[0]) + float(body_max[1:-1].split(",")[0]))
    assert state[0] == pytest.approx(centre_x, abs=1e-9)  # no sideways motion
    assert state[1] == pytest.approx(rest, abs=1e-4)
    assert np.abs(state[3:9]).max() < 1e-6  # at rest
    angle = np.degrees(2 * np.arctan2(state[12], state[9]))
    assert abs(angle) < 0.1


def test_the_plots_draw_a_moving_obstacle_where_it_is(tmp_path):
    """`mpmflow plot` reads bodies.csv: at each snapshot the piston is drawn at its pose, its
    face 0.05 m further in at 1 s than at 0 (a point between the two faces is in the solid
    at 1 s, in the water at 0); the figures are written."""
    import json

    from mpmflow.cli import main
    from mpmflow.plotting.figures import _poses, obstacle_section

    path = tmp_path / "case.toml"
    path.write_text(
        TANK.format(
            ppc=2,
            pressure="zero",
            motion="{type = 'velocity', velocity = [0.05, 0.0]}",
            end=1.0,
            **PISTON_TANK,
        ).replace("snapshots = false", "snapshot_interval = 0.5")
    )
    run = tmp_path / "run"
    assert main(["run", str(path), "--out", str(run), "-q"]) == 0
    summary = json.loads((run / "summary.json").read_text())
    notes: list[str] = []
    poses = _poses(run, notes)
    assert poses is not None and not notes
    X, Y, phi0 = obstacle_section(summary, [0.5, 0.3], notes, 0.0, poses)
    _, _, phi1 = obstacle_section(summary, [0.5, 0.3], notes, 1.0, poses)
    between = (np.abs(X - 0.125) < 0.002) & (np.abs(Y - 0.05) < 0.002)
    assert between.any()
    assert (phi0[between] > 0).all() and (phi1[between] < 0).all()
    assert main(["plot", str(run)]) == 0
    assert (run / "plots" / "snapshots.png").stat().st_size > 1000


@pytest.mark.parametrize("dim", [2, 3])
def test_the_bodies_are_written_for_paraview_where_they_are(tmp_path, dim):
    """With snapshots, each moving obstacle's surface is written beside the particles
    (bodies_NNNNNN.vtu, indexed by bodies.pvd) at its pose: a box turning at 30 degrees/s
    about its centre (3D: about the axis (1, 1, 1)) while its centre moves at U is, at each
    snapshot, the box at t = 0 turned by 30 t degrees and moved by U t, each point's
    velocity U + omega x r, its cells carrying the body's number."""
    import meshio

    from mpmflow.cli import main

    vec = lambda *a: "[" + ", ".join(str(x) for x in a[:dim]) + "]"  # noqa: E731
    U = np.array([0.05, 0.02, 0.01][:dim])
    axis = np.array([1.0, 1.0, 1.0]) / np.sqrt(3) if dim == 3 else np.array([0.0, 0.0, 1.0])
    path = tmp_path / "case.toml"
    path.write_text(
        TANK.format(
            ppc=2,
            pressure="hydrostatic",
            size=vec(0.6, 0.4, 0.4),
            h=0.02,
            water_min=vec(0.0, 0.0, 0.0),
            water_max=vec(0.6, 0.2, 0.4) if dim == 2 else "[0.6, 0.4, 0.2]",
            water_velocity=vec(0.0, 0.0, 0.0),
            body_min=vec(0.25, 0.15, 0.15) if dim == 2 else "[0.25, 0.15, 0.15]",
            body_max=vec(0.35, 0.25, 0.25) if dim == 2 else "[0.35, 0.25, 0.25]",
            motion=f"{{type = 'velocity', velocity = {vec(*U)}, rate = 30.0"
            + (", axis = [1.0, 1.0, 1.0]}" if dim == 3 else "}"),
            gravity=vec(0.0, -9.81) if dim == 2 else "[0.0, 0.0, -9.81]",
            dt=0.01,
            end=0.4,
            interval=0.1,
        ).replace("snapshots = false", "snapshot_interval = 0.2")
    )
    run = tmp_path / "run"
    assert main(["run", str(path), "--out", str(run), "-q"]) == 0
    index = (run / "bodies.pvd").read_text()
    names = [f"bodies_{k:06d}.vtu" for k in range(3)]
    assert all(f'file="{n}"' in index for n in names)
    centre0 = np.array([0.3, 0.2, 0.2][:dim])
    lo, hi = centre0 - 0.05, centre0 + 0.05
    from mpmflow.geometry.shapes import Box

    start, _ = Box(lo, hi).boundary()
    for k, t in enumerate([0.0, 0.2, 0.4]):
        mesh = meshio.read(run / names[k])
        a = np.radians(30.0 * t)
        K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
        R = (np.eye(3) + np.sin(a) * K + (1 - np.cos(a)) * K @ K)[:dim, :dim]
        want = centre0 + U * t + (start - centre0) @ R.T
        assert np.abs(mesh.points[:, :dim] - want).max() < 1e-9, t
        arm = np.zeros((len(want), 3))
        arm[:, :dim] = want - centre0 - U * t
        speed = U + np.cross(np.radians(30.0) * axis, arm)[:, :dim]
        assert np.abs(mesh.point_data["velocity"][:, :dim] - speed).max() < 1e-9, t
        assert (mesh.cell_data["body"][0] == 0).all()


STACK = (
    DRY_TANK.format(title="a box dropped onto another", height=0.8)
    + """
[[obstacles]]
name = "lower"
type = "box"
min = [0.2, 0.0]
max = [0.6, 0.1]
motion = {lower}
[[obstacles]]
name = "upper"
type = "box"
min = [{x0}, 0.3]
max = [{x1}, 0.4]
motion = {{type = "free", density = 500.0}}
"""
    + DRY_END
)


@pytest.mark.parametrize("lower", ["free", "held"])
@pytest.mark.parametrize(
    ("x0", "x1", "rests"), [(0.3, 0.5, True), (0.45, 0.65, True), (0.55, 0.75, False)]
)
def test_a_free_body_lands_on_another_and_rests_or_tips_off(tmp_path, lower, x0, x1, rests):
    """Contact between bodies (BodyTables::contact): a box 0.2 m wide dropped from 0.3 m onto
    a box 0.4 m wide lying on the floor, free (density 500) or held at rest (a path at zero
    velocity). Centred, or overhanging the lower box's edge by 0.05 m with its centre over
    it, it lands and rests flat on it, its centre 0.15 m up, without sliding (frictionless:
    the contact pushes along the face's normal, not the edge's rounded distance: with the
    edge's, the overhanging box slid off at 1 cm/s); the lower one rests on the floor. Its
    centre beyond the edge, it tips off and falls to the floor."""
    motion = (
        "{type = 'free', density = 500.0}"
        if lower == "free"
        else ("{type = 'velocity', velocity = [0.0, 0.0]}")
    )
    path = tmp_path / "stack.toml"
    path.write_text(STACK.format(lower=motion, x0=x0, x1=x1, end=1.0))
    sim = Simulation(load_case(path))
    sim.run()
    state = sim.scheme.core.body_state
    # on the floor: within 0.5 mm (a box knocked sideways may come to rest tilted by up to
    # 0.1 degree on its corners' surface points, sampled from the distance lattice)
    assert state[0, 1] == pytest.approx(0.05, abs=5e-4)
    if rests:  # no sliding: within a micrometre (the impulses' convergence, 1e-9 m/s a sweep)
        assert state[0, 0] == pytest.approx(0.4, abs=1e-6)
        assert state[1, 0] == pytest.approx(0.5 * (x0 + x1), abs=1e-6)
        assert state[1, 1] == pytest.approx(0.15, abs=1e-4)
        assert np.abs(state[:, 3:9]).max() < 1e-6  # both at rest
        assert abs(np.degrees(2 * np.arctan2(state[1, 12], state[1, 9]))) < 0.01
    else:
        assert state[1, 0] > 0.6 + 0.05 and state[1, 1] < 0.1 + 1e-3  # off the edge, down


# gravity tilted by 10 degrees towards +x: the dry tank's floor is an incline (tan = 0.176)
INCLINE = math.radians(10.0)
SLOPE = (
    DRY_TANK.format(title="boxes on an incline", height=0.4)
    + """
[[obstacles]]
name = "lower"
type = "box"
min = [0.2, 0.0]
max = [{x1}, 0.1]
motion = {{type = "free", density = 500.0, friction = {mu}}}
{upper}
[material]
density = 1000.0
[physics]
gravity = [{gx}, {gy}]
[time]
dt = 0.005
end = {end}
[output]
interval = 0.1
snapshots = false
"""
)
UPPER = """[[obstacles]]
name = "upper"
type = "box"
min = [0.3, 0.1]
max = [0.4, 0.2]
motion = {{type = "free", density = 500.0, friction = {mu}}}"""


def _slide(mu: float) -> float:
    """Coulomb's acceleration (m/s^2) down the incline, 0 where friction holds."""
    return max(G * (math.sin(INCLINE) - mu * math.cos(INCLINE)), 0.0)


@pytest.mark.parametrize("mu", [0.0, 0.1, 0.3])
def test_a_box_on_an_incline_slides_or_holds_by_coulombs_law(tmp_path, mu):
    """Friction (obstacles.N.motion.friction, BodyTables::contact): a box resting on the floor
    with gravity 10 degrees off the vertical slides with a = g (sin - mu cos) where mu <
    tan 10 degrees = 0.176, and holds where mu is larger. Semi-implicit Euler (the contacts,
    then the move) gives the velocity a t exactly and the distance a dt^2 n (n + 1) / 2 after
    n steps; a held box does not creep (it did at g sin dt, 8.5 mm/s, when the move came
    before the contacts). It stays flat on the floor."""
    path = tmp_path / "incline.toml"
    end, dt = 0.6, 0.005
    gx, gy = G * math.sin(INCLINE), -G * math.cos(INCLINE)
    path.write_text(SLOPE.format(x1=0.4, mu=mu, upper="", gx=gx, gy=gy, end=end))
    sim = Simulation(load_case(path))
    sim.run()
    state = sim.scheme.core.body_state[0]
    a, n = _slide(mu), round(end / dt)
    assert state[3] == pytest.approx(a * end, rel=1e-6, abs=1e-8)
    assert state[0] - 0.3 == pytest.approx(0.5 * a * dt**2 * n * (n + 1), rel=1e-6, abs=1e-8)
    assert state[1] == pytest.approx(0.05, abs=1e-6)
    assert abs(state[4]) < 1e-8 and abs(state[8]) < 1e-6  # no lift, no turn


@pytest.mark.parametrize("mu", [0.05, 0.3])
def test_a_box_on_another_slides_at_the_mean_of_their_frictions(tmp_path, mu):
    """Between two free bodies mu is the geometric mean of theirs: a box on a longer box
    that friction (0.3) holds on the incline slides at Coulomb's rate for sqrt(0.3 mu)
    (0.122 for mu = 0.05, under tan 10 degrees) and holds at mu = 0.3; the lower one does
    not move."""
    path = tmp_path / "stack.toml"
    end, dt = 0.4, 0.005
    gx, gy = G * math.sin(INCLINE), -G * math.cos(INCLINE)
    upper = UPPER.format(mu=mu)
    path.write_text(SLOPE.format(x1=0.6, mu=0.3, upper=upper, gx=gx, gy=gy, end=end))
    sim = Simulation(load_case(path))
    sim.run()
    lower, top = sim.scheme.core.body_state
    a, n = _slide(math.sqrt(0.3 * mu)), round(end / dt)
    assert lower[0] == pytest.approx(0.4, abs=1e-8) and abs(lower[3]) < 1e-8
    assert top[3] == pytest.approx(a * end, rel=1e-6, abs=1e-8)
    assert top[0] - 0.35 == pytest.approx(0.5 * a * dt**2 * n * (n + 1), rel=1e-6, abs=1e-8)
    assert top[1] == pytest.approx(0.15, abs=1e-6)


HINGED = """
title = "a hinged bar"
[domain]
size = {size}
walls = "slip"
[grid]
spacing = 0.02
[[bodies]]
type = "box"
min = {water_min}
max = {water_max}
particles_per_cell = 2
around_obstacles = true
initial_pressure = "hydrostatic"
[[obstacles]]
name = "bar"
type = "polygon"
vertices = {vertices}
motion = {{type = "free", density = 500.0, pivot = {pivot}, locked = {locked}, rate = {rate}}}
[material]
density = 1000.0
[physics]
gravity = [0.0, -9.81]
[time]
dt = {dt}
end = {end}
[output]
interval = 0.01
snapshots = false
"""


def _bar(pivot, length, width, angle):
    """The corners of a bar length x width (m) from its end's midpoint pivot, pointing at
    angle (radians, below the horizontal)."""
    p = np.asarray(pivot, dtype=float)
    e = np.array([np.cos(angle), -np.sin(angle)])
    n = np.array([np.sin(angle), np.cos(angle)])
    return np.array(
        [
            p - n * width / 2,
            p + length * e - n * width / 2,
            p + length * e + n * width / 2,
            p + n * width / 2,
        ]
    )


def _hinged(tmp_path, corners, pivot, end, rate=0.0, dt="0.005", water=None):
    size, water_min, water_max = water or ("[1.2, 0.8]", "[1.12, 0.0]", "[1.2, 0.04]")
    vertices = "[" + ", ".join(f"[{x:.9f}, {y:.9f}]" for x, y in corners) + "]"
    path = tmp_path / "hinged.toml"
    path.write_text(
        HINGED.format(
            size=size,
            water_min=water_min,
            water_max=water_max,
            vertices=vertices,
            pivot=list(pivot),
            locked='["x", "y"]',
            rate=rate,
            dt=dt,
            end=end,
        )
    )
    sim = Simulation(load_case(path))
    rows = []
    sim.add_writer(
        lambda s: rows.append((s.time, *s.scheme.core.body_state[0].copy())),
        TimeInterval(0.01),
        name="pose",
    )
    sim.run()
    rows = np.array(rows)
    return rows[:, 0], 2 * np.arctan2(rows[:, 13], rows[:, 10]), rows[:, 1:3]


def test_a_hinged_bar_swings_as_a_compound_pendulum(tmp_path):
    """A free body with a pivot and its translations held is hinged there (motion.pivot):
    a bar 0.4 x 0.04 m hanging from the midpoint of its top end, set turning at 30
    degrees/s in air, swings with the compound pendulum's period 2 pi sqrt(I_p / (m g d)),
    I_p its inertia about the hinge (parallel axes), d = 0.2 m, with the amplitude's
    correction (1 + theta0^2 / 16): within 0.1% (0.01% measured), the hinge fixed."""
    t, angle, pivot = _hinged(
        tmp_path, _bar([0.5, 0.7], 0.4, 0.04, np.pi / 2), [0.5, 0.7], end=2.2, rate=30.0
    )
    up = [
        t[i] - angle[i] * (t[i + 1] - t[i]) / (angle[i + 1] - angle[i])
        for i in range(len(t) - 1)
        if angle[i] < 0 <= angle[i + 1]
    ]
    period0 = 2 * np.pi * np.sqrt(((0.4**2 + 0.04**2) / 12 + 0.2**2) / (G * 0.2))
    period = period0 * (1 + np.abs(angle).max() ** 2 / 16)
    assert len(up) == 2 and up[1] - up[0] == pytest.approx(period, rel=1e-3)
    assert np.abs(pivot - [0.5, 0.7]).max() == 0.0


def _floating_angle(length, width, pivot, level0, start, tank):
    """The angle (radians below the horizontal) at which a bar hinged at pivot floats, density
    500 in water, by its moments (hydrostatics of the rectangle, the level lowered by the
    volume it lifts out of the water from its start in a tank this wide)."""

    def area_centroid(P):
        x, y, x1, y1 = P[:, 0], P[:, 1], np.roll(P[:, 0], -1), np.roll(P[:, 1], -1)
        c = x * y1 - x1 * y
        return c.sum() / 2, np.array([((x + x1) * c).sum(), ((y + y1) * c).sum()]) / (3 * c.sum())

    def below(P, y0):
        out = []
        for A, B in zip(P, np.roll(P, -1, axis=0)):
            if A[1] <= y0:
                out.append(A)
            if (A[1] <= y0) != (B[1] <= y0):
                out.append(A + (y0 - A[1]) / (B[1] - A[1]) * (B - A))
        return np.array(out)

    def moment(angle, level):
        corners = _bar(pivot, length, width, angle)
        area, centre = area_centroid(corners)
        wet, wet_centre = area_centroid(below(corners, level))
        return RHO * wet * (wet_centre[0] - pivot[0]) - 500.0 * area * (centre[0] - pivot[0]), wet

    wet0 = moment(start, level0)[1]
    level, angle = level0, start
    for _ in range(20):  # the level and the angle, each at the other's
        lo, hi = 0.01, 0.7
        for _ in range(60):
            angle = 0.5 * (lo + hi)
            lo, hi = (lo, angle) if moment(angle, level)[0] > 0 else (angle, hi)
        level = level0 + (moment(angle, level)[1] - wet0) / tank
    return angle


def test_a_hinged_bar_floats_at_the_angle_of_its_moments(tmp_path):
    """A bar 0.6 x 0.04 m of density 500 hinged 0.1 m above water 0.4 m deep, released at 20
    degrees below the horizontal, settles where buoyancy's moment about the hinge balances
    its weight's (the rectangle's hydrostatics with the level it leaves, 14.09 degrees):
    its mean angle over the last 1.5 s of 5 within 5% at h = 0.02 m (-1.3% measured, the bar
    still rocking by 0.8 degree with the closed tank's sloshing; with a sponge at the far
    end -3.5%, and -3.1% and -0.7% at h = 0.01 and 0.005 m)."""
    pivot, start = [0.4, 0.5], np.radians(20.0)
    t, angle, _ = _hinged(
        tmp_path,
        _bar(pivot, 0.6, 0.04, start),
        pivot,
        end=5.0,
        dt='"auto"',
        water=("[2.0, 0.7]", "[0.0, 0.0]", "[2.0, 0.4]"),
    )
    below = start - angle  # the core turns it counter-clockwise positive
    want = _floating_angle(0.6, 0.04, pivot, 0.4, start, 2.0)
    assert np.degrees(want) == pytest.approx(14.09, abs=0.01)
    assert below[t > 3.5].mean() == pytest.approx(want, rel=0.05)


def test_a_pivot_elsewhere_than_the_centroid_needs_the_translations_held(tmp_path):
    case = TANK.format(
        ppc=2,
        pressure="zero",
        motion="{type = 'free', density = 500.0, pivot = [0.05, 0.3]}",
        end=0.1,
        **PISTON_TANK,
    )
    path = tmp_path / "case.toml"
    path.write_text(case)
    with pytest.raises(CaseError, match=r"hinge.*locked"):
        Simulation(load_case(path))
