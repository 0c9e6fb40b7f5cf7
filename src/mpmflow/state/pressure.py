"""The pressure system's kernels called from Python: element integrals, the domain walls
as contact conditions, the multigrid and sparse products (src/core/quadrature, walls,
multigrid)."""

from collections.abc import Sequence
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike

from .. import _core, arrays
from ..arrays import Bools, Floats, Ints


def gauss_cell_tensors(h: float, K: Floats, C: Floats, V: Floats) -> None:
    """The element integrals K (2^D x 2^D), C (2^D x 2^D x D), V (2^D) of a full cell of side
    h from its 2^D Gauss points, into the arrays (float64; D from C's last axis)."""
    _core.gauss_cell_tensors(float(h), K, C, V)


def particle_cell_tensors(
    x: Floats,
    volume: Floats,
    order: Ints,
    start: Ints,
    cells_list: Ints,
    h: float,
    cells: Sequence[int],
    K: Floats,
    C: Floats,
    V: Floats,
) -> None:
    """The element integrals of the cells ``cells_list`` with their material points as
    quadrature points into K[m], C[m], V[m] (K may have no rows: then C and V only); the
    particles of cell c are order[start[c]:start[c + 1]]."""
    _core.particle_cell_tensors(
        x, volume, order, start, cells_list, float(h), [int(c) for c in cells], K, C, V
    )


def wall_pairs(cells: Sequence[int], periodic: Sequence[bool] = ()) -> tuple[Ints, Ints, Floats]:
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


def apply_walls(
    node: Ints, axis: Ints, sign: Floats, no_slip: ArrayLike, v: Floats, contact: Bools
) -> None:
    """Velocity conditions at the wall nodes, in place in v (nnodes x D): the normal velocity
    zeroed where the wall holds the material (``contact[i, k]``), elsewhere only a velocity
    into the wall; a no-slip pair (``no_slip``: a flag per pair, or one bool for all) zeroes
    the tangential velocity at its node in contact too."""
    _core.apply_walls(node, axis, sign, arrays.pair_flags(no_slip, node), v, contact)


def start_contact(
    node: Ints, axis: Ints, sign: Floats, vstar: Floats, node_row: Ints, contact: Bools
) -> None:
    """The wall contact as the pressure step starts, into ``contact`` (nnodes x D, bool): a
    wall node holds where it carries an unknown or v* presses into the wall."""
    _core.start_contact(node, axis, sign, vstar, node_row, contact)


def release_contact(
    node: Ints,
    axis: Ints,
    sign: Floats,
    vstar: Floats,
    node_row: Ints,
    p_node: Floats,
    contact: Bools,
) -> int:
    """Release the wall nodes in contact under tension that v* leaves (in place); returns
    how many (node, wall) pairs were released."""
    return int(_core.release_contact(node, axis, sign, vstar, node_row, p_node, contact))


COARSEST: int = _core.COARSEST  # unknowns at which the multigrid hierarchy stops (dense factor)
PARALLEL_ROWS: int = _core.PARALLEL_ROWS  # multigrid levels this large run on all threads


class Multigrid(Protocol):
    """The core's multigrid hierarchy (``Multigrid2``/``Multigrid3``, src/core/multigrid.hpp;
    a compiled class without type information): what Python calls of it."""

    def setup(
        self, cols: Ints, vals: Floats, node: Ints, dims: Sequence[int], coarsest: int = ...
    ) -> None:
        """Build the levels (the arrays are held, not copied)."""
        ...

    def pcg(
        self, rhs: Floats, x: Floats, tol: float, maxiter: int, sweeps: int
    ) -> tuple[int, float]:
        """Preconditioned CG from x (updated in place): (iterations, true relative
        residual)."""
        ...

    def vcycle(self, b: Floats, x: Floats, sweeps: int) -> None: ...

    def refresh(self) -> None:
        """The finest level's values changed in place since the setup: read them again."""
        ...

    def levels(self) -> int: ...

    def rows(self) -> int:
        """The unknowns of the finest level."""
        ...


def multigrid(
    cols: ArrayLike,
    vals: ArrayLike,
    node: ArrayLike,
    dims: Sequence[int],
    coarsest: int = COARSEST,
    hierarchy: Multigrid | None = None,
) -> Multigrid:
    """A multigrid hierarchy (``_core.Multigrid2``/``Multigrid3``) set up for the ELL matrix
    (cols, vals: n x 3^D) whose row r is grid point node[r] of a grid of ``dims`` points per
    axis: ``hierarchy`` (an earlier one, whose storage is reused) when given, else a new one.
    It holds the arrays until its next setup; its ``pcg(rhs, x, tol, maxiter, sweeps)``
    updates x in place and returns (iterations, true relative residual); ``vcycle(b, x,
    sweeps)`` applies the preconditioner."""
    dims = tuple(int(d) for d in dims)
    kind = _core.Multigrid2 if len(dims) == 2 else _core.Multigrid3
    mg: Multigrid = hierarchy if isinstance(hierarchy, kind) else kind()
    mg.setup(
        np.ascontiguousarray(cols, dtype=np.int64),
        np.ascontiguousarray(vals, dtype=float),
        np.ascontiguousarray(node, dtype=np.int64),
        dims,
        int(coarsest),
    )
    return mg


def matvec(cols: Ints, vals: Floats, x: Floats, y: Floats) -> None:
    """y = A x (A in ELL form); y: float64, written in place."""
    _core.matvec(cols, vals, x, y)


def residual(cols: Ints, vals: Floats, x: Floats, b: Floats, out: Floats) -> None:
    """out = b - A x (A in ELL form); out: float64, written in place."""
    _core.residual(cols, vals, x, b, out)


def dot(a: Floats, b: Floats) -> float:
    """a . b summed chunk by chunk when long: the same bits on any thread count."""
    return float(_core.dot(a, b))


def worst_row(cols: Ints, vals: Floats, x: Floats, b: Floats) -> int:
    """The row of the largest |b - A x| (NaN counts as largest)."""
    return int(_core.worst_row(cols, vals, x, b, np.empty(len(b))))


def reach(cols: Ints, seed: Bools) -> Bools:
    """The rows of a system (cols: n x slots, -1 = none) reached from the ``seed`` rows over
    its couplings (src/core/pockets.hpp)."""
    n = cols.shape[0]
    reached = np.zeros(n, dtype=bool)
    _core.reach(
        np.ascontiguousarray(cols, dtype=np.int64),
        np.ascontiguousarray(seed, dtype=bool),
        reached,
        np.empty(n, dtype=np.int64),
    )
    return reached
