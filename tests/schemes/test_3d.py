"""3D: the same core as 2D, with z up. Coarse meshes, so that CI stays short."""

import numpy as np
import pytest
from conftest import EXAMPLES, make_case

from mpmflow import Simulation, load_case
from mpmflow.diagnostics.measures import front_and_height
from mpmflow.errors import CaseError
from mpmflow.geometry.bodies import fills_grid, overlap_message
from mpmflow.grid import Grid

RHO, G = 1000.0, 9.81


@pytest.mark.parametrize("depth, end", [(0.195, 1.0), (0.2, 0.2)])
@pytest.mark.slow
def test_column_at_rest_in_3d_is_exact(depth, end):
    """The 3D column at rest with the defaults, surface half a cell off the grid (over 1 s)
    and on a grid line: the particle pressure is rho g (H - z) to 1e-6 relative and no
    particle moves faster than 1e-6 m/s, as in 2D."""
    case = load_case(
        EXAMPLES / "hydrostatic_3d.toml",
        [f"bodies.0.max=[0.1, 0.05, {depth}]", f"time.end={end}", "output.snapshots=false"],
    )
    sim = Simulation(case)
    sim.run()
    assert sim.time == pytest.approx(end)
    P = sim.particles
    assert P.x.shape[1] == 3 and P.count == 10 * 5 * round(depth / 0.005) * 4
    assert np.nanmax(sim.series("max_speed")) <= 1e-6
    exact = RHO * G * (depth - P.x[:, 2])
    assert np.max(np.abs(P.pressure - exact)) <= 1e-6 * exact.max()


def test_every_vector_has_one_entry_per_axis():
    with pytest.raises(
        CaseError,
        match=r"bodies.0.max = \[0.1, 0.2\] has 2 entries but "
        r"domain.size = \[0.1, 0.05, 0.3\] has 3",
    ):
        load_case(EXAMPLES / "hydrostatic_3d.toml", ["bodies.0.max=[0.1, 0.2]"])
    with pytest.raises(CaseError, match="physics.gravity"):
        load_case(EXAMPLES / "hydrostatic_3d.toml", ["physics.gravity=[0, -9.81]"])
    # defaults follow the dimension: gravity down the last axis, bodies at rest
    case = make_case(size=(0.1, 0.05, 0.3), body=((0, 0, 0), (0.1, 0.05, 0.2)), ppc=2)
    assert case.physics.gravity == [0.0, 0.0, -9.81] and case.bodies[0].velocity == [0.0] * 3
    assert make_case().physics.gravity == [0.0, -9.81]


@pytest.mark.parametrize(
    "override, words",
    [(["bodies.0.surface_amplitude=0.01"], "cosine top surface is defined for 2D cases only")],
)
def test_what_is_2d_only_is_refused_in_3d_with_the_fix(override, words):
    with pytest.raises(CaseError, match=words):
        load_case(EXAMPLES / "hydrostatic_3d.toml", override)


def test_overlapping_and_filling_bodies_in_3d():
    case = make_case(size=(0.1, 0.05, 0.3), body=((0, 0, 0), (0.1, 0.05, 0.2)), ppc=2)
    a = case.bodies[0]
    b = a.model_copy(update={"min": [0.05, 0.0, 0.1], "max": [0.1, 0.05, 0.3]})
    message = overlap_message([a, b], 0.01)
    assert message and "x = 0.05 to 0.1 m, y = 0 to 0.05 m, z = 0.1 to 0.2 m" in message
    apart = b.model_copy(update={"min": [0.0, 0.0, 0.2]})  # touches a's top face only
    assert overlap_message([a, apart], 0.01) is None
    assert not fills_grid([a], 0.01, [0.1, 0.05, 0.3])
    assert fills_grid([a, apart], 0.01, [0.1, 0.05, 0.3])
    with pytest.raises(CaseError, match="fill the whole domain"):
        make_case(size=(0.1, 0.05, 0.2), body=((0, 0, 0), (0.1, 0.05, 0.2)), ppc=2)


def test_front_and_height_of_an_extruded_field_are_the_2d_ones():
    rng = np.random.default_rng(3)
    g2, g3 = Grid(0.01, (12, 9)), Grid(0.01, (12, 4, 9))
    theta2 = rng.uniform(0, 1.3, (9, 12))  # [cy, cx]
    theta3 = np.repeat(theta2[:, None, :], 4, axis=1)  # [cz, cy, cx]: the same in every slice
    f2, h2 = front_and_height(g2, theta2.ravel())
    f3, h3 = front_and_height(g3, theta3.ravel())
    assert f3 == pytest.approx(f2, abs=1e-15) and h3 == pytest.approx(h2, abs=1e-15)


