"""A run: ``Simulation``, its time loop, and the writers and callbacks on schedules.

``Simulation(case, out_dir).run()`` steps the scheme from t = 0 to ``time.end`` in chunks
that end at the output times (multiples of ``output.interval``) and at the end; the steps of
a chunk are equal and at most ``time.dt``, so output times are exact. After each chunk the
writers (``writers``, the checkpointer) and the callbacks (``callbacks``) act, each when its
schedule (``schedules``) is due; ``add_writer`` and ``add_callback`` add one, and a callback
may end the run with ``stop``. ``summary.json`` is written at the end, also when the run
fails, stops or is interrupted. ``Simulation.resume(case, out_dir)`` continues from the
latest readable checkpoint.

The same rules hold however the run was started (command line or Python): the case is
validated again as a whole (a field changed after loading is checked against the others),
its memory estimate must fit the machine, the bodies must not overlap or leave the material
without a free surface (``setup``), and the output folder is claimed with a lock for the
run's life (``output.folder``): a second run into it is refused, and a folder that holds
another run is not reused unless ``overwrite=True``.
"""

from __future__ import annotations

import time as _time
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import numpy as np
from numpy.typing import NDArray
from threadpoolctl import threadpool_limits

from .. import checkpoint
from ..boundaries import moving
from ..case import Case, revalidate
from ..cells import CellBins, bin_particles
from ..diagnostics import parts
from ..diagnostics.measures import front_and_height, pressure_noise, totals, volume_measures
from ..errors import SimulationError
from ..fallbacks import Fallbacks
from ..interrupts import StopNow
from ..output.folder import API_HINTS, Hints, Mode, RunFolder
from ..output.summary import write_summary
from ..output.timeseries import COLUMNS
from ..threads import ThreadGovernor
from . import callbacks, checkpointer, energy, setup, writers
from .callbacks import Action, Stop
from .counters import ChunkReport, Counters, add_report
from .schedules import IterationInterval, Schedule, TimeInterval, WallTimeInterval
from .summary import summary as _summary

if TYPE_CHECKING:
    from ..arrays import Floats, Ints
    from ..parallel.comm import Comm
    from ..state import Totals


