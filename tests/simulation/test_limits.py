"""Sizes and lengths a run cannot have: a case that does not fit the memory is refused at
once with the estimate; the estimate follows the measured peak; endless end times and
case files that are not case files are refused in one paragraph."""

import json
import os
import subprocess
import sys
import time

import pytest
from conftest import EXAMPLES

from mpmflow import Simulation, load_case, memory
from mpmflow.cli import main
from mpmflow.errors import CaseError

DAM = EXAMPLES / "dam_break.toml"


def _cli(*args, env=None, timeout=120):
    t0 = time.monotonic()
    res = subprocess.run(
        [sys.executable, "-m", "mpmflow.cli", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=dict(os.environ, **(env or {})),
    )
    return res, time.monotonic() - t0


@pytest.mark.parametrize(
    "settings, limit",
    [(["grid.spacing=1e-5"], None), (["grid.spacing=0.0005", "time.dt=1e-4"], "300M")],
    ids=["1.4 TB", "800 MB in 300 MB"],
)
def test_a_case_too_large_is_refused_before_any_particle_is_made(monkeypatch, settings, limit):
    """The refusal comes from the estimate, before the particles are seeded: seeding is
    replaced by a failure, and the case is refused all the same (4.2e9 particles would take
    hours to seed, or the memory; 1.7e6 about a second)."""
    from mpmflow.simulation import setup

    if limit:
        monkeypatch.setenv("MPMFLOW_MEMORY_LIMIT", limit)

    def seeded(*args, **kwargs):
        raise AssertionError("particles seeded before the memory check")

    monkeypatch.setattr(setup, "build_particles", seeded)
    with pytest.raises(CaseError, match="This case needs about"):
        Simulation(load_case(DAM, settings))


def test_a_case_too_large_for_the_machine_is_refused_at_once(tmp_path):
    """1.8e9 grid nodes and 4.2e9 particles (1.4 TB): no machine of today holds them. The
    command refuses it (before any particle is made: the test above) with the estimate and
    the settings, in one paragraph."""
    res, wall = _cli("run", DAM, "--out", tmp_path / "o", "--set", "grid.spacing=1e-5")
    assert res.returncode == 2, res.stderr
    err = res.stderr
    assert err.count("\n") == 1 and "Traceback" not in err
    assert "This case needs about" in err and " TB (particles " in err
    assert "grid.spacing" in err and "particles_per_cell" in err
    assert "MemAvailable" in err or "cgroup" in err
    assert not (tmp_path / "o").exists()


@pytest.mark.slow
def test_the_limit_comes_from_the_estimate_not_a_fixed_count(tmp_path):
    """1.7e6 particles passed the old fixed limits (5e7) whatever the memory; with 300 MB
    to give, the estimate (about 800 MB: 801 MB measured by benchmarks/investigations/memory.py) refuses them, and 2 GB holds them."""
    fine = ["--set", "grid.spacing=0.0005", "--set", "time.dt=1e-4"]
    res, wall = _cli(
        "run", DAM, "--out", tmp_path / "o", *fine, env={"MPMFLOW_MEMORY_LIMIT": "300M"}
    )
    assert res.returncode == 2, (res.stderr, wall)
    assert "1,663,488 particles" in res.stderr
    assert "This machine can give the run 300 MB (MPMFLOW_MEMORY_LIMIT)" in res.stderr
    case = load_case(DAM, ["grid.spacing=0.0005"])
    est = memory.estimate(case)
    assert 0.7e9 < est.total < 1.2e9
    os.environ["MPMFLOW_MEMORY_LIMIT"] = "2G"
    try:
        assert memory.check(case) is not None
    finally:
        del os.environ["MPMFLOW_MEMORY_LIMIT"]
    res, _ = _cli("run", DAM, "--out", tmp_path / "o", env={"MPMFLOW_MEMORY_LIMIT": "lots"})
    assert (
        res.returncode == 2 and "MPMFLOW_MEMORY_LIMIT = 'lots' is not a memory size" in res.stderr
    )


def test_counts_too_large_for_a_float_are_refused_too():
    """grid.spacing = 1e-300: 1e600 particles overflowed the estimate (OverflowError, a
    traceback; found by the fuzz test)."""
    case = load_case(DAM, ["grid.spacing=1e-300"])
    assert memory.estimate(case).total == float("inf")
    with pytest.raises(
        CaseError,
        match="This case needs more memory than any machine has: "
        "its particles and grid nodes are too many to count",
    ):
        memory.check(case)


@pytest.mark.slow
def test_the_estimate_is_near_the_measured_peak(tmp_path):
    """The dam break at 0.001 m (416k particles), three steps with a snapshot and a
    checkpoint: the estimate printed before the run is within 30% of the process's peak
    resident memory (benchmarks/investigations/memory.py measures more sizes)."""
    args = [
        "run",
        DAM,
        "--out",
        tmp_path / "o",
        "--set",
        "grid.spacing=0.001",
        "--set",
        "time.dt=2.5e-4",
        "--set",
        "time.end=7.5e-4",
        "--set",
        "output.interval=2.5e-4",
    ]
    # the run is started by a small launcher process: a child forked from this test process
    # would count this process's pages (hundreds of MB once other tests ran here) in its own peak, ru_maxrss being taken from the fork on
    launcher = (
        "import os, subprocess, sys\n"
        "p = subprocess.Popen([sys.executable, '-m', 'mpmflow.cli', *sys.argv[1:]], "
        "stderr=subprocess.PIPE, text=True)\n"
        "_, status, usage = os.wait4(p.pid, 0)\n"
        "sys.stderr.write(p.stderr.read())\n"
        "print(os.waitstatus_to_exitcode(status), usage.ru_maxrss)\n"
    )
    res = subprocess.run(
        [sys.executable, "-c", launcher, *map(str, args)],
        capture_output=True,
        text=True,
        env=dict(os.environ, NUMBA_NUM_THREADS="1"),
    )
    err = res.stderr
    code, maxrss = map(int, res.stdout.split())
    assert code == 0, err
    peak = maxrss * 1024
    est = json.loads((tmp_path / "o" / "summary.json").read_text())["memory_estimate_bytes"]
    assert "memory: about" in err
    assert abs(est["total"] / peak - 1) < 0.3, (est["total"], peak)


@pytest.mark.parametrize(
    "setting, words",
    [
        (
            "time.end=1e300",
            "time.end = 1e+300 s is 1e+303 steps of 0.001 s, more than the "
            "999,999,999 a run can take",
        ),
        ("time.dt=1e-12", "is 1e+12 steps of 1e-12 s"),
        # a step of 5e-324 s overflowed the scheme's step counts (found by the fuzz test)
        ("time.end=5e-324", "time.end = 4.94066e-324 s is shorter than one time step of 0.001 s"),
    ],
)
def test_endless_runs_are_refused(tmp_path, capsys, setting, words):
    assert main(["run", str(DAM), "--out", str(tmp_path / "o"), "--set", setting]) == 2
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1


def test_fields_changed_after_loading_get_the_cross_field_checks():
    """Assignments check only their own section; Simulation checks the whole case again."""
    case = load_case(DAM)
    case.time.end = 1e300  # a valid number on its own
    with pytest.raises(CaseError, match="a run can take"):
        Simulation(case)
    case = load_case(DAM)
    case.bodies[0].max = [5.0, 0.2]
    with pytest.raises(CaseError, match="outside the domain"):
        Simulation(case)
    case = load_case(DAM)
    case.bodies.append(case.bodies[0].model_copy())
    with pytest.raises(CaseError, match="The two are the same box"):
        Simulation(case)


def test_a_formulation_set_after_loading_is_the_same_as_set_on_the_command_line():
    from mpmflow.case import resolved

    by_set = load_case(DAM, ["solver.formulation=paper", "solver.flip=0.5"])
    by_api = load_case(DAM, {"solver.flip": 0.5})
    by_api.solver.formulation = "paper"
    assert resolved(by_api) == resolved(by_set)
    assert by_api.solver.free_surface == "node" and by_api.solver.flip == 0.5


@pytest.mark.parametrize(
    "path, words",
    [
        ("/dev/zero", "is larger than 16 MiB, so it is not a case file"),
        ("/dev/null", "missing key `domain`"),
    ],
)
def test_device_files_as_case_files(tmp_path, path, words):
    if not os.path.exists(path):
        pytest.skip(f"no {path}")
    res, wall = _cli("run", path, "--out", tmp_path / "o", timeout=30)
    assert res.returncode == 2 and words in res.stderr and wall < 5, (res.stderr, wall)


def test_a_case_from_a_pipe(tmp_path):
    """Process substitution, mpmflow run <(sed ... case.toml): a FIFO is read like a file."""
    fifo = tmp_path / "case.fifo"
    os.mkfifo(fifo)
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "mpmflow.cli",
            "run",
            str(fifo),
            "--out",
            str(tmp_path / "o"),
            "-q",
            "--set",
            "time.end=0.02",
        ],
        stderr=subprocess.PIPE,
        text=True,
    )
    with open(fifo, "w") as f:
        f.write((EXAMPLES / "hydrostatic.toml").read_text())
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err


@pytest.mark.parametrize(
    "example, power", [("hydrostatic.toml", "square"), ("hydrostatic_3d.toml", "cube")]
)
def test_the_memory_refusal_says_how_memory_grows(monkeypatch, example, power):
    """The 3D refusal said memory grows as the inverse square of grid.spacing: the
    particles and nodes go as its inverse cube in 3D."""
    monkeypatch.setattr(memory, "available", lambda: (memory.PROGRAM, "the test's budget"))
    with pytest.raises(CaseError) as err:
        memory.check(load_case(EXAMPLES / example))
    assert (
        f"Make the case smaller: grid.spacing (memory grows as its inverse {power}), "
        "bodies.N.particles_per_cell" in str(err.value)
    )
