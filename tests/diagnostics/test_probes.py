"""Probes (probes.py): pressure sensors and level gauges in 2D and 3D, probes.csv, the measured
series a case names (probes.N.data) and their figure (mpmflow plot)."""

import numpy as np
import pytest
import tomllib
from conftest import EXAMPLES
from PIL import Image

from mpmflow import load_case, open_run
from mpmflow.case import apply_overrides, validate_case
from mpmflow.cli import main
from mpmflow.diagnostics import probes
from mpmflow.diagnostics.probes import level_at, window_box
from mpmflow.errors import CaseError
from mpmflow.grid import Grid
from mpmflow.simulation import Simulation

RHO, G = 1000.0, 9.81
H = 0.195  # m, depth of examples/hydrostatic*.toml


def _run(example, probes, overrides, out=None):
    case = load_case(EXAMPLES / example, {"output.snapshots": False, **overrides})
    case.probes = probes
    sim = Simulation(case, out)
    sim.run()
    return sim


# the sensors of the column at rest: on the floor, in a floor corner, on both side walls,
# inside the water, just under the surface and above it (dry)
POINTS_2D = {
    "floor": [0.05, 0.0],
    "corner": [0.0, 0.0],
    "left": [0.0, 0.1],
    "right": [0.1, 0.05],
    "inside": [0.043, 0.077],
    "under_surface": [0.05, 0.19],
    "dry": [0.05, 0.2],
}


def _pressure_probes(points, estimate):
    return [
        {"name": f"{k}_{estimate}", "quantity": "pressure", "position": v, "estimate": estimate}
        for k, v in points.items()
    ]


def _check_hydrostatic(sim, points, depth):
    """Every "fit" sensor reads rho g (H - z) at its point (z the last coordinate); errors in
    units of rho g h, h the grid spacing (measured: 3e-11 in 2D, 7e-9 in 3D at 0.01 m; the
    pressure solve's tolerance sets them)."""
    h = sim.grid.spacing
    for name, point in points.items():
        exact = RHO * G * max(depth - point[-1], 0.0)
        value = sim.probe_series(f"{name}_fit")[-1]
        assert abs(value - exact) <= 1e-6 * RHO * G * h, (name, value, exact)
    # the window mean of a floor sensor reads the pressure half a window above its point:
    # the bias the fit removes
    floor = sim.probe_series("floor_mean")[-1]
    np.testing.assert_allclose(floor, RHO * G * (depth - 0.5 * h), rtol=1e-7)


def test_pressure_probes_read_the_hydrostatic_pressure_at_their_point_2d():
    sim = _run(
        "hydrostatic.toml",
        _pressure_probes(POINTS_2D, "fit") + _pressure_probes({"floor": [0.05, 0.0]}, "mean"),
        {"time.end": 0.02},
    )
    _check_hydrostatic(sim, POINTS_2D, H)
    assert sim.probe_series("dry_fit")[-1] == 0.0  # no particle in its window


def _3d(point):
    return [point[0], 0.025, point[1]]


def test_pressure_and_level_probes_in_3d():
    """The 3D column at rest on a coarse mesh (0.025 m, surface on a grid line at 0.2 m):
    pressure sensors as in 2D plus one on the wall y = 0; level gauges on the floor at
    points between cell columns (bilinear weights), on a wall and in a corner, one with its
    foot in the water and one with its foot above it."""
    depth = 0.2
    points = {k: _3d(v) for k, v in POINTS_2D.items() if k not in ("under_surface", "dry")}
    points["wall_y"] = [0.03, 0.0, 0.1]
    points["under_surface"] = [0.05, 0.025, 0.19]
    points["dry"] = [0.05, 0.025, 0.23]
    gauges = {
        "middle": ([0.05, 0.025, 0.0], depth),
        "between": ([0.031, 0.017, 0.0], depth),
        "wall": ([0.1, 0.01, 0.0], depth),
        "corner": ([0.0, 0.0, 0.0], depth),
        "raised": ([0.04, 0.03, 0.1], depth - 0.1),
        "above": ([0.04, 0.03, 0.25], 0.0),
    }
    probes = (
        _pressure_probes(points, "fit")
        + _pressure_probes({"floor": points["floor"]}, "mean")
        + [{"name": k, "quantity": "level", "position": p} for k, (p, _) in gauges.items()]
    )
    sim = _run(
        "hydrostatic_3d.toml",
        probes,
        {"time.end": 0.02, "grid.spacing": 0.025, "bodies.0.max": [0.1, 0.05, depth]},
    )
    _check_hydrostatic(sim, points, depth)
    for name, (_, level) in gauges.items():
        np.testing.assert_allclose(sim.probe_series(name), level, atol=1e-9, err_msg=name)


