"""The FLIP fraction of a step (docs/method.md, step 7); the transfers themselves are the
core's src/core/transfer."""

FLIP_TIME = 1e-3  # s: solver.flip is the FLIP fraction per this much simulated time


def flip_per_step(flip, dt):
    """The FLIP fraction of one step of dt: flip^(dt / 1 ms), the same PIC damping per second
    whatever the step (both schemes)."""
    return flip ** (dt / FLIP_TIME)
