"""The command line: outputs of a run, bad input, solver failure (run as a user would)."""

import csv
import json
import os
import shlex
import signal
import subprocess
import sys
import time
import xml.etree.ElementTree as ET

import meshio
import numpy as np
import pytest
from conftest import EXAMPLES

QUICK = ["--set", "time.end=0.05", "--set", "output.snapshot_interval=0.02"]


def mpmflow(*args, cwd=None):
    return subprocess.run(
        [sys.executable, "-m", "mpmflow.cli", *map(str, args)],
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=300,
    )


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("run") / "out"
    res = mpmflow(
        "run", EXAMPLES / "dam_break.toml", "--out", out, "--set", "grid.spacing=0.008", *QUICK
    )
    assert res.returncode == 0, res.stderr
    return out, res


@pytest.mark.slow
def test_run_writes_timeseries_summary_and_snapshots(quick_run):
    out, _ = quick_run
    with open(out / "timeseries.csv") as f:
        rows = list(csv.DictReader(f))
    assert {"time", "front", "height"} <= set(rows[0])
    times = [float(r["time"]) for r in rows]
    np.testing.assert_allclose(times, np.arange(0, 0.0501, 0.01), atol=1e-12)  # every interval
    assert float(rows[0]["front"]) == pytest.approx(0.114, abs=0.008)
    summary = json.loads((out / "summary.json").read_text())
    for key in ("status", "steps", "particles", "wall_seconds", "case"):
        assert key in summary
    assert summary["status"] == "completed" and summary["steps"] == 50
    assert summary["case"]["grid"]["spacing"] == 0.008  # the resolved case, overrides applied
    assert summary["case"]["solver"]["scheme"] == "projection"
    assert summary["notices"]  # 0.42 m is not a whole number of 0.008 m cells


@pytest.mark.slow
def test_snapshots_form_a_paraview_time_series(quick_run):
    out, _ = quick_run
    datasets = ET.parse(out / "particles.pvd").getroot().find("Collection").findall("DataSet")
    times = [float(d.get("timestep")) for d in datasets]
    np.testing.assert_allclose(times, [0.0, 0.02, 0.04, 0.05], atol=1e-12)
    summary = json.loads((out / "summary.json").read_text())
    for d in datasets:
        mesh = meshio.read(out / d.get("file"))
        assert mesh.points.shape == (summary["particles"], 3)
        assert {"velocity", "pressure"} <= set(mesh.point_data)
    assert not list(out.glob(".*.tmp"))  # atomic writes leave nothing behind


@pytest.mark.slow
def test_refuses_to_overwrite_a_previous_run(quick_run):
    out, _ = quick_run
    res = mpmflow("run", EXAMPLES / "dam_break.toml", "--out", out, *QUICK)
    assert res.returncode == 2
    assert "--overwrite" in res.stderr and "Traceback" not in res.stderr


@pytest.mark.slow
def test_help_explains_commands_keys_and_exit_codes():
    top = mpmflow("--help").stdout
    for word in ("run", "keys", "exit codes", "invalid input"):
        assert word in top
    text = mpmflow("run", "--help").stdout
    for word in ("--out", "--set", "timeseries.csv", "summary.json", "particles.pvd"):
        assert word in text
    keys = mpmflow("keys").stdout
    for key in ("grid.spacing", "time.dt", "time.end", "output.interval", "solver.scheme"):
        assert key in keys


BAD = [
    (["--set", "grid.spaceing=0.01"], "grid.spaceing", "Did you mean `grid.spacing`"),
    (["--set", "grid.spacing=-0.01"], "grid.spacing", "greater than 0"),
    (["--set", "bodies.0.max=[0.5, 0.2]"], "bodies.0", "outside the domain"),
    (["--set", "time.dt=0"], "time.dt", "greater than 0"),
    (["--set", "time.dt=-1e-3"], "time.dt", "greater than 0"),
    (["--set", "solver.scheme=implicit"], "solver.scheme", "explicit"),
    (["--set", "solver.sparse_cell_threshold=0.95"], "sparse_cell_threshold", "smaller"),
    (["--set", "nonsense"], "nonsense", "dotted.key=value"),
]


@pytest.mark.parametrize("args, key, hint", BAD)
@pytest.mark.slow
def test_bad_settings_give_one_clear_error(tmp_path, args, key, hint):
    res = mpmflow("run", EXAMPLES / "hydrostatic.toml", "--out", tmp_path / "o", *args)
    assert res.returncode == 2
    assert "Traceback" not in res.stderr
    assert key in res.stderr and hint in res.stderr
    assert res.stderr.count("\n") == 1  # one paragraph
    assert not (tmp_path / "o").exists()  # nothing was run


