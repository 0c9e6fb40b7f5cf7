"""Shapes of bodies and obstacles: containment and signed distance against analytic values,
closed meshes read from files (and refused when open, empty or missing), seeded counts equal
to the sizing counts, and each bad geometry refused with its key and fix (exit code 2)."""

import os
import struct
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
import trimesh

from mpmflow.case import validate
from mpmflow.cli import main
from mpmflow.errors import CaseError
from mpmflow.geometry import meshes, shapes
from mpmflow.geometry.seeding import build_particles
from mpmflow.grid import Grid

RNG = np.random.default_rng(15)


# --------------------------------------------------------------------------- primitives


def test_box_in_2d_and_3d():
    box = shapes.Box([0.0, 0.0, 0.0], [1.0, 2.0, 3.0])
    x = np.array(
        [
            [0.5, 1.0, 1.5],
            [0.0, 1.0, 1.5],
            [1.0, 2.0, 3.0],
            [1.0 + 1e-13, 1, 1],
            [1.1, 1.0, 1.5],
            [2.0, 3.0, 3.0],
            [0.1, 1.0, 1.5],
        ]
    )
    assert box.contains(x).tolist() == [True, True, True, True, False, False, True]
    np.testing.assert_allclose(
        box.signed_distance(x), [-0.5, 0.0, 0.0, 1e-13, 0.1, np.sqrt(2.0), -0.1], atol=1e-15
    )
    assert box.volume() == 6.0
    square = shapes.Box([0, 0], [1, 1])
    np.testing.assert_allclose(
        square.signed_distance([[2.0, 2.0], [0.5, 0.25]]), [np.sqrt(2.0), -0.25]
    )
    lo, hi = square.bounds()
    assert lo.tolist() == [0, 0] and hi.tolist() == [1, 1]


def test_disc_and_sphere():
    disc = shapes.Ball([1.0, 1.0], 0.5)
    x = np.array([[1.0, 1.0], [1.5, 1.0], [2.0, 1.0], [1.0, 1.2]])
    np.testing.assert_allclose(disc.signed_distance(x), [-0.5, 0.0, 0.5, -0.3])
    assert disc.contains(x).tolist() == [True, True, False, True]
    assert disc.volume() == pytest.approx(np.pi * 0.25)
    sphere = shapes.Ball([0.0, 0.0, 1.0], 2.0)
    np.testing.assert_allclose(sphere.signed_distance([[0, 0, 4.0], [0, 0, 0]]), [1.0, -1.0])
    assert sphere.volume() == pytest.approx(4 / 3 * np.pi * 8)
    assert sphere.support([0, 0, 1]) == 3.0


def test_cylinder_any_axis_exact_distance():
    axis = np.array([1.0, 1.0, 0.0]) / np.sqrt(2)
    cyl = shapes.Cylinder([0.0, 0.0, 0.0], [2.0, 2.0, 0.0], 0.5, 2.0)
    side = np.cross(axis, [0, 0, 1])
    x = np.array(
        [
            axis * 1.0,  # on the axis, halfway: 0.5 to the side
            axis * 1.0 + side * 0.8,  # 0.3 outside the side
            -axis * 0.25,  # 0.25 below the base
            axis * 2.25 + side * 0.9,  # beyond the top rim: corner distance
            axis * 1.9,  # 0.1 below the top face
            side * 0.5,
        ]
    )  # on the base's rim
    expected = [-0.5, 0.3, 0.25, np.hypot(0.25, 0.4), -0.1, 0.0]
    np.testing.assert_allclose(cyl.signed_distance(x), expected, atol=1e-14)
    assert cyl.contains(x).tolist() == [True, False, False, False, True, True]
    assert cyl.volume() == pytest.approx(np.pi * 0.25 * 2.0)
    lo, hi = cyl.bounds()
    reach = 0.5 * np.sqrt(1 - axis**2)
    np.testing.assert_allclose(lo, [0, 0, 0] - reach)
    np.testing.assert_allclose(hi, axis * 2 + reach)
    upright = shapes.Cylinder([0, 0, 0], [0, 0, 3], 1.0, 2.0)
    assert upright.support([0, 0, 1]) == 2.0 and upright.support([1, 0, 0]) == 1.0