def test_a_half_full_cell_is_half_full_to_rounding():
    """Half a cell of particles reads 0.49999999999999994 in 3D where it reads 0.5 in 2D (the
    dam break of the next test at 0.15 s: 125 such 3D cells, 25 such 2D cells, one per
    slice); both are half full, so the front does not move a cell back in 3D
    (measures.HALF_FULL)."""
    g2, g3 = Grid(0.01, (6, 3)), Grid(0.01, (6, 2, 3))
    theta2 = np.zeros((3, 6))
    theta2[:, :3] = 1.0
    theta2[:, 3] = 0.5
    theta3 = np.repeat(theta2[:, None, :], 2, axis=1)
    theta3[:, :, 3] = np.nextafter(0.5, 0.0)  # 0.49999999999999994
    f2, h2 = front_and_height(g2, theta2.ravel())
    f3, h3 = front_and_height(g3, theta3.ravel())
    assert f2 == pytest.approx(0.035, abs=1e-12)  # the half-full cell's centre
    assert f3 == pytest.approx(f2, abs=1e-12) and h3 == pytest.approx(h2, abs=1e-12)


def test_the_3d_dam_break_across_a_slip_tank_is_the_2d_one():
    """examples/dam_break_3d.toml extrudes the 2D dam break across a tank 5 cells wide with
    slip walls, so each slice of it is the 2D flow on the same mesh and particle spacing:
    over the collapse's first 0.15 s the two follow each other to 1e-5 m (measured: 1.1e-6
    m), and their fronts and heights are the same. Until half a cell of particles was read
    as half full to rounding (0.49999999999999994 in 3D, 0.5 in 2D: state.HALF_FULL, which
    the volume correction and the outputs' measures read), the 3D correction took such a cell's neighbours as surface
    rows where the 2D one did not: the particles parted by 2.5e-6 m at the toe in the 16th
    step and the fronts by 0.07 a at 0.15 s. Later the two still part (the heights by 0.035 a
    at 0.21 s: the validation's 3D rows): the side walls never pull, and from the 46th step
    their nodes near the surface are held at p = 0 where the slices' interior reads -0.01
    Pa."""
    over = ["output.snapshots=false", "time.end=0.15"]
    sim3 = Simulation(load_case(EXAMPLES / "dam_break_3d.toml", over))
    sim2 = Simulation(
        load_case(
            EXAMPLES / "dam_break.toml",
            [*over, "grid.spacing=0.008", "bodies.0.particles_per_cell=2"],
        )
    )
    start = {(round(x, 9), round(z, 9)): k for k, (x, z) in enumerate(sim2.particles.x)}
    match = np.array([start[(round(x, 9), round(z, 9))] for x, _, z in sim3.particles.x])
    across = sim3.particles.x[:, 1].copy()
    sim3.run()
    sim2.run()
    x3, x2 = sim3.particles.x, sim2.particles.x[match]
    assert np.abs(x3[:, [0, 2]] - x2).max() < 1e-5  # m
    assert np.abs(x3[:, 1] - across).max() < 1e-5  # m (measured: 5.6e-7 m across the tank)
    for name in ("front", "height"):
        assert np.abs(sim3.series(name) - sim2.series(name)).max() < 1e-6  # m


@pytest.mark.slow
def test_3d_outputs_read_back_and_plot(tmp_path):
    """Snapshots keep z, energies are in J (not J/m), and `mpmflow plot` draws the x-z slice
    through the middle of the width and, beside it, the water's surface in 3D."""
    pytest.importorskip("matplotlib")
    from mpmflow import open_run
    from mpmflow.plotting.figures import plot_run, side_view

    case = load_case(EXAMPLES / "hydrostatic_3d.toml", ["time.end=0.02"])
    sim = Simulation(case, tmp_path / "o")
    sim.run()
    run = open_run(tmp_path / "o")
    assert run.units["kinetic_energy"] == "J" and run.units["potential_energy"] == "J"
    snap = run.snapshots[-1].read()
    np.testing.assert_allclose(snap["x"], sim.particles.x, rtol=1e-6)
    xz, p, plane, names, caption = side_view(snap["x"], snap["pressure"], [0.1, 0.05, 0.3], 0.01)
    assert names == ("x", "z") and plane == [0.1, 0.3] and "y = 0.025" in caption
    in_slice = np.abs(snap["x"][:, 1] - 0.025) <= 0.005
    assert 0 < len(xz) == in_slice.sum() < len(snap["x"])  # a slice, not everything
    np.testing.assert_array_equal(xz, snap["x"][in_slice][:, [0, 2]])
    figures = plot_run(tmp_path / "o", tmp_path / "plots")
    assert any(f.name == "snapshots.png" for f in figures)
    # beside each slice its water surface, and their overview
    names = {f.relative_to(tmp_path / "plots").as_posix() for f in figures}
    for k in range(len(run.snapshots)):
        assert {f"snapshots/particles_{k:06d}.png", f"snapshots/surface_{k:06d}.png"} <= names
    assert "surfaces.png" in names and all(f.stat().st_size > 1000 for f in figures)