@pytest.mark.parametrize(
    "text, hint",
    [
        ("[domain\nsize = [1, 1]\n", "not valid TOML"),
        ("[domain]\nsize = [1.0, 1.0]\nsise = 2\n", "`domain.sise`"),
        ("[grid]\nspacing = 0.1\n", "missing key `domain`"),
    ],
)
@pytest.mark.slow
def test_bad_case_files(tmp_path, text, hint):
    case = tmp_path / "case.toml"
    case.write_text(text)
    res = mpmflow("run", case, "--out", tmp_path / "o")
    assert res.returncode == 2 and "Traceback" not in res.stderr
    assert hint in res.stderr


@pytest.mark.slow
def test_missing_case_file(tmp_path):
    res = mpmflow("run", tmp_path / "none.toml", "--out", tmp_path / "o")
    assert res.returncode == 2 and "does not exist" in res.stderr


@pytest.mark.slow
def test_pressure_solve_failure_stops_the_run_and_says_where(tmp_path):
    out = tmp_path / "o"
    res = mpmflow(
        "run",
        EXAMPLES / "hydrostatic.toml",
        "--out",
        out,
        "--set",
        "solver.max_iterations=1",
        "--set",
        "solver.tolerance=1e-14",
    )
    assert res.returncode == 3 and "Traceback" not in res.stderr
    assert "did not converge at step 1" in res.stderr and "largest residual at node" in res.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and "did not converge" in summary["message"]
    assert (out / "timeseries.csv").read_text().startswith("time,front,height")


@pytest.mark.slow
def test_keys_into_a_pipe_closed_early_exits_quietly():
    """`mpmflow keys | head -1` raised BrokenPipeError with a traceback: the reader going
    away now stops the command quietly with 141 (128 + SIGPIPE), as other tools do."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "mpmflow.cli", "keys"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    proc.stdout.close()  # the reader is gone before the first line is written
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 141 and err == b"", err
    res = subprocess.run(
        [
            "bash",
            "-c",
            f"{shlex.quote(sys.executable)} -m mpmflow.cli keys "
            '| head -1; echo "${PIPESTATUS[0]}"',
        ],
        capture_output=True,
        text=True,
        timeout=60,
    )
    lines = res.stdout.splitlines()
    assert lines[0].startswith("title  (") and lines[1] in ("0", "141"), res.stdout
    assert res.stderr == ""


@pytest.mark.parametrize(
    "signum, delay", [(signal.SIGTERM, 0.25), (signal.SIGINT, 0.5), (signal.SIGTERM, 1.0)]
)
@pytest.mark.slow
def test_a_signal_in_the_first_second_stops_with_a_message(tmp_path, signum, delay):
    """SIGTERM during the first ~0.6 s (imports, loading, placing particles) killed the
    command without a word: whenever it comes, the command now says what it did and exits
    128 + the signal's number. (Where the command is at a given delay depends on the
    machine's speed: before the time loop nothing was run; in it, a checkpoint is written.)"""
    out = tmp_path / "o"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "mpmflow.cli",
            "run",
            str(EXAMPLES / "dam_break.toml"),
            "--out",
            str(out),
            "-q",
            "--set",
            "grid.spacing=0.001",
            "--set",
            "time.dt=2.5e-4",
        ],
        stderr=subprocess.PIPE,
        text=True,
    )
    time.sleep(delay)
    proc.send_signal(signum)
    _, err = proc.communicate(timeout=120)
    name = signal.Signals(signum).name
    assert proc.returncode == 128 + signum, (proc.returncode, err)
    assert "Traceback" not in err
    if "before the run started" in err:
        assert err == f"mpmflow: stopped by {name} before the run started: nothing was run.\n"
        assert not (out / "timeseries.csv").exists()
    else:
        assert f"mpmflow: {name} received: stopping at the next output time" in err, err
        assert "mpmflow: interrupted at t = " in err and "--restart" in err
        summary = json.loads((out / "summary.json").read_text())
        assert summary["status"] == "interrupted"
        assert (out / summary["last_checkpoint"]).is_file()


