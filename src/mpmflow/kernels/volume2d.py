"""The volume correction on the cell-centred grid (2D): density, its Poisson system, and the
face displacements (see ``mpmflow.volume_correction``).

Cells are the points of this grid: cell c = cx + ncx * cy sits at ((cx + 1/2) h, (cy + 1/2) h).
Faces carry the displacement: x-face (ix, cy), ix = 0..ncx, between cells ix - 1 and ix, is
entry ix + (ncx + 1) * cy of ``dx_face``; y-face (cx, iy) is entry cx + ncx * iy of ``dy_face``.
"""

import numpy as np
from numba import njit, prange

from .parallel import strips

STRIPS = 16  # the density scatter cuts the cell rows into 2 STRIPS strips


@njit(cache=True)
def _mirror(k, n):
    """Cell index k of a ghost cell beyond a wall folded back onto its mirror image."""
    if k < 0:
        return -k - 1
    if k >= n:
        return 2 * n - k - 1
    return k


@njit(cache=True)
def _scatter_density(r0, r1, x, volume, order, start, inv_h, ncx, ncy, out):
    """Dual-grid density of the particles of cell rows r0 to r1 - 1, cell by cell."""
    for s in range(start[r0 * ncx], start[r1 * ncx]):
        p = order[s]
        sx = x[p, 0] * inv_h - 0.5
        sy = x[p, 1] * inv_h - 0.5
        i0 = int(np.floor(sx))
        j0 = int(np.floor(sy))
        fx = sx - i0
        fy = sy - j0
        for dj in range(2):
            j = _mirror(j0 + dj, ncy)
            wy = fy if dj == 1 else 1.0 - fy
            for di in range(2):
                i = _mirror(i0 + di, ncx)
                wx = fx if di == 1 else 1.0 - fx
                out[i + ncx * j] += wx * wy * volume[p]