@pytest.mark.parametrize("depth", [0.195, 0.2])
def test_water_surface_of_a_column_at_rest_is_the_column(depth):
    """The marching-cubes surface (volume fraction 1/2) of the 3D column at rest, its top
    half a cell off the grid (the top cells half full) and on a grid line: every vertex
    lies on the column's faces (the surface is closed on the walls and the floor), and
    its top is the water's depth (float32 vertices: to 1e-6 m)."""
    from mpmflow.plotting.surface import volume_fraction, water_surface

    case = load_case(
        EXAMPLES / "hydrostatic_3d.toml",
        [f"bodies.0.max=[0.1, 0.05, {depth}]", "output.snapshots=false"],
    )
    sim = Simulation(case)
    f = volume_fraction(sim.particles.x, sim.particles.volume, sim.grid.spacing, sim.grid.cells)
    assert f.shape == (10, 5, 30) and f.max() == 1.0
    verts, faces = water_surface(f, sim.grid.spacing)
    hi = np.array([0.1, 0.05, depth])
    np.testing.assert_allclose(verts.min(axis=0), 0.0, atol=1e-6)
    np.testing.assert_allclose(verts.max(axis=0), hi, atol=1e-6)
    # the distance of each vertex to the column's surface (all lie inside its box)
    to_face = np.minimum(verts, hi - verts).min(axis=1)
    assert to_face.min() >= -1e-6 and to_face.max() <= 1e-6
    top = verts[:, 2] > depth - 0.25 * sim.grid.spacing
    np.testing.assert_allclose(verts[top, 2], depth, atol=1e-6)


def test_water_surface_area_of_whole_cells_is_the_box_with_chamfered_edges():
    """On whole cells (top on a grid line), marching cubes draws the column's box with
    every edge cut by a chamfer of legs h/2: the area is the box's less (1 - 1/sqrt 2) h
    per metre of edge, to within the eight corners' (h/2)^2 each (0.3% of the area; the
    chamfers alone are 6%)."""
    from mpmflow.plotting.surface import surface_area, volume_fraction, water_surface

    case = load_case(
        EXAMPLES / "hydrostatic_3d.toml",
        ["bodies.0.max=[0.1, 0.05, 0.2]", "output.snapshots=false"],
    )
    sim = Simulation(case)
    h = sim.grid.spacing
    f = volume_fraction(sim.particles.x, sim.particles.volume, h, sim.grid.cells)
    area = surface_area(*water_surface(f, h))
    a, b, c = 0.1, 0.05, 0.2
    box, edges = 2 * (a * b + b * c + c * a), 4 * (a + b + c)
    chamfered = box - (1 - 1 / np.sqrt(2)) * h * edges
    assert abs(area - chamfered) <= 8 * (h / 2) ** 2
    assert area < box - 0.05 * box


def test_a_dry_field_has_no_surface_and_obstacles_are_drawn_as_their_surfaces():
    """No cell at 1/2: no triangles (not an error). The obstacles' triangles: a box's six
    faces exactly, a cylinder (marching cubes on its signed distance) within 3% of its
    area, every vertex within a sample of its surface."""
    from mpmflow.case import resolved
    from mpmflow.plotting.surface import obstacle_triangles, surface_area, water_surface

    verts, faces = water_surface(np.full((4, 3, 5), 0.49), 0.01)
    assert verts.shape == (0, 3) and faces.shape == (0, 3)
    case = load_case(
        EXAMPLES / "stl_drop_3d.toml",
        [
            "obstacles=[{type = 'box', min = [0.2, 0.05, 0.0], max = [0.25, 0.15, 0.04]}, "
            "{type = 'cylinder', centre = [0.0637, 0.1513, 0.0], axis = [0, 0, 1], "
            "radius = 0.0213, length = 0.15}]"
        ],
    )
    notes = []
    tris = obstacle_triangles({"case": resolved(case)}, notes)
    assert notes == []
    box, cyl = tris[:12], tris[12:]
    flat = box.reshape(-1, 3)
    assert surface_area(flat, np.arange(len(flat)).reshape(-1, 3)) == pytest.approx(
        2 * (0.05 * 0.1 + 0.1 * 0.04 + 0.04 * 0.05), rel=1e-12
    )
    r, length = 0.0213, 0.15
    flat = cyl.reshape(-1, 3)
    exact = 2 * np.pi * r * length + 2 * np.pi * r**2
    assert surface_area(flat, np.arange(len(flat)).reshape(-1, 3)) == pytest.approx(exact, rel=0.03)
    d = case.obstacle_shape(1).signed_distance(flat)
    assert np.abs(d).max() <= 0.1 * length / 32  # a tenth of a sample