def test_level_probes_2d_on_the_column_whose_surface_is_half_a_cell_off_a_grid_line():
    """Depth 0.195 m on the 0.01 m mesh: the cell under the surface is half full, and the
    f = 1/2 rule puts the level at the depth; a foot in the water reads the depth above it."""
    gauges = {
        "wall": [0.0, 0.0],
        "between": [0.033, 0.0],
        "raised": [0.07, 0.1],
        "above": [0.07, 0.25],
    }
    sim = _run(
        "hydrostatic.toml",
        [{"name": k, "quantity": "level", "position": p} for k, p in gauges.items()],
        {"time.end": 0.02},
    )
    for name, level in (("wall", H), ("between", H), ("raised", H - 0.1), ("above", 0.0)):
        np.testing.assert_allclose(sim.probe_series(name), level, atol=1e-9, err_msg=name)


def _columns(grid, depths):
    """Cell volume fractions of columns filled to whole numbers of cells (depths[i][j])."""
    f = np.zeros(grid.cells)
    for index in np.ndindex(*grid.cells[:-1]):
        f[index][: depths[index]] = 1.0
    return f


FIRST = "first_drop"


def test_level_in_3d_interpolates_the_four_cell_columns_around_the_gauge_bilinearly():
    """Columns filled to 4, 4, 4 and 8 cells (the deep one at i = j = 1): at the point
    between their centres each weighs 1/4, the profile is 1 below 4 cells and 1/4 from 4 to 8,
    so it drops below 1/2 between the centres of cells 3 and 4, at (3.5 + 0.5/0.75) h. Three
    quarters of the way to the deep column in x and y it weighs 9/16: the profile drops
    below 1/2 between cells 7 and 8, at (7.5 + (9/16 - 1/2)/(9/16)) h."""
    h = 0.1
    grid = Grid(h, (2, 2, 12))
    f = _columns(grid, np.array([[4, 4], [4, 8]]))
    np.testing.assert_allclose(level_at(grid, f, [h, h, 0.0], gauge=FIRST), (3.5 + 0.5 / 0.75) * h)
    at = 0.5 * h + 0.75 * h
    np.testing.assert_allclose(level_at(grid, f, [at, at, 0.0], gauge=FIRST), (7.5 + 1 / 9) * h)
    # the centre of a column reads that column alone
    np.testing.assert_allclose(level_at(grid, f, [1.5 * h, 1.5 * h, 0.0], gauge=FIRST), 8 * h)
    np.testing.assert_allclose(level_at(grid, f, [1.5 * h, 1.5 * h, 2 * h], gauge=FIRST), 6 * h)
    # the same rule as in 2D: the plane y = 0.5 h of the 3D field is the 2D field
    grid2 = Grid(h, (2, 12))
    f2 = _columns(grid2, np.array([4, 8]))
    assert level_at(grid2, f2, [at, 0.0], gauge=FIRST) == pytest.approx((7.5 + 0.25 / 0.75) * h)
    f3 = _columns(grid, np.array([[4, 4], [8, 8]]))
    assert level_at(grid, f3, [at, 0.3 * h, 0.0], gauge=FIRST) == pytest.approx(
        level_at(grid2, f2, [at, 0], gauge=FIRST)
    )


