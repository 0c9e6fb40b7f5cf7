"""Output cost linear in the run's length: an append-only time series with a recoverable
tail, a snapshot index that grows in place, checkpoints that carry state, not history."""

import signal

import numpy as np
import pytest
from conftest import EXAMPLES, make_case

from mpmflow import Simulation, load_case, open_run
from mpmflow.checkpoint import checkpoints
from mpmflow.cli import main
from mpmflow.errors import CaseError
from mpmflow.output.snapshots import read_index


def _tiny(end, snapshots=False, **more):
    """4 particles, an output row every step of 1 ms, a checkpoint every 0.1 s."""
    return make_case(
        size=(0.04, 0.04),
        spacing=0.01,
        body=((0.0, 0.0), (0.02, 0.02)),
        ppc=1,
        dt=1e-3,
        end=end,
        output={"interval": 1e-3, "snapshots": snapshots},
        checkpoint={"interval": 0.1},
        **more,
    )


def _bytes_written():
    """Bytes this process has passed to write() so far (Linux /proc/self/io)."""
    for line in open("/proc/self/io"):
        if line.startswith("wchar:"):
            return int(line.split()[1])
    raise AssertionError("no wchar in /proc/self/io")


def _run_and_count(case, out):
    before = _bytes_written()
    Simulation(case, out).run()
    return _bytes_written() - before


@pytest.mark.slow
def test_thousands_of_rows_cost_linear_bytes_and_fixed_size_checkpoints(tmp_path):
    """2,000 and 4,000 rows, a row every step: the bytes written double (they grew 4-fold
    when the whole file was rewritten after every row), and the last checkpoint does not
    grow with the rows (it carried all of them)."""
    small = _run_and_count(_tiny(2.0), tmp_path / "a")
    large = _run_and_count(_tiny(4.0), tmp_path / "b")
    rows_a = (tmp_path / "a" / "timeseries.csv").read_text().count("\n") - 1
    rows_b = (tmp_path / "b" / "timeseries.csv").read_text().count("\n") - 1
    assert (rows_a, rows_b) == (2001, 4001)
    assert large / small < 2.1, (small, large)
    size_a = checkpoints(tmp_path / "a")[-1].stat().st_size
    size_b = checkpoints(tmp_path / "b")[-1].stat().st_size
    assert abs(size_b - size_a) < 64, (size_a, size_b)  # a digit or two of the meta


@pytest.mark.slow
def test_the_snapshot_index_grows_in_place(tmp_path):
    """A snapshot every step: each one adds the same bytes to particles.pvd, which stays a
    whole XML file (ParaView can open it at any time)."""
    import xml.etree.ElementTree as ET

    small = _run_and_count(_tiny(0.3, snapshots=True), tmp_path / "a")
    large = _run_and_count(_tiny(0.6, snapshots=True), tmp_path / "b")
    assert large / small < 2.1, (small, large)
    entries, complete = read_index(tmp_path / "b" / "particles.pvd")
    assert complete and len(entries) == 601
    root = ET.parse(tmp_path / "b" / "particles.pvd").getroot()
    assert len(root.find("Collection").findall("DataSet")) == 601


def test_a_torn_last_row_is_dropped_by_readers_and_by_the_restart(tmp_path):
    """After a crash of the machine the last row may be cut short: open_run leaves it out
    with a note, and --restart cuts the file back to the checkpoint and continues, ending
    as the uninterrupted run."""
    whole_dir, out = tmp_path / "whole", tmp_path / "parts"
    Simulation(_tiny(0.2), whole_dir).run()
    first = Simulation(_tiny(0.2), out)

    def stop(sim):
        if sim.time >= 0.05 - 1e-12:
            sim.stop_signal = signal.SIGINT

    first.on_output = stop
    assert first.run()["status"] == "interrupted"
    with open(out / "timeseries.csv", "a") as f:  # rows after the checkpoint, the last torn
        f.write("0.051,0.02,0.02,51,0,0.01,0,0,0,0,1,0,1,4,0\n0.052,0.0")
    run = open_run(out)
    assert run.timeseries["time"][-1] == pytest.approx(0.051)
    assert any("cut short" in note for note in run.notes)
    rest = Simulation.resume(_tiny(0.2), out)
    rest.run()
    assert (out / "timeseries.csv").read_text() == (whole_dir / "timeseries.csv").read_text()
    # the resumed run's series holds the rows before the checkpoint too (read back)
    assert len(rest.series("time")) == 201
    np.testing.assert_allclose(rest.series("time"), np.round(np.arange(201) * 1e-3, 9))


