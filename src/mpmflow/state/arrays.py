"""Arrays as the core's bindings take them (C-contiguous, of the right dtype)."""

from typing import Any

import numpy as np


def cells(grid: Any) -> list[int]:
    return [int(c) for c in grid.cells]


def ints(a: Any) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.int64)


def floats(a: Any) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float64)


def pair_flags(flags: Any, node: Any) -> np.ndarray:
    """A bool per wall pair: ``flags`` as given, or one bool repeated."""
    return np.ascontiguousarray(np.broadcast_to(np.asarray(flags, dtype=np.bool_), np.shape(node)))
