"""The validation suite's small versions (`mpmflow validate --quick`, ~20 s): the report is
written, and the physics rows the quick meshes can decide come out as they should."""

import csv
import subprocess
import sys

import numpy as np
import pytest

from mpmflow import validation
from mpmflow.case import validate
from mpmflow.cli import main
from mpmflow.errors import CaseError
from mpmflow.geometry.seeding import build_particles
from mpmflow.grid import Grid
from mpmflow.validation import run_validation
from mpmflow.validation.report import TITLE, check_report_folder


@pytest.fixture(scope="module")
def quick(tmp_path_factory, shared_data):
    out = tmp_path_factory.mktemp("validation")
    results, counts = run_validation(out, quick=True)
    rows = {(r.case, r.quantity): r for res in results for r in res.rows}
    return out, rows, counts


def row(rows, case, start):
    hits = [r for (c, q), r in rows.items() if c == case and q.startswith(start)]
    assert len(hits) == 1, (case, start, [q for c, q in rows if c == case])
    return hits[0]


@pytest.mark.slow
def test_report_has_the_summary_table_first_and_a_csv_row_per_row(quick):
    out, rows, counts = quick
    text = (out / "README.md").read_text()
    assert text.index("## Summary") < text.index("## Hydrostatic column")
    assert "| case | quantity | error measure | value | tolerance | result |" in text
    for png in (
        "hydrostatic.png",
        "sloshing.png",
        "dam_break_ar2.png",
        "dam_break_ar1.png",
        "lobovsky.png",
        "volume.png",
        "long_run.png",
        "spheric.png",
        "spheric_3d.png",
    ):
        assert (out / png).stat().st_size > 1000
        assert f"]({png})" in text
    with open(out / "summary.csv") as f:
        table = list(csv.DictReader(f))
    assert len(table) == len(rows) == sum(counts.values())
    assert {r["status"] for r in table} <= {"pass", "miss", "n/a"}
    # every tolerance has its justification, every miss its explanation in the report
    assert all(r.justification for r in rows.values())
    for r in rows.values():
        if r.status != "pass":
            assert r.miss and r.miss in text
    assert not list(out.glob(".*.tmp"))


@pytest.mark.slow
def test_hydrostatic_column_is_exact_and_still(quick):
    _, rows, _ = quick
    for h in ("0.02", "0.01", "0.005"):
        for kind in ("L2", "max"):
            assert row(rows, "hydrostatic", f"default: pressure ({kind}), h = {h} m").value < 1e-6
    assert row(rows, "hydrostatic", "default: spurious velocity").value < 1e-8
    assert row(rows, "hydrostatic", "default: checkerboard").value < 1e-8
    # exact to round-off: the default formulation has no order row
    assert not [q for c, q in rows if c == "hydrostatic" and q.startswith("default: pressure, c")]


@pytest.mark.slow
def test_hydrostatic_paper_formulation_converges_at_first_order(quick):
    """The paper's node-based surface puts p = 0 half a cell above the surface (H = 0.2 - h/2):
    an error of sqrt(3) h / (2 H) in L2, first order (measured: order 1.03, errors 3-4% above
    the offset's)."""
    _, rows, _ = quick
    order = row(rows, "hydrostatic", "paper: pressure, convergence")
    assert order.status == "pass" and order.value >= 1.0
    assert order.value < 1.2  # first order, not better: the offset is all of the error
    for h in (0.02, 0.01, 0.005):
        offset = np.sqrt(3) * (h / 2) / (0.2 - h / 2)
        l2 = row(rows, "hydrostatic", f"paper: pressure (L2), h = {h} m").value
        assert offset <= l2 <= 1.1 * offset, (h, l2, offset)


@pytest.mark.slow
def test_sloshing_period_within_two_percent_at_20_cells_over_the_depth(quick):
    _, rows, _ = quick
    r = row(rows, "sloshing", "period, h = 0.01 m")
    assert r.status == "pass" and r.value < 0.02
    # the wave neither dies nor runs away within 3 s (measured: grows ~2.5% per period)
    assert abs(row(rows, "sloshing", "amplitude change").value) < 0.05


@pytest.mark.slow
def test_dam_break_against_martin_moyce_and_vof_at_0008(quick):
    _, rows, _ = quick
    for q in (
        "height, h = 0.008 m",
        "front vs M&M",
        "front vs K&O",
        "front vs VOF",
        "height vs VOF",
    ):
        assert row(rows, "dam break AR2", q).status == "pass", q
    assert row(rows, "dam break AR2", "height, h = 0.008 m").value <= 0.08
    assert row(rows, "dam break AR1", "height vs M&M").status == "pass"
    assert row(rows, "dam break AR1", "front vs M&M").status == "pass"


