"""Where the material is, by node: the nodal volume fraction, the cells enclosed by the
material, and the pressure unknowns (2D and 3D; ``geometry`` for the index conventions).

A node's cells are the 2^D cells it is a corner of: cell b (0 <= b < 2^D) has index
i_k - 1 + ((b >> k) & 1) along axis k, and the node is that cell's corner
sum_k (1 - ((b >> k) & 1)) 2^k. Loops over nodes deal slabs of nodes (one index along the
last axis) round the parallel chunks, so every chunk gets nodes in the water and in the
air alike, and each node's result depends on its neighbours only, not on the thread count.

The free surface (which nodes carry a pressure unknown), ``solver.free_surface``:

``node``   (the paper): every node of the cells in the system is an unknown unless it
           borders a cell left out of the system (empty or sparse); those get p = 0.
``subcell``: the surface is the level f = 1/2 of the nodal volume fraction f (mean theta
           of the node's cells, each clipped to 1). Unknowns are the nodes with f > 1/2
           all of whose cells are in the system; the others are ghost nodes whose pressure
           extrapolates linearly to p = 0 at the surface (``ghost``).
           For a flat surface at any height this places p = 0 exactly at the surface, not
           at the nearest node row. A cell all of whose nodes lie inside the fluid stays in
           the system even when few particles are left in it: a gap that opens between
           particle lines inside the water is not a free surface (``quadrature``).
"""

import numpy as np
from numba import njit, prange

from .parallel import CHUNKS


@njit(cache=True)
def cell_of_node(ix, b, cells, cs):
    """Flat index of cell b of the node with coordinates ``ix`` (-1 when outside the grid)."""
    c = 0
    for k in range(len(cells)):
        j = ix[k] - 1 + ((b >> k) & 1)
        if j < 0 or j >= cells[k]:
            return -1
        c += j * cs[k]
    return c


@njit(cache=True)
def _first_of_slab(slab, cells, ix):
    """Coordinates of the first node of a slab (its index along the last axis)."""
    for k in range(len(cells) - 1):
        ix[k] = 0
    ix[len(cells) - 1] = slab


@njit(cache=True)
def _next(ix, cells, extra):
    """Step the coordinates ``ix`` to the next point of the slab (axis 0 fastest) on a grid
    of cells[k] + extra points along axis k."""
    for k in range(len(cells) - 1):
        ix[k] += 1
        if ix[k] < cells[k] + extra:
            return
        ix[k] = 0


@njit(cache=True)
def _layout(cells):
    """(cell strides, nodes per slab, number of slabs) of the node grid."""
    D = len(cells)
    cs = np.empty(D, dtype=np.int64)
    c = 1
    for k in range(D):
        cs[k] = c
        c *= cells[k]
    per = 1
    for k in range(D - 1):
        per *= cells[k] + 1
    return cs, per, cells[D - 1] + 1


@njit(cache=True, parallel=True)
def nodal_fraction(cells, theta, open_, node_f):
    """Nodal volume fraction: the mean of the node's in-domain cells' theta, each clipped to 1,
    weighted by the cells' fluid fraction ``open_`` (1 but in cells an obstacle cuts; a
    cell inside a solid does not count, as a cell beyond a wall)."""
    D = len(cells)
    cs, per, nslabs = _layout(cells)
    for t in prange(CHUNKS):
        ix = np.empty(D, dtype=np.int64)
        for slab in range(t, nslabs, CHUNKS):
            _first_of_slab(slab, cells, ix)
            for i in range(slab * per, (slab + 1) * per):
                fsum = 0.0
                ncell = 0.0
                for b in range(1 << D):
                    c = cell_of_node(ix, b, cells, cs)
                    if c >= 0 and open_[c] > 0.0:
                        fsum += open_[c] * min(theta[c], 1.0)
                        ncell += open_[c]
                node_f[i] = fsum / ncell if ncell > 0.0 else 0.0
                _next(ix, cells, 1)


@njit(cache=True, parallel=True)
def enclosed_cells(cells, node_f, enclosed):
    """Cells all of whose 2^D nodes lie inside the material (f > 1/2)."""
    D = len(cells)
    ns = np.empty(D, dtype=np.int64)
    n = 1
    for k in range(D):
        ns[k] = n
        n *= cells[k] + 1
    off = np.empty(1 << D, dtype=np.int64)
    off[0] = 0
    for k in range(D):
        for a in range(1 << k):
            off[a + (1 << k)] = off[a] + ns[k]
    per = 1
    for k in range(D - 1):
        per *= cells[k]
    nslabs = cells[D - 1]
    for t in prange(CHUNKS):
        cx = np.empty(D, dtype=np.int64)
        for slab in range(t, nslabs, CHUNKS):
            _first_of_slab(slab, cells, cx)
            for c in range(slab * per, (slab + 1) * per):
                first = 0
                for k in range(D):
                    first += cx[k] * ns[k]
                inside = True
                for a in range(1 << D):
                    if not node_f[first + off[a]] > 0.5:
                        inside = False
                        break
                enclosed[c] = inside
                _next(cx, cells, 0)


@njit(cache=True, parallel=True)
def classify_nodes(cells, cell_slot, static_slot, node_f, subcell, node_row):
    """Number the pressure unknowns; returns their count. A node is an unknown when all its
    in-domain cells outside solids (``static_slot`` >= 0) take part in the system
    (``cell_slot`` >= 0), there is at least one such cell (a node inside a solid is none)
    and, with ``subcell``, its volume fraction exceeds 1/2. Unknowns are numbered in node
    order."""
    D = len(cells)
    cs, per, nslabs = _layout(cells)
    for t in prange(CHUNKS):
        ix = np.empty(D, dtype=np.int64)
        for slab in range(t, nslabs, CHUNKS):
            _first_of_slab(slab, cells, ix)
            for i in range(slab * per, (slab + 1) * per):
                unknown = not (subcell and node_f[i] <= 0.5)
                fluid = False  # some cell of the node lies outside every solid
                for b in range(1 << D):
                    c = cell_of_node(ix, b, cells, cs)
                    if c >= 0 and static_slot[c] >= 0:
                        fluid = True
                        if cell_slot[c] < 0:
                            unknown = False
                node_row[i] = 0 if unknown and fluid else -1
                _next(ix, cells, 1)
    return number(node_row)


@njit(cache=True)
def number(row):
    """Number the entries >= 0 in order; returns how many."""
    n = 0
    for i in range(row.shape[0]):
        if row[i] >= 0:
            row[i] = n
            n += 1
    return n