def test_non_convex_polygon():
    # an L: the notch [1, 2] x [1, 2] is outside
    ell = shapes.Polygon([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]])
    x = np.array(
        [
            [0.5, 0.5],
            [1.5, 1.5],
            [1.5, 0.5],
            [0.5, 1.5],
            [1.0, 1.5],
            [2.0, 0.0],
            [3.0, 0.5],
            [1.2, 1.1],
            [0.5, 0.0],
        ]
    )
    assert ell.contains(x).tolist() == [True, False, True, True, True, True, False, False, True]
    np.testing.assert_allclose(
        ell.signed_distance(x), [-0.5, 0.5, -0.5, -0.5, 0.0, 0.0, 1.0, 0.1, 0.0], atol=1e-15
    )
    assert ell.volume() == 3.0
    # a ray through vertices (y = 1 passes the corners (2, 1) and (1, 1)) counts right
    assert ell.contains([[0.5, 1.0], [-1.0, 1.0], [1.5, 1.0]]).tolist() == [True, False, True]
    # the same polygon clockwise
    assert ell.contains(x).tolist() == shapes.Polygon(ell.vertices[::-1]).contains(x).tolist()


def test_only_simple_polygons_are_accepted():
    assert shapes.polygon_problem([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]]) is None
    assert "no area" in shapes.polygon_problem([[0, 0], [1, 1], [2, 2]])
    crossing = shapes.polygon_problem([[0, 0], [2, 0], [0, 1], [2, 2], [0, 2]])
    assert "edges 1 (corners 1 to 2) and 4 (corners 4 to 0) touch" in crossing
    # a bow tie's two loops enclose areas that cancel: it was said to "enclose no area"
    bow_tie = shapes.polygon_problem([[0.2, 0.0], [0.25, 0.05], [0.25, 0.0], [0.2, 0.05]])
    assert bow_tie == (
        "vertices: the polygon's edges 0 (corners 0 to 1) and 2 (corners 2 to "
        "3) cross, so it is not a simple polygon; list its corners in order "
        "around the boundary"
    )
    assert "lie on one line" in shapes.polygon_problem([[0, 0], [1, 0], [2, 0], [3, 0]])


def test_a_polygon_on_one_line_but_for_rounding_is_refused_by_the_case(tmp_path, capsys):
    """Three corners on the line y = x + 0.02 whose cross products round to 1e-19 m^2, not
    0: the polygon was accepted and seeded the 3 lattice points on its edge (issue 40). A
    thin polygon that is not a line still passes."""
    line = [[0.005, 0.025], [0.015, 0.035], [0.025, 0.045]]
    assert "lie on one line" in shapes.polygon_problem(line)
    assert shapes.polygon_problem([[0.0, 0.0], [1.0, 0.0], [0.5, 1e-6]]) is None
    vertices = ", ".join(f"[{x}, {y}]" for x, y in line)
    (tmp_path / "case.toml").write_text(
        "[domain]\nsize = [0.2, 0.2]\n[grid]\nspacing = 0.02\n[[bodies]]\n"
        f'type = "polygon"\nvertices = [{vertices}]\n[time]\ndt = 1e-3\nend = 2e-3\n'
    )
    code = main(["run", str(tmp_path / "case.toml"), "--out", str(tmp_path / "o"), "-q"])
    err = capsys.readouterr().err
    assert code == 2 and "bodies.0: vertices: the polygon's corners lie on one line" in err


def test_polygon_against_a_box_on_random_points():
    box = shapes.Box([0.2, 0.1], [0.7, 0.4])
    poly = shapes.Polygon([[0.2, 0.1], [0.7, 0.1], [0.7, 0.4], [0.2, 0.4]])
    x = RNG.uniform(0, 1, (5000, 2))
    assert (poly.contains(x) == box.contains(x)).all()
    np.testing.assert_allclose(poly.signed_distance(x), box.signed_distance(x), atol=1e-14)