def test_a_restart_refuses_a_time_series_cut_below_its_checkpoint(tmp_path, capsys):
    out = tmp_path / "o"
    args = [
        "run",
        str(EXAMPLES / "hydrostatic.toml"),
        "--out",
        str(out),
        "-q",
        "--set",
        "grid.spacing=0.02",
        "--set",
        "time.end=0.1",
    ]
    assert main(args) == 0
    text = (out / "timeseries.csv").read_text()
    (out / "timeseries.csv").write_text(text[: len(text) // 2])
    assert main(args[:-1] + ["time.end=0.2", "--restart"]) == 2
    err = capsys.readouterr().err
    assert "timeseries.csv" in err and "does not hold the 11 rows" in err
    assert "--overwrite" in err and "Traceback" not in err


def test_a_restart_refuses_a_time_series_of_other_columns(tmp_path, capsys):
    """A run whose timeseries.csv has other columns than this version writes (one written
    before the time series gained body_energy) is refused by name, not as a damaged file."""
    out = tmp_path / "o"
    args = ["run", str(EXAMPLES / "hydrostatic.toml"), "--out", str(out), "-q"]
    args += ["--set", "grid.spacing=0.02", "--set", "time.end=0.1"]
    assert main(args) == 0
    lines = (out / "timeseries.csv").read_text().splitlines()
    k = lines[0].split(",").index("body_energy")
    older = [",".join(c for j, c in enumerate(line.split(",")) if j != k) for line in lines]
    (out / "timeseries.csv").write_text("\n".join(older) + "\n")
    assert main(args[:-1] + ["time.end=0.2", "--restart"]) == 2
    err = capsys.readouterr().err
    assert "has other columns than this run writes" in err and "body_energy" in err
    assert "--overwrite" in err and "Traceback" not in err


def test_a_checkpoint_holds_positions_not_rows(tmp_path):
    from mpmflow.checkpoint import read

    Simulation(_tiny(0.2), tmp_path).run()
    _, meta = read(checkpoints(tmp_path)[-1])
    assert "rows" not in meta and "snapshots" not in meta
    size = (tmp_path / "timeseries.csv").stat().st_size
    assert meta["outputs"]["timeseries"] == {"rows": 201, "bytes": size}


def test_a_resumed_run_refuses_a_missing_index(tmp_path):
    case = _tiny(0.2, snapshots=True)
    first = Simulation(case, tmp_path)

    def stop(sim):
        if sim.time >= 0.05 - 1e-12:
            sim.stop_signal = signal.SIGINT

    first.on_output = stop
    first.run()
    (tmp_path / "particles.pvd").unlink()
    with pytest.raises(CaseError, match="lists 0 snapshots, the checkpoint was written after 51"):
        Simulation.resume(case, tmp_path).run()


def test_load_case_overrides_and_open_run_read_everything(tmp_path):
    """The Python API: overrides as a dict, probes added after loading, a run, and its
    results read back: time series, probes, snapshots, summary. The water at rest gives
    exact probe values: the wall pressure rho g (H - y) and the level H."""
    case = load_case(
        EXAMPLES / "hydrostatic.toml", {"time.end": 0.1, "output.snapshot_interval": 0.05}
    )
    case.probes = [
        {"name": "wall_p", "quantity": "pressure", "position": [0.1, 0.05]},
        {"name": "gauge", "quantity": "level", "position": [0.03, 0.0]},
    ]
    sim = Simulation(case, tmp_path)
    summary = sim.run()
    run = open_run(tmp_path)
    assert run.status == "completed" and run.summary == summary
    assert len(run.timeseries["time"]) == 11 and run.notes == []
    np.testing.assert_allclose(
        run.timeseries["max_pressure"], sim.series("max_pressure"), rtol=1e-8
    )
    assert set(run.probes) == {"time", "wall_p", "gauge"}
    # the window of the sensor on the right wall: the last cell column, y 0.045-0.055 m,
    # whose particles sit at a mean depth of 0.195 - 0.05 m (the pressure is computed in
    # the first step: 0 before it)
    np.testing.assert_allclose(run.probes["wall_p"][1:], 1000 * 9.81 * (0.195 - 0.05), rtol=1e-6)
    np.testing.assert_allclose(run.probes["gauge"], 0.195, rtol=1e-9)
    np.testing.assert_allclose(run.probes["wall_p"], sim.probe_series("wall_p"), rtol=1e-8)
    assert [s.time for s in run.snapshots] == [0.0, 0.05, 0.1]
    last = run.snapshots[-1].read()
    assert last["x"].shape == (summary["particles"], 2)
    np.testing.assert_allclose(last["pressure"], sim.particles.pressure)
    assert run.units["wall_p"] == "Pa" and run.units["gauge"] == "m"
    assert run.units["front"] == "m"


def test_an_override_replaces_a_list_of_tables_whole():
    """probes (and bodies) as one override: a dict value, or TOML on the command line;
    the entries get the same checks as the file's."""
    probe = {"name": "wall_p", "quantity": "pressure", "position": [0.1, 0.05]}
    by_dict = load_case(EXAMPLES / "hydrostatic.toml", {"probes": [probe]})
    by_set = load_case(
        EXAMPLES / "hydrostatic.toml",
        ['probes=[{name = "wall_p", quantity = "pressure", position = [0.1, 0.05]}]'],
    )
    assert by_dict == by_set and by_dict.probes[0].position == [0.1, 0.05]
    two = load_case(
        EXAMPLES / "hydrostatic.toml",
        {
            "bodies": [
                {"min": [0.0, 0.0], "max": [0.05, 0.1]},
                {"min": [0.05, 0.0], "max": [0.1, 0.1]},
            ]
        },
    )
    assert len(two.bodies) == 2
    with pytest.raises(CaseError, match="missing key `probes.0.quantity`"):
        load_case(EXAMPLES / "hydrostatic.toml", {"probes": [{"name": "x", "position": [0, 0]}]})
    with pytest.raises(CaseError, match="unknown case key `probe`"):
        load_case(EXAMPLES / "hydrostatic.toml", {"probe": [probe]})
