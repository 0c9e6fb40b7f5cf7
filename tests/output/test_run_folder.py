"""One run per output folder: a lock held for the run's life refuses a second run or restart
into it (command line or Python, naming the holder's PID), a folder holding a run is never
silently reused, and the leftovers of a killed run's writes are removed."""

import json
import os
import subprocess
import sys
import time

import meshio
import numpy as np
import pytest
from conftest import EXAMPLES

from mpmflow import Simulation, load_case
from mpmflow.checkpoint import checkpoints
from mpmflow.cli import main
from mpmflow.errors import CaseError
from mpmflow.output.folder import FolderBusy
from mpmflow.output.snapshots import read_index

CASE = EXAMPLES / "dam_break.toml"
# two distinguishable runs: other meshes (particle counts), snapshot times and titles
RUN_A = [
    "--set",
    "grid.spacing=0.008",
    "--set",
    "time.end=1.0",  # seconds of run: the other starts while it holds the folder
    "--set",
    "output.snapshot_interval=0.1",
    "--set",
    "title=A",
]
RUN_B = [
    "--set",
    "grid.spacing=0.01",
    "--set",
    "time.end=0.3",
    "--set",
    "output.snapshot_interval=0.05",
    "--set",
    "title=B",
]


def _start(out, *args):
    return subprocess.Popen(
        [sys.executable, "-m", "mpmflow.cli", "run", str(CASE), "--out", str(out), "-q", *args],
        stderr=subprocess.PIPE,
        text=True,
    )


def _assert_outputs_of_one_run(out, title):
    """Every output in ``out`` comes from the run titled ``title``, and they are complete."""
    summary = json.loads((out / "summary.json").read_text())
    assert summary["case"]["title"] == title and summary["status"] == "completed"
    case = summary["case"]
    rows = np.genfromtxt(out / "timeseries.csv", delimiter=",", names=True)
    expected = np.arange(0, case["time"]["end"] + 1e-9, case["output"]["interval"])
    np.testing.assert_allclose(rows["time"], expected, atol=1e-9)
    entries, complete = read_index(out / "particles.pvd")
    assert complete
    interval, end = case["output"]["snapshot_interval"], case["time"]["end"]
    times = np.arange(0, end + 1e-9, interval)
    if times[-1] < end - 1e-9:
        times = np.append(times, end)  # the end has its snapshot
    np.testing.assert_allclose([t for t, _ in entries], times, atol=1e-9)
    files = sorted(p.name for p in out.glob("particles_*.vtu"))
    assert files == sorted(f for _, f in entries)  # no snapshot of another run
    for name in files:
        assert meshio.read(out / name).points.shape[0] == summary["particles"]
    assert checkpoints(out)[-1].name == summary["last_checkpoint"]


@pytest.mark.slow
def test_two_runs_started_together_into_one_folder(tmp_path):
    """Started at the same moment: one runs, the other is refused with exit 2 naming the
    first's PID; the folder holds the first's outputs only, complete."""
    out = tmp_path / "o"
    a, b = _start(out, *RUN_A), _start(out, *RUN_B)
    errs = [p.communicate(timeout=300)[1] for p in (a, b)]
    codes = [a.returncode, b.returncode]
    assert sorted(codes) == [0, 2], (codes, errs)
    winner, loser = (0, 1) if codes[0] == 0 else (1, 0)
    pid = (a, b)[winner].pid
    err = errs[loser]
    assert "Traceback" not in err and err.count("\n") == 1, err
    assert f"is in use by another mpmflow run (PID {pid}" in err
    assert "Two runs in one folder would mix their outputs" in err
    _assert_outputs_of_one_run(out, "AB"[winner])


