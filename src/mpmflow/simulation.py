"""A run: the time loop, its output schedule, and the run's bookkeeping.

``Simulation(case, out_dir).run()`` steps the scheme from t = 0 to ``time.end``; the steps
between two output times are equal and at most ``time.dt``, so output times are exact.
Outputs go to ``out_dir`` (see ``mpmflow.output``); ``summary.json`` is written at the end,
also when the run fails or is interrupted. Checkpoints (``mpmflow.checkpoint``) are written
every ``checkpoint.interval``, at the end and when ``stop_signal`` is set (by the CLI's
signal handlers; without ``out_dir`` the run stops without one);
``Simulation.resume(case, out_dir, path)`` continues from one.
"""

import signal
import time as _time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from . import checkpoint
from ._version import __version__
from .case import resolved
from .cells import bin_particles
from .diagnostics import (front_and_height, kinetic_energy, potential_energy, pressure_noise,
                          volume_measures)
from .errors import CaseError, SimulationError
from .interrupts import StopNow
from .output.snapshots import SnapshotWriter
from .output.summary import write_summary
from .output.timeseries import COLUMNS, TimeSeriesWriter
from .particles import Particles
from .schemes import make_scheme
from .setup_case import build_grid, build_particles
from .stability import case_stable_time_step, sound_speed, time_step


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


@dataclass
class Outputs:
    timeseries: TimeSeriesWriter | None = None
    snapshots: SnapshotWriter | None = None


