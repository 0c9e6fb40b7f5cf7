"""A Simulation run by schedules: the schedules' arithmetic, writers and callbacks added
through the public API, a callback that stops the run, and restart keeping every
schedule's phase."""

import json
import re
import runpy
import signal
from types import SimpleNamespace

import numpy as np
import pytest
from conftest import EXAMPLES, ROOT

import mpmflow
from mpmflow import IterationInterval, Simulation, TimeInterval, WallTimeInterval, load_case
from mpmflow.checkpoint import checkpoints, read


def _moments(schedule, times, dt=1e-3):
    """The chunk ends (output times) at which ``schedule`` acts."""
    acted = []
    for k, t in enumerate(times, start=1):
        sim = SimpleNamespace(time=t, steps=10 * k, dt=dt)
        if schedule.due(sim):
            schedule.fired(sim)
            acted.append(round(t, 9))
    return acted


def test_a_time_interval_acts_at_the_first_output_time_at_or_after_each_multiple():
    times = [0.01 * k for k in range(1, 13)]  # summed products: 0.01 * 3 is 0.030000000000000002
    assert _moments(TimeInterval(0.05), times) == [0.05, 0.1]
    assert _moments(TimeInterval(0.015), times) == [0.02, 0.03, 0.05, 0.06, 0.08, 0.09, 0.11, 0.12]
    assert _moments(TimeInterval(0.001), times) == [round(t, 9) for t in times]
    # an end that is not a multiple: the next moment is the next multiple after it
    s = TimeInterval(0.01)
    s.fired(SimpleNamespace(time=0.105, steps=105, dt=1e-3))
    assert s.next_time() == pytest.approx(0.11)


def test_iteration_and_wall_time_intervals():
    s = IterationInterval(25)
    acted = []
    for steps in range(10, 110, 10):
        sim = SimpleNamespace(time=0.0, steps=steps, dt=1e-3)
        if s.due(sim):
            s.fired(sim)
            acted.append(steps)
    assert acted == [30, 50, 80, 100]
    w = WallTimeInterval(3600)
    sim = SimpleNamespace(time=0.0, steps=1, dt=1e-3, run_seconds=lambda: 3600.5)
    assert w.due(sim)  # an hour and a bit of wall time since the run started
    sim.run_seconds = lambda: 0.1
    assert not WallTimeInterval(3600).due(sim)
    for bad in (
        lambda: TimeInterval(0),
        lambda: IterationInterval(0),
        lambda: IterationInterval(2.5),
        lambda: WallTimeInterval(-1),
    ):
        with pytest.raises(ValueError):
            bad()


def test_a_shared_schedule_lets_every_action_on_it_act():
    s = TimeInterval(0.02)
    sim = SimpleNamespace(time=0.02, steps=20, dt=1e-3)
    assert s.due(sim)
    s.fired(sim)
    assert s.due(sim)  # the next writer on it, at the same moment
    sim.steps, sim.time = 30, 0.03
    assert not s.due(sim)


def _case(*more):
    return load_case(
        EXAMPLES / "dam_break.toml",
        [
            "grid.spacing=0.01",
            "time.end=0.1",
            "checkpoint.interval=0.03",
            "output.snapshot_interval=0.02",
            *more,
        ],
    )


class Recorder:
    """A writer object: records (time, steps) and whether it was opened and closed."""

    def __init__(self):
        self.calls, self.opened, self.closed = [], None, False

    def open(self, sim, resume):
        self.opened = resume

    def __call__(self, sim):
        self.calls.append((round(sim.time, 9), sim.steps))

    def close(self):
        self.closed = True


def _add(sim, seen):
    """The same writer and callbacks, for a run and for its restart."""
    writer = seen.setdefault("writer", Recorder())
    sim.add_writer(writer, TimeInterval(0.04), name="every_40ms")
    sim.add_callback(
        lambda s: seen.setdefault("steps", []).append(s.steps),
        IterationInterval(25),
        name="every_25_steps",
    )
    sim.add_callback(
        lambda s: seen.setdefault("chunks", []).append(round(s.time, 9)), name="each_chunk"
    )
    return writer