# --------------------------------------------------------------------------- meshes


def _write(mesh, path):
    mesh.export(path)
    return path


def test_mesh_box_and_sphere_match_the_analytic_shapes(tmp_path):
    path = _write(trimesh.creation.box(extents=[0.2, 0.1, 0.3]), tmp_path / "box.stl")
    mesh = meshes.load_mesh(path, translate=[0.5, 0.5, 0.5])
    box = shapes.Box([0.4, 0.45, 0.35], [0.6, 0.55, 0.65])
    x = RNG.uniform(0.3, 0.7, (20000, 3))
    assert (mesh.contains(x) == box.contains(x)).all()
    # STL stores float32 coordinates: exact to their rounding
    np.testing.assert_allclose(mesh.signed_distance(x), box.signed_distance(x), atol=1e-7)
    assert mesh.volume() == pytest.approx(0.006)
    np.testing.assert_allclose(mesh.bounds()[0], box.lo)

    ico = trimesh.creation.icosphere(subdivisions=3, radius=1.0)
    path = _write(ico, tmp_path / "ball.obj")
    mesh = meshes.load_mesh(path, scale=0.1)  # file in decimetres
    x = RNG.uniform(-0.12, 0.12, (20000, 3))
    r = np.linalg.norm(x, axis=1)
    facet = 0.1 * (1 - np.min(np.linalg.norm(ico.triangles_center, axis=1)))  # facet error
    sure = np.abs(r - 0.1) > facet
    assert (mesh.contains(x)[sure] == (r < 0.1)[sure]).all()
    np.testing.assert_allclose(mesh.signed_distance(x), r - 0.1, atol=facet)


def test_mesh_points_on_the_surface_count_as_inside(tmp_path):
    mesh = meshes.load_mesh(_write(trimesh.creation.box(extents=[1, 1, 1]), tmp_path / "b.stl"))
    faces = np.array([[0.5, 0.1, -0.2], [0.5, 0.5, 0.5], [0.0, 0.0, -0.5], [0.5 + 1e-9, 0, 0]])
    assert mesh.contains(faces).tolist() == [True, True, True, False]


def test_winding_number_tolerates_a_missing_triangle():
    ico = trimesh.creation.icosphere(subdivisions=2, radius=1.0)
    holed = meshes.Mesh(ico.vertices, ico.faces[1:])
    hole = ico.triangles_center[0]
    x = RNG.uniform(-1.2, 1.2, (20000, 3))
    r = np.linalg.norm(x, axis=1)
    far = (np.linalg.norm(x - hole, axis=1) > 0.5) & (np.abs(r - 1) > 0.05)
    assert (holed.contains(x)[far] == (r < 1)[far]).all()


def test_meshes_that_are_open_empty_missing_or_unreadable_are_refused(tmp_path):
    ico = trimesh.creation.icosphere(subdivisions=1)
    open_mesh = trimesh.Trimesh(ico.vertices, ico.faces[1:])
    _write(open_mesh, tmp_path / "open.stl")
    with pytest.raises(
        ValueError,
        match=r"bodies.1.path = 'open.stl' is not a closed surface: "
        r"3 boundary edges.*trimesh.repair.fill_holes",
    ):
        meshes.load_mesh(tmp_path / "open.stl", key="bodies.1", shown="open.stl")
    (tmp_path / "empty.stl").write_bytes(b"")
    with pytest.raises(ValueError, match="empty.stl.*(holds no triangles|cannot be read)"):
        meshes.load_mesh(tmp_path / "empty.stl", key="obstacles.0")
    with pytest.raises(ValueError, match="obstacles.0.path = .*none.stl.* does not exist"):
        meshes.load_mesh(tmp_path / "none.stl", key="obstacles.0")
    (tmp_path / "junk.obj").write_text("this is not an obj file\n")
    with pytest.raises(ValueError, match="junk.obj"):
        meshes.load_mesh(tmp_path / "junk.obj", key="obstacles.0")


