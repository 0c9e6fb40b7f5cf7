"""A run: the time loop, its output schedule, and the run's bookkeeping.

``Simulation(case, out_dir).run()`` steps the scheme from t = 0 to ``time.end``; the steps
between two output times are equal and at most ``time.dt``, so output times are exact.
Outputs go to ``out_dir`` (see ``mpmflow.output``); ``summary.json`` is written at the end,
also when the run fails or is interrupted. Checkpoints (``mpmflow.checkpoint``) are written
every ``checkpoint.interval``, at the end and when ``stop_signal`` is set (by the CLI's
signal handlers; without ``out_dir`` the run stops without one);
``Simulation.resume(case, out_dir)`` continues from the latest readable one.

The same rules hold however the run was started (command line or Python): the case is
validated again as a whole (a field changed after loading is checked against the others),
its memory estimate must fit the machine, the bodies must not overlap or leave the material
without a free surface, and the output folder is claimed with a lock for the run's life
(``output.folder``): a second run into it is refused, and a folder that holds another run
is not reused unless ``overwrite=True``.
"""

import signal
import time as _time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from . import checkpoint, memory, obstacles, probes
from .fallbacks import Fallbacks
from .materials import stiffness
from ._version import __version__
from .case import resolved, revalidate
from .cells import bin_particles
from .diagnostics import (front_and_height, kinetic_energy, potential_energy, pressure_noise,
                          volume_measures)
from .errors import CaseError, SimulationError, SolverError
from .interrupts import StopNow
from .output.folder import API_HINTS, RunFolder
from .output.snapshots import SnapshotWriter
from .output.summary import write_summary
from .output.timeseries import (COLUMNS, CsvAppender, SeriesBuffer, TimeSeriesWriter,
                                read_table)
from .output.timeseries import units as timeseries_units
from .particles import Particles, subset
from .schemes import make_scheme
from .setup_case import build_grid, build_particles
from .stability import case_stable_time_step, sound_speed, time_step
from .threads import ThreadGovernor, setting_from


@dataclass
class Counters:
    moved_inside: int = 0
    solves: int = 0
    iterations: int = 0
    iterations_since_output: int = 0
    max_iterations: int = 0
    max_unknowns: int = 0
    released: int = 0
    worst_residual: float = 0.0
    viscous_iterations: int = 0


@dataclass
class Outputs:
    timeseries: TimeSeriesWriter | None = None
    probes: CsvAppender | None = None
    snapshots: SnapshotWriter | None = None

    def close(self):
        for w in (self.timeseries, self.probes):
            if w is not None:
                w.close()


