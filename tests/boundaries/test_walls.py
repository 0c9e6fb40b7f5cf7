"""Walls push but never pull: water leaves a ceiling and a wall it moves away from."""

import math

import numpy as np
import pytest
from conftest import EXAMPLES, make_case

from mpmflow import Simulation
from mpmflow.case import load_case
from mpmflow.errors import CaseError


def test_water_does_not_hang_from_the_ceiling():
    # a block touching the ceiling of a closed box falls freely under gravity
    case = make_case(
        size=(0.1, 0.2),
        spacing=0.01,
        body=((0.0, 0.12), (0.1, 0.2)),
        end=0.1,
        output={"snapshots": False},
    )
    sim = Simulation(case)
    top0 = sim.particles.x[:, 1].max()
    sim.run()
    fall = top0 - sim.particles.x[:, 1].max()
    assert fall == pytest.approx(0.5 * 9.81 * 0.1**2, rel=0.1)


def test_material_leaves_a_wall_it_moves_away_from():
    case = make_case(
        size=(0.3, 0.1),
        spacing=0.01,
        body=((0.0, 0.0), (0.05, 0.05)),
        end=0.05,
        physics={"gravity": [0.0, 0.0]},
        output={"snapshots": False},
    )
    data = case.model_dump()
    data["bodies"][0]["velocity"] = [1.0, 0.0]
    from mpmflow.case import validate

    sim = Simulation(validate(data))
    sim.run()
    # moving right at 1 m/s without gravity: the block left the left wall by ~5 cm
    assert sim.particles.x[:, 0].min() == pytest.approx(0.05 + 0.00125, abs=0.005)
    assert np.allclose(sim.particles.v[:, 0], 1.0, atol=1e-6)


# --- a condition per side (domain.walls = {axis or side = condition}) ---

G = 9.81


def _film_3d(walls, end=0.75):
    """A Newtonian layer H = 0.05 m deep (nu = 0.01 m^2/s) on a 10 degree incline along x
    (periodic), between walls at y = 0 and y = W = 0.04 m: the mean x velocity of the
    particles in each (y, z) band of one cell (rows y, columns z) at ``end``, the particles'
    largest |v_y| and |v_z|, the band centres and the slope's g sin(theta)."""
    theta = math.radians(10.0)
    h, H, W = 0.005, 0.05, 0.04
    case = load_case(
        EXAMPLES / "poiseuille_film.toml",
        [
            "domain.size=[0.04, 0.04, 0.08]",
            "domain.periodic=[true, false, false]",
            f"domain.walls={walls}",
            "bodies.0.min=[0.0, 0.0, 0.0]",
            f"bodies.0.max=[0.04, {W}, {H}]",
            "bodies.0.particles_per_cell=2",
            f"physics.gravity=[{G * math.sin(theta)}, 0.0, {-G * math.cos(theta)}]",
            f"time.end={end}",
            "time.dt=2e-3",
            "output.snapshots=false",
            "output.interval=0.05",
        ],
    )
    sim = Simulation(case)
    sim.run()
    x, v = sim.particles.x, sim.particles.v
    ny, nz = round(W / h), round(H / h)
    iy = np.minimum((x[:, 1] / h).astype(int), ny - 1)
    iz = np.minimum((x[:, 2] / h).astype(int), nz - 1)
    U = np.array([[v[(iy == j) & (iz == k), 0].mean() for k in range(nz)] for j in range(ny)])
    centres = lambda n: (np.arange(n) + 0.5) * h  # noqa: E731
    return (
        U,
        np.abs(v[:, 1]).max(),
        np.abs(v[:, 2]).max(),
        centres(ny),
        centres(nz),
        G * math.sin(theta),
    )


@pytest.mark.slow
def test_a_layer_on_a_no_slip_floor_between_slip_side_walls_is_uniform_across():
    """walls = {y = "slip", z_min = "no_slip"}: the slip side walls hold no shear, so the
    film is the Nusselt film of an infinitely wide incline, the same in every y band (3
    viscous times from rest: the start-up has decayed to 6e-4 of the steady speed)."""
    U, vy, vz, yc, zc, gs = _film_3d("{y='slip', z_min='no_slip'}")
    nu, H = 0.01, 0.05
    nusselt = gs / nu * (H * zc - zc**2 / 2)
    assert np.ptp(U, axis=0).max() < 1e-6 * U.max()  # no shear at the side walls
    assert vy < 1e-6 and vz < 1e-6
    # the film's profile: within 1% from the fourth band up, 6% in the second and third
    # (the first band's mean is a sheared wall cell's)
    np.testing.assert_allclose(U[0, 3:], nusselt[3:], rtol=0.01)
    np.testing.assert_allclose(U[0, 1:3], nusselt[1:3], rtol=0.06)