def _cube_triangles():
    """The 12 triangles (12, 3, 3) of the unit cube [0, 1]^3, facing outwards."""
    cube = trimesh.creation.box(extents=[1, 1, 1])
    return cube.vertices[cube.faces] + 0.5


def binary_stl(triangles, count=None, header=b"binary"):
    """A binary STL's bytes: 80-byte header, triangle count (``count``: the header's, by
    default the true one), then each triangle (normal, 3 corners, attribute)."""
    out = [header.ljust(80, b" "), struct.pack("<I", len(triangles) if count is None else count)]
    out += [struct.pack("<12fH", 0.0, 0.0, 0.0, *np.ravel(t), 0) for t in triangles]
    return b"".join(out)


def ascii_stl(triangles, name="cube"):
    lines = [f"solid {name}"]
    for t in triangles:
        lines += ["facet normal 0 0 0", "outer loop"]
        lines += [f"vertex {x:.9g} {y:.9g} {z:.9g}" for x, y, z in t]
        lines += ["endloop", "endfacet"]
    return "\n".join(lines + [f"endsolid {name}", ""])


def test_valid_stl_files_trimesh_alone_refuses_are_read(tmp_path):
    """They were refused with "No module named 'charset_normalizer'" and advice to export
    again: an ASCII STL with a Latin-1 solid name, binary STLs whose header count is off.
    A binary count off is read as the file's size says (the note tells the user); a file
    cut inside a triangle is refused, saying so."""
    tri = _cube_triangles()
    files = {
        "latin1.stl": ascii_stl(tri, "Würfel").encode("latin-1"),
        "utf8.stl": ascii_stl(tri, "Würfel").encode("utf-8"),
        "latin1.obj": (
            "o Würfel\n"
            + "".join(f"v {x} {y} {z}\n" for x, y, z in tri.reshape(-1, 3))
            + "".join(f"f {3 * k + 1} {3 * k + 2} {3 * k + 3}\n" for k in range(12))
        ).encode("latin-1"),
        "right.stl": binary_stl(tri, header=b"solid but binary"),
        "too_many.stl": binary_stl(tri, count=15),
        "too_few.stl": binary_stl(tri, count=3),
        "zero.stl": binary_stl(tri, count=0, header=b"solid streamed"),
    }
    for name, data in files.items():
        (tmp_path / name).write_bytes(data)
        mesh = meshes.load_mesh(tmp_path / name, key="bodies.1", shown=name)
        assert mesh.volume() == pytest.approx(1.0) and len(mesh.faces) == 12, name
        assert mesh.contains([[0.5, 0.5, 0.5], [1.5, 0.5, 0.5]]).tolist() == [True, False]
        counted = {"too_many.stl": 15, "too_few.stl": 3, "zero.stl": 0}.get(name)
        assert mesh.notes == (
            []
            if counted is None
            else [
                f"bodies.1.path = '{name}': the binary STL's header counts {counted} triangles "
                "but its 684 bytes hold 12; the 12 triangles of the file were read"
            ]
        )
    (tmp_path / "cut.stl").write_bytes(binary_stl(tri)[:-7])
    with pytest.raises(ValueError) as err:
        meshes.load_mesh(tmp_path / "cut.stl", key="obstacles.0", shown="cut.stl")
    assert str(err.value) == (
        "obstacles.0.path = 'cut.stl' is a binary STL whose header counts 12 triangles (684 "
        "bytes), but the file has 677 bytes: 11 whole triangles and 43 bytes more, so it is "
        "cut short inside a triangle or has bytes appended, and which triangles it holds is "
        "unclear; export it again from your CAD tool."
    )
    # cut at a triangle's end: the 11 triangles are read, and the open surface refused
    # with the count's note
    (tmp_path / "short.stl").write_bytes(binary_stl(tri)[:-50])
    with pytest.raises(
        ValueError,
        match=r"'short.stl' is not a closed surface \(the binary "
        r"STL's header counts 12 triangles but its 634 bytes hold 11; the 11 "
        r"triangles of the file were read\): 3 boundary edges",
    ):
        meshes.load_mesh(tmp_path / "short.stl", key="obstacles.0", shown="short.stl")


