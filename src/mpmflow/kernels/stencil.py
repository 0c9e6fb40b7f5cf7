"""A node's cells and its 3^D stencil of couplings, for 2D and 3D (``geometry``).

The pressure system couples each node to its neighbours at offsets in {-1, 0, 1}^D through
the element integrals of the cells around it. These helpers gather them: which of the
node's 2^D cells take part in the system, the node's corner in each, and the coupling to each
neighbour summed over the cells, in slot sum_k (d_k + 1) 3^k (the centre is slot (3^D - 1)/2).
Cells and corners are visited in the order of their bits, the order of the 2D kernels that
came before, so 2D sums are the same to the last bit.
"""

import numpy as np
from numba import njit


@njit(cache=True)
def tables(cells):
    """(node strides, cell strides, slot[a, c]: the stencil slot of corner c seen from corner
    a of the same cell, offset[s]: the flat node offset of slot s) for the grid ``cells``."""
    D = len(cells)
    NC = 1 << D
    ns = np.empty(D, dtype=np.int64)
    cs = np.empty(D, dtype=np.int64)
    n = 1
    c = 1
    for k in range(D):
        ns[k] = n
        cs[k] = c
        n *= cells[k] + 1
        c *= cells[k]
    slot = np.empty((NC, NC), dtype=np.int64)
    for a in range(NC):
        for b in range(NC):
            s = 0
            p3 = 1
            for k in range(D):
                s += (((b >> k) & 1) - ((a >> k) & 1) + 1) * p3
                p3 *= 3
            slot[a, b] = s
    NS = 1
    for k in range(D):
        NS *= 3
    offset = np.empty(NS, dtype=np.int64)
    for s in range(NS):
        o = 0
        r = s
        for k in range(D):
            o += (r % 3 - 1) * ns[k]
            r //= 3
        offset[s] = o
    return ns, cs, slot, offset


@njit(cache=True, inline="always")
def node_cell(ix, b, cells, ns, cs):
    """Cell b (0 <= b < 2^D) of the node with coordinates ``ix``: (its flat index, -1 when
    outside the grid; its first node; the node's corner in it)."""
    c = 0
    first = 0
    a = 0
    for k in range(len(cells)):
        bit = (b >> k) & 1
        j = ix[k] - 1 + bit
        if j < 0 or j >= cells[k]:
            return -1, 0, 0
        c += j * cs[k]
        first += j * ns[k]
        if bit == 0:
            a += 1 << k
    return c, first, a


@njit(cache=True)
def node_cells(ix, cells, ns, cs, cell_slot, slots, local, base):
    """The cells around the node with coordinates ``ix`` that take part in the system: their
    slot in the element integrals, the node's corner in each, and each cell's first node.
    Returns how many (at most 2^D)."""
    n = 0
    for b in range(1 << len(cells)):
        c, first, a = node_cell(ix, b, cells, ns, cs)
        if c < 0:
            continue
        s = cell_slot[c]
        if s < 0:
            continue
        slots[n] = s
        local[n] = a
        base[n] = first
        n += 1
    return n


@njit(cache=True)
def node_stencil(ix, cells, ns, cs, cell_slot, K, slot, S, slots, local, base):
    """Couplings sum_e K_e[a_i, b] of the node with coordinates ``ix`` to its 3^D neighbours,
    into S (by slot). Returns the number of its cells in the system."""
    S[:] = 0.0
    n = node_cells(ix, cells, ns, cs, cell_slot, slots, local, base)
    NC = K.shape[1]
    for m in range(n):
        a = local[m]
        for b in range(NC):
            S[slot[a, b]] += K[slots[m], a, b]
    return n


@njit(cache=True)
def first_of_slab(slab, cells, ix):
    """Coordinates of the first node of a slab (its index along the last axis)."""
    for k in range(len(cells) - 1):
        ix[k] = 0
    ix[len(cells) - 1] = slab


@njit(cache=True)
def next_in_slab(ix, cells):
    """Step the node coordinates ``ix`` to the next node of the slab (axis 0 fastest)."""
    for k in range(len(cells) - 1):
        ix[k] += 1
        if ix[k] <= cells[k]:
            return
        ix[k] = 0


@njit(cache=True)
def coords(i, cells, ix):
    """The coordinates of node i into ``ix``."""
    for k in range(len(cells)):
        n = cells[k] + 1
        ix[k] = i % n
        i //= n