class Simulation:
    """A run of ``case`` (from ``mpmflow.load_case``) writing into ``out_dir`` (None: no
    files, results in memory only: ``series``, ``probe_series``, ``particles``).

    ``overwrite``: replace the outputs of an earlier run in ``out_dir`` (otherwise such a
    folder is refused when the run starts). ``progress``: callable(t, step, end) after each
    output time. Raises CaseError (``mpmflow.errors``) for a case that cannot run here:
    cross-field checks, memory, overlapping or too tightly packed bodies, no free surface."""

    def __init__(self, case, out_dir=None, progress=None, overwrite=False):
        case = revalidate(case)
        self.case = case
        setting_from(case.execution.threads)  # a bad MPMFLOW_THREADS is refused here
        self.memory = memory.check(case)
        # the content of the files the case reads, as this run reads them (checkpoints keep
        # it, and a restart with other files is refused)
        self._files = checkpoint.file_hashes(case)
        self.grid = build_grid(case)
        self.particles = build_particles(case, self.grid)
        if self.particles.count == 0:
            raise CaseError("The bodies hold no particles: every body is thinner than one "
                            "particle spacing (grid.spacing / bodies.N.particles_per_cell). "
                            "Enlarge the bodies or raise particles_per_cell.")
        self.scheme = make_scheme(case, self.grid, self.particles)
        self.notices = []
        solids = getattr(self.scheme, "solids", None)
        if solids is not None:
            inside = obstacles.in_solid_cells(solids, self.grid, self.particles.x)
            if inside.all():
                raise CaseError(
                    "Every particle lies in cells the grid takes as solid: the bodies fill "
                    "only the space that obstacles touching the walls close off on this grid. "
                    f"Refine grid.spacing (now {case.grid.spacing:g} m) or move the bodies.")
            if inside.any():
                self.particles = subset(self.particles, ~inside)
                self.scheme.particles = self.particles
                self.notices.append(
                    f"{int(inside.sum())} particle{'s' if inside.sum() > 1 else ''} seeded "
                    "round an obstacle lie in cells the grid takes as solid (where an obstacle touches two or three walls, the "
                    "corner between it and the walls is closed within the first cell) and "
                    "are left out; a finer grid.spacing resolves that corner")
        if hasattr(self.scheme, "check_free_surface"):
            try:
                self.scheme.check_free_surface()
            except SolverError:
                raise CaseError(
                    "The material touches no free surface at the start: the bodies leave too "
                    "little empty space in the domain (under about one grid cell next to the "
                    "material), so the projection scheme's pressure has no level to refer to "
                    "and its system is singular. Leave at least one grid cell of empty space "
                    f"(grid.spacing = {case.grid.spacing:g} m) above the material: lower the "
                    "top of the bodies (bodies.N.max) or enlarge domain.size.") from None
        self.dt = time_step(case)
        self.out_dir = Path(out_dir) if out_dir is not None else None
        self.overwrite = bool(overwrite)
        self.progress = progress
        self.time = 0.0
        self.steps = 0
        self.counters = Counters()
        self.fallbacks = Fallbacks()  # the caps and fallbacks that acted
        try:  # a viscous material too stiff for the time step: refused, or told
            self.notices += stiffness.check(case, self.particles, self.dt)
        except ValueError as err:
            raise CaseError(str(err)) from None
        # what reading the mesh files had to decide (a binary STL's wrong triangle count)
        for shape in ([case.body_shape(k) for k in range(len(case.bodies))]
                      + [case.obstacle_shape(k) for k in range(len(case.obstacles))]):
            self.notices += getattr(shape, "notes", [])
        if self.grid.adjusted(case.domain.size):
            used = " x ".join(f"{s:.6g}" for s in self.grid.size)
            asked = " x ".join(f"{s:.6g}" for s in case.domain.size)
            self.notices.append(
                f"domain {asked} m is not a whole number of {case.grid.spacing:g} m cells; the "
                f"walls are placed on the grid at {used} m")
        self.mass0 = float(self.particles.mass.sum())
        self.volume0 = float(self.particles.volume.sum())
        self.count0 = self.particles.count
        self._outputs = Outputs()
        self._opened = False
        self._folder = None  # the claimed output folder (output.folder.RunFolder)
        self._wall0 = None
        self._wall_before = 0.0  # wall seconds of the runs this one continues
        self._series = SeriesBuffer(COLUMNS)  # the timeseries rows, also kept in memory
        self._probes = SeriesBuffer(probes.columns(case)) if case.probes else None
        self.on_output = None  # optional callable(sim), called after each output row
        # the output schedule: the next output, snapshot and checkpoint are the k-th multiple
        # of their interval
        self.k_out = self.k_snap = self.k_checkpoint = 1
        self._resume_outputs = None  # the positions of the output files in the checkpoint
        self.resumed_from = None  # the checkpoint this run continues, if any
        self.threads = None  # the ThreadGovernor while a run goes
        self.last_checkpoint = None
        self.stop_signal = None  # set (to a signal number) to stop at the next output time
        self.stop_now = None  # set (to a signal number) to stop after the current chunk,
        # without a checkpoint (the CLI's second signal: its StopNow may be lost in a __del__)

    # ------------------------------------------------------------------ checkpoints
    def _checkpoint(self):
        """Write a checkpoint of the current state (after its output row). It holds the
        state, not the history: of the outputs written so far only where each file ends
        (those files are fsynced first, so that what it counts is on the disk)."""
        arrays = {name: getattr(self.particles, name) for name in Particles.FIELDS}
        arrays.update({f"scheme.{k}": v for k, v in self.scheme.state().items()})
        o = self._outputs
        for w in (o.timeseries, o.probes, o.snapshots):
            if w is not None:
                w.sync()
        outputs = {"timeseries": o.timeseries.position(),
                   "probes": o.probes.position() if o.probes is not None else None,
                   "snapshots": len(o.snapshots.entries) if o.snapshots is not None else None}
        meta = {"mpmflow_version": __version__, "case": resolved(self.case),
                "time": self.time, "steps": self.steps, "dt": self.dt,
                "k_out": self.k_out, "k_snap": self.k_snap,
                "k_checkpoint": self.k_checkpoint, "counters": asdict(self.counters),
                "fallbacks": self.fallbacks.rows(),
                "outputs": outputs, "mass0": self.mass0,
                "volume0": self.volume0, "count0": self.count0,
                "wall_seconds": self._wall_seconds(), "files": self._files}
        self.last_checkpoint = checkpoint.write(self.out_dir, self.steps, arrays, meta)

    _META = ("case", "time", "steps", "dt", "k_out", "k_snap", "k_checkpoint", "counters",
             "outputs", "mass0", "volume0", "count0", "wall_seconds")

    @classmethod
    def resume(cls, case, out_dir, path=None, progress=None, hints=API_HINTS):
        """The run of ``out_dir`` continued from a checkpoint: ``path``, or (None) the latest
        readable one, passing over damaged ones with a notice (in ``notices``). Same
        settings except a later time.end (to extend the run) and execution.*; CaseError
        otherwise, ``checkpoint.CheckpointError`` when the file is damaged or lacks an
        entry. The folder is claimed (locked) at once and stays so until the run ends or
        ``close()``."""
        folder = RunFolder.claim(out_dir, "restart", hints)
        try:
            if path is None:
                sim = cls._resume_latest(case, out_dir, progress)
            else:
                sim = cls._resume_from(case, out_dir, path, progress)
        except BaseException:
            folder.release()
            raise
        sim._folder = folder
        sim.notices[:0] = folder.notes
        return sim

    @classmethod
    def _resume_latest(cls, case, out_dir, progress):
        checkpoint.latest(out_dir)  # CaseError when there is none
        damaged = []
        for path in reversed(checkpoint.checkpoints(out_dir)):
            try:
                sim = cls._resume_from(case, out_dir, path, progress)
            except checkpoint.CheckpointError as err:
                damaged.append(err)
                continue
            sim.notices[:0] = [
                f"checkpoint {err.path} cannot be read ({err.why}); it is damaged, e.g. cut "
                f"short by a crash. Continuing from the one before it, {path.name}."
                for err in damaged]
            return sim
        if len(damaged) == 1:
            raise damaged[0]
        raise CaseError(f"--restart: no checkpoint in {out_dir} can be read: "
                        + "; ".join(f"{e.path.name} ({e.why})" for e in damaged)
                        + ". They are damaged, e.g. cut short by a crash. Start the run again "
                        "with --overwrite instead of --restart.")

    @classmethod
    def _resume_from(cls, case, out_dir, path, progress):
        arrays, meta = checkpoint.read(path)
        missing = [f"meta {k}" for k in cls._META if k not in meta]
        missing += [f"array {k}" for k in Particles.FIELDS if k not in arrays]
        if missing:
            raise checkpoint.CheckpointError(path, "it lacks " + ", ".join(missing))
        case = revalidate(case)
        checkpoint.check_same_case(meta["case"], resolved(case), path)
        checkpoint.check_same_files(meta.get("files"), checkpoint.file_hashes(case), path)
        if meta["time"] >= case.time.end:
            raise CaseError(
                f"--restart: checkpoint {path} is at t = {meta['time']:.6g} s, which already "
                f"reaches time.end = {case.time.end:g} s. To extend the run give a later end, "
                f"e.g. --set time.end={2 * case.time.end:g}.")
        sim = cls(case, out_dir, progress)
        P = sim.particles
        for name in Particles.FIELDS:
            saved = arrays[name]
            if saved.shape != getattr(P, name).shape:
                raise CaseError(f"--restart: checkpoint {path} holds {saved.shape[0]} "
                                f"particles, the case {P.count}; it belongs to another case.")
            np.copyto(getattr(P, name), saved)
        try:
            sim.scheme.restore({k.removeprefix("scheme."): v for k, v in arrays.items()
                                if k.startswith("scheme.")})
            sim.counters = Counters(**meta["counters"])
            sim.fallbacks = Fallbacks(meta.get("fallbacks", ()))
        except (KeyError, TypeError, ValueError) as err:
            raise checkpoint.CheckpointError(path, f"its scheme state or counters do not fit: "
                                        f"{type(err).__name__}: {err}") from None
        sim.time, sim.steps, sim.dt = meta["time"], meta["steps"], meta["dt"]
        sim.k_out, sim.k_snap = meta["k_out"], meta["k_snap"]
        sim.k_checkpoint = meta["k_checkpoint"]
        sim._resume_outputs = meta["outputs"]
        sim.mass0, sim.volume0, sim.count0 = meta["mass0"], meta["volume0"], meta["count0"]
        sim._wall_before = meta["wall_seconds"]
        sim.resumed_from = Path(path)
        return sim

    def _wall_seconds(self):
        now = _time.perf_counter() - self._wall0 if self._wall0 else 0.0
        return self._wall_before + now

    def describe(self):
        """The case summary the command line prints before a run (lines of text): what
        runs, how many steps and outputs, and the memory estimate."""
        case, g, est = self.case, self.grid, self.memory
        steps = max(1, round((case.time.end - self.time) / self.dt))
        cells = " x ".join(str(n) for n in g.cells)
        snaps = (f", a snapshot every {case.output.snapshot_interval or case.output.interval:g}"
                 " s" if case.output.snapshots else ", no snapshots")
        title = f"{case.title}: " if case.title else ""
        budget, source = memory.available()
        return [
            f"{title}{case.solver.scheme} scheme, {self.particles.count:,} particles, {cells} "
            f"cells of {g.spacing:g} m; about {steps:,} steps of {self.dt:.3g} s to t = "
            f"{case.time.end:g} s; a row every {case.output.interval:g} s{snaps}"
            + (f", {len(case.probes)} probes" if case.probes else "")
            + f" (about {memory.size(est.disk_bytes)} on disk)",
            f"memory: {est.text()}; the machine can give {memory.size(budget)} ({source})",
        ]

    # ------------------------------------------------------------------ the output folder
    def claim(self, hints=API_HINTS):
        """Lock ``out_dir`` for this run and prepare it (see ``output.folder``); done by
        ``run()`` if not before. CaseError (FolderBusy) when another run holds it, or when
        it holds another run's outputs and ``overwrite`` is not set."""
        if self.out_dir is None or self._folder is not None:
            return
        mode = "restart" if self.resumed_from else "overwrite" if self.overwrite else "new"
        self._folder = RunFolder.claim(self.out_dir, mode, hints)
        self.notices[:0] = self._folder.notes

    def close(self):
        """Close the output files and release the folder's lock (``run()`` does it when it
        ends; needed only for a Simulation that is resumed or claimed and then not run)."""
        self._outputs.close()
        if self._folder is not None:
            self._folder.release()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # ------------------------------------------------------------------ outputs
    def _open_outputs(self):
        if self.out_dir is None or self._opened:
            return
        self._opened = True
        res = self._resume_outputs or {}
        folder = self.out_dir
        self._outputs.timeseries = TimeSeriesWriter(folder / "timeseries.csv",
                                                    res.get("timeseries"))
        if self.case.probes:
            self._outputs.probes = CsvAppender(folder / "probes.csv", probes.columns(self.case),
                                               res.get("probes"), probes.header(self.case))
        if self.case.output.snapshots:
            self._outputs.snapshots = SnapshotWriter(folder, resume=res.get("snapshots"))
        if self._resume_outputs is not None:  # the earlier rows, for series()
            self._series.extend(read_table(folder / "timeseries.csv")[0])
            if self._probes is not None:
                self._probes.extend(read_table(folder / "probes.csv")[0])

    @property
    def rows(self):
        """The timeseries rows so far, as dicts (built on each call; see ``series``)."""
        return self._series.rows()

    def measure(self, bins=None):
        """The diagnostics of one timeseries row at the current state."""
        P, g = self.particles, self.grid
        bins = bins if bins is not None else self._bins()
        front, height = front_and_height(g, bins.theta)
        speed = np.sqrt(np.sum(P.v**2, axis=1))
        return {
            "time": self.time,
            "front": front,
            "height": height,
            "step": self.steps,
            "kinetic_energy": kinetic_energy(P),
            "potential_energy": potential_energy(P, self.case.physics.gravity),
            "max_speed": float(speed.max()),
            "max_pressure": float(P.pressure.max()),
            "pressure_noise": pressure_noise(g, P),
            **volume_measures(bins.theta, g.cell_volume, self.volume0, self._open()),
            "max_particles_per_cell": int(np.diff(bins.start).max()),
            "pressure_unknowns": int(self.scheme.last_unknowns),
            "solver_iterations": int(self.counters.iterations_since_output),
        }

    def _open(self):
        """The cells' fluid fractions when obstacles cut cells (None: no obstacle)."""
        solids = getattr(self.scheme, "solids", None)
        return solids.open if solids is not None and solids.present else None

    def _bins(self):
        """Particles binned by cell, theta over the cells' fluid part."""
        return bin_particles(self.grid, self.particles, open_=self._open())

    def _output(self, snapshot):
        bins = self._bins()
        row = self.measure(bins)
        self._series.append(row)
        self.counters.iterations_since_output = 0
        if self._outputs.timeseries is not None:
            self._outputs.timeseries.append(row)
        if self._probes is not None:
            solids = getattr(self.scheme, "solids", None)
            values = probes.measure(self.case, self.grid, self.particles, bins, self.time,
                                    solids.distance if solids is not None and solids.solids
                                    else None, self.fallbacks)
            self._probes.append(values)
            if self._outputs.probes is not None:
                self._outputs.probes.append(values)
        del bins
        if snapshot and self._outputs.snapshots is not None:
            self._outputs.snapshots.write(self.time, self.particles)
        if self.on_output is not None:
            self.on_output(self)
        return row

    def series(self, name):
        """One timeseries column as an array (see ``output.timeseries.COLUMNS``)."""
        if name not in COLUMNS:
            raise KeyError(f"{name!r} is not a timeseries column; the columns are "
                           + ", ".join(COLUMNS))
        return self._series.column(name)

    def probe_series(self, name):
        """One probe's values at the output times (``series("time")``)."""
        if self._probes is None or name not in self._probes.columns:
            raise KeyError(f"no probe named {name!r}; the case's probes are "
                           + (", ".join(p.name for p in self.case.probes) or "none"))
        return self._probes.column(name)

    # ------------------------------------------------------------------ time loop
    def run(self, wall_budget=None):
        """Run to ``time.end``; returns the summary dict (also written to summary.json).

        ``wall_budget`` (s of wall time): stop at the first output time after it is spent,
        with status "budget" (used by the study for explicit runs at the real K). When
        ``stop_signal`` is set (the CLI's SIGINT/SIGTERM handlers do), the run stops at the
        next output time with a checkpoint and status "interrupted".

        BLAS (NumPy's OpenBLAS) is held to one thread while the run lasts: the compiled
        core uses the cores through its OpenMP threads, and BLAS threads spinning after a
        NumPy call took them away (measured: 2 threads 4.4 times slower than 1 at 416k
        particles; with BLAS on one thread, 1.5 times faster)."""
        try:
            self.claim()
            self.threads = ThreadGovernor(self.case.execution.threads)
            with threadpool_limits(limits=1, user_api="blas"):
                self.threads.start(self.time)
                try:
                    return self._run(wall_budget)
                finally:
                    self.threads.stop()
        finally:
            self.close()

    def _run(self, wall_budget):
        case = self.case
        end = case.time.end
        self._wall0 = _time.perf_counter()
        status, message = "failed", ""
        try:
            self._open_outputs()
            if self.resumed_from is None:
                self._output(snapshot=True)
            while self.time < end:
                self._chunk()
                if self.stop_now is not None:
                    raise StopNow(self.stop_now)
                if self.stop_signal is not None and self.time < end:
                    status = "interrupted"
                    message = (f"interrupted by {signal.Signals(self.stop_signal).name} at "
                               f"t = {self.time:.6g} s (step {self.steps}); ")
                    if self.out_dir is not None:
                        self._checkpoint()
                        message += f"checkpoint {self.last_checkpoint.name} written"
                    else:
                        message += "no checkpoint: no output folder"
                    break
                if (wall_budget is not None and self.time < end
                        and _time.perf_counter() - self._wall0 > wall_budget):
                    status, message = "budget", (f"stopped at t = {self.time:.6g} s when the "
                                                 f"wall budget of {wall_budget:g} s was spent")
                    break
            else:
                status = "completed"
                if self.out_dir is not None:
                    self._checkpoint()  # to extend the run later with a later time.end
        except SimulationError as err:
            message = str(err)
            raise
        except (KeyboardInterrupt, StopNow) as err:
            status, message = "interrupted", (
                f"stopped at once by a second {err.name}, without a checkpoint (the last one "
                "written is kept)" if isinstance(err, StopNow) else
                "stopped at once by KeyboardInterrupt (Ctrl-C), without a checkpoint")
            raise
        except OSError as err:
            message = f"Writing the outputs failed: {err}. Check the --out folder and free space."
            raise SimulationError(message) from None
        except Exception as err:  # a bug: record it, then let the traceback through
            message = f"internal error: {type(err).__name__}: {err}"
            raise
        finally:
            self.summary = self._summary(status, message)
            if self.out_dir is not None and self.out_dir.is_dir():
                try:
                    write_summary(self.out_dir / "summary.json", self.summary)
                except OSError:
                    pass  # the run's own error (often the same one) is the one to report
        return self.summary

    def _chunk(self):
        """The steps up to the next output time, then its output row (and snapshot and
        checkpoint when due). The steps are as few as dt allows and all equal, so no step is
        a sliver of dt (the pressure scales with 1/dt)."""
        case, dt = self.case, self.dt
        end, interval = case.time.end, case.output.interval
        # an interval shorter than the output interval means every output; taken as the
        # output interval, so that time / interval stays finite (a 5e-324 s interval)
        snap_interval = max(case.output.snapshot_interval or interval, interval)
        t_next = min(self.k_out * interval, end)
        n = max(1, int(np.ceil((t_next - self.time) / dt - 1e-6)))
        self._advance((t_next - self.time) / n, n)
        self.time = t_next
        if self.progress is not None:
            self.progress(self.time, self.steps, end)
        # recomputed, not incremented: after an end that is not an output time (0.105 with
        # interval 0.01) the next output of an extended run is 0.11, not 0.12
        self.k_out = int(np.floor(self.time / interval + 1e-9)) + 1
        snap = self.time >= self.k_snap * snap_interval - 1e-9 * dt or self.time >= end
        if snap:
            self.k_snap = int(np.floor(self.time / snap_interval + 1e-9)) + 1
        self._output(snapshot=snap)
        if self.threads is not None:
            self.threads.update(self.time)
        every = max(case.checkpoint.interval, interval)
        if self.time >= self.k_checkpoint * every - 1e-9 * dt:
            self.k_checkpoint = int(np.floor(self.time / every + 1e-9)) + 1
            if self.out_dir is not None and self.time < end:  # the end has its own
                self._checkpoint()

    def _advance(self, dt, n):
        """n steps of size dt, then a check that the particles are finite."""
        first, t0 = self.steps + 1, self.time

        def where(k):
            return f" at step {first + k} (t = {t0 + (k + 1) * dt:.6g} s)"

        span = (f" in steps {first} to {first + n - 1} (t = {t0:.6g} to {t0 + n * dt:.6g} s)"
                if n > 1 else where(0))
        report = self.scheme.advance(dt, n, where=where)
        self.steps += getattr(report, "steps", n)  # time.dt = "auto": the steps it took
        self.time = t0 + n * dt
        c = self.counters
        c.moved_inside += report.moved_inside
        self.fallbacks.count("particles put back inside the domain or out of an obstacle",
                             "domain walls and obstacles", report.moved_inside, self.time)
        self.fallbacks.count("viscosity held at material.max_viscosity",
                             f"material ({self.case.material.model})",
                             getattr(report, "capped", 0), self.time)
        self.fallbacks.count("volume correction displacement clamped at half a cell per step",
                             "solver.volume_correction", getattr(report, "clamped", 0),
                             self.time)
        self.fallbacks.count("water sealed from the free surface held at p = 0 at its top",
                             "pressure system", getattr(report, "pockets", 0), self.time)
        c.solves += report.solves
        c.iterations += report.iterations
        c.iterations_since_output += report.iterations
        c.max_iterations = max(c.max_iterations, report.max_iterations)
        c.max_unknowns = max(c.max_unknowns, report.unknowns)
        c.released += report.released
        c.worst_residual = max(c.worst_residual, report.residual)
        c.viscous_iterations += getattr(report, "viscous_iterations", 0)
        P = self.particles
        if not (np.isfinite(P.v).all() and np.isfinite(P.x).all()):
            bad = np.flatnonzero(~np.isfinite(P.v).all(axis=1) | ~np.isfinite(P.x).all(axis=1))
            raise SimulationError(
                f"The run blew up{span}: {bad.size} particles have non-finite velocity or "
                f"position (first: particle {bad[0]}). The outputs up to t = {t0:.6g} s are "
                "kept. Try a smaller time.dt.")
        with np.errstate(over="ignore"):  # a speed beyond 1e154 m/s is inf: still caught
            speed = np.sqrt(np.sum(P.v**2, axis=1))
        fastest = int(np.argmax(speed))
        limit = self.case.solver.max_speed
        if not speed[fastest] <= limit:
            xy = ", ".join(f"{c:.4g}" for c in P.x[fastest])
            raise SimulationError(
                f"The run blew up{span}: particle {fastest} at ({xy}) m moves at "
                f"{speed[fastest]:.4g} m/s, above solver.max_speed = {limit:g} m/s. The outputs "
                f"up to t = {t0:.6g} s are kept. Try a smaller time.dt, or raise "
                "solver.max_speed if such speeds are real.")

    def _explicit_summary(self):
        if self.case.solver.scheme != "explicit":
            return {}
        m = self.case.material
        return {"sound_speed": sound_speed(m.bulk_modulus, m.density),
                "stable_time_step": case_stable_time_step(self.case)}

    def _adaptive_summary(self):
        """time.dt = "auto" with the projection scheme: the steps' range."""
        scheme = self.scheme
        if not getattr(scheme, "auto", False) or not hasattr(scheme, "dt_range"):
            return {}
        shortest, longest = scheme.dt_range
        return {"adaptive_steps": {"courant": self.case.time.courant,
                                   "max_dt": self.case.time.max_dt,
                                   "shortest": shortest if np.isfinite(shortest) else None,
                                   "longest": longest or None}}

    def _summary(self, status, message):
        P, c = self.particles, self.counters
        wall = self._wall_seconds()
        bins = self._bins()
        mass = float(P.mass.sum())
        return {
            "status": status,
            "message": message,
            "mpmflow_version": __version__,
            "time": self.time,
            "steps": self.steps,
            "particles": P.count,
            "particles_lost": self.count0 - P.count,
            "particles_moved_inside": c.moved_inside,
            "mass_initial": self.mass0,
            "mass_final": mass,
            "mass_relative_change": (mass - self.mass0) / self.mass0,
            "max_particles_per_cell": int(np.diff(bins.start).max()),
            "wall_seconds": wall,
            "restarted_from": self.resumed_from.name if self.resumed_from else None,
            "last_checkpoint": self.last_checkpoint.name if self.last_checkpoint else None,
            "scheme": self.case.solver.scheme,
            "dt": self.dt,
            **self._explicit_summary(),
            **self._adaptive_summary(),
            "grid": {"spacing": self.grid.spacing, "cells": list(self.grid.cells),
                     "domain_used": [float(s) for s in self.grid.size]},
            "pressure_solver": {"solves": c.solves, "iterations": c.iterations,
                                "max_iterations_per_step": c.max_iterations,
                                "max_unknowns": c.max_unknowns,
                                "worst_relative_residual": c.worst_residual,
                                "wall_nodes_released": c.released},
            "viscous_solver": ({"iterations": c.viscous_iterations,
                                "model": self.case.material.model}
                               if self.case.material.model != "water" else None),
            "notices": self.notices,
            "caps_and_fallbacks": self.fallbacks.rows(),
            "threads": self.threads.record() if self.threads is not None else None,
            "memory_estimate_bytes": self.memory.as_dict(),
            "probes": {p.name: {"quantity": p.quantity, "position": p.position,
                                "unit": probes.UNITS[p.quantity],
                                **({"window": probes.window(p, self.grid, self.case),
                                    "estimate": p.estimate}
                                   if p.quantity == "pressure" else {})}
                       for p in self.case.probes},
            "units": dict(timeseries_units(self.grid.dim),
                          mass="kg/m" if self.grid.dim == 2 else "kg", wall_seconds="s", domain_used="m", spacing="m",
                          dt="s", sound_speed="m/s", stable_time_step="s",
                          memory_estimate_bytes="B"),
            "case": resolved(self.case),
        }
