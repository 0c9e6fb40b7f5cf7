"""When a writer or a callback acts: schedules, each owning its "is it time" arithmetic.

The loop hands the core a chunk of steps at a time: from one output time (a multiple of
``output.interval``) to the next, or to ``time.end``. After each chunk it asks, writer by
writer and callback by callback, whether its schedule is ``due``; a due schedule is
``fired`` (moved on to its next moment) and then its writer or callback acts. So a
schedule acts at the first chunk end at or after each of its moments: a ``TimeInterval``
of 0.05 s with rows every 0.01 s acts at 0.05, 0.1, ...; one of 0.015 s at 0.02, 0.03,
0.05, 0.06, ... (each the first output time at or after a multiple), and one shorter than
``output.interval`` at every output time.

A schedule may be shared by several writers and callbacks: once fired it stays due for the
rest of that moment (the same step count), so all of them act. ``state()`` is what a
checkpoint keeps of it and ``restore()`` puts back, so that a restarted run acts at the
same moments as the uninterrupted one.
"""

import math
from typing import Any, Protocol

# a moment counts as reached within this share of a time step below it, and the next
# multiple is found from the time plus this share of one interval: the rounding of a time
# summed from steps (0.1 + 0.2 = 0.30000000000000004) neither skips a moment nor repeats one
MARGIN = 1e-9


class Clock(Protocol):
    """What a schedule reads of the running Simulation."""

    time: float  # s, simulated
    steps: int  # steps taken
    dt: float  # s, the time step

    def run_seconds(self) -> float:
        """Wall time (s) since this run() started."""
        ...


class Schedule:
    """The interface: ``due(sim)``, ``fired(sim)``, ``state()`` and ``restore(state)``;
    ``sim`` is the running Simulation (a ``Clock``)."""

    _at: int | None = None  # the step count at which it last fired

    def due(self, sim: Clock) -> bool:
        return self._at == sim.steps or self._reached(sim)

    def fired(self, sim: Clock) -> None:
        self._at = sim.steps
        self._advance(sim)

    def _reached(self, sim: Clock) -> bool:
        raise NotImplementedError

    def _advance(self, sim: Clock) -> None:
        raise NotImplementedError

    def state(self) -> dict[str, Any]:
        return {}

    def restore(self, state: dict[str, Any]) -> None:
        pass


class TimeInterval(Schedule):
    """Every ``interval`` seconds of simulated time (at the first chunk end at or after
    each multiple)."""

    def __init__(self, interval: float) -> None:
        if not (isinstance(interval, (int, float)) and math.isfinite(interval) and interval > 0):
            raise ValueError(
                f"TimeInterval: the interval must be a positive number of seconds, not {interval!r}"
            )
        self.interval = float(interval)
        self.k = 1  # the next moment is the k-th multiple

    def next_time(self) -> float:
        return self.k * self.interval

    def _reached(self, sim: Clock) -> bool:
        return sim.time >= self.k * self.interval - MARGIN * sim.dt

    def _advance(self, sim: Clock) -> None:
        # recomputed from the time, not incremented: after an end that is not a multiple
        # (0.105 with 0.01) the next moment of an extended run is 0.11, not 0.12
        self.k = math.floor(sim.time / self.interval + MARGIN) + 1

    def state(self) -> dict[str, Any]:
        return {"k": self.k}

    def restore(self, state: dict[str, Any]) -> None:
        self.k = int(state["k"])

    def __repr__(self) -> str:
        return f"TimeInterval({self.interval:g})"


class IterationInterval(Schedule):
    """Every ``n`` steps (at the first chunk end at or after each multiple);
    ``IterationInterval(1)``: after every chunk."""

    def __init__(self, n: int) -> None:
        if not (isinstance(n, int) and n >= 1):
            raise ValueError(f"IterationInterval: n must be a whole number >= 1, not {n!r}")
        self.n = n
        self.k = 1

    def _reached(self, sim: Clock) -> bool:
        return sim.steps >= self.k * self.n

    def _advance(self, sim: Clock) -> None:
        self.k = sim.steps // self.n + 1

    def state(self) -> dict[str, Any]:
        return {"k": self.k}

    def restore(self, state: dict[str, Any]) -> None:
        self.k = int(state["k"])

    def __repr__(self) -> str:
        return f"IterationInterval({self.n})"


class WallTimeInterval(Schedule):
    """Every ``seconds`` of wall time, counted from the start of ``run()`` (a restarted
    run counts from its own start: wall time is not carried over)."""

    def __init__(self, seconds: float) -> None:
        if not (isinstance(seconds, (int, float)) and seconds > 0):
            raise ValueError(f"WallTimeInterval: seconds must be positive, not {seconds!r}")
        self.seconds = float(seconds)
        self.k = 1

    def _reached(self, sim: Clock) -> bool:
        return sim.run_seconds() > self.k * self.seconds

    def _advance(self, sim: Clock) -> None:
        self.k = math.floor(sim.run_seconds() / self.seconds) + 1

    def __repr__(self) -> str:
        return f"WallTimeInterval({self.seconds:g})"
