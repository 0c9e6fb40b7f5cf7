"""The scheme's state and the one door to the compiled core (``mpmflow._core``).

Nothing else in mpmflow imports the core: the rest of the package calls the functions
here, which take NumPy arrays and grids and call the C++ kernels (src/core, one header/
source pair per concept). The core is built once, at install (scikit-build-core, CMake);
nothing compiles at run time.
"""

import numpy as np

from . import _core

CHUNKS = _core.CHUNKS


def max_threads():
    """The threads the core's parallel loops use."""
    return _core.max_threads()


def set_threads(n):
    """Run the core's parallel loops on n threads."""
    _core.set_threads(int(n))


# --- multigrid ---
COARSEST = _core.COARSEST  # unknowns at which the multigrid hierarchy stops (dense factor)
PARALLEL_ROWS = _core.PARALLEL_ROWS  # multigrid levels this large run on all threads


def multigrid(cols, vals, node, dims, coarsest=COARSEST, hierarchy=None):
    """A multigrid hierarchy (``_core.Multigrid2``/``Multigrid3``) set up for the ELL matrix
    (cols, vals: n x 3^D) whose row r is grid point node[r] of a grid of ``dims`` points per
    axis: ``hierarchy`` (an earlier one, whose storage is reused) when given, else a new one.
    It holds the arrays until its next setup; its ``pcg(rhs, x, tol, maxiter, sweeps)``
    updates x in place and returns (iterations, true relative residual); ``vcycle(b, x,
    sweeps)`` applies the preconditioner."""
    dims = tuple(int(d) for d in dims)
    kind = _core.Multigrid2 if len(dims) == 2 else _core.Multigrid3
    mg = hierarchy if isinstance(hierarchy, kind) else kind()
    mg.setup(np.ascontiguousarray(cols, dtype=np.int64), np.ascontiguousarray(vals, dtype=float),
             np.ascontiguousarray(node, dtype=np.int64), dims, int(coarsest))
    return mg


def matvec(cols, vals, x, y):
    """y = A x (A in ELL form); y: float64, written in place."""
    _core.matvec(cols, vals, x, y)


def residual(cols, vals, x, b, out):
    """out = b - A x (A in ELL form); out: float64, written in place."""
    _core.residual(cols, vals, x, b, out)


def dot(a, b):
    """a . b summed chunk by chunk when long: the same bits on any thread count."""
    return _core.dot(a, b)


def worst_row(cols, vals, x, b):
    """The row of the largest |b - A x| (NaN counts as largest)."""
    return _core.worst_row(cols, vals, x, b, np.empty(len(b)))
