"""Interruptions and failures: Ctrl-C / SIGTERM leave a resumable checkpoint and intact
outputs; a blow-up (NaN, a speed above solver.max_speed) stops with step, time and cause;
a particle pushed outside the domain is put back and counted, never lost."""

import csv
import json
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from conftest import EXAMPLES, make_case

from mpmflow import Simulation, load_case
from mpmflow.checkpoint import checkpoints, read
from mpmflow.cli import main
from mpmflow.output.timeseries import COLUMNS
from mpmflow.particles import Particles
from mpmflow.schemes.projection import ProjectionScheme

LONG = [
    "--set",
    "grid.spacing=0.008",
    "--set",
    "time.end=1.0",
    "--set",
    "output.snapshot_interval=0.1",
    "--set",
    "checkpoint.interval=0.25",
]


def _start(out, *extra):
    return subprocess.Popen(
        [
            sys.executable,
            "-m",
            "mpmflow.cli",
            "run",
            str(EXAMPLES / "dam_break.toml"),
            "--out",
            str(out),
            "-q",
            *LONG,
            *extra,
        ],
        stderr=subprocess.PIPE,
        text=True,
    )


def _wait_for_rows(path, rows, proc, timeout=120):
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        if path.exists() and len(path.read_text().splitlines()) > rows:
            return
        assert proc.poll() is None, proc.stderr.read()
        time.sleep(0.01)
    raise AssertionError(f"{path} did not get {rows} rows in {timeout} s")


def _complete_rows(out):
    with open(out / "timeseries.csv") as f:
        rows = list(csv.reader(f))
    assert rows[0] == list(COLUMNS)
    for row in rows[1:]:
        assert len(row) == len(COLUMNS) and all(np.isfinite(float(v)) for v in row[:3])
    return [float(r[0]) for r in rows[1:]]


