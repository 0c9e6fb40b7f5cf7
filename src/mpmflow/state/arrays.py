"""Arrays as the core's bindings take them (C-contiguous, of the right dtype)."""

import numpy as np


def cells(grid):
    return [int(c) for c in grid.cells]


def ints(a):
    return np.ascontiguousarray(a, dtype=np.int64)


def floats(a):
    return np.ascontiguousarray(a, dtype=np.float64)


def pair_flags(flags, node):
    """A bool per wall pair: ``flags`` as given, or one bool repeated."""
    return np.ascontiguousarray(np.broadcast_to(np.asarray(flags, dtype=np.bool_), np.shape(node)))
