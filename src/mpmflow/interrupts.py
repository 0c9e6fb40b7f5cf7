"""Ctrl-C (SIGINT) and SIGTERM during a run: stop cleanly at the next output time.

The first signal asks the run to stop (``Simulation.stop_signal``): it finishes the steps up
to the next output time, writes that output and a checkpoint, and returns with status
"interrupted". A second signal stops at once (``StopNow``, carrying the signal number),
without a new checkpoint; the last one written is kept. The handlers are installed only
while ``mpmflow run`` runs.
"""

import os
import signal
import sys
from contextlib import contextmanager

SIGNALS = (signal.SIGINT, signal.SIGTERM)


class StopNow(BaseException):
    """A second SIGINT/SIGTERM: stop at once. A BaseException (like KeyboardInterrupt) so
    that no ``except Exception`` on the way takes it for an error."""

    def __init__(self, signum):
        super().__init__(signum)
        self.signum = int(signum)

    @property
    def name(self):
        return signal.Signals(self.signum).name


def exit_code(signum):
    """The shell's convention: 128 + signal number (130 for SIGINT, 143 for SIGTERM)."""
    return 128 + int(signum)


def _say(text):
    """Write to stderr from a signal handler. os.write, not print: the handler can run in
    the middle of a write to sys.stderr (the progress bar's), and a second write to the
    same buffered stream then raises RuntimeError (reentrant call)."""
    try:
        os.write(2, text.encode())
    except OSError:
        pass  # no stderr to tell: stopping matters more


@contextmanager
def stop_on_signals(sim):
    def handler(signum, frame):
        if sim.stop_signal is not None:
            sim.stop_now = signum  # the run loop raises StopNow too, should this one be lost
            raise StopNow(signum)
        sim.stop_signal = signum
        _say(f"\nmpmflow: {signal.Signals(signum).name} received: stopping at the next output "
             "time with a checkpoint (send it again to stop at once, without one).\n")

    def unraisable(info):
        # a handler that runs inside a __del__ (Numba frees llvmlite objects while it loads
        # the kernels) has its exception printed as "Exception ignored ... Traceback" and
        # dropped; StopNow is then raised by the run loop after the current chunk
        if not isinstance(info.exc_value, StopNow):
            previous_hook(info)

    previous = {s: signal.signal(s, handler) for s in SIGNALS}
    previous_hook, sys.unraisablehook = sys.unraisablehook, unraisable
    try:
        yield
    finally:
        sys.unraisablehook = previous_hook
        for s, old in previous.items():
            signal.signal(s, old)
