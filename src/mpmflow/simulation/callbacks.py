"""Callbacks: what the loop does after a chunk of steps besides writing outputs.

A callback is a function of the running Simulation on a schedule (``schedules``). The
built-in ones, in the order they act:

- ``blow_up_guard``: every chunk, the particles must be finite and no faster than
  ``solver.max_speed``; SimulationError otherwise (the outputs so far are kept);
- ``drained``: every chunk, when no particle is left (all through the outlets), the run
  stops, "completed", with a notice;
- ``progress``: every chunk, ``sim.progress(t, step, end)`` when set (the CLI's bar);
- (the writers, ``writers``), then ``on_output``: at the output times, ``sim.on_output(sim)``
  when set;
- ``govern_threads``: every chunk, the thread governor's look at the machine
  (``threads.ThreadGovernor.update``, at most once a second of wall time);
- the callbacks added with ``Simulation.add_callback``, in the order they were added;
- (the checkpointer), then ``stop_on_signal``: every chunk, a second SIGINT/SIGTERM
  (``sim.stop_now``) stops at once, a first one (``sim.stop_signal``) with a checkpoint;
- ``wall_budget``: ``run(wall_budget=s)``'s limit, on a ``WallTimeInterval(s)``.

A callback ends the run with ``sim.stop(message)``: the writers and callbacks due at that
moment still act (so that the checkpoint written then holds every schedule's phase), then
the run ends, and the summary's status is "stopped" (or the status given) with the
message.
"""

from __future__ import annotations

import signal
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from ..diagnostics import parts
from ..errors import CaseError, SimulationError
from ..interrupts import StopNow
from . import energy
from .schedules import Schedule

if TYPE_CHECKING:
    from .loop import Simulation


@dataclass
class Action:
    """A writer or callback on its schedule. ``at_start``: also at t = 0 of a new run
    (writers: the initial state); ``at_end``: also at time.end whatever the schedule."""

    name: str
    func: Callable[[Simulation], None]
    schedule: Schedule
    at_start: bool = False
    at_end: bool = False
    writer: bool = False
    builtin: bool = field(default=False, repr=False)

    def due(self, sim: Simulation, end: float) -> bool:
        return self.schedule.due(sim) or (self.at_end and sim.time >= end)


@dataclass
class Stop:
    """A stop asked for (``Simulation.stop``): the summary's message and status, and
    whether a checkpoint of that state is written."""

    message: str
    status: str
    checkpoint: bool


def blow_up_guard(sim: Simulation) -> None:
    """SimulationError when a particle's velocity or position is not finite, or a particle
    is faster than solver.max_speed, after the last chunk (``sim.last_chunk``). The message
    names the settings that likely caused it (``energy.advice``) and how far KE + PE had
    risen by the last output (``energy.so_far``). No particle left (all through the
    outlets): nothing to check."""
    assert sim.last_chunk is not None  # the guard acts after a chunk
    first, n, t0, dt = sim.last_chunk
    span = (
        f" in steps {first} to {first + n - 1} (t = {t0:.6g} to {t0 + n * dt:.6g} s)"
        if n > 1
        else f" at step {first} (t = {t0 + dt:.6g} s)"
    )
    if sim.particle_count() == 0:
        return
    t = sim.totals()
    if t.nonfinite:
        raise SimulationError(
            f"The run blew up{span}: {t.nonfinite} particles have non-finite velocity or "
            f"position (first: particle {t.first_nonfinite}). The outputs up to t = "
            f"{t0:.6g} s are kept.{energy.so_far(sim)} {energy.advice(sim)}"
        )
    # (a speed beyond 1e154 m/s squares to inf, and is still caught)
    fastest = t.fastest
    limit = sim.case.solver.max_speed
    if not t.max_speed <= limit:
        where = parts.position(sim.comm, sim.ids, sim.particles.x, fastest)
        xy = ", ".join(f"{c:.4g}" for c in where)
        raise SimulationError(
            f"The run blew up{span}: particle {fastest} at ({xy}) m moves at "
            f"{t.max_speed:.4g} m/s, above solver.max_speed = {limit:g} m/s. The outputs "
            f"up to t = {t0:.6g} s are kept.{energy.so_far(sim)} {energy.advice(sim)} Raise "
            "solver.max_speed only if such speeds are real."
        )


def drained(sim: Simulation) -> None:
    """Every particle has left through the outlets: the run ends here, completed, with a
    notice (nothing is left to step; no checkpoint: nothing to continue)."""
    if sim.particle_count() == 0 and sim.stopping is None:
        message = (
            f"every particle left through the outlets by t = {sim.time:.6g} s (step "
            f"{sim.steps}): the run ends there"
        )
        sim.notices.append(message)
        sim.stop(message, status="completed", checkpoint=False)


def progress(sim: Simulation) -> None:
    if sim.progress is not None:
        sim.progress(sim.time, sim.steps, sim.case.time.end)


def on_output(sim: Simulation) -> None:
    if sim.on_output is not None:
        sim.on_output(sim)


def govern_threads(sim: Simulation) -> None:
    if sim.threads is not None:
        sim.threads.update(sim.time)


def stop_on_signal(sim: Simulation) -> None:
    """The CLI's signal handlers (``interrupts.stop_on_signals``) only set ``stop_signal``
    (and ``stop_now``); the run stops here, between chunks."""
    if sim.stop_now is not None:  # its StopNow may have been lost in a __del__
        raise StopNow(sim.stop_now)
    if sim.stop_signal is None or sim.time >= sim.case.time.end or sim.stopping is not None:
        return
    message = (
        f"interrupted by {signal.Signals(sim.stop_signal).name} at "
        f"t = {sim.time:.6g} s (step {sim.steps}); "
    )
    if sim.checkpoint_dir is not None:  # over ranks: on every rank, each writes its piece
        path = sim.checkpoint()
        message += f"checkpoint {path.name} written"
    else:
        message += "no checkpoint: no output folder"
    sim.stop(message, status="interrupted", checkpoint=False)


def refuse_budget_over_ranks(scheme: object) -> None:
    """``run(wall_budget=...)`` on several MPI ranks: each rank would read its own clock and
    stop at its own output time, leaving the others waiting in the next exchange."""
    if getattr(getattr(scheme, "comm", None), "size", 1) > 1:
        raise CaseError(
            "run(wall_budget=...) is not agreed between MPI ranks yet: run without a wall "
            "budget on several ranks (Ctrl-C or SIGTERM stops every rank at the same output "
            "time), or on one process."
        )


def wall_budget(budget: float) -> Callable[[Simulation], None]:
    """``run(wall_budget=budget)``: stop at the first chunk end after it is spent."""

    def stop_when_spent(sim: Simulation) -> None:
        if sim.time < sim.case.time.end:
            sim.stop(
                f"stopped at t = {sim.time:.6g} s when the wall budget of {budget:g} s was spent",
                status="budget",
                checkpoint=False,
            )

    return stop_when_spent