def test_a_wrong_count_is_a_notice_of_the_run(tmp_path):
    (tmp_path / "cube.stl").write_bytes(binary_stl(_cube_triangles() * 0.06, count=0))
    case = _case(
        BASE3,
        [
            {"min": [0, 0, 0], "max": [0.2, 0.2, 0.1]},
            {"type": "mesh", "path": "cube.stl", "translate": [0.07, 0.07, 0.2]},
        ],
        base_dir=tmp_path,
    )
    from mpmflow import Simulation

    notices = Simulation(case).notices
    assert [n for n in notices if "cube.stl" in n] == [
        f"bodies.1.path = '{tmp_path / 'cube.stl'}': the binary STL's header counts 0 "
        "triangles but its 684 bytes hold 12; the 12 triangles of the file were read"
    ]


def test_a_folder_as_the_mesh_path_is_named_a_folder(tmp_path):
    """It was reported as missing."""
    (tmp_path / "parts.stl").mkdir()
    with pytest.raises(ValueError) as err:
        meshes.load_mesh(tmp_path / "parts.stl", key="obstacles.0", shown="parts.stl")
    assert str(err.value) == (
        "obstacles.0.path = 'parts.stl' is a folder, not a file; give the path of an STL or "
        "OBJ file (relative paths are taken from the case file's folder)."
    )


def test_a_mesh_enclosing_no_volume_is_refused_without_a_library_warning(tmp_path):
    """A zero-size mesh printed trimesh's RuntimeWarning (with its file and line) and, as
    an obstacle, was said to be 0 m thin: "refine grid.spacing to at most 0 m"."""
    tri = _cube_triangles()
    flat = tri.copy()
    flat[..., 2] = 0.0
    (tmp_path / "point.stl").write_bytes(binary_stl(tri * 0.0))
    (tmp_path / "flat.stl").write_bytes(binary_stl(flat))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # any library warning fails the test
        with pytest.raises(CaseError) as err:
            _case(
                BASE3,
                [{"min": [0, 0, 0], "max": [0.2, 0.2, 0.1]}],
                [
                    {
                        "type": "mesh",
                        "path": "flat.stl",
                        "scale": 0.1,
                        "translate": [0.05, 0.05, 0.15],
                    }
                ],
                base_dir=tmp_path,
            )
        assert (
            "obstacles.0.path = 'flat.stl' encloses no volume: its corners span 1 x 1 x 0 "
            "(file units), flat or a single point, so it has no inside; export the closed "
            "surface of the solid." in str(err.value)
        )
        assert "at most 0 m" not in str(err.value)
        with pytest.raises(
            ValueError, match="'point.stl' holds no triangles .*only triangles with no area"
        ):
            meshes.load_mesh(tmp_path / "point.stl", key="obstacles.0", shown="point.stl")


def test_a_scale_past_the_floating_point_range_is_refused_without_a_numpy_warning(tmp_path):
    """The input fuzz's find: a cube 1e38 file units across at scale = 1e300 printed NumPy's
    "overflow encountered in multiply" before the refusal named the scale."""
    (tmp_path / "big.stl").write_bytes(binary_stl(_cube_triangles() * 1e38))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # any library warning fails the test
        with pytest.raises(ValueError, match=r"obstacles.0.scale = 1e\+300 takes the coord"):
            meshes.load_mesh(
                tmp_path / "big.stl", scale=1e300, key="obstacles.0", shown="'big.stl'"
            )


def test_an_inside_out_mesh_is_turned_outwards(tmp_path):
    ico = trimesh.creation.icosphere(subdivisions=1)
    inverted = trimesh.Trimesh(ico.vertices, ico.faces[:, ::-1], process=False)
    mesh = meshes.load_mesh(_write(inverted, tmp_path / "inv.stl"))
    assert mesh.contains([[0, 0, 0], [2, 0, 0]]).tolist() == [True, False]