def _progress_frames(out, end, *extra):
    """The progress bar's frames of ``mpmflow run`` on a small column, as (time shown, step
    shown); tqdm told by its environment to draw at every update (it reads it on import)."""
    import os
    import re

    env = dict(os.environ, TQDM_MININTERVAL="0", TQDM_MINITERS="0")
    res = subprocess.run(
        [
            sys.executable,
            "-m",
            "mpmflow.cli",
            "run",
            EXAMPLES / "hydrostatic.toml",
            "--out",
            out,
            "--set",
            "grid.spacing=0.02",
            "--set",
            "output.snapshots=false",
            "--set",
            f"time.end={end}",
            *extra,
        ],
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
    )
    assert res.returncode == 0, res.stderr
    return [
        (round(float(t), 3), int(s))
        for t, s in re.findall(r"t = ([0-9.]+)/[0-9.]+ s \[[^\]]*\], step (\d+)", res.stderr)
    ]


@pytest.mark.slow
def test_progress_bar_shows_the_steps_taken_by_the_time_it_shows(tmp_path):
    """The step count lagged the time by one output interval (t = 0.02 s beside step 10 at
    1 ms steps): each frame now shows the steps the run had taken at the time beside it,
    from step 0 at t = 0, and a restart's frames go on from its checkpoint's step."""
    out = tmp_path / "run"
    frames = _progress_frames(out, 0.03)
    rows = list(csv.DictReader(open(out / "timeseries.csv")))
    taken = {round(float(r["time"]), 3): int(r["step"]) for r in rows}
    assert sorted(set(frames)) == sorted(taken.items())  # every output, and only those
    assert taken == {0.0: 0, 0.01: 10, 0.02: 20, 0.03: 30}
    frames = _progress_frames(out, 0.05, "--restart")
    assert frames[0] == (0.03, 30) and sorted(set(frames)) == [(0.03, 30), (0.04, 40), (0.05, 50)]


OBSTACLE_CASE = (
    "[domain]\nsize = [0.3, 0.3]\n[grid]\nspacing = 0.01\n[time]\ndt = 1e-3\nend = 2e-3\n"
    "[output]\ninterval = 1e-3\nsnapshots = false\n[[bodies]]\nmin = [0.0, 0.0]\n"
    "max = [0.1, 0.1]\n[[obstacles]]\nmin = [0.2, 0.0]\nmax = [0.25, 0.05]\n"
)


def _run_in_process(tmp_path, capsys, text, *args):
    from mpmflow.cli import main

    (tmp_path / "case.toml").write_text(text)
    out = tmp_path / "o"
    code = main(["run", str(tmp_path / "case.toml"), "--out", str(out), "-q", "--overwrite", *args])
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return code, err


@pytest.mark.parametrize(
    "text, args, message",
    [
        # an index out of range for obstacles gave an example naming bodies
        (
            OBSTACLE_CASE,
            ["--set", "obstacles.3.min=[0.2, 0.0]"],
            "--set obstacles.3.min: `obstacles` has 1 entry; use an index from 0 to 0, e.g. --set "
            "obstacles.0.min=[0.2, 0.0].",
        ),
        (
            OBSTACLE_CASE,
            ["--set", "obstacles.3={min = [0.2, 0.1], max = [0.25, 0.15]}"],
            "--set obstacles.3: `obstacles` has 1 entry; use an index from 0 to 0, e.g. --set "
            "obstacles.0={min = [0.2, 0.1], max = [0.25, 0.15]}, or --set 'obstacles.1={type = "
            '"box", min = [...], max = [...]}\' to add one.',
        ),
        # a case without obstacles: "obstacles: Input should be a valid list"
        (
            OBSTACLE_CASE.split("[[obstacles]]")[0],
            ["--set", "obstacles.0.min=[0.2, 0.0]"],
            "--set obstacles.0.min: `obstacles` has no entries; add one first, e.g. --set "
            "'obstacles.0={type = \"box\", min = [...], max = [...]}', or a [[obstacles]] table in "
            "the case file.",
        ),
        # [[obstacle]] suggested `obstacles.0.min`
        (
            OBSTACLE_CASE.replace("[[obstacles]]", "[[obstacle]]"),
            [],
            "unknown key `obstacle`. Did you mean `obstacles` ([[obstacles]] tables)?",
        ),
        (
            OBSTACLE_CASE,
            ["--set", "obstacle.0.max=[0.25, 0.06]"],
            "unknown case key `obstacle.0.max`. Did you mean `obstacles.0.max`?",
        ),
    ],
)
def test_list_keys_are_named_in_their_messages(tmp_path, capsys, text, args, message):
    code, err = _run_in_process(tmp_path, capsys, text, *args)
    assert code == 2 and err.count("\n") == 1 and message in err, err