@pytest.mark.slow
def test_a_run_or_restart_into_a_busy_folder_is_refused(tmp_path):
    """While a run goes, a second run (even with --overwrite), a restart and a Python-API
    run into its folder are refused; the first run finishes with complete outputs."""
    out = tmp_path / "o"
    # seconds of stepping (0.004 m, 2,000 steps), so that it is still going when the
    # others try
    first = _start(
        out, "--set", "time.end=2.0", "--set", "output.snapshot_interval=0.5", "--set", "title=A"
    )
    t0 = time.monotonic()
    while (
        not (out / "timeseries.csv").exists()
        or len((out / "timeseries.csv").read_text().splitlines()) < 3
    ):
        assert first.poll() is None, first.stderr.read()
        assert time.monotonic() - t0 < 120
        time.sleep(0.01)
    for extra in (["--overwrite"], ["--restart"], []):
        assert first.poll() is None, "the first run ended before the test could try"
        res = subprocess.run(
            [
                sys.executable,
                "-m",
                "mpmflow.cli",
                "run",
                str(CASE),
                "--out",
                str(out),
                "-q",
                *RUN_A,
                *extra,
            ],
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert res.returncode == 2, (extra, res.stderr)
        assert f"PID {first.pid}" in res.stderr and "Traceback" not in res.stderr
        assert "kill -TERM" in res.stderr
    case = load_case(CASE, ["grid.spacing=0.008", "time.end=0.4"])
    with pytest.raises(FolderBusy) as err:
        Simulation(case, out, overwrite=True).run()
    assert err.value.pid == first.pid and "give another out_dir" in str(err.value)
    with pytest.raises(FolderBusy):
        Simulation.resume(case, out)
    _, err = first.communicate(timeout=300)
    assert first.returncode == 0, err
    _assert_outputs_of_one_run(out, "A")


def test_the_lock_holds_within_one_process(tmp_path):
    case = load_case(CASE, ["grid.spacing=0.02", "time.end=0.02"])
    holder = Simulation(case, tmp_path / "o")
    holder.claim()
    with pytest.raises(FolderBusy) as err:
        Simulation(case, tmp_path / "o").run()
    assert f"PID {os.getpid()}" in str(err.value)
    holder.close()  # released: the folder is free again
    assert Simulation(case, tmp_path / "o").run()["status"] == "completed"


def test_the_api_does_not_reuse_a_folder_holding_a_run(tmp_path):
    """A Python-API run into a folder holding another run used to delete its own
    checkpoints and keep the other's: it is refused, unless overwrite=True, which replaces
    the old outputs."""
    out = tmp_path / "o"
    long = load_case(CASE, ["grid.spacing=0.02", "time.end=0.3", "checkpoint.interval=0.1"])
    Simulation(long, out).run()
    old = {p.name for p in checkpoints(out)}
    short = load_case(CASE, ["grid.spacing=0.02", "time.end=0.05"])
    with pytest.raises(CaseError, match="already holds the results of a run"):
        Simulation(short, out).run()
    assert {p.name for p in checkpoints(out)} == old  # untouched
    Simulation(short, out, overwrite=True).run()
    assert [p.name for p in checkpoints(out)] == ["checkpoint_000000050.npz"]
    _assert_outputs_of_one_run(out, short.title)


def test_leftovers_of_a_killed_write_are_removed(tmp_path, capsys):
    """A checkpoint write killed half-way leaves .checkpoint_*.tmp: --restart and
    --overwrite remove it (with a note), as nothing else can be writing there."""
    out = tmp_path / "o"
    args = [
        "run",
        str(CASE),
        "--out",
        str(out),
        "-q",
        "--set",
        "grid.spacing=0.02",
        "--set",
        "time.end=0.1",
    ]
    assert main(args) == 0
    stale = [out / ".checkpoint_000000200.npz.x8k2_q.tmp", out / ".timeseries.csv.abc.tmp"]
    for path in stale:
        path.write_bytes(b"half a file")
    mine = out / ".notes.tmp"  # not a name mpmflow writes: left alone
    mine.write_text("keep")
    capsys.readouterr()
    assert main(args[:-1] + ["time.end=0.2", "--restart"]) == 0
    err = capsys.readouterr().err
    assert "deleted 2 temporary file(s)" in err and "killed while writing" in err
    assert not any(p.exists() for p in stale) and mine.exists()
    stale[0].write_bytes(b"half a file")
    assert main(args + ["--overwrite"]) == 0
    assert not stale[0].exists() and "deleted 1 temporary file(s)" in capsys.readouterr().err
