"""The explicit weakly compressible scheme: stable step, column at rest, dam break against
the projection scheme and the VOF reference, and the study command."""

import math
import subprocess
import sys

import numpy as np
import pytest
from conftest import EXAMPLES

from mpmflow import Simulation, load_case
from mpmflow.errors import CaseError
from mpmflow.stability import stable_time_step
from mpmflow.studies.paper import reduced_bulk_modulus
from mpmflow.studies.reference_data import errors_against_vof

RHO, G = 1000.0, 9.81
EXPLICIT = ["solver.scheme=explicit", "output.snapshots=false"]


def test_stable_step_is_the_sound_crossing_time():
    assert stable_time_step(0.004, 2.2e9, 1000.0) == pytest.approx(0.004 / math.sqrt(2.2e6))
    assert stable_time_step(0.01, 4e5, 1000.0, speed=5.0) == pytest.approx(0.01 / 25.0)


def test_dt_above_the_stable_step_is_refused_with_the_limit():
    with pytest.raises(CaseError) as err:
        load_case(EXAMPLES / "dam_break.toml", EXPLICIT + ["time.dt=1e-5"])
    limit = 0.004 / math.sqrt(2.2e6)
    msg = str(err.value)
    assert "time.dt" in msg and f"{limit:.4g} s" in msg and "auto" in msg
    # just below the limit is accepted
    load_case(EXAMPLES / "dam_break.toml", EXPLICIT + [f"time.dt={0.999 * limit}"])


@pytest.mark.slow
def test_cli_refuses_an_unstable_step(tmp_path):
    res = subprocess.run(
        [
            sys.executable,
            "-m",
            "mpmflow.cli",
            "run",
            str(EXAMPLES / "dam_break.toml"),
            "--out",
            str(tmp_path / "o"),
            "--set",
            "solver.scheme=explicit",
        ],
        capture_output=True,
        text=True,
    )
    assert res.returncode == 2
    assert "stable step" in res.stderr and "2.697e-06 s" in res.stderr
    assert "Traceback" not in res.stderr


def test_auto_step_is_safety_times_the_limit():
    case = load_case(
        EXAMPLES / "hydrostatic.toml",
        EXPLICIT + ["time.dt=auto", "time.safety_factor=0.3", "material.bulk_modulus=4e5"],
    )
    sim = Simulation(case)
    assert sim.dt == pytest.approx(0.3 * 0.01 / 20.0)
    # the projection scheme takes "auto" too (issue 23): its steps follow the flow, up to
    # time.max_dt (tests/test_adaptive_steps.py)
    projection = load_case(EXAMPLES / "hydrostatic.toml", ["time.dt=auto"])
    assert Simulation(projection).dt == projection.time.max_dt


@pytest.mark.slow
def test_column_at_rest_settles_to_hydrostatic():
    """Acceptance: released without pressure, the column rings (sound speed 20 m/s); its
    pressure averaged over 0.5-1.0 s is within 2% (relative L2) of rho g (H - y)."""
    depth = 0.195
    case = load_case(
        EXAMPLES / "hydrostatic.toml",
        EXPLICIT + ["time.dt=auto", "material.bulk_modulus=4e5", "time.end=1.0"],
    )
    sim = Simulation(case)
    samples = []
    sim.on_output = lambda s: (
        samples.append(s.particles.pressure.copy()) if s.time > 0.5 + 1e-9 else None
    )
    sim.run()
    assert len(samples) == 50
    mean = np.mean(samples, axis=0)
    P = sim.particles
    exact = RHO * G * (depth - P.x[:, 1])
    err = np.sqrt(np.sum((mean - exact) ** 2) / np.sum(exact**2))
    assert err < 0.02
    # it did ring: a single snapshot is far from hydrostatic, so the average is what settles
    snap = np.sqrt(np.sum((P.pressure - exact) ** 2) / np.sum(exact**2))
    assert snap > 5 * err
    # the compressed volume matches the pressure: V/V0 = J = 1 - p/K on average, within 5% of
    # the compression itself (p is reported smoothed through the nodes, J is per cell)
    J = P.volume / (P.mass / RHO)
    compression = 1 - J.mean()
    assert compression > 0.003  # the column is compressed by its weight: ~rho g H / (2K)
    assert abs(J.mean() - (1 - P.pressure.mean() / case.material.bulk_modulus)) < 0.05 * compression


def test_hydrostatic_start_stays_at_rest():
    case = load_case(
        EXAMPLES / "hydrostatic.toml",
        EXPLICIT
        + [
            "time.dt=auto",
            "material.bulk_modulus=4e5",
            "time.end=0.5",
            "bodies.0.initial_pressure=hydrostatic",
        ],
    )
    sim = Simulation(case)
    sim.run()
    assert np.max(sim.series("max_speed")) < 1e-3
    P = sim.particles
    exact = RHO * G * (0.195 - P.x[:, 1])
    assert np.sqrt(np.sum((P.pressure - exact) ** 2) / np.sum(exact**2)) < 0.02