@njit(cache=True, parallel=True)
def dual_density_2d(x, volume, order, start, h, ncx, ncy, out):
    """Particle volume per cell volume, sampled at the cell centres with the bilinear hat of
    the cell-centred grid: out_c = sum_p N_c(x_p) V_p / h^2. A wall mirrors the particles next
    to it (a ghost cell's weight goes to its mirror cell), so a uniform material reads 1 up
    to the walls. Particles come binned by cell (``order``, ``start``); cell rows are cut into
    strips of at least 2 rows, even strips scattered in parallel, then odd ones (a particle
    reaches one cell row up or down), so the sums do not depend on the thread count."""
    inv_h = 1.0 / h
    for c in prange(out.shape[0]):
        out[c] = 0.0
    bounds = np.empty(2 * STRIPS + 1, dtype=np.int64)
    k = strips(start[::ncx], 2 * STRIPS, 2, bounds)
    for parity in range(2):
        for t in prange((k - parity + 1) // 2):
            u = 2 * t + parity
            _scatter_density(bounds[u], bounds[u + 1], x, volume, order, start, inv_h, ncx,
                             ncy, out)
    scale = inv_h * inv_h
    for c in prange(out.shape[0]):
        out[c] *= scale


@njit(cache=True, inline="always")
def _wall_released(cx, cy, ncx, ncy, contact):
    """Whether cell (cx, cy) lies against a wall that does not hold the material there (one
    of the wall nodes of its wall edge is out of contact): the material has left that wall,
    which is then a free surface."""
    nnx = ncx + 1
    i = cx + nnx * cy
    if cx == 0 and not (contact[i, 0] and contact[i + nnx, 0]):
        return True
    if cx == ncx - 1 and not (contact[i + 1, 0] and contact[i + nnx + 1, 0]):
        return True
    if cy == 0 and not (contact[i, 1] and contact[i + 1, 1]):
        return True
    if cy == ncy - 1 and not (contact[i + nnx, 1] and contact[i + nnx + 1, 1]):
        return True
    return False


@njit(cache=True)
def assemble_2d(ncx, ncy, theta, density, wet, contact, cell_row, cols, vals, rhs, cells):
    """The Poisson system of the correction on the cells holding material (theta > 0).

    Numbers those cells (``cell_row``, -1 elsewhere; ``cells[r]``: the cell of row r) and
    writes the 5-point Laplacian in unit spacing in the 9-slot ELL form of
    ``kernels.multigrid`` (slot 3 (dy + 1) + (dx + 1)): an empty neighbour cell is held at
    q = 0 (air), a wall is a Neumann boundary. rhs_r = density - 1, the excess volume
    fraction. Near a free surface the density reads low because part of the kernel lies in
    air, so only an excess counts in a cell whose 3 x 3 neighbourhood holds a cell with
    theta < ``wet``, or that lies against a wall the material has left (``contact``: the
    pressure step's wall contact of each node and wall axis). Returns (number of rows,
    whether any row touches air)."""
    n = 0
    for c in range(ncx * ncy):
        if theta[c] > 0.0:
            cell_row[c] = n
            cells[n] = c
            n += 1
        else:
            cell_row[c] = -1
    anchored = False
    for r in range(n):
        c = cells[r]
        cx = c % ncx
        cy = c // ncx
        for s in range(9):
            cols[r, s] = -1
            vals[r, s] = 0.0
        diag = 0.0
        for k in range(4):
            dx = 1 if k == 0 else (-1 if k == 1 else 0)
            dy = 1 if k == 2 else (-1 if k == 3 else 0)
            jx = cx + dx
            jy = cy + dy
            if jx < 0 or jx >= ncx or jy < 0 or jy >= ncy:
                continue
            diag += 1.0
            j = cell_row[jx + ncx * jy]
            if j >= 0:
                slot = 3 * (dy + 1) + (dx + 1)
                cols[r, slot] = j
                vals[r, slot] = -1.0
            else:
                anchored = True
        cols[r, 4] = r
        vals[r, 4] = diag
        surface = _wall_released(cx, cy, ncx, ncy, contact)
        for jy in range(max(cy - 1, 0), min(cy + 2, ncy)):
            for jx in range(max(cx - 1, 0), min(cx + 2, ncx)):
                if theta[jx + ncx * jy] < wet:
                    surface = True
        excess = density[c] - 1.0
        rhs[r] = max(excess, 0.0) if surface else excess
    return n, anchored


@njit(cache=True, inline="always")
def _face(cell_row, q, a, b, scale, dmax):
    """Displacement (m) across the face from cell a to cell b: -scale (q_b - q_a), air q = 0,
    limited to dmax; 0 between two cells without material."""
    ra = cell_row[a]
    rb = cell_row[b]
    if ra < 0 and rb < 0:
        return 0.0
    qa = q[ra] if ra >= 0 else 0.0
    qb = q[rb] if rb >= 0 else 0.0
    return min(max(-scale * (qb - qa), -dmax), dmax)


@njit(cache=True, parallel=True)
def face_displacements_2d(ncx, ncy, cell_row, q, scale, dmax, dx_face, dy_face):
    """d = -scale grad q on the inner faces (m); 0 on the walls."""
    for cy in prange(ncy):
        dx_face[(ncx + 1) * cy] = 0.0
        dx_face[ncx + (ncx + 1) * cy] = 0.0
        for ix in range(1, ncx):
            dx_face[ix + (ncx + 1) * cy] = _face(cell_row, q, ix - 1 + ncx * cy, ix + ncx * cy,
                                                 scale, dmax)
    for iy in prange(ncy + 1):
        for cx in range(ncx):
            if iy == 0 or iy == ncy:
                dy_face[cx + ncx * iy] = 0.0
            else:
                dy_face[cx + ncx * iy] = _face(cell_row, q, cx + ncx * (iy - 1),
                                               cx + ncx * iy, scale, dmax)


@njit(cache=True, inline="always")
def _staggered(f, nx, ny, sx, sy):
    """Bilinear interpolation of samples f[i + nx j] at integer points (i, j), clamped to the
    outermost samples."""
    i0 = int(np.floor(sx))
    j0 = int(np.floor(sy))
    fx = sx - i0
    fy = sy - j0
    acc = 0.0
    for dj in range(2):
        j = min(max(j0 + dj, 0), ny - 1)
        wy = fy if dj == 1 else 1.0 - fy
        for di in range(2):
            i = min(max(i0 + di, 0), nx - 1)
            wx = fx if di == 1 else 1.0 - fx
            acc += wx * wy * f[i + nx * j]
    return acc


@njit(cache=True, inline="always")
def displacement_at(x0, x1, inv_h, ncx, ncy, dx_face, dy_face):
    """The face displacements interpolated to the point (x0, x1) (m): each component from its
    own faces (x-faces sit at (ix h, (cy + 1/2) h), y-faces at ((cx + 1/2) h, iy h))."""
    sx = x0 * inv_h
    sy = x1 * inv_h
    return (_staggered(dx_face, ncx + 1, ncy, sx, sy - 0.5),
            _staggered(dy_face, ncx, ncy + 1, sx - 0.5, sy))