@pytest.mark.slow
def test_time_step_differences_stay_below_the_data_tolerance(quick):
    """Known miss of the quarter-tolerance rows (see the report); the differences must stay
    below the 0.08 a used against the experiments."""
    _, rows, _ = quick
    for q in ("front, dt = 0.001", "height, dt = 0.001", "front, dt = 0.002", "height, dt = 0.002"):
        assert row(rows, "time step", q).value < 0.08


@pytest.mark.slow
def test_lobovsky_levels_and_impact_peaks(quick):
    """Released at once and by the experiment's gate, the levels before the reflected jet
    and the impact's peaks at the lower sensors within the experiment's scatter."""
    _, rows, _ = quick
    for tag in ("", "gate: "):
        for gauge in ("H1", "H2", "H3"):
            assert row(rows, "Lobovsky", f"{tag}water level {gauge}").status == "pass"
        for s in ("sensor 1", "sensor 2", "sensor 3"):
            assert row(rows, "Lobovsky", f"{tag}peak pressure, {s}").status == "pass"
    for s in ("sensor 1", "sensor 2", "sensor 3"):
        assert row(rows, "Lobovsky", f"peak time, {s}").status == "pass"


@pytest.mark.slow
def test_volume_measures_stay_within_a_surface_row(quick):
    """On the quick meshes (0.01 m sloshing for 3 s, 0.008 m dam break for 0.45 s) the
    wetted region stays within half a cell row of surface of the water's volume (h L / 2 V:
    2.5% of the sloshing water, 4% of the column at the impact), where the earlier density
    correction let the water loosen by 5-12%; the count-based packed share stays below the
    13% that 5 rows of 4 particles in every other strained cell would give."""
    _, rows, _ = quick
    assert abs(row(rows, "volume", "sloshing: wetted region").value) < 0.025
    assert abs(row(rows, "volume", "dam break: wetted region").value) < 0.04
    assert row(rows, "volume", "sloshing: packed cells").value < 0.13
    assert row(rows, "volume", "dam break: packed cells").value < 0.13


@pytest.mark.slow
def test_long_runs_keep_volume_energy_and_period(quick):
    """The long-run case's quick version (sloshing 0.01 m for 10 s, dam break 0.008 m for
    6 s) with the issue's tolerances: wetted region and settled level of the dam break, the
    sloshing energy and period, and no packing by the hat measure."""
    _, rows, _ = quick
    for q in (
        "dam break, h = 0.008 m, 6 s: wetted region",
        "dam break, h = 0.008 m, 6 s: settled level",
        "sloshing, h = 0.01 m, 10 s: energy rise",
        "sloshing, h = 0.01 m, 10 s: period",
        "sloshing, h = 0.01 m, 10 s: packed share, hat measure",
    ):
        assert row(rows, "long_run", q).status == "pass", q


@pytest.mark.slow
def test_3d_rows_the_quick_meshes_decide(quick):
    """The 3D column at rest is exact; the 3D dam break carries the 2D run's energy per
    metre of width (its front and height rows are in the report, pass or miss)."""
    _, rows, _ = quick
    for q in (
        "column at rest, surface half a cell off the grid: pressure",
        "column at rest, surface half a cell off the grid: speed",
        "column at rest, surface on a grid line: pressure",
        "dam break 0.008 m: peak kinetic energy per width against 2D",
    ):
        assert row(rows, "3D", q).status == "pass", q


@pytest.mark.slow
def test_channel_flow_rows_the_quick_meshes_decide(quick):
    """The finer of each flow's two quick meshes meets the issue's criteria (the coarser
    ones are in the report, pass or miss); each error falls at least at first order."""
    out, rows, _ = quick
    for case, q in (
        ("poiseuille", "start-up profile at 0.1 T_visc, h = 0.0025 m"),
        ("poiseuille", "steady profile, h = 0.0025 m"),
        ("poiseuille", "start-up profile, observed order"),
        ("poiseuille", "steady profile, observed order"),
        ("bingham_plug", "plug width, h = 0.005 m"),
        ("bingham_plug", "plug speed, h = 0.005 m"),
        ("bingham_plug", "profile, observed order"),
        ("mu_i_layer", "surface velocity, h = 0.002 m"),
        ("mu_i_layer", "surface velocity, observed order"),
    ):
        assert row(rows, case, q).status == "pass", (case, q)
    for png in ("poiseuille.png", "bingham_plug.png", "mu_i_layer.png"):
        assert (out / png).stat().st_size > 1000