@pytest.mark.slow
def test_3d_column_at_rest_settles_to_hydrostatic():
    """The explicit scheme in 3D (issue 23): the 3D column released without pressure rings
    and settles, as the 2D one, to rho g (H - z) within the 2D test's 2% (averaged over
    0.5-1.0 s), its compression matching its pressure."""
    depth = 0.195
    case = load_case(
        EXAMPLES / "hydrostatic_3d.toml",
        EXPLICIT + ["time.dt=auto", "material.bulk_modulus=4e5", "time.end=1.0"],
    )
    sim = Simulation(case)
    samples = []
    sim.on_output = lambda s: (
        samples.append(s.particles.pressure.copy()) if s.time > 0.5 + 1e-9 else None
    )
    sim.run()
    assert len(samples) == 50
    mean = np.mean(samples, axis=0)
    P = sim.particles
    exact = RHO * G * (depth - P.x[:, 2])
    err = np.sqrt(np.sum((mean - exact) ** 2) / np.sum(exact**2))
    assert err < 0.02  # measured 0.0074
    snap = np.sqrt(np.sum((P.pressure - exact) ** 2) / np.sum(exact**2))
    assert snap > 5 * err
    J = P.volume / (P.mass / RHO)
    compression = 1 - J.mean()
    assert compression > 0.003
    assert abs(J.mean() - (1 - P.pressure.mean() / case.material.bulk_modulus)) < 0.05 * compression


@pytest.mark.slow
def test_3d_dam_break_across_a_narrow_slip_tank_is_the_2d_one():
    """The explicit scheme in 3D (issue 23): the dam break in a tank five cells wide with
    slip walls, at the reduced K, keeps its mass, and its front and height follow the 2D
    run on the same mesh at every output to 0.002 a (measured: equal to rounding), the
    front well on its way to the far wall by 0.2 s."""
    k = reduced_bulk_modulus(load_case(EXAMPLES / "dam_break.toml"))
    common = EXPLICIT + [
        "grid.spacing=0.008",
        "bodies.0.particles_per_cell=2",
        "time.dt=auto",
        f"material.bulk_modulus={k}",
        "bodies.0.initial_pressure=hydrostatic",
        "time.end=0.2",
    ]
    runs = []
    for example in ("dam_break.toml", "dam_break_3d.toml"):
        sim = Simulation(load_case(EXAMPLES / example, common))
        sim.run()
        runs.append(sim)
    two, three = runs
    assert three.grid.dim == 3 and three.time == pytest.approx(0.2)
    assert np.array_equal(two.series("time"), three.series("time"))
    a = 0.114
    assert np.max(np.abs(three.series("front") - two.series("front"))) / a <= 0.002
    assert np.max(np.abs(three.series("height") - two.series("height"))) / a <= 0.002
    assert three.series("front")[-1] > 3 * a
    assert three.particles.mass.sum() == pytest.approx(three.mass0, rel=1e-12)
    assert np.max(np.abs(three.particles.v[:, 1])) < 1e-6  # no flow across the tank


def _series(overrides, end=0.3):
    sim = Simulation(
        load_case(
            EXAMPLES / "dam_break.toml",
            ["grid.spacing=0.008", f"time.end={end}", "output.snapshots=false", *overrides],
        )
    )
    sim.run()
    return sim.series("time"), sim.series("front"), sim.series("height")


@pytest.fixture(scope="module")
def reduced_k_runs():
    """The dam break at 0.008 m to 0.4 s, projection and explicit with K for a sound speed ten
    times the free-fall speed (default settings): (t, front, height) of each."""
    k = reduced_bulk_modulus(load_case(EXAMPLES / "dam_break.toml"))
    assert math.sqrt(k / RHO) == pytest.approx(10 * math.sqrt(2 * G * 0.228))
    projection = _series([], end=0.4)
    explicit = _series(
        [
            "solver.scheme=explicit",
            "time.dt=auto",
            f"material.bulk_modulus={k}",
            "bodies.0.initial_pressure=hydrostatic",
        ],
        end=0.4,
    )
    assert np.array_equal(projection[0], explicit[0])
    return projection, explicit


@pytest.mark.slow
def test_reduced_k_dam_break_is_within_the_vof_tolerance_at_every_output(reduced_k_runs):
    """Acceptance (issue 13): front (t <= 0.2 s) and height (t <= 0.4 s) of the explicit run
    within 0.08 a of the VOF reference at every output (measured 0.065 a and 0.068 a)."""
    _, (t_e, f_e, h_e) = reduced_k_runs
    err = errors_against_vof(t_e, f_e, h_e, 0.114, 0.2, 0.4)
    assert err["front"] <= 0.08 and err["height"] <= 0.08


