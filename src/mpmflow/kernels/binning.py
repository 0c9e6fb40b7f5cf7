"""Particles to cells: cell index of each particle, counting sort, cell volume fractions."""

from numba import njit, prange

from .geometry import cell_of
from .parallel import CHUNKS

BLOCK = 128  # cells per block of cell_volume_fraction


@njit(cache=True, parallel=True)
def cell_index(x, h, cells, out):
    """Flat cell index of every particle (any dimension; ``cells``: the cell counts). Particles
    on the upper domain edge go to the last cell, beyond the grid to the nearest cell."""
    inv_h = 1.0 / h
    n = x.shape[0]
    nchunks = min(CHUNKS, max(n, 1))
    for t in prange(nchunks):
        for p in range(t * n // nchunks, (t + 1) * n // nchunks):
            c = 0
            stride = 1
            for k in range(len(cells)):
                c += cell_of(x[p, k] * inv_h, cells[k]) * stride
                stride *= cells[k]
            out[p] = c


@njit(cache=True)
def counting_sort(cell, ncells, start, order):
    """Group particles by cell: particles of cell c are ``order[start[c]:start[c+1]]``.

    ``start`` has ncells+1 entries; the sort is stable (particles keep their order in a cell).
    """
    start[:] = 0
    for p in range(cell.shape[0]):
        start[cell[p] + 1] += 1
    for c in range(ncells):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    for p in range(cell.shape[0]):
        c = cell[p]
        order[fill[c]] = p
        fill[c] += 1


@njit(cache=True, parallel=True)
def cell_volume_fraction(order, start, volume, cell_volume, open_, theta):
    """theta_e = sum of particle volumes in cell e / cell volume (eqs. 8-9 of the paper),
    from the sorted particles (each cell summed in particle order); in a cell an obstacle
    cuts, over its fluid part (``open_``: the fluid fraction, ``mpmflow.obstacles``)."""
    inv = 1.0 / cell_volume
    n = theta.shape[0]
    for t in prange(CHUNKS):
        # blocks of BLOCK cells dealt round the chunks: each chunk has cells everywhere, so
        # the work is even wherever the particles are
        for b0 in range(t * BLOCK, n, CHUNKS * BLOCK):
            for c in range(b0, min(b0 + BLOCK, n)):
                total = 0.0
                for s in range(start[c], start[c + 1]):
                    total += volume[order[s]]
                theta[c] = total * inv
                if 0.0 < open_[c] < 1.0:
                    theta[c] /= open_[c]