def test_the_integral_gauge_reads_the_water_on_its_line_gathered_into_one_layer():
    """The default gauge (issue 25): the integral of the interpolated fraction from the foot
    up. The columns above: at the point between them each weighs 1/4, so 4 h full and 4 h
    at 1/4: 5 h; three quarters of the way to the deep one, 4 h + 4 h 9/16; the centre of
    the deep column 8 h, from a foot at 2 h 6 h, from a foot at 2.5 h 5.5 h."""
    h = 0.1
    grid = Grid(h, (2, 2, 12))
    f = _columns(grid, np.array([[4, 4], [4, 8]]))
    np.testing.assert_allclose(level_at(grid, f, [h, h, 0.0]), 5 * h)
    at = 0.5 * h + 0.75 * h
    np.testing.assert_allclose(level_at(grid, f, [at, at, 0.0]), (4 + 4 * 9 / 16) * h)
    np.testing.assert_allclose(level_at(grid, f, [1.5 * h, 1.5 * h, 0.0]), 8 * h)
    np.testing.assert_allclose(level_at(grid, f, [1.5 * h, 1.5 * h, 2 * h]), 6 * h)
    np.testing.assert_allclose(level_at(grid, f, [1.5 * h, 1.5 * h, 2.5 * h]), 5.5 * h)


def test_the_integral_gauge_counts_a_strained_lattice_by_its_volume():
    """A column of water 8 cells deep whose particles (4 a cell) sit 5 and 3 a cell in
    alternate cells, as a strained lattice puts them: the cell fractions are 1.25 and 0.75,
    and the integral gauge reads the particles' volume per area, 8 cells (a clip at 1 read
    7 cells); the first drop still finds the top of the layer (within the last cell)."""
    from mpmflow.cells import bin_particles
    from mpmflow.particles import Particles

    h, s = 0.01, 0.005
    grid = Grid(h, (1, 12))
    x = []
    for c in range(8):
        n = 5 if c % 2 == 0 else 3
        for j in range(n):
            x.append([0.5 * h, (c + (j + 0.5) / n) * h])
    x = np.array(x)
    n = len(x)
    P = Particles(x, np.zeros((n, 2)), np.zeros(n), np.full(n, RHO * s * s), np.full(n, s * s))
    case = load_case(
        EXAMPLES / "hydrostatic.toml",
        {
            "probes": [
                {"name": "wire", "quantity": "level", "position": [0.5 * h, 0.0]},
                {"name": "top", "quantity": "level", "position": [0.5 * h, 0.0], "gauge": FIRST},
            ]
        },
    )
    row = probes.measure(case, grid, P, bin_particles(grid, P), 0.0)
    assert row["wire"] == pytest.approx(8 * h, rel=1e-12)
    assert 7 * h <= row["top"] <= 8 * h


def test_an_aerated_foot_or_a_splash_under_each_gauge():
    """The SPHERIC drop-outs: a bore 8 cells deep over a foot cell 40% full (air
    entrained at the floor) reads 0 with "first_drop" and 7.4 cells with the integral; a
    drop of one cell two cells above a 4-cell layer is left out by "first_drop" and counted
    by its volume in the integral."""
    h = 0.01
    grid = Grid(h, (1, 12))
    bore = np.zeros((1, 12))
    bore[0, :8] = 1.0
    bore[0, 0] = 0.4
    assert level_at(grid, bore, [0.005, 0.0], gauge=FIRST) == 0.0
    np.testing.assert_allclose(level_at(grid, bore, [0.005, 0.0]), 7.4 * h)
    splash = np.zeros((1, 12))
    splash[0, :4] = 1.0
    splash[0, 6] = 1.0
    np.testing.assert_allclose(level_at(grid, splash, [0.005, 0.0], gauge=FIRST), 4 * h)
    np.testing.assert_allclose(level_at(grid, splash, [0.005, 0.0]), 5 * h)


def test_the_window_lies_on_the_water_side_of_a_wall_and_of_an_obstacle_face():
    size = [1.0, 0.5, 0.8]
    lo, hi = window_box([1.0, 0.25, 0.003], 0.01, size)
    # on the wall x = 1 it lies inside; near the floor it is centred and cut there
    np.testing.assert_allclose(lo, [0.99, 0.245, 0.0])
    np.testing.assert_allclose(hi, [1.0, 0.255, 0.008])

    def box(points):  # a solid cube [0.4, 0.6]^2 x [0, 0.2]: signed distance, < 0 inside
        points = np.atleast_2d(points)
        c, half = np.array([0.5, 0.25, 0.1]), np.array([0.1, 0.1, 0.1])
        q = np.abs(points - c) - half
        out = np.linalg.norm(np.maximum(q, 0.0), axis=1)
        return out + np.minimum(q.max(axis=1), 0.0)

    # a sensor on the face x = 0.6: the window moves along +x by half its side
    lo, hi = window_box([0.6, 0.25, 0.05], 0.01, size, solid_distance=box)
    np.testing.assert_allclose(lo, [0.6, 0.245, 0.045], atol=1e-9)
    np.testing.assert_allclose(hi, [0.61, 0.255, 0.055], atol=1e-9)
    # on the top face z = 0.2: along +z
    lo, hi = window_box([0.45, 0.25, 0.2], 0.02, size, solid_distance=box)
    np.testing.assert_allclose(lo, [0.44, 0.24, 0.2], atol=1e-9)
    # away from the solid: unchanged
    lo, _ = window_box([0.8, 0.25, 0.05], 0.01, size, solid_distance=box)
    np.testing.assert_allclose(lo, [0.795, 0.245, 0.045])


