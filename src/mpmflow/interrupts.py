"""Ctrl-C (SIGINT) and SIGTERM during a run: stop cleanly at the next output time.

The first signal asks the run to stop (``Simulation.stop_signal``): it finishes the steps up
to the next output time, writes that output and a checkpoint, and returns with status
"interrupted". A second signal stops at once (``StopNow``, carrying the signal number),
without a new checkpoint; the last one written is kept. These handlers are installed only
while ``mpmflow run`` runs its time loop; outside it (``EarlySignals``, from the start of
the command) a signal stops at once with a message.
"""

from __future__ import annotations

import os
import signal
import sys
from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager
from types import FrameType
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .simulation import Simulation

# a signal handler, as signal.signal takes it
Handler = Callable[[int, FrameType | None], None]

SIGNALS = (signal.SIGINT, signal.SIGTERM)


class _Signalled(BaseException):
    """A signal that stops the command, with its number. A BaseException (like
    KeyboardInterrupt) so that no ``except Exception`` on the way takes it for an error."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = int(signum)

    @property
    def name(self) -> str:
        return signal.Signals(self.signum).name


class StopNow(_Signalled):
    """A second SIGINT/SIGTERM: stop at once."""


def exit_code(signum: int) -> int:
    """The shell's convention: 128 + signal number (130 for SIGINT, 143 for SIGTERM)."""
    return 128 + int(signum)


def _say(text: str) -> None:
    """Write to stderr from a signal handler. os.write, not print: the handler can run in
    the middle of a write to sys.stderr (the progress bar's), and a second write to the
    same buffered stream then raises RuntimeError (reentrant call)."""
    try:
        os.write(2, text.encode())
    except OSError:
        pass  # no stderr to tell: stopping matters more


@contextmanager
def stop_on_signals(sim: Simulation) -> Iterator[None]:
    def handler(signum: int, frame: FrameType | None) -> None:
        if sim.stop_signal is not None:
            sim.stop_now = signum  # the run loop raises StopNow too, should this one be lost
            raise StopNow(signum)
        sim.stop_signal = signum
        _say(
            f"\nmpmflow: {signal.Signals(signum).name} received: stopping at the next output "
            "time with a checkpoint (send it again to stop at once, without one).\n"
        )

    # StopNow lost in a __del__ is raised by the run loop after the current chunk
    with _handling(handler, quiet=(StopNow,)):
        yield


@contextmanager
def _handling(handler: Handler, quiet: tuple[type[BaseException], ...]) -> Iterator[None]:
    """``handler`` on SIGINT and SIGTERM, and the exceptions of the types ``quiet`` left
    unprinted when they are raised where Python cannot propagate them: a handler that runs
    inside a __del__ (a library freeing objects while it loads) has its exception printed as
    "Exception ignored ... Traceback" and dropped, and the caller raises it again itself.
    ValueError outside the main thread (where no handler can be installed)."""
    previous = {s: signal.signal(s, handler) for s in SIGNALS}
    previous_hook = sys.unraisablehook

    def unraisable(info: sys.UnraisableHookArgs) -> None:
        if not isinstance(info.exc_value, quiet):
            previous_hook(info)

    sys.unraisablehook = unraisable
    try:
        yield
    finally:
        sys.unraisablehook = previous_hook
        for s, old in previous.items():
            signal.signal(s, old)


class EarlyStop(_Signalled):
    """SIGINT/SIGTERM outside the time loop (while the command starts or finishes)."""


class EarlySignals:
    """The command line's handlers for SIGINT and SIGTERM outside the time loop.

    Without them SIGTERM during the first second of a command (imports, loading the case,
    placing the particles) killed it without a word. A signal then raises EarlyStop, which
    the command reports (exit 130 / 143). Should the exception be lost (raised inside a
    __del__ while a library frees objects), ``check()``, called between the phases of the
    command, raises it again."""

    def __init__(self) -> None:
        self.pending: int | None = None
        self.phase = "before"  # "after" once the run has ended
        self.deferring = False

    def _handler(self, signum: int, frame: FrameType | None) -> None:
        self.pending = signum
        if not self.deferring:
            raise EarlyStop(signum)

    @contextmanager
    def deferred(self) -> Iterator[None]:
        """Signals are only recorded inside (``check()`` after raises them): an exception
        raised while a compiled extension initialises (the core, libigl) comes out as an
        ImportError or SystemError with a traceback instead of as EarlyStop."""
        self.deferring = True
        try:
            yield
        finally:
            self.deferring = False

    def check(self) -> None:
        if self.pending is not None:
            raise EarlyStop(self.pending)

    def when(self) -> str:
        if self.phase == "after":
            return "after the run ended (its outputs are written)"
        return "before the run started: nothing was run"

    @contextmanager
    def installed(self) -> Iterator[None]:
        self.pending, self.phase = None, "before"
        with ExitStack() as stack:
            try:
                stack.enter_context(_handling(self._handler, quiet=(EarlyStop, StopNow)))
            except ValueError:  # not in the main thread (an embedding program): leave them
                pass
            yield
