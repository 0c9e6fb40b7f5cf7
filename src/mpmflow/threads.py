"""How many threads the compiled kernels use: so that a busy machine degrades gracefully.

A parallel region of the kernels ends when its slowest thread ends. With a thread per core
and another program busy on one of the cores, every region waits for the thread that shares
its core with that program: a run beside one busy process took 2.6 times as long on two
threads as alone, while one thread would have lost nothing. So with ``execution.threads =
"auto"`` (the default) a run uses the cores that other programs leave idle:

- at the start, the cores it may use (its CPU affinity and the cgroup's CPU quota, at most
  the core's thread pool, ``OMP_NUM_THREADS``) less the programs running at that moment
  (``procs_running`` of /proc/stat, the least of three looks 1 ms apart);
- then at output times, at most once a second of wall time, the cores less the CPU time
  other programs used since the last look, in cores (/proc/stat's busy time on this run's
  CPUs less this process's own CPU time); a core counts as free when at least 3/4 of it
  was idle.

A number (``execution.threads = 2``, or the environment variable MPMFLOW_THREADS when the
setting is "auto") fixes the threads for the whole run. Results are the same on any number
of threads (the parallel kernels sum in a fixed order), so the choice changes only the
speed. Where /proc/stat does not exist (macOS), "auto" uses the one-minute load average
instead: slower to follow a change. The choices are recorded in summary.json
(``threads``).
"""

import math
import os
import time
from collections.abc import Iterable
from pathlib import Path
from typing import Literal

from .errors import CaseError

ENV = "MPMFLOW_THREADS"
INTERVAL = 1.0  # s of wall time between two looks
FREE = 0.75  # the share of a core that must be idle for it to count as free

try:
    _TICK = os.sysconf("SC_CLK_TCK")
except (ValueError, OSError, AttributeError):  # pragma: no cover
    _TICK = 100


def pool_size() -> int:
    """The most threads the core's parallel loops may use (OMP_NUM_THREADS, default: the
    cores), as it was when mpmflow was imported."""
    from . import state

    return state.POOL


def usable_cpus() -> list[int]:
    """The CPUs this process may run on (affinity), as a sorted list of CPU numbers."""
    try:
        return sorted(os.sched_getaffinity(0))
    except AttributeError:  # macOS
        return list(range(os.cpu_count() or 1))


def cpu_quota() -> float:
    """The cgroup's CPU quota in cores (cpu.max), or inf."""
    try:
        quota, period = Path("/sys/fs/cgroup/cpu.max").read_text().split()[:2]
        if quota != "max":
            return max(1.0, int(quota) / int(period))
    except (OSError, ValueError):
        pass
    return math.inf


# ("auto", None) or ("fixed", n)
Setting = tuple[Literal["auto", "fixed"], int | None]


def setting_from(value: int | Literal["auto"]) -> Setting:
    """("auto", None) or ("fixed", n) for the case's execution.threads, with MPMFLOW_THREADS
    taking the place of "auto"; CaseError for a bad value or more threads than the core's
    pool."""
    source = "execution.threads"
    if value == "auto":
        env = os.environ.get(ENV, "").strip()
        if env and env != "auto":
            source = f"the environment variable {ENV}"
            try:
                number: int | None = int(env)
            except ValueError:
                number = None
            if number is None or number < 1:
                raise CaseError(
                    f"{ENV} = {env!r} is not a number of threads; give a whole "
                    'number of at least 1, or "auto", or unset it.'
                )
            value = number
    if value == "auto":
        return "auto", None
    pool = pool_size()
    if value > pool:
        raise CaseError(
            f"{source} = {value} is more threads than the core runs here ({pool}: "
            "OMP_NUM_THREADS, or the number of cores); give at most "
            f'{pool}, or "auto".'
        )
    return "fixed", int(value)


class CpuMeter:
    """CPU time used by other programs on this run's CPUs, between two looks."""

    def __init__(self, cpus: Iterable[int]) -> None:
        self.names = {f"cpu{c}" for c in cpus}
        self.last = self._look()

    def _look(self) -> tuple[float, float, float] | None:
        busy = 0
        try:
            with open("/proc/stat") as f:
                for line in f:
                    if not line.startswith("cpu"):
                        break
                    parts = line.split()
                    if parts[0] in self.names:
                        v = [int(x) for x in parts[1:9]]
                        busy += v[0] + v[1] + v[2] + v[5] + v[6] + v[7]
        except (OSError, ValueError, IndexError):
            return None
        t = os.times()
        return time.monotonic(), busy / _TICK, t.user + t.system

    def others(self) -> tuple[float | None, float]:
        """(cores used by other programs since the last look, seconds since it)."""
        now = self._look()
        if now is None or self.last is None:
            return None, 0.0
        (w0, b0, o0), (w1, b1, o1) = self.last, now
        self.last = now
        wall = w1 - w0
        if wall <= 0:
            return None, 0.0
        return max(0.0, ((b1 - b0) - (o1 - o0)) / wall), wall


