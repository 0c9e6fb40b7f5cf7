"""Each body's seeded mass against rho V (issue 40, geometry/mass.py): the lattice rounding
of a body more than 2% off is told at the start of the run, per body, with the fix; a body
about the size of its particles (more than a factor 2 off) is refused."""

import json

import pytest
import trimesh

from mpmflow import load_case
from mpmflow.cli import main
from mpmflow.geometry import mass

BOX = """
[domain]
size = [0.4, 0.4]
[grid]
spacing = 0.02
[[bodies]]
min = [0.0, 0.0]
max = [0.2, 0.104]
particles_per_cell = 2
[time]
dt = 1e-3
end = 2e-3
[output]
interval = 1e-3
snapshots = false
"""


@pytest.fixture
def box_case(tmp_path):
    path = tmp_path / "case.toml"
    path.write_text(BOX)
    return path


@pytest.mark.parametrize(
    ("top", "said"),
    [
        (
            0.104,
            "200 particles carrying 20 kg/m, 3.8% less than its shape holds rho V = 1000 "
            "kg/m^3 x 0.0208 m^2 = 20.8 kg/m",
        ),
        (
            0.106,
            "220 particles carrying 22 kg/m, 3.8% more than its shape holds rho V = 1000 "
            "kg/m^3 x 0.0212 m^2 = 21.2 kg/m",
        ),
    ],
)
def test_a_box_top_between_lattice_faces_is_told_with_the_aligned_values(box_case, top, said):
    (notice,) = mass.check(load_case(box_case, [f"bodies.0.max=[0.2, {top}]"]))
    assert notice.startswith("bodies.0 (a box) is seeded with " + said), notice
    assert f"max[1] = {top:g} m lies between 0.1 and 0.11" in notice
    assert "put them on multiples of 0.01 m (bodies.0.min/max)" in notice
    assert "raise bodies.0.particles_per_cell (now 2, at most 16)" in notice


def test_a_box_on_the_lattice_or_within_2_percent_is_quiet(box_case):
    assert mass.check(load_case(box_case, ["bodies.0.max=[0.2, 0.1]"])) == []
    # 0.24% off at 16 particles per cell (83 rows of 1.25 mm): below the notice
    assert mass.check(load_case(box_case, ["bodies.0.particles_per_cell=16"])) == []


@pytest.mark.parametrize(
    ("radius", "off"), [(0.012, "11.6% less"), (0.015, "43.4% less"), (0.025, "18.5% less")]
)
def test_discs_a_few_cells_across_are_told_per_body(box_case, radius, off):
    disc = f'bodies.1={{type = "disc", centre = [0.3, 0.3], radius = {radius}}}'
    notices = mass.check(load_case(box_case, ["bodies.0.max=[0.2, 0.1]", disc]))
    (notice,) = notices  # the box is on the lattice: only the disc is told
    assert notice.startswith("bodies.1 (a disc)") and off in notice, notice
    assert "its boundary cuts the lattice's cells" in notice


def test_the_notice_is_on_the_run_s_start_and_in_its_summary(box_case, tmp_path, capsys):
    assert main(["run", str(box_case), "--out", str(tmp_path / "o"), "-q"]) == 0
    err = capsys.readouterr().err
    assert "mpmflow: note: bodies.0 (a box) is seeded with 200 particles" in err
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert any(n.startswith("bodies.0 (a box) is seeded") for n in summary["notices"])


def test_a_mesh_sphere_smaller_than_its_particles_is_refused(tmp_path, capsys):
    """A 2 mm sphere centred on a point of a 5 mm lattice became one particle of 30 times
    its mass."""
    trimesh.creation.icosphere(subdivisions=3, radius=0.001).export(tmp_path / "drop.stl")
    (tmp_path / "case.toml").write_text(
        "[domain]\nsize = [0.1, 0.1, 0.1]\n[grid]\nspacing = 0.01\n[[bodies]]\n"
        'type = "mesh"\npath = "drop.stl"\ntranslate = [0.0525, 0.0525, 0.0525]\n'
        "[time]\ndt = 1e-3\nend = 2e-3\n"
    )
    code = main(["run", str(tmp_path / "case.toml"), "--out", str(tmp_path / "o"), "-q"])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err and err.count("\n") == 1, err
    assert "mpmflow: error: bodies.0 (a mesh) is seeded with 1 particle carrying 0.000125 kg" in err
    assert "30.1 times the mass its shape holds rho V = 1000 kg/m^3 x 4.153e-09 m^3" in err
    assert "the body is about the size of its particles" in err
    assert err.endswith(
        "raise bodies.0.particles_per_cell (at most 16) or refine grid.spacing, "
        "or remove bodies.0.\n"
    )
    assert not (tmp_path / "o" / "summary.json").exists()


def test_a_body_holding_under_half_its_mass_is_refused(box_case):
    """1.9 by 1.9 lattice spacings hold one point: a quarter of the square's mass."""
    case = load_case(box_case, ["bodies.0.min=[0.0051, 0.0051]", "bodies.0.max=[0.0241, 0.0241]"])
    with pytest.raises(ValueError, match=r"0\.277 times the mass its shape holds"):
        mass.check(case)


def test_a_pool_round_an_obstacle_is_measured_without_it(box_case):
    """around_obstacles: the points the obstacle takes are meant to go; the pool's own
    shape is on the lattice, so nothing is told."""
    case = load_case(
        box_case,
        [
            "bodies.0.max=[0.4, 0.2]",
            "bodies.0.around_obstacles=true",
            'obstacles=[{type = "disc", centre = [0.2, 0.1], radius = 0.05}]',
        ],
    )
    assert case.particle_counts()[0] < 800 and mass.check(case) == []
