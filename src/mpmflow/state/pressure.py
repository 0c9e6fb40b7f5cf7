"""The pressure system's kernels called from Python: element integrals, the domain walls
as contact conditions, the multigrid and sparse products (src/core/quadrature, walls,
multigrid)."""

from collections.abc import Sequence

import numpy as np

from .. import _core
from . import arrays


def gauss_cell_tensors(h, K, C, V):
    """The element integrals K (2^D x 2^D), C (2^D x 2^D x D), V (2^D) of a full cell of side
    h from its 2^D Gauss points, into the arrays (float64; D from C's last axis)."""
    _core.gauss_cell_tensors(float(h), K, C, V)


def particle_cell_tensors(x, volume, order, start, cells_list, h, cells, K, C, V):
    """The element integrals of the cells ``cells_list`` with their material points as
    quadrature points into K[m], C[m], V[m] (K may have no rows: then C and V only); the
    particles of cell c are order[start[c]:start[c + 1]]."""
    _core.particle_cell_tensors(
        x, volume, order, start, cells_list, float(h), [int(c) for c in cells], K, C, V
    )


def wall_pairs(
    cells: Sequence[int], periodic: Sequence[bool] = ()
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(node, axis, sign) arrays of every wall node and wall of the grid ``cells``: the walls
    normal to axis 0 first, then axis 1, ...; the lower wall (sign -1) before the upper. A
    periodic axis (``periodic[k]``) has no walls."""
    cells = [int(c) for c in cells]
    periodic = [bool(p) for p in periodic]
    n = _core.wall_pair_count(cells, periodic)
    node = np.empty(n, dtype=np.int64)
    axis = np.empty(n, dtype=np.int64)
    sign = np.empty(n)
    _core.wall_pairs(cells, periodic, node, axis, sign)
    return node, axis, sign


def apply_walls(node, axis, sign, no_slip, v, contact):
    """Velocity conditions at the wall nodes, in place in v (nnodes x D): the normal velocity
    zeroed where the wall holds the material (``contact[i, k]``), elsewhere only a velocity
    into the wall; a no-slip pair (``no_slip``: a flag per pair, or one bool for all) zeroes
    the tangential velocity at its node in contact too."""
    _core.apply_walls(node, axis, sign, arrays.pair_flags(no_slip, node), v, contact)


def start_contact(node, axis, sign, vstar, node_row, contact):
    """The wall contact as the pressure step starts, into ``contact`` (nnodes x D, bool): a
    wall node holds where it carries an unknown or v* presses into the wall."""
    _core.start_contact(node, axis, sign, vstar, node_row, contact)


def release_contact(node, axis, sign, vstar, node_row, p_node, contact):
    """Release the wall nodes in contact under tension that v* leaves (in place); returns
    how many (node, wall) pairs were released."""
    return _core.release_contact(node, axis, sign, vstar, node_row, p_node, contact)


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
    mg.setup(
        np.ascontiguousarray(cols, dtype=np.int64),
        np.ascontiguousarray(vals, dtype=float),
        np.ascontiguousarray(node, dtype=np.int64),
        dims,
        int(coarsest),
    )
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