class Simulation:
    def __init__(self, case, out_dir=None, progress=None):
        self.case = case
        self.grid = build_grid(case)
        self.particles = build_particles(case, self.grid)
        if self.particles.count == 0:
            raise CaseError("The bodies hold no particles: every box is thinner than one particle "
                            "spacing (grid.spacing / bodies.N.particles_per_cell). Enlarge the "
                            "boxes or raise particles_per_cell.")
        self.scheme = make_scheme(case, self.grid, self.particles)
        self.dt = time_step(case)
        self.out_dir = Path(out_dir) if out_dir is not None else None
        self.progress = progress
        self.time = 0.0
        self.steps = 0
        self.counters = Counters()
        self.notices = []
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
        self._wall0 = None
        self._wall_before = 0.0  # wall seconds of the runs this one continues
        self.rows = []  # the timeseries rows, also kept in memory
        self.on_output = None  # optional callable(sim), called after each output row
        # the output schedule: the next output, snapshot and checkpoint are the k-th multiple
        # of their interval
        self.k_out = self.k_snap = self.k_checkpoint = 1
        self.snapshot_entries = []  # (time, file) of the snapshots of a continued run
        self.resumed_from = None  # the checkpoint this run continues, if any
        self.last_checkpoint = None
        self.stop_signal = None  # set (to a signal number) to stop at the next output time
        self.stop_now = None  # set (to a signal number) to stop after the current chunk,
        # without a checkpoint (the CLI's second signal: its StopNow may be lost in a __del__)

    # ------------------------------------------------------------------ checkpoints
    def _checkpoint(self):
        """Write a checkpoint of the current state (after its output row)."""
        arrays = {name: getattr(self.particles, name) for name in Particles.FIELDS}
        arrays.update({f"scheme.{k}": v for k, v in self.scheme.state().items()})
        snaps = self._outputs.snapshots.entries if self._outputs.snapshots is not None else []
        meta = {"mpmflow_version": __version__, "case": resolved(self.case),
                "time": self.time, "steps": self.steps, "dt": self.dt,
                "k_out": self.k_out, "k_snap": self.k_snap,
                "k_checkpoint": self.k_checkpoint, "counters": asdict(self.counters),
                "rows": self.rows, "snapshots": snaps, "mass0": self.mass0,
                "volume0": self.volume0, "count0": self.count0,
                "wall_seconds": self._wall_seconds()}
        self.last_checkpoint = checkpoint.write(self.out_dir, self.steps, arrays, meta)

    _META = ("case", "time", "steps", "dt", "k_out", "k_snap", "k_checkpoint", "counters",
             "rows", "snapshots", "mass0", "volume0", "count0", "wall_seconds")

    @classmethod
    def resume(cls, case, out_dir, path, progress=None):
        """The run of ``out_dir`` continued from checkpoint ``path``: same settings except
        possibly a later time.end (CaseError otherwise; ``checkpoint.CheckpointError`` when
        the file is damaged or lacks an entry)."""
        arrays, meta = checkpoint.read(path)
        missing = [f"meta {k}" for k in cls._META if k not in meta]
        missing += [f"array {k}" for k in Particles.FIELDS if k not in arrays]
        if missing:
            raise checkpoint.CheckpointError(path, "it lacks " + ", ".join(missing))
        checkpoint.check_same_case(meta["case"], resolved(case), path)
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
        except (KeyError, TypeError, ValueError) as err:
            raise checkpoint.CheckpointError(path, f"its scheme state or counters do not fit: "
                                        f"{type(err).__name__}: {err}") from None
        sim.time, sim.steps, sim.dt = meta["time"], meta["steps"], meta["dt"]
        sim.k_out, sim.k_snap = meta["k_out"], meta["k_snap"]
        sim.k_checkpoint = meta["k_checkpoint"]
        sim.rows = meta["rows"]
        sim.snapshot_entries = meta["snapshots"]
        sim.mass0, sim.volume0, sim.count0 = meta["mass0"], meta["volume0"], meta["count0"]
        sim._wall_before = meta["wall_seconds"]
        sim.resumed_from = Path(path)
        return sim

    def _wall_seconds(self):
        now = _time.perf_counter() - self._wall0 if self._wall0 else 0.0
        return self._wall_before + now

    # ------------------------------------------------------------------ outputs
    def _open_outputs(self):
        if self.out_dir is None:
            return
        self.out_dir.mkdir(parents=True, exist_ok=True)
        self._outputs.timeseries = TimeSeriesWriter(self.out_dir / "timeseries.csv", self.rows)
        if self.case.output.snapshots:
            self._outputs.snapshots = SnapshotWriter(self.out_dir,
                                                     entries=self.snapshot_entries)

    def measure(self):
        """The diagnostics of one timeseries row at the current state."""
        P, g = self.particles, self.grid
        bins = bin_particles(g, P)
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
            **volume_measures(bins.theta, g.cell_volume, self.volume0),
            "max_particles_per_cell": int(np.diff(bins.start).max()),
            "pressure_unknowns": int(self.scheme.last_unknowns),
            "solver_iterations": int(self.counters.iterations_since_output),
        }

    def _output(self, snapshot):
        row = self.measure()
        self.rows.append(row)
        self.counters.iterations_since_output = 0
        if self._outputs.timeseries is not None:
            self._outputs.timeseries.append(row)
        if snapshot and self._outputs.snapshots is not None:
            self._outputs.snapshots.write(self.time, self.particles)
        if self.on_output is not None:
            self.on_output(self)
        return row

    def series(self, name):
        """One timeseries column as an array (see ``output.timeseries.COLUMNS``)."""
        return np.array([row[name] for row in self.rows], dtype=float)

    # ------------------------------------------------------------------ time loop
    def run(self, wall_budget=None):
        """Run to ``time.end``; returns the summary dict (also written to summary.json).

        ``wall_budget`` (s of wall time): stop at the first output time after it is spent,
        with status "budget" (used by the study for explicit runs at the real K). When
        ``stop_signal`` is set (the CLI's SIGINT/SIGTERM handlers do), the run stops at the
        next output time with a checkpoint and status "interrupted".

        BLAS (NumPy's OpenBLAS) is held to one thread while the run lasts: the compiled
        kernels use the cores through Numba's threads, and BLAS threads spinning after a
        NumPy call took them away (measured: 2 threads 4.4 times slower than 1 at 416k
        particles; with BLAS on one thread, 1.5 times faster)."""
        with threadpool_limits(limits=1, user_api="blas"):
            return self._run(wall_budget)

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
        snap_interval = case.output.snapshot_interval or interval
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
        every = case.checkpoint.interval
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
        c.solves += report.solves
        c.iterations += report.iterations
        c.iterations_since_output += report.iterations
        c.max_iterations = max(c.max_iterations, report.max_iterations)
        c.max_unknowns = max(c.max_unknowns, report.unknowns)
        c.released += report.released
        c.worst_residual = max(c.worst_residual, report.residual)
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

    def _summary(self, status, message):
        P, c = self.particles, self.counters
        wall = self._wall_seconds()
        bins = bin_particles(self.grid, P)
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
            "grid": {"spacing": self.grid.spacing, "cells": list(self.grid.cells),
                     "domain_used": [float(s) for s in self.grid.size]},
            "pressure_solver": {"solves": c.solves, "iterations": c.iterations,
                                "max_iterations_per_step": c.max_iterations,
                                "max_unknowns": c.max_unknowns,
                                "worst_relative_residual": c.worst_residual,
                                "wall_nodes_released": c.released},
            "notices": self.notices,
            "units": dict(COLUMNS, mass="kg/m", wall_seconds="s", domain_used="m", spacing="m",
                          dt="s", sound_speed="m/s", stable_time_step="s"),
            "case": resolved(self.case),
        }