@pytest.mark.xfail(
    strict=True,
    reason=(
        "issue 13 is blocked on this criterion: the explicit front is 0.087 a and the height "
        "0.074 a from the projection's (0.06 a asked). The projection's surge tip runs ahead as a "
        "sheet one or two particles thick at a slightly negative pressure; the explicit tip, whose "
        "pressure cannot go below zero, stays blunt. The gap shrinks with the mesh (0.094, 0.087, "
        "0.050 a at 0.0114, 0.008, 0.004 m) and no explicit cure measured closes it "
        "(docs/method.md, 'The explicit comparator')."
    ),
)
@pytest.mark.slow
def test_reduced_k_dam_break_matches_the_projection_at_every_output(reduced_k_runs):
    """Acceptance (issue 13): front (t <= 0.2 s) and height (t <= 0.4 s) within 0.06 a of the
    projection scheme on the same mesh at every output."""
    (t, f_p, h_p), (_, f_e, h_e) = reduced_k_runs
    a = 0.114
    early = t <= 0.2 + 1e-9
    assert np.max(np.abs(f_e - f_p)[early]) / a <= 0.06
    assert np.max(np.abs(h_e - h_p)) / a <= 0.06


@pytest.mark.slow
def test_real_k_dam_break_survives_the_wall_impact():
    """Issue 13: at K = 2.2 GPa (0.0114 m, time.dt = "auto") lone particles splashing off the
    right wall at ~0.3 s drove the run to 500 m/s and stopped it at 0.31 s; with cells too
    empty to define a volumetric strain left out (solver.explicit_cell_threshold, default
    0.1) it passes the impact, its fastest particles those of the jet up the wall."""
    sim = Simulation(
        load_case(
            EXAMPLES / "dam_break.toml",
            EXPLICIT
            + [
                "grid.spacing=0.0114",
                "time.end=0.4",
                "time.dt=auto",
                "material.bulk_modulus=2.2e9",
                "bodies.0.initial_pressure=hydrostatic",
            ],
        )
    )
    sim.run()
    assert sim.time == pytest.approx(0.4)
    # the jet up the right wall reaches ~6 m/s (three times the free-fall speed sqrt(2 g H),
    # as at the reduced K); the runs that blew up reached 100-500 m/s
    assert np.max(sim.series("max_speed")) < 10.0
    # time.dt = "auto": every step at most safety_factor (0.5) of h / (c + |v|), and not
    # needlessly small (the steps of one output interval are equal, so at most twice as many)
    c = math.sqrt(2.2e9 / RHO)
    fewest = 0.4 / (0.5 * 0.0114 / c)
    assert fewest <= sim.steps < 2 * fewest


@pytest.mark.slow
def test_study_quick(tmp_path):
    """The study command end to end on its smoke-test size: tables and figures written."""
    res = subprocess.run(
        [sys.executable, "-m", "mpmflow.cli", "study", "paper", "--out", str(tmp_path), "--quick"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert res.returncode == 0, res.stderr
    for name in (
        "study.md",
        "study.csv",
        "fig2_height_front_ar2.png",
        "fig3_pressure_ar2.png",
        "fig4_surface_ar2.png",
    ):
        assert (tmp_path / name).stat().st_size > 0
    rows = (tmp_path / "study.csv").read_text().splitlines()
    assert len(rows) == 4  # header + projection, explicit real K, explicit reduced K
    # each run's outputs written from nothing into OUT/runs (git keeps none: issue 40)
    runs = sorted((tmp_path / "runs").iterdir())
    assert len(runs) == 3 and all((r / "summary.json").is_file() for r in runs)
    assert "time-step ratio" in (tmp_path / "study.md").read_text()


@pytest.mark.parametrize(
    "override, feature, instead",
    [
        (
            ["obstacles.0={type='box', min=[0.2, 0.0], max=[0.25, 0.05]}"],
            r"fixed obstacles \(\[\[obstacles\]\]\)",
            r"remove the \[\[obstacles\]\]",
        ),
        (
            ["material.model=newtonian", "material.viscosity=0.01"],
            r"materials other than inviscid water \(material.model\)",
            'set material.model = "water"',
        ),
    ],
)
def test_what_the_explicit_scheme_does_not_support_is_refused_with_the_fix(
    override, feature, instead
):
    """The rule asks the schemes' table (case.capabilities) and names the schemes that would
    do."""
    with pytest.raises(
        CaseError,
        match=rf'solver.scheme = "explicit" does not support '
        rf'{feature}; set solver.scheme = "projection", or {instead}',
    ):
        load_case(
            EXAMPLES / "dam_break.toml",
            ["solver.scheme=explicit", "time.dt=auto", "material.bulk_modulus=4e5", *override],
        )