@pytest.mark.slow
def test_frictional_column_fails_where_the_experiment_did(quick):
    """Bui et al.'s column at 5 mm: the failure line meets the floor within the report's
    10% of the measured place (4.5% at this mesh)."""
    _, rows, _ = quick
    assert row(rows, "bui_collapse", "failure line's foot").status == "pass"
    for q in ("run-out", "failure line's angle", "at rest"):
        assert np.isfinite(row(rows, "bui_collapse", q).value)
    for a in ("0.5", "1.42"):
        assert np.isfinite(row(rows, "granular_collapse_cd", f"run-out, a = {a},").value)


@pytest.mark.slow
def test_wedge_entry_peaks_where_the_similarity_solution_does(quick):
    """The wedge of deadrise 20 degrees at the quick report's mesh (h = 2 mm, V t up to 12
    h): the pressure's peak on the face within the issue's 10% of Zhao & Faltinsen's value
    and height (measured -4.1% and +0.6%; at 1 mm in the full report +0.1% and -1.1%)."""
    _, rows, _ = quick
    assert row(rows, "wedge_entry", "peak's height on the wedge").passed
    assert row(rows, "wedge_entry", "peak pressure coefficient").passed


def test_the_cli_names_every_validation_case():
    from mpmflow.cli import VALIDATION_CASES

    assert VALIDATION_CASES == tuple(validation.CASES)


