"""The volume correction on the cell-centred grid, 2D and 3D: its Poisson system and the
displacement on the cell faces (see ``mpmflow.volume_correction``).

Cells are the points of this grid (flat index axis 0 fastest). The faces normal to axis k
carry that component of the displacement: face (i_0, ..., i_{D-1}) with i_k = 0 to cells[k]
lies between cells i_k - 1 and i_k along k; its flat index runs over cells[k] + 1 values
along k and cells[j] along the others, axis 0 fastest (``transfer.face_displacement``
interpolates them).
"""

import numpy as np
from numba import njit, prange

from .geometry import cell_strides, node_strides
from .parallel import CHUNKS
from .transfer import scatter_cell_volume


@njit(cache=True)
def cell_volume(x, volume, h, cells, out):
    """sum_p N_c(x_p) V_p on every cell centre (``transfer.scatter_cell_volume``), over all
    particles; the particle-to-grid pass computes the same during a step."""
    D = len(cells)
    cs = np.empty(D, dtype=np.int64)
    cell_strides(cells, cs)
    frac = np.empty(D)
    first = np.empty(D, dtype=np.int64)
    out[:] = 0.0
    inv_h = 1.0 / h
    for p in range(x.shape[0]):
        scatter_cell_volume(x, p, volume[p], inv_h, cells, cs, frac, first, out)


@njit(cache=True)
def _wall_released(cx, cells, ns, contact):
    """Whether the cell with coordinates ``cx`` lies against a wall that does not hold the
    material there (one of the nodes of its wall face is out of contact for that wall): the
    material has left that wall, which is then a free surface."""
    D = len(cells)
    first = 0
    for k in range(D):
        first += cx[k] * ns[k]
    for k in range(D):
        for side in range(2):
            if cx[k] != (0 if side == 0 else cells[k] - 1):
                continue
            for a in range(1 << D):
                if ((a >> k) & 1) != side:
                    continue
                i = first
                for m in range(D):
                    if (a >> m) & 1:
                        i += ns[m]
                if not contact[i, k]:
                    return True
    return False


@njit(cache=True)
def assemble(cells, theta, density, wet, contact, static_slot, cell_row, cols, vals, rhs,
             rows):
    """The Poisson system of the correction on the cells holding material (theta > 0).

    Numbers those cells (``cell_row``, -1 elsewhere; ``rows[r]``: the cell of row r) and
    writes the (2D + 1)-point Laplacian in unit spacing in the 3^D-slot ELL form of
    ``multigrid``: an empty neighbour cell is held at q = 0 (air), a wall is a Neumann
    boundary. rhs_r = density - 1, the excess volume fraction. Near a free surface the
    density reads low because part of the kernel lies in air, so only an excess counts in a
    cell whose 3^D neighbourhood holds a cell with theta < ``wet``, or that lies against a wall
    the material has left (``contact``: the pressure step's wall contact of each node and wall
    axis). A cell inside an obstacle (``static_slot`` < 0) is a wall; in a cell an obstacle
    cuts, or next to one, only an excess counts too: the hat-kernel density reads low there
    (part of the kernel lies in the solid), and a deficit would pull particles into the
    obstacle. Returns (number of rows, whether any row touches air)."""
    D = len(cells)
    NS = cols.shape[1]
    centre = NS // 2
    ns = np.empty(D, dtype=np.int64)
    cs = np.empty(D, dtype=np.int64)
    node_strides(cells, ns)
    nc = cell_strides(cells, cs)
    n = 0
    for c in range(nc):
        if theta[c] > 0.0 and static_slot[c] >= 0:
            cell_row[c] = n
            rows[n] = c
            n += 1
        else:
            cell_row[c] = -1
    anchored = False
    cx = np.empty(D, dtype=np.int64)
    for r in range(n):
        c = rows[r]
        rem = c
        for k in range(D):
            cx[k] = rem % cells[k]
            rem //= cells[k]
        for s in range(NS):
            cols[r, s] = -1
            vals[r, s] = 0.0
        diag = 0.0
        p3 = 1
        for k in range(D):
            for step in (1, -1):
                j = cx[k] + step
                if j < 0 or j >= cells[k] or static_slot[c + step * cs[k]] < 0:
                    continue  # a wall or a solid: no flux
                diag += 1.0
                nb = cell_row[c + step * cs[k]]
                if nb >= 0:
                    s = centre + step * p3
                    cols[r, s] = nb
                    vals[r, s] = -1.0
                else:
                    anchored = True
            p3 *= 3
        cols[r, centre] = r
        vals[r, centre] = diag
        surface = _wall_released(cx, cells, ns, contact)
        if not surface:
            for b in range(NS):
                j = 0
                inside = True
                rem = b
                for k in range(D):
                    jk = cx[k] + rem % 3 - 1
                    rem //= 3
                    if jk < 0 or jk >= cells[k]:
                        inside = False
                        break
                    j += jk * cs[k]
                if inside and (theta[j] < wet or static_slot[j] != 0):
                    surface = True
                    break
        excess = density[c] - 1.0
        rhs[r] = max(excess, 0.0) if surface else excess
    return n, anchored


@njit(cache=True)
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


@njit(cache=True)
def _face_cells(face, k, cells, cs):
    """(index along k, flat index of the cell at index 0 along k with the face's other
    coordinates) of face ``face`` normal to axis k."""
    c = 0
    ik = 0
    for j in range(len(cells)):
        n = cells[j] + 1 if j == k else cells[j]
        ij = face % n
        face //= n
        if j == k:
            ik = ij
        else:
            c += ij * cs[j]
    return ik, c


@njit(cache=True)
def _faces(lo, hi, k, cells, cs, cell_row, static_slot, q, scale, dmax, f):
    """Faces lo to hi - 1 normal to axis k (``face_displacements``)."""
    for idx in range(lo, hi):
        ik, c = _face_cells(idx, k, cells, cs)
        b = c + ik * cs[k]
        if ik == 0 or ik == cells[k] or static_slot[b] < 0 or static_slot[b - cs[k]] < 0:
            f[idx] = 0.0
        else:
            f[idx] = _face(cell_row, q, b - cs[k], b, scale, dmax)


@njit(cache=True, parallel=True)
def face_displacements(cells, cell_row, static_slot, q, scale, dmax, faces):
    """d = -scale grad q on the inner faces normal to each axis (m), 0 on the walls and on
    the faces of cells inside obstacles (``static_slot`` < 0);
    ``faces[k]``: the faces normal to axis k."""
    D = len(cells)
    cs = np.empty(D, dtype=np.int64)
    nc = 1
    for k in range(D):
        cs[k] = nc
        nc *= cells[k]
    for k in range(D):
        f = faces[k]
        n = f.shape[0]
        for t in prange(CHUNKS):
            _faces(t * n // CHUNKS, (t + 1) * n // CHUNKS, k, cells, cs, cell_row, static_slot,
                   q, scale, dmax, f)
