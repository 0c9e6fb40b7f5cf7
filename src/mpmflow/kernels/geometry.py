"""Index arithmetic of the uniform grid, written once for 2D and 3D.

Every kernel receives the grid as ``cells``, a tuple of the cell counts along the axes: its
length D is part of its Numba type, so each kernel is compiled once per dimension and the
small loops over axes and corners have constant bounds (the compiler unrolls them). Flat
indices run along axis 0 fastest:

* node (i_0, ..., i_{D-1}) is sum_k i_k ns_k with ns_0 = 1, ns_k = ns_{k-1} (cells[k-1] + 1);
* cell (c_0, ...) is sum_k c_k cs_k with cs_k the product of the cell counts below k;
* corner a of a cell (0 <= a < 2^D) is offset (a >> k) & 1 along axis k, so the cell's node
  a is the cell's first node plus sum_k ((a >> k) & 1) ns_k (the order of the 2D kernels:
  0 = (0, 0), 1 = (1, 0), 2 = (0, 1), 3 = (1, 1));
* a neighbour at offset (d_0, ...) in {-1, 0, 1}^D of a node is stencil slot
  sum_k (d_k + 1) 3^k (9 slots in 2D, 27 in 3D).
"""

import numpy as np
from numba import njit
from numba.extending import overload


def zeros_of(t):
    """A tuple of float zeros as long as the tuple ``t`` (compiled code only): the start of a
    per-particle sum over D components held in registers, D taken from ``cells``' type."""
    raise NotImplementedError("zeros_of is for compiled code")


@overload(zeros_of)
def _zeros_of(t):
    zero = (0.0,) * len(t)
    return lambda t: zero


@njit(cache=True)
def cell_of(s, n):
    """The cell (0 to n - 1) holding grid coordinate s = x / h; points beyond the grid go to
    the nearest cell. Clamped before the conversion to an integer, so NaN goes to cell 0
    instead of an undefined index."""
    if not s > 0.0:  # also NaN
        return 0
    if s >= n - 1.0:
        return n - 1
    return int(s)


@njit(cache=True)
def node_strides(cells, out):
    """ns_k into ``out`` (length D); returns the number of nodes."""
    n = 1
    for k in range(len(cells)):
        out[k] = n
        n *= cells[k] + 1
    return n


@njit(cache=True)
def cell_strides(cells, out):
    """cs_k into ``out`` (length D); returns the number of cells."""
    n = 1
    for k in range(len(cells)):
        out[k] = n
        n *= cells[k]
    return n


@njit(cache=True)
def node_count(cells):
    n = 1
    for k in range(len(cells)):
        n *= cells[k] + 1
    return n


@njit(cache=True)
def cell_count(cells):
    n = 1
    for k in range(len(cells)):
        n *= cells[k]
    return n


@njit(cache=True)
def locate(x, p, inv_h, cells, ns, frac):
    """The first node of the cell holding particle p and its local coordinates in that
    cell (``frac``, length D, each in [0, 1])."""
    base = 0
    for k in range(len(cells)):
        s = x[p, k] * inv_h
        c = cell_of(s, cells[k])
        frac[k] = s - c
        base += c * ns[k]
    return base


@njit(cache=True)
def corner_offsets(ns, off):
    """Flat offsets of the 2^D corners of a cell from its first node into ``off``."""
    off[0] = 0
    for k in range(ns.shape[0]):
        for a in range(1 << k):
            off[a + (1 << k)] = off[a] + ns[k]


@njit(cache=True, inline="always")
def weights_at(x, p, inv_h, cells, ns, w):
    """The first node of the cell holding particle p, and the multilinear weights of its
    2^D corners into ``w`` (built axis by axis: 2^(D+1) products instead of D 2^D)."""
    base = 0
    w[0] = 1.0
    for k in range(len(cells)):
        s = x[p, k] * inv_h
        c = cell_of(s, cells[k])
        f = s - c
        base += c * ns[k]
        for a in range(1 << k):
            w[a + (1 << k)] = w[a] * f
            w[a] *= 1.0 - f
    return base


@njit(cache=True)
def corner_weight(a, frac):
    """Multilinear shape function of corner a at local coordinates ``frac``."""
    w = 1.0
    for k in range(frac.shape[0]):
        w *= frac[k] if (a >> k) & 1 else 1.0 - frac[k]
    return w


@njit(cache=True)
def corner_offset(a, ns):
    """Flat offset of corner a from its cell's first node."""
    o = 0
    for k in range(ns.shape[0]):
        if (a >> k) & 1:
            o += ns[k]
    return o


@njit(cache=True)
def corner_gradient(a, k, frac, inv_h):
    """d N_a / d x_k at local coordinates ``frac`` (1/m)."""
    g = inv_h if (a >> k) & 1 else -inv_h
    for j in range(frac.shape[0]):
        if j != k:
            g *= frac[j] if (a >> j) & 1 else 1.0 - frac[j]
    return g


@njit(cache=True)
def node_coords(i, cells, out):
    """The integer coordinates of node i into ``out``."""
    for k in range(len(cells)):
        n = cells[k] + 1
        out[k] = i % n
        i //= n


@njit(cache=True)
def cell_coords(c, cells, out):
    """The integer coordinates of cell c into ``out``."""
    for k in range(len(cells)):
        out[k] = c % cells[k]
        c //= cells[k]


def strides(cells):
    """(node strides, cell strides) as arrays, for callers outside compiled code."""
    ns = np.empty(len(cells), dtype=np.int64)
    cs = np.empty(len(cells), dtype=np.int64)
    node_strides(tuple(cells), ns)
    cell_strides(tuple(cells), cs)
    return ns, cs