def _own_running() -> int:
    """This process's threads that are running or runnable now (OpenMP's workers spin for a
    while after a parallel region)."""
    n = 0
    for task in Path("/proc/self/task").iterdir():
        try:
            stat = (task / "stat").read_text()
        except OSError:
            continue
        if stat[stat.rindex(")") + 2 :].startswith("R"):
            n += 1
    return n


def running_now() -> int | None:
    """Other programs' runnable threads now: the least of three looks at procs_running of
    /proc/stat, 1 ms apart, less this process's running threads; None where it cannot be
    read."""
    counts = []
    for k in range(3):
        try:
            for line in Path("/proc/stat").read_text().splitlines():
                if line.startswith("procs_running"):
                    counts.append(int(line.split()[1]) - _own_running())
        except (OSError, ValueError, IndexError):
            return None
        if k < 2:
            time.sleep(0.001)
    return max(0, min(counts)) if counts else None


class ThreadGovernor:
    """Sets the core's threads for a run: ``start()``, ``update(t)`` at output times, ``stop()``."""

    def __init__(self, setting: int | Literal["auto"]) -> None:
        self.mode, self.fixed = setting_from(setting)
        self.cpus = usable_cpus()
        self.cores = max(1, int(min(len(self.cpus), cpu_quota())))
        self.limit = min(pool_size(), self.cores)
        self.meter: CpuMeter | None = None
        self.threads: int | None = None
        # (simulated time, threads, cores used by others)
        self.changes: list[tuple[float, int, float | None]] = []
        self._previous: int | None = None

    def take(self, n: float, t: float, others: float | None) -> None:
        """Run on n threads from simulated time t (at least one, at most the limit;
        ``others``: the cores other programs kept busy, for the record)."""
        from . import state

        n = max(1, min(int(n), self.limit if self.mode == "auto" else pool_size()))
        if n != self.threads:
            state.set_threads(n)
            self.threads = n
            self.changes.append((t, n, None if others is None else round(others, 2)))

    def choose(self, others: float) -> int:
        """The threads to take when other programs keep ``others`` cores busy: a core
        counts as free when FREE of it is idle."""
        return math.floor(self.cores - others + (1 - FREE))

    def start(self, t: float = 0.0) -> None:
        from . import state

        self._previous = state.max_threads()
        if self.mode == "fixed":
            assert self.fixed is not None  # setting_from gives a number with "fixed"
            self.take(self.fixed, t, None)
            return
        self.meter = CpuMeter(self.cpus)
        others: float | None = None
        if self.meter.last is not None and len(self.cpus) == (os.cpu_count() or 0):
            others = running_now()
        if others is None and self.meter.last is None and hasattr(os, "getloadavg"):
            others = os.getloadavg()[0]
        self.take(self.choose(others or 0.0), t, others)
        self._next = time.monotonic() + INTERVAL

    def update(self, t: float) -> None:
        """At an output time: look again, at most once per INTERVAL of wall time."""
        if self.mode == "fixed" or time.monotonic() < self._next:
            return
        self._next = time.monotonic() + INTERVAL
        assert self.meter is not None and self.threads is not None  # set by start()
        others: float | None
        if self.meter.last is not None:
            others, _ = self.meter.others()
        elif hasattr(os, "getloadavg"):
            others = max(0.0, os.getloadavg()[0] - self.threads)
        else:
            others = None
        if others is not None:
            self.take(self.choose(others), t, others)

    def stop(self) -> None:
        """Give the core back the threads it had before the run."""
        from . import state

        if self._previous is not None:
            state.set_threads(self._previous)
            self._previous = None

    def record(self) -> dict[str, object]:
        """For summary.json."""
        return {
            "setting": self.mode if self.mode == "auto" else self.fixed,
            "cores": self.cores,
            "pool": pool_size(),
            "changes": [
                {"time": t, "threads": n, "others_busy_cores": o} for t, n, o in self.changes
            ],
        }
