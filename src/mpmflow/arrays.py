"""Arrays as the core's bindings take them (C-contiguous, of the right dtype), and their
types: the core's kernels take float64, int64 and bool arrays (src/core/view.hpp). Outside
the ``state`` package, so that code that only names these types (the case, the geometry)
does not load the compiled core."""

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .grid import Grid

Floats = NDArray[np.float64]  # the core's ``double`` arrays
Ints = NDArray[np.int64]  # the core's ``index_t`` arrays (indices, counts)
Bools = NDArray[np.bool_]  # the core's ``bool`` arrays (flags, contact)


def cells(grid: Grid) -> list[int]:
    return [int(c) for c in grid.cells]


def ints(a: ArrayLike) -> Ints:
    return np.ascontiguousarray(a, dtype=np.int64)


def floats(a: ArrayLike) -> Floats:
    return np.ascontiguousarray(a, dtype=np.float64)


def pair_flags(flags: ArrayLike, node: ArrayLike) -> Bools:
    """A bool per wall pair: ``flags`` as given, or one bool repeated."""
    return np.ascontiguousarray(np.broadcast_to(np.asarray(flags, dtype=np.bool_), np.shape(node)))