def test_probes_csv_names_each_column_with_its_unit(tmp_path):
    probes = [
        {"name": "wall_p", "quantity": "pressure", "position": [0.1, 0.05]},
        {"name": "gauge.1", "quantity": "level", "position": [0.03, 0.0]},
    ]
    _run("hydrostatic.toml", probes, {"time.end": 0.02}, out=tmp_path)
    lines = (tmp_path / "probes.csv").read_text().splitlines()
    assert lines[0] == "time [s],wall_p [Pa],gauge.1 [m]"
    assert len(lines) == 4  # t = 0, 0.01, 0.02 s
    run = open_run(tmp_path)
    assert set(run.probes) == {"time", "wall_p", "gauge.1"}
    np.testing.assert_allclose(run.probes["time"], [0.0, 0.01, 0.02])
    np.testing.assert_allclose(run.probes["wall_p"][1:], RHO * G * (H - 0.05), rtol=1e-9)
    assert run.units["wall_p"] == "Pa" and run.units["gauge.1"] == "m"
    assert run.summary["probes"]["wall_p"] == {
        "quantity": "pressure",
        "position": [0.1, 0.05],
        "unit": "Pa",
        "window": 0.01,
        "estimate": "fit",
    }


DATA = "time [s],P1 [Pa],H1 [m]\n0.0,0.0,0.195\n0.05,1400.0,0.195\n0.1,1430.0,0.195\n"


def _case_with_data(folder, data):
    (folder / "measured.csv").write_text(DATA)
    text = (EXAMPLES / "hydrostatic.toml").read_text()
    text = text.replace("end = 1.0 ", "end = 0.1 ")
    text += (
        f'\n[[probes]]\nname = "P1"\nquantity = "pressure"\nposition = [0.1, 0.05]\ndata = {data}\n'
    )
    path = folder / "case.toml"
    path.write_text(text)
    return path


def test_probe_data_is_found_beside_the_case_file(tmp_path, monkeypatch):
    (tmp_path / "cases").mkdir()
    path = _case_with_data(tmp_path / "cases", '{path = "measured.csv", column = "P1 [Pa]"}')
    monkeypatch.chdir(tmp_path)  # not the case file's folder
    case = load_case(path)
    data = case.probes[0].data
    assert data.path == str((tmp_path / "cases" / "measured.csv").resolve())
    assert data.column == "P1 [Pa]" and data.time_column == "time [s]"
    assert validate_case(case).model_dump() == case.model_dump()  # found from anywhere


@pytest.mark.parametrize(
    "data, words",
    [
        (
            '{path = "nowhere.csv", column = "P1 [Pa]"}',
            "probes.0.data.path = 'nowhere.csv': the file",
        ),
        (
            '{path = "measured.csv", column = "P2 [Pa]"}',
            "probes.0.data.column = 'P2 [Pa]' is not a column of measured.csv, whose header names "
            "'time [s]', 'P1 [Pa]', 'H1 [m]'; set probes.0.data.column to one of them",
        ),
        (
            '{path = "measured.csv", column = "P1 [Pa]", time_column = "t"}',
            "probes.0.data.time_column = 't' is not a column of measured.csv",
        ),
    ],
)
def test_a_missing_data_file_or_column_is_one_clear_error(tmp_path, data, words):
    path = _case_with_data(tmp_path, data)
    with pytest.raises(CaseError) as err:
        load_case(path)
    message = str(err.value)
    assert words in message and "\n" not in message, message


