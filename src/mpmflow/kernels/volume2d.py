"""The volume correction on the cell-centred grid (2D): density, its Poisson system, and the
face displacements (see ``mpmflow.volume_correction``).

Cells are the points of this grid: cell c = cx + ncx * cy sits at ((cx + 1/2) h, (cy + 1/2) h).
Faces carry the displacement: x-face (ix, cy), ix = 0..ncx, between cells ix - 1 and ix, is
entry ix + (ncx + 1) * cy of ``dx_face``; y-face (cx, iy) is entry cx + ncx * iy of ``dy_face``.
"""

import numpy as np
from numba import njit, prange



@njit(cache=True, inline="always")
def scatter_cell_volume(sx, sy, volume, ncx, ncy, cell_vol):
    """Add a particle of volume ``volume`` at grid coordinates (sx, sy) = x / h to the cell
    centres with the bilinear hat of the cell-centred grid. A wall mirrors the particles next
    to it: the weight of a ghost cell beyond the wall goes to its mirror, the cell against
    the wall, so a uniform material reads full up to the walls. Points beyond the grid (and
    NaN) count at its edge, so no index leaves the arrays."""
    if not sx >= 0.0:
        sx = 0.0
    elif sx > ncx:
        sx = ncx
    if not sy >= 0.0:
        sy = 0.0
    elif sy > ncy:
        sy = ncy
    sx -= 0.5
    sy -= 0.5
    i0 = int(sx + 1.0) - 1  # floor: sx > -1 inside the domain
    j0 = int(sy + 1.0) - 1
    fx = sx - i0
    fy = sy - j0
    i1 = i0 + 1
    j1 = j0 + 1
    if i0 < 0:
        i0 = 0
    if i1 > ncx - 1:
        i1 = ncx - 1
    if j0 < 0:
        j0 = 0
    if j1 > ncy - 1:
        j1 = ncy - 1
    cell_vol[i0 + ncx * j0] += (1.0 - fx) * (1.0 - fy) * volume
    cell_vol[i1 + ncx * j0] += fx * (1.0 - fy) * volume
    cell_vol[i0 + ncx * j1] += (1.0 - fx) * fy * volume
    cell_vol[i1 + ncx * j1] += fx * fy * volume


@njit(cache=True)
def cell_volume_2d(x, volume, h, ncx, ncy, out):
    """sum_p N_c(x_p) V_p on every cell centre (``scatter_cell_volume``), over all particles;
    the particle-to-grid kernel computes the same in its own pass during a step."""
    out[:] = 0.0
    inv_h = 1.0 / h
    for p in range(x.shape[0]):
        scatter_cell_volume(x[p, 0] * inv_h, x[p, 1] * inv_h, volume[p], ncx, ncy, out)


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
def _interpolate(f, sn, st, s_normal, n_normal, s_along, n_along):
    """Bilinear interpolation of face samples f[sn k + st m]: normal position k (faces on the
    cell edges, k = 0 to n_normal) and tangential position m + 1/2 (the cell rows, m = 0 to
    n_along - 1), at (s_normal, s_along) in units of h, 0 <= s <= n; clamped to the outermost
    row of faces along the tangent."""
    k0 = int(s_normal)
    if k0 > n_normal - 1:
        k0 = n_normal - 1
    a = s_normal - k0
    t = s_along - 0.5
    m0 = int(t + 1.0) - 1  # floor: t >= -1/2
    b = t - m0
    m1 = m0 + 1
    if m0 < 0:
        m0 = 0
    if m1 > n_along - 1:
        m1 = n_along - 1
    r0 = sn * k0 + st * m0
    r1 = sn * k0 + st * m1
    return ((1.0 - b) * ((1.0 - a) * f[r0] + a * f[r0 + sn])
            + b * ((1.0 - a) * f[r1] + a * f[r1 + sn]))


@njit(cache=True, inline="always")
def displacement_at(x0, x1, inv_h, ncx, ncy, dx_face, dy_face):
    """The face displacements interpolated to the point (x0, x1) (m), each component from its
    own faces: x-face ix + (ncx + 1) cy sits at (ix h, (cy + 1/2) h), y-face cx + ncx iy at
    ((cx + 1/2) h, iy h). Points beyond the domain count at its edge."""
    sx = min(max(x0 * inv_h, 0.0), float(ncx))
    sy = min(max(x1 * inv_h, 0.0), float(ncy))
    return (_interpolate(dx_face, 1, ncx + 1, sx, ncx, sy, ncy),
            _interpolate(dy_face, ncx, 1, sy, ncy, sx, ncx))