@pytest.mark.slow
def test_added_writers_and_callbacks_act_on_their_schedules(tmp_path):
    seen = {}
    sim = Simulation(_case(), tmp_path / "o")
    writer = _add(sim, seen)
    summary = sim.run()
    assert summary["status"] == "completed"
    # a writer: at t = 0, at its moments, and at time.end; a callback: not at t = 0
    assert [t for t, _ in writer.calls] == [0.0, 0.04, 0.08, 0.1]
    assert seen["steps"] == [30, 50, 80, 100]
    assert seen["chunks"] == [round(0.01 * k, 9) for k in range(1, 11)]
    assert writer.closed and writer.opened is None
    # the phases of added schedules are in the checkpoints, under their names
    meta = read(checkpoints(tmp_path / "o")[-1])[1]
    assert meta["schedules"] == {
        "every_40ms": {"k": 3},
        "every_25_steps": {"k": 5},
        "each_chunk": {"k": 101},
    }
    with pytest.raises(ValueError, match="named 'every_40ms'"):
        sim.add_writer(Recorder(), name="every_40ms")
    with pytest.raises(TypeError, match="not callable"):
        sim.add_callback(42)
    with pytest.raises(TypeError, match="not a schedule"):
        sim.add_callback(print, 0.01)


def test_a_run_without_added_schedules_keeps_the_checkpoint_meta_as_before(tmp_path):
    Simulation(_case("time.end=0.03"), tmp_path).run()
    meta = read(checkpoints(tmp_path)[-1])[1]
    assert "schedules" not in meta and (meta["k_out"], meta["k_snap"]) == (4, 2)


@pytest.mark.slow
def test_restart_keeps_every_schedules_phase(tmp_path):
    """Interrupted at 0.05 s and resumed, the added writer and callbacks act at the same
    times and steps as in the uninterrupted run (without the phases, the writer on 0.04 s
    would act again at 0.06 s, and the one on 25 steps at step 60)."""
    whole = {}
    sim = Simulation(_case())
    _add(sim, whole)
    sim.run()
    parts = {}
    first = Simulation(_case(), tmp_path)
    _add(first, parts)

    def stop(s):
        if s.time >= 0.05 - 1e-12:
            s.stop_signal = signal.SIGINT

    first.on_output = stop
    assert first.run()["status"] == "interrupted"
    rest = Simulation.resume(_case(), tmp_path)
    _add(rest, parts)
    assert rest.run()["status"] == "completed"
    assert parts["writer"].calls == whole["writer"].calls
    assert parts["writer"].opened is None  # a writer without a position() resumes from None
    assert parts["steps"] == whole["steps"] == [30, 50, 80, 100]
    assert parts["chunks"] == whole["chunks"]


def _documented_example():
    text = (ROOT / "docs" / "getting-started.md").read_text()
    section = text.split("### Writers and callbacks on schedules", 1)[1]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


def test_the_documented_callback_stops_the_run_when_the_front_reaches_the_wall(
    tmp_path, monkeypatch
):
    """docs/getting-started.md's example, run as written: the summary says that the run
    stopped and why, the outputs go up to that time, and a checkpoint of it is written."""
    (tmp_path / "examples").symlink_to(EXAMPLES)
    (tmp_path / "example.py").write_text(_documented_example())
    monkeypatch.chdir(tmp_path)
    names = runpy.run_path(str(tmp_path / "example.py"))
    summary, sim = names["summary"], names["sim"]
    assert summary["status"] == "stopped"
    assert summary["message"].startswith("the front reached x = 0.4")
    assert 0.15 < summary["time"] < 0.3 and summary["time"] < sim.case.time.end
    out = tmp_path / "runs" / "to_the_wall"
    assert json.loads((out / "summary.json").read_text())["status"] == "stopped"
    rows = (out / "timeseries.csv").read_text().split()[1:]
    last = [float(v) for v in rows[-1].split(",")]
    assert last[0] == pytest.approx(summary["time"]) and last[1] >= 0.41
    front = np.array([float(r.split(",")[1]) for r in rows])
    assert (front[:-1] < 0.41).all()  # it stopped at the first row at the wall
    assert summary["last_checkpoint"] == f"checkpoint_{summary['steps']:09d}.npz"
    assert (out / summary["last_checkpoint"]).is_file()
    # the added writer at its own times up to the stop (a stop is not time.end, so the
    # writers are not made to write there)
    assert [round(t, 9) for t, _ in names["energy"]] == [
        round(0.05 * k, 9) for k in range(int(summary["time"] / 0.05 + 1e-9) + 1)
    ]
    assert isinstance(mpmflow.TimeInterval(0.1), TimeInterval)