def test_the_spheric_test2_file_names_its_columns_for_probes(tmp_path):
    """The SPHERIC Test 2 measurements (README section E of the data) can be named as they
    are labelled: P1 [Pa] and "H3 as labelled in source [m]" (the gauge at x = 0.496 m)."""
    from mpmflow.studies.reference_data import data_dir

    path = data_dir() / "validation" / "spheric_test2_kleefsman2005_marin_exp_P1-P8_H1-H4.csv"
    case = load_case(
        EXAMPLES / "hydrostatic_3d.toml",
        {
            "probes": [
                {
                    "name": "P1",
                    "quantity": "pressure",
                    "position": [0.1, 0.025, 0.021],
                    "data": {"path": str(path), "column": "P1 [Pa]"},
                },
                {
                    "name": "H3",
                    "quantity": "level",
                    "position": [0.05, 0.025, 0.0],
                    "data": {"path": str(path), "column": "H3 as labelled in source [m]"},
                },
            ]
        },
    )
    assert [p.data.column for p in case.probes] == ["P1 [Pa]", "H3 as labelled in source [m]"]


@pytest.mark.slow
def test_plot_draws_the_probes_over_their_measured_series(tmp_path, capsys):
    path = _case_with_data(tmp_path, '{path = "measured.csv", column = "P1 [Pa]"}')
    run = tmp_path / "run"
    assert (
        main(
            [
                "run",
                str(path),
                "--out",
                str(run),
                "-q",
                "--set",
                'probes=[{name = "P1", quantity = "pressure", position = [0.1, 0.05], '
                'data = {path = "measured.csv", column = "P1 [Pa]"}}, '
                '{name = "gauge", quantity = "level", position = [0.05, 0.0], '
                'data = {path = "measured.csv", column = "H1 [m]"}}]',
            ]
        )
        == 0
    )
    assert main(["plot", str(run)]) == 0
    figure = run / "plots" / "probes.png"
    with Image.open(figure) as im:  # two panels: pressures, levels
        assert im.format == "PNG" and im.size == (800, 560)
    assert "note" not in capsys.readouterr().err
    # the measured file gone: the probes are drawn without it, and a note says so
    (tmp_path / "measured.csv").unlink()
    assert main(["plot", str(run)]) == 0
    err = capsys.readouterr().err
    assert err.count("probes.png shows P1 without it") == 1, err
    assert figure.stat().st_size > 1000


def test_plot_without_probes_draws_no_probe_figure(tmp_path):
    run = tmp_path / "run"
    assert (
        main(
            [
                "run",
                str(EXAMPLES / "hydrostatic.toml"),
                "--out",
                str(run),
                "-q",
                "--set",
                "time.end=0.02",
                "--set",
                "output.snapshots=false",
            ]
        )
        == 0
    )
    assert main(["plot", str(run)]) == 0
    assert (run / "plots" / "timeseries.png").is_file()
    assert not (run / "plots" / "probes.png").exists()


def _column_with_block(example, block, depth, points, overrides):
    """The column at rest at the default seeding density (particles_per_cell = 2), a solid
    block standing on the floor in it (obstacles.0: min, max), pressure sensors at
    ``points`` (fit), and the run's caps and fallbacks."""
    with open(EXAMPLES / example, "rb") as f:
        data = tomllib.load(f)
    del data["bodies"][0]["particles_per_cell"]
    data["bodies"][0]["around_obstacles"] = True
    data["obstacles"] = [{"type": "box", "min": block[0], "max": block[1]}]
    data["output"]["snapshots"] = False
    apply_overrides(data, overrides)
    case = validate_case(data)
    assert case.bodies[0].particles_per_cell == 2  # the default
    case.probes = _pressure_probes(points, "fit")
    sim = Simulation(case, None)
    sim.run()
    for name, point in points.items():
        exact = RHO * G * (depth - point[-1])
        value = sim.probe_series(f"{name}_fit")[-1]
        assert abs(value - exact) <= 1e-6 * RHO * G * depth, (name, value, exact)
    return sim


