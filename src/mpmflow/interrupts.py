"""Ctrl-C (SIGINT) and SIGTERM during a run: stop cleanly at the next output time.

The first signal asks the run to stop (``Simulation.stop_signal``): it finishes the steps up
to the next output time, writes that output and a checkpoint, and returns with status
"interrupted". A second signal stops at once (KeyboardInterrupt), without a checkpoint;
the last periodic one is kept. The handlers are installed only while ``mpmflow run`` runs.
"""

import signal
import sys
from contextlib import contextmanager

SIGNALS = (signal.SIGINT, signal.SIGTERM)


def exit_code(signum):
    """The shell's convention: 128 + signal number (130 for SIGINT, 143 for SIGTERM)."""
    return 128 + int(signum)


@contextmanager
def stop_on_signals(sim):
    def handler(signum, frame):
        if sim.stop_signal is not None:
            raise KeyboardInterrupt
        sim.stop_signal = signum
        print(f"\nmpmflow: {signal.Signals(signum).name} received: stopping at the next output "
              "time with a checkpoint (send it again to stop at once, without one).",
              file=sys.stderr, flush=True)

    previous = {s: signal.signal(s, handler) for s in SIGNALS}
    try:
        yield
    finally:
        for s, old in previous.items():
            signal.signal(s, old)