def test_a_whole_table_of_a_list_can_be_set(tmp_path, capsys):
    """--set obstacles.0={...} was an unknown key though --set obstacles=[...] worked: an
    index replaces that table, the next index adds one."""
    from mpmflow import load_case

    (tmp_path / "case.toml").write_text(OBSTACLE_CASE)
    loaded = load_case(
        tmp_path / "case.toml",
        [
            "obstacles.0={min = [0.2, 0.1], max = [0.25, 0.15]}",
            "obstacles.1={type = 'disc', centre = [0.2, 0.25], radius = 0.03}",
            "bodies.0={min = [0.0, 0.0], max = [0.1, 0.05]}",
        ],
    )
    assert [o.type for o in loaded.obstacles] == ["box", "disc"]
    assert loaded.obstacles[0].min == [0.2, 0.1] and loaded.bodies[0].max == [0.1, 0.05]
    code, err = _run_in_process(
        tmp_path,
        capsys,
        OBSTACLE_CASE,
        "--set",
        "obstacles.0={min = [0.2, 0.1], max = [0.25, 0.15]}",
    )
    assert code == 0, err


# ----------------------------------------------------------- output paths (issue 40)
SMALL_CASE = (
    "[domain]\nsize = [0.2, 0.2]\n[grid]\nspacing = 0.02\n[time]\ndt = 1e-3\nend = 2e-3\n"
    "[output]\ninterval = 1e-3\nsnapshots = false\n[[bodies]]\nmin = [0.0, 0.0]\n"
    "max = [0.1, 0.1]\n"
)


@pytest.mark.parametrize(
    "command",
    [
        ["run", "CASE", "--out", ""],
        ["study", "paper", "--quick", "--out", ""],
        ["validate", "--case", "hydrostatic", "--out", ""],
        ["plot", "RUN", "--out", ""],
    ],
)
def test_an_empty_out_is_refused_not_taken_for_the_current_folder(
    tmp_path, capsys, monkeypatch, command
):
    from mpmflow.cli import main

    (tmp_path / "case.toml").write_text(SMALL_CASE)
    monkeypatch.chdir(tmp_path)
    if "RUN" in command:  # a run to plot
        assert main(["run", "case.toml", "--out", "run", "-q"]) == 0
    before = sorted(tmp_path.rglob("*"))
    code = main([{"CASE": "case.toml", "RUN": "run"}.get(a, a) for a in command])
    err = capsys.readouterr().err
    assert code == 2 and '--out "" is empty, which would write into the current folder' in err
    assert sorted(tmp_path.rglob("*")) == before  # nothing written


@pytest.mark.parametrize("out", ["a" * 300, "runs/" + "b" * 300 + "/c"])
def test_an_out_the_system_refuses_is_one_message_with_the_fix(tmp_path, capsys, out):
    from mpmflow.cli import main

    (tmp_path / "case.toml").write_text(SMALL_CASE)
    code = main(["run", str(tmp_path / "case.toml"), "--out", str(tmp_path / out), "-q"])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err and err.count("\n") == 1, err
    assert f"--out {tmp_path / out} cannot be " in err
    assert "File name too long. Shorten it: each name in a path may have at most 255" in err


def test_an_os_error_of_a_path_is_exit_2_naming_it(tmp_path, capsys):
    """An OSError that reaches the command line is one message naming the path and what the
    system said, exit 2 (here plot's run folder, whose name is too long to look up)."""
    from mpmflow.cli import main

    run = tmp_path / ("r" * 300)
    assert main(["plot", str(run)]) == 2
    err = capsys.readouterr().err
    assert err == f"mpmflow: error: {run}: File name too long. Shorten it: each name in a " + (
        "path may have at most 255 bytes, the whole path 4096.\n"
    )


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="no /dev/full here")
def test_keys_into_a_full_disk_is_a_message_not_a_traceback():
    for args in (["keys"], ["keys", "--json"], ["keys", "--markdown"]):
        with open("/dev/full", "w") as full:
            res = subprocess.run(
                [sys.executable, "-m", "mpmflow.cli", *args],
                stdout=full,
                stderr=subprocess.PIPE,
                text=True,
                timeout=60,
            )
        assert res.returncode == 2, res.stderr
        assert res.stderr == (
            "mpmflow: error: writing the command's output (standard output, or a file in its "
            "output folder) failed: No space left on device. Free some space on that disk, or "
            "write it to another disk.\n"
        )