class Simulation:
    """A run of ``case`` (from ``mpmflow.load_case``) writing into ``out_dir`` (None: no
    files, results in memory only: ``series``, ``probe_series``, ``particles``).

    ``overwrite``: replace the outputs of an earlier run in ``out_dir`` (otherwise such a
    folder is refused when the run starts). ``progress``: callable(t, step, end) after each
    chunk. Raises CaseError (``mpmflow.errors``) for a case that cannot run here:
    cross-field checks, memory, overlapping or too tightly packed bodies, no free surface."""

    def __init__(
        self,
        case: Case,
        out_dir: str | Path | None = None,
        progress: Callable[[float, int, float], None] | None = None,
        overwrite: bool = False,
    ) -> None:
        case = revalidate(case)
        self.case = case
        made = setup.build(case)
        self.memory, self.files, self.grid = made.memory, made.files, made.grid
        self.particles, self.scheme, self.notices = made.particles, made.scheme, made.notices
        self.dt = made.dt
        self.out_dir = Path(out_dir) if out_dir is not None else None
        # where checkpoints go: the output folder; over MPI ranks, on every rank (each
        # writes its piece; parallel.run), where only rank 0 writes the other outputs
        self.checkpoint_dir = self.out_dir
        self.overwrite = bool(overwrite)
        self.progress = progress
        # optional callable(sim), called after each output row
        self.on_output: Callable[[Simulation], None] | None = None
        self.time = 0.0
        self.steps = 0
        self.counters = Counters()
        self.fallbacks = Fallbacks()  # the caps and fallbacks that acted
        # the whole run's (over ranks, the scheme has parted the particles by now)
        self.mass0 = self.particle_sum("mass")
        self.volume0 = self.particle_sum("volume")
        self.count0 = self.particle_count()
        self.threads: ThreadGovernor | None = None  # while a run goes
        self.last_checkpoint: Path | None = None
        self.resumed_from: Path | None = None  # the checkpoint this run continues, if any
        # what that checkpoint recorded of the outputs and schedules (its JSON)
        self.resume_state: dict[str, Any] | None = None
        # set (to a signal number) to stop at the next output time
        self.stop_signal: int | None = None
        # set (to a signal number) to stop after the current chunk, without a checkpoint
        # (the CLI's second signal: its StopNow may be lost in a __del__)
        self.stop_now: int | None = None
        # (first step, steps, t0, dt) of the last chunk
        self.last_chunk: tuple[int, int, float, float] | None = None
        self.wall_before = 0.0  # wall seconds of the runs this one continues
        self._wall0: float | None = None
        self._folder: RunFolder | None = None  # the claimed output folder
        self._opened = False
        self._stop: Stop | None = None
        self._binned: CellBins | None = None
        self._totals: Totals | None = None
        self._schedules_and_actions()

    def _schedules_and_actions(self) -> None:
        out = self.case.output
        # the output times, where chunks end; snapshots and checkpoints at the first output
        # time at or after each multiple of their interval (a shorter interval: every
        # output; taken as the output interval, so that time / interval stays finite)
        self.output_times = TimeInterval(out.interval)
        self.snapshot_times = TimeInterval(max(out.snapshot_interval or out.interval, out.interval))
        self.checkpoint_times = TimeInterval(max(self.case.checkpoint.interval, out.interval))
        chunks = IterationInterval(1)
        # the built-in writers by name, in the order they act (rows in memory: the first two)
        self._timeseries = writers.TimeSeries()
        self._probes = writers.Probes(self.case) if self.case.probes else None
        self.builtin_writers: dict[str, writers.Builtin] = {"timeseries": self._timeseries}
        if self._probes is not None:
            self.builtin_writers["probes"] = self._probes
        if self.case.output.centre_of_mass:
            self.builtin_writers["centre_of_mass"] = writers.CentreOfMass(self.case)
        movers = getattr(self.scheme, "movers", None)
        if movers:
            self.builtin_writers["bodies"] = writers.Bodies(movers, self.grid.dim)
        self.builtin_writers["snapshots"] = writers.Snapshots(movers)
        w = self.builtin_writers

        builtin = partial(Action, builtin=True)
        self.actions = [
            builtin("blow_up_guard", callbacks.blow_up_guard, chunks),
            builtin("drained", callbacks.drained, chunks),
            builtin("progress", callbacks.progress, chunks),
            *[
                builtin(
                    name,
                    w[name],
                    self.snapshot_times if name == "snapshots" else self.output_times,
                    at_start=True,
                    at_end=True,
                    writer=True,
                )
                for name in w
            ],
            builtin(
                "on_output", callbacks.on_output, self.output_times, at_start=True, at_end=True
            ),
            builtin("govern_threads", callbacks.govern_threads, chunks),
            builtin(
                "checkpointer", checkpointer.Checkpointer(), self.checkpoint_times, writer=True
            ),
            builtin("stop_on_signal", callbacks.stop_on_signal, chunks),
        ]

    # ------------------------------------------------------------------ public API
    def add_writer(
        self,
        writer: Callable[[Simulation], None],
        schedule: Schedule | None = None,
        name: str | None = None,
    ) -> Action:
        """Add ``writer``, a callable(sim), to act on ``schedule`` (default: the output
        times, ``TimeInterval(output.interval)``), at t = 0 and at time.end: after the
        built-in writers, before the checkpointer. It may have ``open(sim, resume)``,
        ``sync()`` and ``close()`` (see ``writers``). ``name`` (default: the function's or
        class's name) must be unique: a checkpoint keeps its schedule's phase under it."""
        schedule = TimeInterval(self.case.output.interval) if schedule is None else schedule
        action = self._action(writer, schedule, name, at_start=True, at_end=True, writer=True)
        # before the callbacks at the output times: the writers added before it come first
        self.actions.insert(
            next(k for k, a in enumerate(self.actions) if a.name == "on_output"), action
        )
        return action

    def add_callback(
        self,
        func: Callable[[Simulation], None],
        schedule: Schedule | None = None,
        name: str | None = None,
    ) -> Action:
        """Add ``func``, a callable(sim), to act on ``schedule`` (default: after every
        chunk, ``IterationInterval(1)``): after the writers and the built-in callbacks,
        before the checkpointer (so that a checkpoint follows every action of its moment).
        It may end the run with ``sim.stop(message)``. ``name``: as for ``add_writer``."""
        schedule = IterationInterval(1) if schedule is None else schedule
        action = self._action(func, schedule, name)
        self.actions.insert(
            next(k for k, a in enumerate(self.actions) if a.name == "checkpointer"), action
        )
        return action

    def _action(
        self, func: Callable[[Simulation], None], schedule: Schedule, name: str | None, **kw: bool
    ) -> Action:
        if not callable(func):
            raise TypeError(
                f"{func!r} is not callable: a writer or callback is a function of the Simulation"
            )
        if not all(hasattr(schedule, m) for m in ("due", "fired", "state", "restore")):
            raise TypeError(
                f"{schedule!r} is not a schedule (mpmflow.simulation.TimeInterval, "
                "IterationInterval, WallTimeInterval)"
            )
        name = name or cast(str, getattr(func, "__name__", type(func).__name__))
        if any(a.name == name for a in self.actions):
            raise ValueError(
                f"a writer or callback named {name!r} is in the run already; give another name="
            )
        return Action(name, func, schedule, **kw)

    def stop(self, message: str, status: str = "stopped", checkpoint: bool = True) -> None:
        """End the run once the writers and callbacks of the current moment have acted
        (call it from a callback): the summary's ``status`` and ``message`` say why; with
        ``checkpoint`` (and an output folder) a checkpoint of that state is written. The
        first stop asked for at a moment is the one that counts."""
        if self._stop is None:
            self._stop = Stop(message, status, checkpoint)

    @property
    def stopping(self) -> Stop | None:
        """The stop asked for (``stop``), None while the run goes on."""
        return self._stop

    def checkpoint(self) -> Path:
        """Write a checkpoint of the current state now; returns its path."""
        return checkpointer.write(self)

    @classmethod
    def resume(
        cls,
        case: Case,
        out_dir: str | Path,
        path: str | Path | None = None,
        progress: Callable[[float, int, float], None] | None = None,
        hints: Hints = API_HINTS,
    ) -> Simulation:
        """The run of ``out_dir`` continued from a checkpoint: ``path``, or (None) the latest
        readable one, passing over damaged ones with a notice (in ``notices``). Same
        settings except a later time.end (to extend the run) and execution.*; CaseError
        otherwise, ``checkpoint.CheckpointError`` when the file is damaged or lacks an
        entry. The folder is claimed (locked) at once and stays so until the run ends or
        ``close()``. Writers and callbacks added to the first run are added again to this
        one before ``run()``; their schedules continue where the checkpoint left them."""
        folder = RunFolder.claim(out_dir, "restart", hints)
        try:
            if path is None:
                sim = checkpointer.resume_latest(cls, case, out_dir, progress)
            else:
                sim = checkpointer.resume_from(cls, case, out_dir, path, progress)
        except BaseException:
            folder.release()
            raise
        sim._folder = folder
        sim.notices[:0] = folder.notes
        return sim

    def run_seconds(self) -> float:
        """Wall time (s) since this run() started (0 before it starts)."""
        return _time.perf_counter() - self._wall0 if self._wall0 else 0.0

    def wall_seconds(self) -> float:
        """Wall time of the run so far, with that of the runs it continues."""
        return self.wall_before + self.run_seconds()

    def describe(self) -> list[str]:
        """The case summary the command line prints before a run (lines of text): what
        runs, how many steps and outputs, and the memory estimate."""
        return setup.describe(self)

    # ------------------------------------------------------------------ the output folder
    def claim(self, hints: Hints = API_HINTS) -> None:
        """Lock ``out_dir`` for this run and prepare it (see ``output.folder``); done by
        ``run()`` if not before. CaseError (FolderBusy) when another run holds it, or when
        it holds another run's outputs and ``overwrite`` is not set."""
        if self.out_dir is None or self._folder is not None:
            return
        mode: Mode = "restart" if self.resumed_from else "overwrite" if self.overwrite else "new"
        self._folder = RunFolder.claim(self.out_dir, mode, hints)
        self.notices[:0] = self._folder.notes

    def close(self) -> None:
        """Close the writers' files and release the folder's lock (``run()`` does it when
        it ends; needed only for a Simulation that is resumed or claimed and then not run)."""
        for action in self.actions:
            if action.writer and hasattr(action.func, "close"):
                action.func.close()
        if self._folder is not None:
            self._folder.release()

    def __enter__(self) -> Simulation:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _open_outputs(self) -> None:
        """Open the writers' files (a resumed run's cut back to its checkpoint) and put
        the checkpoint's phases back into the added writers' and callbacks' schedules."""
        if self._opened:
            return
        self._opened = True
        resume = self.resume_state or {}
        outputs = resume.get("outputs")
        for action in self.actions:
            if action.writer and hasattr(action.func, "open"):
                action.func.open(self, None if outputs is None else outputs.get(action.name))
            saved = resume.get("schedules", {}).get(action.name)
            if saved is not None and not action.builtin:
                action.schedule.restore(saved)

    # ------------------------------------------------------------------ measures
    @property
    def history(self) -> dict[str, NDArray[np.float64]]:
        """A solid's particle history (material.model = "elastic", "von_mises",
        "drucker_prager"), in the particles' order: "stress", the deviatoric stress (count x D
        x D, Pa; in 2D the plane-strain deviator, out-of-plane entry 0), "plastic_strain", the
        equivalent plastic strain, and "yielding", 1 where the particle yielded in the last
        step, else 0. Empty for a fluid. The scheme's own arrays: copy to keep them."""
        history: dict[str, NDArray[np.float64]] = getattr(self.scheme, "history", {})
        return history

    @property
    def rows(self) -> list[dict[str, float]]:
        """The timeseries rows so far, as dicts (built on each call; see ``series``)."""
        return self._timeseries.buffer.rows()

    def series(self, name: str) -> NDArray[np.float64]:
        """One timeseries column as an array (see ``output.timeseries.COLUMNS``)."""
        if name not in COLUMNS:
            raise KeyError(
                f"{name!r} is not a timeseries column; the columns are " + ", ".join(COLUMNS)
            )
        return self._timeseries.buffer.column(name)

    def probe_series(self, name: str) -> NDArray[np.float64]:
        """One probe's values at the output times (``series("time")``)."""
        probes = self._probes
        if probes is None or name not in probes.buffer.columns:
            raise KeyError(
                f"no probe named {name!r}; the case's probes are "
                + (", ".join(p.name for p in self.case.probes) or "none")
            )
        return probes.buffer.column(name)

    def measure(self, bins: CellBins | None = None) -> dict[str, float]:
        """The diagnostics of one timeseries row at the current state. With ``bins`` (the
        writers pass ``binned()``) the output time's shared bins and totals; without, both
        measured afresh."""
        P, g = self.particles, self.grid
        # every particle left through the outlets: no largest value (nan)
        if bins is None:
            bins, t = self._bins(), self._measure_totals()
        else:
            t = self.totals()
        front, height = front_and_height(g, bins.theta)
        return {
            "time": self.time,
            "front": front,
            "height": height,
            "step": self.steps,
            "kinetic_energy": t.kinetic,
            "potential_energy": t.potential,
            "body_energy": self.body_energy(),
            "max_speed": t.max_speed,
            "max_pressure": t.max_pressure,
            "pressure_noise": pressure_noise(g, P, self._add(), bins),
            **volume_measures(bins.theta, g.cell_volume, self.volume0, self._open()),
            "max_particles_per_cell": self.most_per_cell(bins),
            "pressure_unknowns": int(self.scheme.last_unknowns),
            "solver_iterations": int(self.counters.iterations_since_output),
        }

    def body_energy(self) -> float:
        """The free bodies' kinetic and potential energy now (J; 2D J/m;
        ``moving.free_energy``): with the particles' KE + PE, the energy of a closed tank
        holding free bodies. 0 without free bodies."""
        movers = getattr(self.scheme, "movers", None)
        if not movers or not any(m.free is not None for m in movers):
            return 0.0
        state = self.scheme.body_values()[2]  # type: ignore[attr-defined]
        return moving.free_energy(movers, state, self.case.physics.gravity)

    def _open(self) -> NDArray[np.float64] | None:
        """The cells' fluid fractions when obstacles cut cells (None: no obstacle)."""
        solids = getattr(self.scheme, "solids", None)
        return solids.open if solids is not None and solids.present else None

    def _bins(self) -> CellBins:
        """Particles binned by cell, theta over the cells' fluid part (the whole run's:
        with the particles in parts, summed over them)."""
        return bin_particles(self.grid, self.particles, open_=self._open(), add=self._add())

    # ------------------------------------------------------------------ particles in parts
    @property
    def comm(self) -> Comm:
        """The ranks that hold this run's particles in parts, one part each (a run over MPI
        ranks: ``sim.particles`` is this rank's part); one process otherwise. The measures
        combine the parts (``diagnostics.parts``). Collective on the first call of a run
        over ranks (the scheme parts its particles then)."""
        parted: Callable[[], Comm] | None = getattr(self.scheme, "parted", None)
        return parted() if parted is not None else parts.ALONE

    @property
    def ids(self) -> Ints | None:
        """The numbers in the run of ``particles`` when they are one part of several (None:
        the whole run, in its order)."""
        ids: Ints | None = getattr(self.scheme, "ids", None)
        return ids

    def _add(self) -> Callable[[Floats], Floats] | None:
        """The sum of an array over the parts (None: one part, nothing to add)."""
        comm = self.comm
        return None if comm.size == 1 else partial(parts.add, comm)

    def particle_count(self) -> int:
        """The particles of the whole run (collective over ranks)."""
        return parts.count(self.comm, self.particles.count)

    def particle_sum(self, field: str) -> float:
        """The sum of a particle field (``mass``, kg; ``volume``, m^3) over the whole run."""
        mine = float(getattr(self.particles, field).sum())
        return float(parts.add(self.comm, np.array([mine]))[0]) if self.comm.size > 1 else mine

    def most_per_cell(self, bins: CellBins) -> int:
        """The largest number of particles in one cell (a cell's are all in one part)."""
        return int(parts.largest(self.comm, float(np.diff(bins.start).max())))

    def _measure_totals(self) -> Totals:
        return parts.totals(self.comm, totals(self.particles, self.case.physics.gravity), self.ids)

    def binned(self) -> CellBins:
        """The particles binned by cell at this output time, shared by the writers."""
        if self._binned is None:
            self._binned = self._bins()
        return self._binned

    def totals(self) -> Totals:
        """The particles' energies, fastest particle, largest pressure and non-finite
        particles at this output time (``diagnostics.measures.totals``), shared by the
        writers and the blow-up guard."""
        if self._totals is None:
            self._totals = self._measure_totals()
        return self._totals

    def forget_bins(self) -> None:
        """Drop the output time's shared bins and totals (measured again when asked)."""
        self._binned = None
        self._totals = None

    # ------------------------------------------------------------------ time loop
    def run(self, wall_budget: float | None = None) -> dict[str, Any]:
        """Run to ``time.end``; returns the summary dict (also written to summary.json).

        ``wall_budget`` (s of wall time): stop at the first output time after it is spent,
        with status "budget" (used by the study for explicit runs at the real K). When
        ``stop_signal`` is set (the CLI's SIGINT/SIGTERM handlers do), the run stops at the
        next output time with a checkpoint and status "interrupted".

        BLAS (NumPy's OpenBLAS) is held to one thread while the run lasts: the compiled
        core uses the cores through its OpenMP threads, and BLAS threads spinning after a
        NumPy call took them away (measured: 2 threads 4.4 times slower than 1 at 416k
        particles; with BLAS on one thread, 1.5 times faster)."""
        if wall_budget is not None:
            callbacks.refuse_budget_over_ranks(self.scheme)
            after = next(k for k, a in enumerate(self.actions) if a.name == "stop_on_signal")
            self.actions.insert(
                after + 1,
                Action(
                    "wall_budget",
                    callbacks.wall_budget(wall_budget),
                    WallTimeInterval(wall_budget),
                    builtin=True,
                ),
            )
        try:
            self.claim()
            self.threads = ThreadGovernor(self.case.execution.threads)
            with threadpool_limits(limits=1, user_api="blas"):
                self.threads.start(self.time)
                try:
                    return self._run()
                finally:
                    self.threads.stop()
        finally:
            self.close()

    def _run(self) -> dict[str, Any]:
        self._wall0 = _time.perf_counter()
        status, message = "failed", ""
        try:
            self._open_outputs()
            status, message = self._loop()
        except SimulationError as err:
            message = str(err)
            raise
        except (KeyboardInterrupt, StopNow) as err:
            status, message = (
                "interrupted",
                (
                    f"stopped at once by a second {err.name}, without a checkpoint (the last one "
                    "written is kept)"
                    if isinstance(err, StopNow)
                    else "stopped at once by KeyboardInterrupt (Ctrl-C), without a checkpoint"
                ),
            )
            raise
        except OSError as err:
            message = f"Writing the outputs failed: {err}. Check the --out folder and free space."
            raise SimulationError(message) from None
        except Exception as err:  # a bug: record it, then let the traceback through
            message = f"internal error: {type(err).__name__}: {err}"
            raise
        finally:
            self.notices += energy.notices(self)  # a rise of KE + PE above its start
            self.summary = _summary(self, status, message)
            if self.out_dir is not None and self.out_dir.is_dir():
                try:
                    write_summary(self.out_dir / "summary.json", self.summary)
                except OSError:
                    pass  # the run's own error (often the same one) is the one to report
        return self.summary

    def _loop(self) -> tuple[str, str]:
        """The time loop: chunks of steps to the next output time, each followed by the
        writers and callbacks that are due; (status, message) at its end."""
        end = self.case.time.end
        if self.resumed_from is None:
            self._act(start=True)
        while self.time < end and self._stop is None:
            t_next = min(self.output_times.next_time(), end)
            # as few steps as dt allows, all equal: no step is a sliver of dt (the pressure
            # scales with 1/dt)
            n = max(1, int(np.ceil((t_next - self.time) / self.dt - 1e-6)))
            self._advance((t_next - self.time) / n, n)
            self.time = t_next
            self._act()
        stop = self._stop or Stop("", "completed", True)  # the end: to extend it later
        if (
            stop.checkpoint
            and self.checkpoint_dir is not None
            and self.last_checkpoint != checkpoint.path_for(self.checkpoint_dir, self.steps)
        ):
            self.checkpoint()
        return stop.status, stop.message

    def _act(self, start: bool = False) -> None:
        """The writers and callbacks whose schedules are due (at t = 0: the writers')."""
        end = self.case.time.end
        try:
            for action in self.actions:
                if start:
                    if action.at_start:
                        action.func(self)
                elif action.due(self, end):
                    action.schedule.fired(self)
                    action.func(self)
        finally:
            self.forget_bins()

    def _advance(self, dt: float, n: int) -> None:
        """n steps of size dt, and the counters of what they did."""
        self.forget_bins()  # what was measured before (outside an output time too) is old
        first, t0 = self.steps + 1, self.time

        def where(k: int) -> str:
            return f" at step {first + k} (t = {t0 + (k + 1) * dt:.6g} s)"

        report: ChunkReport = self.scheme.advance(dt, n, where=where)
        self.last_chunk = (first, n, t0, dt)
        self.steps += getattr(report, "steps", n)  # time.dt = "auto": the steps it took
        self.time = t0 + n * dt
        add_report(self.counters, self.fallbacks, report, self.case, self.time)