@pytest.mark.slow
def test_validate_command_rejects_bad_input(tmp_path):
    afile = tmp_path / "file"
    afile.write_text("x")
    for args in (["--out", str(afile)], ["--out", str(tmp_path / "r"), "--case", "nosuch"]):
        res = subprocess.run(
            [sys.executable, "-m", "mpmflow.cli", "validate", *args],
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert res.returncode == 2, res.stderr
        assert "error:" in res.stderr


def _case(amplitude, top=0.2, height=0.3):
    return validate(
        dict(
            domain=dict(size=[0.4, height]),
            grid=dict(spacing=0.01),
            bodies=[
                dict(min=[0, 0], max=[0.4, top], particles_per_cell=4, surface_amplitude=amplitude)
            ],
            time=dict(dt=1e-3, end=0.01),
        )
    )


def test_cosine_surface_body_holds_the_mean_depth_and_its_shape():
    case = _case(0.008)
    P = build_particles(case, Grid.of_case(case))
    dp = 0.0025
    assert P.count * dp * dp == pytest.approx(0.4 * 0.2, rel=0.01)
    left, right = P.x[P.x[:, 0] < dp], P.x[P.x[:, 0] > 0.4 - dp]
    assert left[:, 1].max() == pytest.approx(0.208, abs=dp)
    assert right[:, 1].max() == pytest.approx(0.192, abs=dp)
    assert np.all(P.x[:, 1] < 0.2 + 0.008 * np.cos(np.pi * P.x[:, 0] / 0.4))


@pytest.mark.parametrize(
    "amplitude, top, height, words",
    [
        (0.25, 0.2, 0.5, "smaller than the box's height"),
        (0.05, 0.28, 0.3, "above the domain's top"),
    ],
)
def test_cosine_surface_bad_values_are_clear_errors(amplitude, top, height, words):
    with pytest.raises(CaseError, match=words):
        _case(amplitude, top, height)


def test_validate_refuses_a_readme_it_did_not_write(tmp_path, capsys):
    out = tmp_path / "project"
    out.mkdir()
    (out / "README.md").write_text("# My project\n\nprecious\n")
    assert main(["validate", "--out", str(out), "--quick", "--case", "hydrostatic"]) == 2
    err = capsys.readouterr().err
    assert "holds a README.md that is not a validation report" in err and "Traceback" not in err
    assert (out / "README.md").read_text() == "# My project\n\nprecious\n"
    assert sorted(p.name for p in out.iterdir()) == ["README.md"]  # nothing was run
    (out / "README.md").write_text(TITLE + "\n\nan earlier report\n")
    check_report_folder(out)  # an earlier report may be replaced


def test_validate_runs_a_case_from_the_command_line(tmp_path, capsys, shared_data):
    """The command end to end: each case's line as it finishes, the report written (an
    annotation of its progress callback once raised NameError before any case ran)."""
    out = tmp_path / "report"
    assert main(["validate", "--out", str(out), "--quick", "--case", "hydrostatic"]) == 0
    err = capsys.readouterr().err
    assert "Traceback" not in err and "rows pass" in err
    assert "## Hydrostatic column" in (out / "README.md").read_text()


def test_validate_checks_matplotlib_and_the_examples_before_running(tmp_path, capsys, monkeypatch):
    """Both used to fail only after the runs (a traceback, or a CaseError per case)."""
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # import matplotlib fails
    assert main(["validate", "--out", str(tmp_path / "a"), "--quick"]) == 2
    err = capsys.readouterr().err
    assert "mpmflow validate needs matplotlib: pip install 'mpmflow[plot]'" in err
    assert not (tmp_path / "a").exists()
    monkeypatch.undo()
    monkeypatch.setattr(validation, "EXAMPLES", tmp_path / "no_examples")
    assert main(["validate", "--out", str(tmp_path / "b"), "--quick", "--case", "volume"]) == 2
    err = capsys.readouterr().err
    assert "runs the case files in the examples/ folder of a source checkout" in err
    assert "sloshing.toml, " in err and "dam_break.toml are missing" in err  # volume's needs
    assert "Traceback" not in err and not (tmp_path / "b").exists()


def test_validate_checks_scikit_image_before_running_spheric(tmp_path, capsys, monkeypatch):
    """The SPHERIC case's 3D pictures need scikit-image: checked before the runs when the
    case is among those run, not asked of the others."""
    monkeypatch.setitem(sys.modules, "skimage", None)
    assert main(["validate", "--out", str(tmp_path / "a"), "--quick", "--case", "spheric"]) == 2
    err = capsys.readouterr().err
    assert (
        "mpmflow validate (the SPHERIC case's 3D pictures) needs scikit-image for the 3D "
        "water surface: pip install 'mpmflow[plot]'"
    ) in err
    assert "Traceback" not in err and not (tmp_path / "a").exists()
    monkeypatch.setattr(validation, "EXAMPLES", tmp_path / "no_examples")
    assert main(["validate", "--out", str(tmp_path / "b"), "--quick", "--case", "volume"]) == 2
    assert "scikit-image" not in capsys.readouterr().err  # stopped by the examples instead


@pytest.mark.slow
def test_spheric_test2_first_impact_on_the_box_at_the_coarse_mesh(quick):
    """SPHERIC Test 2 at 0.05 m (quick): the wave reaches the box's front face (P1) within
    the tolerance of the measured 0.393 s, and the impulse of that impact is within 30%
    (measured: 0.017 s and 0.28)."""
    out, rows, _ = quick
    assert row(rows, "SPHERIC 2", "0.05 m: first impact at P1").passed
    assert row(rows, "SPHERIC 2", "0.05 m: impulse of the first impact at P1").passed
    # the 3D pictures at the photograph times the quick run reaches (it ends at 0.75 s)
    assert (
        "![The water at 0.05 m at 0.4, 0.6 s (the experiment's photograph"
        in (out / "README.md").read_text()
    )


@pytest.mark.parametrize("k", [1.0, 1.5])
@pytest.mark.parametrize("jitter", [0.0, 0.2])
def test_the_slump_measure_reads_a_deposit_of_known_shape(k, jitter):
    """The bingham_slump row's measure on particles (spacing 2.5 mm, as the example's) that
    fill h = sqrt(2 k s (L - |x - c|)), s = tau_y / (rho g) = 5.1 mm, L = 0.28 m (the
    arrested half-length of the example's column), with and without a random displacement
    of a fifth of the spacing: it reads k within 5%. (The earlier measure read 0.91 for
    k = 1 without displacement and up to 1.21 with it.)"""
    from mpmflow.validation.materials import arrest_ratios

    s, L, c, a = 50.0 / 9810.0, 0.28, 0.4, 0.0025
    pts = [
        (xv, y)
        for xv in np.arange(c - L + a / 2, c + L, a)
        for y in np.arange(a / 2, np.sqrt(max(2 * k * s * (L - abs(xv - c)), 0.0)), a)
    ]
    x = np.array(pts) + np.random.default_rng(1).normal(0.0, jitter * a, (len(pts), 2))
    values = arrest_ratios(x, c, a, s)
    assert np.all(np.abs(np.array(values) / k - 1) < 0.05), values