# --------------------------------------------------------------------------- cases

BASE2 = {
    "domain": {"size": [0.42, 0.44]},
    "grid": {"spacing": 0.01},
    "time": {"dt": 1e-3, "end": 0.01},
    "output": {"snapshots": False},
}
BASE3 = {
    "domain": {"size": [0.2, 0.2, 0.3]},
    "grid": {"spacing": 0.02},
    "time": {"dt": 1e-3, "end": 0.01},
    "output": {"snapshots": False},
}


def _case(base, bodies, obstacles=(), probes=(), base_dir=None):
    data = {**base, "bodies": list(bodies), "obstacles": list(obstacles), "probes": list(probes)}
    return validate(data, base_dir=base_dir)


def _seeded(case):
    grid = Grid.covering(case.domain.size, case.grid.spacing)
    return build_particles(case, grid)


def test_every_shape_seeds_the_count_it_was_sized_with(tmp_path):
    _write(trimesh.creation.icosphere(subdivisions=2, radius=0.05), tmp_path / "ball.stl")
    cases = [
        _case(
            BASE2, [{"type": "disc", "centre": [0.2, 0.2], "radius": 0.1, "particles_per_cell": 3}]
        ),
        _case(
            BASE2,
            [
                {
                    "type": "polygon",
                    "vertices": [[0, 0], [0.3, 0], [0.3, 0.1], [0.1, 0.1], [0.1, 0.3], [0, 0.3]],
                }
            ],
        ),
        _case(
            BASE2,
            [
                {
                    "min": [0, 0],
                    "max": [0.42, 0.2],
                    "particles_per_cell": 4,
                    "around_obstacles": True,
                }
            ],
            [{"type": "disc", "centre": [0.21, 0.1], "radius": 0.05}],
        ),
        _case(BASE3, [{"type": "sphere", "centre": [0.1, 0.1, 0.1], "radius": 0.07}]),
        _case(
            BASE3,
            [
                {
                    "type": "cylinder",
                    "centre": [0.1, 0.1, 0.0],
                    "axis": [0, 0, 1],
                    "radius": 0.06,
                    "length": 0.1,
                }
            ],
        ),
        _case(
            BASE3,
            [{"type": "mesh", "path": "ball.stl", "translate": [0.1, 0.1, 0.1]}],
            base_dir=tmp_path,
        ),
        _case(
            BASE3,
            [{"min": [0, 0, 0], "max": [0.2, 0.2, 0.15], "around_obstacles": True}],
            [{"type": "mesh", "path": "ball.stl", "translate": [0.1, 0.1, 0.08]}],
            base_dir=tmp_path,
        ),
    ]
    for case in cases:
        particles = _seeded(case)
        assert particles.count == sum(case.particle_counts()) > 0
        vol = particles.volume.sum()
        expected = sum(case.body_shape(k).volume() for k in range(len(case.bodies))) - sum(
            case.obstacle_shape(k).volume() for k in range(len(case.obstacles))
        )
        assert vol == pytest.approx(expected, rel=0.1)
        for k in range(len(case.obstacles)):  # nothing starts inside an obstacle
            assert not case.obstacle_shape(k).contains(particles.x).any()


def test_hydrostatic_pressure_below_the_highest_point():
    case = _case(
        BASE2,
        [{"type": "disc", "centre": [0.2, 0.2], "radius": 0.1, "initial_pressure": "hydrostatic"}],
    )
    p = _seeded(case)
    np.testing.assert_allclose(p.pressure, 1000 * 9.81 * (0.3 - p.x[:, 1]))