@pytest.mark.slow
def test_a_slip_floor_between_no_slip_side_walls_gives_the_channel_profile():
    """The reverse, walls = {y = "no_slip"} (the floor and top slip): the walls at y = 0
    and W hold the flow, so each z band is plane Poiseuille across y, g sin(theta) y (W -
    y) / (2 nu), the same at every depth (the floor holds no shear). Measured: the bands
    next to the free surface run up to 13% faster (its partial cells hold less viscous
    stress), so the profile is read below them; the bands one cell off the walls run 7 to
    10% fast, the others are within 3% up to 4 cells below the surface (4% above)."""
    U, vy, vz, yc, zc, gs = _film_3d("{y='no_slip'}", end=0.5)
    nu, W = 0.01, 0.04
    channel = gs / (2 * nu) * yc * (W - yc)
    np.testing.assert_allclose(U, U[::-1], rtol=1e-5)  # symmetric across the channel
    middle = U[1:-1, :-2]  # the bands off the walls, below the free surface's two
    error = np.abs(middle / channel[1:-1, None] - 1)
    assert error[1:-1, :6].max() < 0.03 and error[1:-1].max() < 0.05 and error.max() < 0.12
    assert np.ptp(middle[:, :6], axis=1).max() < 0.02 * U.max()  # the same at every depth
    assert U[0, :-2].max() < 0.2 * U.max()  # held at the side walls


@pytest.mark.parametrize("scheme", ["projection", "explicit"])
def test_each_side_keeps_its_own_condition(scheme):
    """A water block sliding along the floor at 0.5 m/s, away from the side walls (it
    spreads from x = 0.1..0.15 m to 0.11..0.19 m in 0.05 s): whatever the side walls are, a
    slip floor gives the run of all-slip walls bit for bit, and a no-slip floor that of
    all-no-slip walls, braking the block to a mean 0.33 m/s; the string form is the table
    that names every wall."""
    more = [
        "domain.size=[0.4, 0.1]",
        "grid.spacing=0.01",
        "bodies.0.min=[0.1, 0.0]",
        "bodies.0.max=[0.15, 0.03]",
        "bodies.0.velocity=[0.5, 0.0]",
        "time.end=0.05",
        "output.snapshots=false",
    ]
    if scheme == "explicit":
        more += ["solver.scheme=explicit", "time.dt=auto", "material.bulk_modulus=4e5"]

    def mean_u(walls):
        sim = Simulation(load_case(EXAMPLES / "hydrostatic.toml", more + [f"domain.walls={walls}"]))
        sim.run()
        return sim.particles.v[:, 0].mean(), sim.particles.x.copy()

    slip, x_slip = mean_u("{x='no_slip', y_max='no_slip'}")  # the floor slips
    smooth, x_smooth = mean_u("slip")
    held, x_held = mean_u("{y_min='no_slip'}")
    rough, x_rough = mean_u("no_slip")
    _, x_table = mean_u("{x='no_slip', y='no_slip'}")
    assert slip == pytest.approx(0.5, rel=0.01) and np.array_equal(x_slip, x_smooth)
    assert held < 0.4 and np.array_equal(x_held, x_rough)
    assert np.array_equal(x_table, x_rough)


@pytest.mark.parametrize(
    "override, message",
    [
        (
            ["domain.walls={z_min='no_slip'}"],
            r"'z_min' is not a side of a 2D domain \(did you "
            r"mean y_min\?\); the keys are the axes x, y \(both walls\) and the sides x_min, x_max, "
            r"y_min, y_max",
        ),
        (["domain.walls={floor='no_slip'}"], r"'floor' is not a side of a 2D domain"),
        (
            ["domain.walls={y_min='rough'}"],
            r"y_min = 'rough' is not a wall condition: give "
            r"\"slip\", \"no_slip\", \"bonded\" or \"outlet\"",
        ),
        (["domain.walls=rough"], r"'rough' is not a wall condition"),
        (["domain.walls={}"], r"the table of sides is empty"),
        (
            ["domain.periodic=[true, false]", "domain.walls={x_max='no_slip', y='no_slip'}"],
            r"domain.walls names x_max, but x is periodic \(domain.periodic\), so it has no walls",
        ),
        (
            [
                "domain.walls.y_min=no_slip",
                "obstacles.0={type='box', min=[0.03, 0.22], max=[0.06, 0.25]}",
            ],
            r'obstacles.0.walls = "domain" \(the default\) takes the condition of domain.walls, but '
            r'domain.walls gives its walls different ones \(\{x = "slip", y = "slip", y_min = '
            r'"no_slip"\}\); set obstacles.0.walls = "slip" or "no_slip"',
        ),
    ],
)
def test_bad_wall_sides_are_refused_with_the_fix(override, message):
    with pytest.raises(CaseError, match=message):
        load_case(EXAMPLES / "hydrostatic.toml", override)


def test_one_side_set_on_the_command_line_keeps_the_others():
    """--set domain.walls.y_max=slip over walls = "no_slip" (x periodic): the other walls
    stay no-slip; a side's key overrides its axis's."""
    case = load_case(EXAMPLES / "poiseuille_film.toml", ["domain.walls.y_max=slip"])
    assert case.domain.walls == {"y": "no_slip", "y_max": "slip"}
    assert case.domain.wall_conditions()[1] == ("no_slip", "slip")
    assert case.domain.no_slip_sides() == [False, False, True, False]  # x periodic: unused
    case = load_case(EXAMPLES / "dam_break_3d.toml", ["domain.walls={z_min='no_slip'}"])
    assert case.domain.no_slip_sides() == [False, False, False, False, True, False]
    # an obstacle may take the domain's condition where every wall has the same one
    case = load_case(
        EXAMPLES / "hydrostatic.toml",
        [
            "domain.walls={x='no_slip', y='no_slip'}",
            "obstacles.0={type='box', min=[0.03, 0.22], max=[0.06, 0.25]}",
        ],
    )
    assert case.domain.uniform_walls() == "no_slip"