def test_sensors_at_the_default_density_read_rho_g_h_on_the_floor_walls_and_an_obstacle():
    """Issue 24, item 1: at particles_per_cell = 2 (the default) a one-cell window of a 2D
    floor sensor holds 4 particles, fewer than a fit's 6, and the probe read the window's
    mean, half a cell of head low (1422.45 Pa for 1471.5 Pa at 0.15 m). The default window
    now holds a fit's particles, so the floor, a side wall and the faces of a block standing
    in the water read rho g (H - z) to 1e-6."""
    depth = 0.15
    points = {
        "floor": [0.05, 0.0],
        "wall": [0.0, 0.07],
        "right_wall": [0.1, 0.03],
        "block_top": [0.075, 0.04],
        "block_side": [0.06, 0.02],
    }
    sim = _column_with_block(
        "hydrostatic.toml",
        ([0.06, 0.0], [0.09, 0.04]),
        depth,
        points,
        {"time.end": 0.02, "bodies.0.max": [0.1, depth]},
    )
    assert sim.fallbacks.rows() == []
    assert probes.window(sim.case.probes[0], sim.grid, sim.case) == 2 * sim.grid.spacing


def test_sensors_at_the_default_density_read_rho_g_h_in_3d():
    depth = 0.2
    points = {
        "floor": [0.05, 0.025, 0.0],
        "wall": [0.0, 0.025, 0.1],
        "wall_y": [0.03, 0.0, 0.1],
        "block_top": [0.075, 0.025, 0.05],
        "block_side": [0.05, 0.025, 0.025],
    }
    sim = _column_with_block(
        "hydrostatic_3d.toml",
        ([0.05, 0.0, 0.0], [0.1, 0.05, 0.05]),
        depth,
        points,
        {"time.end": 0.02, "grid.spacing": 0.025, "bodies.0.max": [0.1, 0.05, depth]},
    )
    assert sim.fallbacks.rows() == []


def test_a_window_too_sparse_for_a_fit_reads_the_mean_and_says_so():
    """A floor window set to 0.004 m holds one layer of particles (at 0.0025 m, 4 per
    cell axis on the 0.01 m mesh): the probe reads their mean, the pressure of that layer,
    and the summary counts it at every output."""
    sim = _run(
        "hydrostatic.toml",
        [{"name": "floor", "quantity": "pressure", "position": [0.05, 0.0], "window": 0.004}],
        {"time.end": 0.02},
    )
    np.testing.assert_allclose(sim.probe_series("floor")[-1], RHO * G * (H - 0.0025), rtol=1e-7)
    (row,) = sim.fallbacks.rows()
    assert (row["what"], row["where"]) == ("probe fit fell back to the window mean", "probe floor")
    assert row["count"] == len(sim.probe_series("floor"))


def test_fallbacks_are_in_the_summary_on_the_last_line_and_survive_a_restart(tmp_path, capsys):
    """A fit's fallback to the mean is counted once per output (t = 0 to 0.04 s) in summary.json's caps_and_fallbacks,
    named on the run's last line, and a run stopped and restarted counts the whole run."""
    import json
    import signal

    args = [
        "run",
        str(EXAMPLES / "hydrostatic.toml"),
        "--set",
        "time.end=0.04",
        "--set",
        "output.snapshots=false",
        "--set",
        "checkpoint.interval=0.01",
        "--set",
        "probes=[{name='floor', quantity='pressure', position=[0.05, 0.0], window=0.004}]",
    ]
    assert main(args + ["--out", str(tmp_path / "whole")]) == 0
    last = capsys.readouterr().err.strip().splitlines()[-1]
    assert "probe fit fell back to the window mean (probe floor: 5 outputs)" in last, last
    (row,) = json.loads((tmp_path / "whole" / "summary.json").read_text())["caps_and_fallbacks"]
    assert (row["count"], row["first_time"], row["last_time"]) == (5, 0.0, 0.04)

    case = load_case(EXAMPLES / "hydrostatic.toml", [a for a in args[3::2]])
    first = Simulation(case, tmp_path / "parts")

    def stop(sim):
        if sim.time >= 0.02 - 1e-12:
            sim.stop_signal = signal.SIGINT

    first.on_output = stop
    assert first.run()["status"] == "interrupted"
    rest = Simulation.resume(case, tmp_path / "parts")
    assert rest.run()["status"] == "completed"
    assert rest.fallbacks.rows() == [row]