def test_relative_mesh_paths_start_at_the_case_file(tmp_path, monkeypatch):
    from mpmflow.case import load_case, revalidate

    (tmp_path / "geo").mkdir()
    _write(trimesh.creation.box(extents=[0.06, 0.06, 0.06]), tmp_path / "geo" / "block.stl")
    (tmp_path / "case.toml").write_text(
        "[domain]\nsize = [0.2, 0.2, 0.3]\n[grid]\nspacing = 0.02\n[time]\ndt = 1e-3\n"
        "end = 0.01\n[[bodies]]\nmin = [0, 0, 0]\nmax = [0.2, 0.2, 0.1]\n"
        '[[obstacles]]\ntype = "mesh"\npath = "geo/block.stl"\ntranslate = [0.1, 0.1, 0.2]\n'
    )
    monkeypatch.chdir("/")
    case = load_case(tmp_path / "case.toml", ["obstacles.0.translate=[0.1, 0.1, 0.15]"])
    assert case.obstacle_shape(0).bounds()[0][2] == pytest.approx(0.12)
    assert revalidate(case).obstacle_shape(0).volume() == pytest.approx(0.06**3)


BAD = [
    (
        BASE2,
        [{"type": "sphere", "centre": [0.1, 0.1, 0.1], "radius": 0.05}],
        [],
        [],
        "bodies.0.type = 'sphere' is a shape of 3D cases",
    ),
    (
        BASE3,
        [{"type": "disc", "centre": [0.1, 0.1], "radius": 0.05}],
        [],
        [],
        "bodies.0.type = 'disc' is a shape of 2D cases",
    ),
    (
        BASE2,
        [{"type": "disc", "centre": [0.4, 0.2], "radius": 0.05}],
        [],
        [],
        "bodies.0 \\(a disc\\) spans .* outside the domain .* move it inside \\(bodies.0.centre\\)",
    ),
    (
        BASE2,
        [{"max": [0.1, 0.1], "min": [0, 0]}],
        [{"type": "disc", "centre": [0.6, 0.2], "radius": 0.05}],
        [],
        "obstacles.0 \\(a disc\\) spans .* beyond the domain",
    ),
    (
        BASE2,
        [{"max": [0.1, 0.1], "min": [0, 0]}],
        [{"type": "disc", "centre": [0.3, 0.2], "radius": 0.008}],
        [],
        "obstacles.0 \\(a disc\\) is 0.016 m thin .* refine grid.spacing",
    ),
    (
        BASE2,
        [
            {"type": "disc", "centre": [0.2, 0.1], "radius": 0.05},
            {"min": [0, 0], "max": [0.42, 0.08]},
        ],
        [],
        [],
        "bodies.0 \\(a disc\\) and bodies.1 \\(a box\\) overlap: \\d+ lattice points",
    ),
    (
        BASE2,
        [{"min": [0.15, 0.05], "max": [0.25, 0.15]}],
        [{"type": "disc", "centre": [0.2, 0.1], "radius": 0.1}],
        [],
        "bodies.0 \\(a box\\) lies wholly inside obstacles: all 400 of its lattice points",
    ),
    (
        BASE2,
        [{"min": [0, 0], "max": [0.42, 0.2]}],
        [{"type": "disc", "centre": [0.2, 0.1], "radius": 0.05}],
        [],
        "bodies.0 \\(a box\\) overlaps obstacles.0 \\(a disc\\): \\d+ of its \\d+ lattice points .* "
        "set bodies.0.around_obstacles = true",
    ),
    (
        BASE2,
        [{"min": [0, 0], "max": [0.42, 0.2], "around_obstacles": True}],
        [{"type": "disc", "centre": [0.2, 0.1], "radius": 0.05}],
        [{"name": "p", "quantity": "pressure", "position": [0.2, 0.12]}],
        "probes.0.position = .* lies 0.03 m inside obstacles.0",
    ),
    (
        BASE2,
        [{"type": "polygon", "vertices": [[0, 0], [0.2, 0], [0, 0.2], [0.2, 0.2]]}],
        [],
        [],
        "vertices: the polygon's",
    ),
    (
        BASE3,
        [{"min": [0, 0, 0], "max": [0.2, 0.2, 0.1]}],
        [{"type": "mesh", "path": "missing.stl"}],
        [],
        "obstacles.0.path = 'missing.stl' does not exist .*case file's folder",
    ),
    (
        BASE2,
        [{"type": "disc", "centre": [0.2, 0.2], "radius": 0.1, "min": [0, 0]}],
        [],
        [],
        '`bodies.0.min` is not a key of a "disc"',
    ),
]