@pytest.mark.slow
def test_sigint_checkpoints_and_the_restart_matches_an_uninterrupted_run(tmp_path):
    out = tmp_path / "o"
    proc = _start(out)
    _wait_for_rows(out / "timeseries.csv", 3, proc)  # stepping: t = 0.02 s written
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "Traceback" not in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted" and 0.02 <= summary["time"] < 1.0
    assert f"interrupted at t = {summary['time']:.6g} s (step {summary['steps']})" in err
    assert "Resume with: mpmflow run" in err and "--restart" in err
    assert "--set grid.spacing=0.008" in err  # the resume command repeats the settings
    times = _complete_rows(out)
    assert times[-1] == pytest.approx(summary["time"], abs=1e-12)
    assert checkpoints(out)[-1].name == summary["last_checkpoint"]
    assert not list(out.glob(".*.tmp"))
    # continue to the end: exactly the uninterrupted run
    res = subprocess.run(
        [
            sys.executable,
            "-m",
            "mpmflow.cli",
            "run",
            str(EXAMPLES / "dam_break.toml"),
            "--out",
            str(out),
            "-q",
            *LONG,
            "--restart",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert res.returncode == 0, res.stderr
    assert "continuing from" in res.stderr
    whole = Simulation(load_case(EXAMPLES / "dam_break.toml", LONG[1::2]), tmp_path / "whole")
    whole.run()
    arrays, meta = read(checkpoints(out)[-1])
    assert meta["time"] == whole.time == 1.0 and meta["steps"] == whole.steps
    for name in Particles.FIELDS:
        assert np.array_equal(arrays[name], getattr(whole.particles, name)), name
    for name in ("timeseries.csv", "particles.pvd"):
        assert (out / name).read_text() == (tmp_path / "whole" / name).read_text()
    assert json.loads((out / "summary.json").read_text())["status"] == "completed"


def test_sigterm_checkpoints_and_exits_143(tmp_path):
    out = tmp_path / "o"
    proc = _start(out)
    _wait_for_rows(out / "timeseries.csv", 2, proc)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 143 and "Traceback" not in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted" and "SIGTERM" in summary["message"]
    _complete_rows(out)
    assert checkpoints(out)


def test_nan_stops_the_run_with_step_time_and_cause(tmp_path, monkeypatch, capsys):
    advance = ProjectionScheme.advance

    def poisoned(self, dt, nsteps, where):
        """The real steps, then a NaN velocity in the chunk after t = 0.02 s."""
        report = advance(self, dt, nsteps, where)
        if getattr(self, "test_steps", 0) >= 20:
            self.particles.v[7, 0] = np.nan
        self.test_steps = getattr(self, "test_steps", 0) + nsteps
        return report

    monkeypatch.setattr(ProjectionScheme, "advance", poisoned)
    out = tmp_path / "o"
    code = main(
        [
            "run",
            str(EXAMPLES / "dam_break.toml"),
            "--out",
            str(out),
            "-q",
            "--set",
            "grid.spacing=0.008",
            "--set",
            "time.end=0.1",
            "--set",
            "checkpoint.interval=0.01",
        ]
    )
    err = capsys.readouterr().err
    expected = (
        "The run blew up in steps 21 to 30 (t = 0.02 to 0.03 s): 1 particles have "
        "non-finite velocity or position (first: particle 7). The outputs up to "
        "t = 0.02 s are kept."
    )
    assert code == 3 and expected in err and "Traceback" not in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and expected in summary["message"]
    assert _complete_rows(out)[-1] == pytest.approx(0.02)  # the last good output
    assert summary["last_checkpoint"] == "checkpoint_000000020.npz"  # none of the bad state
    assert [p.name for p in checkpoints(out)][-1] == "checkpoint_000000020.npz"


def test_a_speed_above_the_bound_stops_the_run(tmp_path, capsys):
    out = tmp_path / "o"
    code = main(
        [
            "run",
            str(EXAMPLES / "dam_break.toml"),
            "--out",
            str(out),
            "-q",
            "--set",
            "grid.spacing=0.008",
            "--set",
            "time.end=0.3",
            "--set",
            "solver.max_speed=1.0",
        ]
    )
    err = capsys.readouterr().err
    assert code == 3 and "Traceback" not in err
    assert "moves at" in err and "above solver.max_speed = 1 m/s" in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed"
    rows = np.genfromtxt(out / "timeseries.csv", delimiter=",", names=True)
    assert rows["max_speed"].max() <= 1.0  # every row kept is below the bound
    assert rows["time"][-1] < 0.3


@pytest.mark.parametrize(
    "scheme", [{}, {"solver": {"scheme": "explicit"}, "material": {"bulk_modulus": 4e5}}]
)
def test_a_particle_pushed_outside_is_put_back_and_counted(scheme):
    dt = 1e-3 if not scheme else 1e-4
    case = make_case(
        size=(0.1, 0.3),
        spacing=0.01,
        body=((0.0, 0.0), (0.1, 0.1)),
        dt=dt,
        end=dt,
        output={"snapshots": False, "interval": dt},
        **scheme,
    )
    sim = Simulation(case)
    P = sim.particles
    P.x[0] = [-0.002, 0.05]  # beyond the left wall
    P.x[1] = [0.05, 0.3 + 0.004]  # above the ceiling
    P.v[1] = [0.0, 2.0]  # and moving out
    summary = sim.run()
    assert summary["particles_moved_inside"] == 2
    assert (P.x >= 0).all() and (P.x <= [0.1, 0.3]).all()
    assert P.x[0, 0] > 0 and P.x[1, 1] < 0.3 and P.v[1, 1] <= 0.0


def test_a_body_faster_than_the_bound_is_refused_before_the_run(tmp_path, capsys):
    code = main(
        [
            "run",
            str(EXAMPLES / "hydrostatic.toml"),
            "--out",
            str(tmp_path / "o"),
            "--set",
            "bodies.0.velocity=[300.0, 400.0]",
        ]
    )
    err = capsys.readouterr().err
    assert code == 2 and "bodies.0.velocity = [300.0, 400.0] m/s is 500 m/s fast" in err
    assert "solver.max_speed = 100 m/s" in err and not (tmp_path / "o").exists()


def test_a_second_sigterm_stops_at_once_with_143(tmp_path):
    """The first SIGTERM asks for a stop at the next output time; a second one, sent while
    the long chunk to that output time runs, stops without a checkpoint: exit 143 (not
    130), reported as SIGTERM, no traceback (also when the signal lands in a __del__: the
    run loop then stops after the chunk)."""
    out = tmp_path / "o"
    # one chunk to t = 1 s at 0.004 m: seconds of stepping, so the second signal lands in
    # it even on a fast machine (at 0.008 m to 0.5 s the chunk could end first)
    proc = _start(
        out,
        "--set",
        "grid.spacing=0.004",
        "--set",
        "output.interval=1.0",
        "--set",
        "checkpoint.interval=1.0",
    )
    _wait_for_rows(out / "timeseries.csv", 1, proc)  # the row at t = 0: stepping
    proc.send_signal(signal.SIGTERM)
    for line in proc.stderr:  # the handler's message: the first signal was handled
        if "SIGTERM received: stopping at the next output time" in line:
            break
    else:
        raise AssertionError("the first SIGTERM's message never came")
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 143, err
    assert "Traceback" not in err and "by the user" not in err, err
    assert "stopped at once by a second SIGTERM, without a new checkpoint" in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted" and summary["time"] < 1.0
    assert "second SIGTERM" in summary["message"] and summary["last_checkpoint"] is None
    assert not checkpoints(out) and not list(out.glob(".*.tmp"))


def test_a_stop_request_without_an_output_folder():
    """``stop_signal`` is public: a library run without out_dir stops at the next output
    time without a checkpoint (it used to fail in Path(None))."""
    sim = Simulation(
        load_case(
            EXAMPLES / "hydrostatic.toml",
            ["time.end=0.05", "output.interval=0.01", "grid.spacing=0.02"],
        )
    )

    def hook(s):
        if s.time >= 0.02 - 1e-12:
            s.stop_signal = signal.SIGTERM

    sim.on_output = hook
    summary = sim.run()
    assert summary["status"] == "interrupted" and summary["time"] == pytest.approx(0.02)
    assert summary["message"] == (
        f"interrupted by SIGTERM at t = 0.02 s (step {sim.steps}); no checkpoint: no output folder"
    )