@pytest.mark.parametrize("base, bodies, obstacles, probes, words", BAD)
def test_bad_geometry_is_refused_with_the_key_and_the_fix(base, bodies, obstacles, probes, words):
    with pytest.raises(CaseError, match=words):
        _case(base, bodies, obstacles, probes)


@pytest.mark.slow
def test_the_cli_refuses_an_open_mesh_in_one_paragraph(tmp_path):
    ico = trimesh.creation.icosphere(subdivisions=1, radius=0.03)
    _write(trimesh.Trimesh(ico.vertices, ico.faces[2:]), tmp_path / "open.stl")
    (tmp_path / "case.toml").write_text(
        "[domain]\nsize = [0.2, 0.2, 0.3]\n[grid]\nspacing = 0.02\n[time]\ndt = 1e-3\n"
        "end = 0.01\n[[bodies]]\nmin = [0, 0, 0]\nmax = [0.2, 0.2, 0.1]\n"
        '[[obstacles]]\ntype = "mesh"\npath = "open.stl"\ntranslate = [0.1, 0.1, 0.2]\n'
    )
    env = {**os.environ, "PYTHONPATH": str(Path(shapes.__file__).parents[2])}
    res = subprocess.run(
        [sys.executable, "-m", "mpmflow.cli", "run", "case.toml", "--out", "o"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=300,
        env=env,
    )
    assert res.returncode == 2 and "Traceback" not in res.stderr
    assert "obstacles.0.path = 'open.stl' is not a closed surface" in res.stderr
    assert "fill_holes" in res.stderr and res.stderr.count("\n") == 1


D2 = {"domain": {"size": [0.2, 0.2]}, "grid": {"spacing": 0.02}, "time": {"dt": 1e-3, "end": 0.01}}
D3 = {**D2, "domain": {"size": [0.2, 0.2, 0.2]}}


@pytest.mark.parametrize(
    ("case", "shape", "said"),
    [
        (D2, {"type": "disc", "centre": [0.1, 0.1], "radius": 0.0}, "radius` = 0.0"),
        (D2, {"min": [0.1, 0.1], "max": [0.1, 0.15]}, "along x max = [0.1, 0.15] does not"),
        (D3, {"type": "sphere", "centre": [0.1, 0.1, 0.1], "radius": 0.0}, "radius` = 0.0"),
        (
            D3,
            {"type": "cylinder", "centre": [0.1, 0.1, 0], "axis": [0, 0, 1], "radius": 0.05}
            | {"length": 0.0},
            "length` = 0.0",
        ),
        (D2, {"type": "polygon", "vertices": [[0.0, 0.0], [0.0, 0.0], [0.1, 0.0]]}, "one line"),
        (D2, {"type": "polygon", "vertices": [[0.05, 0.05]] * 3}, "one line"),
        (
            D3,
            {"type": "cylinder", "centre": [0.1, 0.1, 0], "axis": [0, 0, 1], "radius": 1e-300}
            | {"length": 0.1},
            "seeds no particle",
        ),
    ],
)
@pytest.mark.parametrize("kind", ["bodies", "obstacles"])
def test_degenerate_shapes_are_refused_by_key(case, shape, said, kind):
    """A shape of no size (zero radius, length or width, corners on one point or line) is
    refused as a body and as an obstacle, by key (issue 40)."""
    body = {"min": [0.0] * len(case["domain"]["size"]), "max": [0.04] * len(case["domain"]["size"])}
    data = {**case, "bodies": [shape]} if kind == "bodies" else {**case, "bodies": [body]}
    if kind == "obstacles":
        data["obstacles"] = [shape]
        said = said.replace("bodies.0", "obstacles.0")
        if said == "seeds no particle":
            said = "thin"  # an obstacle is refused for being thinner than two cells
    with pytest.raises(CaseError) as err:
        validate(data)
    assert said in str(err.value) and f"{kind}.0" in str(err.value), str(err.value)
