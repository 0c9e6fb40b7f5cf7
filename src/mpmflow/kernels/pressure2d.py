"""Pressure Poisson system (eq. 13), ghost pressures and corrector (eq. 16) on the 2D grid.

Element integrals come as stacked arrays ``K[s], C[s], V[s]`` (see ``quadrature2d``) and
``cell_slot[c]`` says which slot cell c uses: -1 = left out of the system (sparse cell),
0 = the full-cell Gauss tensors, s > 0 = the cell's own material-point tensors.

Free-surface treatment (``subcell``): a node's volume fraction ``f`` is the mean of its
cells' volume fractions; the surface is the f = 0.5 level. The coupling of an unknown
node i to a node g outside the fluid uses the pressure extrapolated linearly along the
edge i-g to p = 0 at the surface, ``p_g = (1 - 1/theta) p_i`` with
``theta = (f_i - 1/2) / (f_i - f_g)`` the fractional distance from i to the surface. This
is the ghost-fluid method of Gibou et al. (2002); it changes only the diagonal, so the
matrix stays symmetric positive definite. With ``subcell`` off, nodes outside the
unknown set have p = 0 (the paper's free-surface nodes).
"""

import numpy as np
from numba import njit, prange

from .parallel import CHUNKS



@njit(cache=True, parallel=True)
def nodal_fraction_2d(ncx, ncy, theta, node_f):
    """Nodal volume fraction: mean of the node's in-domain cells' theta, each clipped to 1."""
    nnx = ncx + 1
    for t in prange(CHUNKS):
        for iy in range(t, ncy + 1, CHUNKS):
            for ix in range(nnx):
                fsum = 0.0
                ncell = 0
                for cy in range(max(iy - 1, 0), min(iy + 1, ncy)):
                    for cx in range(max(ix - 1, 0), min(ix + 1, ncx)):
                        fsum += min(theta[cx + ncx * cy], 1.0)
                        ncell += 1
                node_f[ix + nnx * iy] = fsum / ncell


@njit(cache=True, parallel=True)
def enclosed_cells_2d(ncx, ncy, node_f, enclosed):
    """Cells whose four nodes all lie inside the fluid (f > 1/2)."""
    nnx = ncx + 1
    for t in prange(CHUNKS):
        for cy in range(t, ncy, CHUNKS):
            for cx in range(ncx):
                i = cx + nnx * cy
                enclosed[cx + ncx * cy] = (node_f[i] > 0.5 and node_f[i + 1] > 0.5 and
                                           node_f[i + nnx] > 0.5 and node_f[i + nnx + 1] > 0.5)


@njit(cache=True, parallel=True)
def classify_nodes_2d(ncx, ncy, cell_slot, node_f, subcell, node_row):
    """Number the unknowns; returns their count.

    A node is an unknown when all its cells inside the domain take part in the system and,
    with ``subcell``, its volume fraction exceeds 1/2. Unknowns are numbered in node order.
    """
    nnx = ncx + 1
    nny = ncy + 1
    for t in prange(CHUNKS):
        for iy in range(t, nny, CHUNKS):
            for ix in range(nnx):
                i = ix + nnx * iy
                unknown = not (subcell and node_f[i] <= 0.5)
                for cy in range(max(iy - 1, 0), min(iy + 1, ncy)):
                    for cx in range(max(ix - 1, 0), min(ix + 1, ncx)):
                        if cell_slot[cx + ncx * cy] < 0:
                            unknown = False
                node_row[i] = 0 if unknown else -1
    return _number(node_row)


@njit(cache=True)
def _number(node_row):
    """Number the entries >= 0 in order; returns how many."""
    nrows = 0
    for i in range(node_row.shape[0]):
        if node_row[i] >= 0:
            node_row[i] = nrows
            nrows += 1
    return nrows


@njit(cache=True, inline="always")
def _ghost_factor(f_i, f_g, theta_min):
    """(1 - 1/theta): p_g = factor * p_i, linear extrapolation to p = 0 at f = 1/2."""
    if f_i - f_g <= 0.0:
        return 0.0
    t = (f_i - 0.5) / (f_i - f_g)
    if t >= 1.0:
        return 0.0
    if t < theta_min:
        t = theta_min
    return 1.0 - 1.0 / t


@njit(cache=True, inline="always")
def _cells_of_node(ix, iy, ncx, ncy, cell_slot, slots, local, base):
    """The cells around node (ix, iy) that take part in the system: their slot, the node's
    local index in each, and each cell's first node. Returns how many (at most 4)."""
    nnx = ncx + 1
    n = 0
    for dcy in range(-1, 1):
        cy = iy + dcy
        if cy < 0 or cy >= ncy:
            continue
        for dcx in range(-1, 1):
            cx = ix + dcx
            if cx < 0 or cx >= ncx:
                continue
            s = cell_slot[cx + ncx * cy]
            if s < 0:
                continue
            slots[n] = s
            local[n] = -dcx + 2 * (-dcy)
            base[n] = cx + nnx * cy
            n += 1
    return n


@njit(cache=True)
def _stencil(ix, iy, ncx, ncy, cell_slot, K, S, slots, local, base):
    """Couplings sum_e K_e[a_i, b_j] of node (ix, iy) to its 3x3 neighbours, S[dy+1, dx+1].

    ``slots``, ``local``, ``base``: scratch arrays of 4 for ``_cells_of_node``."""
    S[:] = 0.0
    n = _cells_of_node(ix, iy, ncx, ncy, cell_slot, slots, local, base)
    for k in range(n):
        a = local[k]
        for b in range(4):
            # node b of the cell sits at offset (b - a) from node i, per axis
            S[(b >> 1) - (a >> 1) + 1, (b & 1) - (a & 1) + 1] += K[slots[k], a, b]
    return n


@njit(cache=True, parallel=True)
def assemble_matrix_2d(ncx, ncy, cell_slot, K, node_row, node_f, subcell, theta_min, cols, vals,
                       anchored):
    """Assemble L of eq. (14) row by row in ELL form.

    Row r (the unknown at node i) holds its coupling to the neighbour at offset (dx, dy) in
    slot ``3*(dy+1) + (dx+1)`` (column -1 where there is none); with rows numbered in node
    order the slots are in increasing column order. Couplings to nodes that are not
    unknowns go to the diagonal through the ghost extrapolation (``subcell``) or vanish
    (p = 0 there). ``anchored[r]`` tells whether row r couples to such a node (a system with
    no anchored row is pure Neumann, hence singular).
    """
    for t in prange(CHUNKS):
        _matrix_rows(t, ncx, ncy, cell_slot, K, node_row, node_f, subcell, theta_min, cols,
                     vals, anchored)


@njit(cache=True)
def _matrix_rows(t, ncx, ncy, cell_slot, K, node_row, node_f, subcell, theta_min, cols, vals,
                 anchored):
    """The rows of the unknowns on node rows t, t + CHUNKS, t + 2 CHUNKS, ... (see
    ``assemble_matrix_2d``; rows far apart share the work out evenly wherever the water is)."""
    nnx = ncx + 1
    S = np.empty((3, 3))
    slots = np.empty(4, dtype=np.int64)
    local = np.empty(4, dtype=np.int64)
    base = np.empty(4, dtype=np.int64)
    for iy in range(t, ncy + 1, CHUNKS):
        for ix in range(nnx):
            i = ix + nnx * iy
            r = node_row[i]
            if r < 0:
                continue
            _stencil(ix, iy, ncx, ncy, cell_slot, K, S, slots, local, base)
            anchored[r] = False
            for dy in range(3):
                for dx in range(3):
                    sv = S[dy, dx]
                    if (dy == 1 and dx == 1) or sv == 0.0:
                        continue
                    j = (ix + dx - 1) + nnx * (iy + dy - 1)
                    if node_row[j] < 0:
                        anchored[r] = True
                        if subcell and sv < 0.0:
                            S[1, 1] += sv * _ghost_factor(node_f[i], node_f[j], theta_min)
                        S[dy, dx] = 0.0
            for dy in range(3):
                for dx in range(3):
                    slot = 3 * dy + dx
                    sv = S[dy, dx]
                    if sv == 0.0:
                        cols[r, slot] = -1
                        vals[r, slot] = 0.0
                    else:
                        cols[r, slot] = node_row[(ix + dx - 1) + nnx * (iy + dy - 1)]
                        vals[r, slot] = sv


@njit(cache=True, parallel=True)
def assemble_rhs_2d(ncx, ncy, spacing, cell_slot, C, V, node_vol, row_nodes, vstar, contact,
                    wall_flux, expansion, rho_over_dt, rhs):
    """Right-hand side of eq. (13) for every unknown (``row_nodes[r]``: the node of row r).

    rhs_i = -(rho/dt) sum_e C_e[a_i, b, k] v*_{b,k}                (divergence, eq. 15)
            + (rho/dt) int_{wetted walls in contact} N_i v*.n ds   (if wall_flux)
            + (rho/dt) expansion * max(vol_i - V_i, 0)
    ``contact[i, k]`` marks wall nodes whose wall normal to axis k holds the material.
    ``vol_i`` = sum_p N_i V_p is the material volume the particles give node i and
    V_i = sum_e V_e[a_i] the node's volume in the system: the last term asks for
    div v = expansion * (vol_i/V_i - 1) (1/s) where particles are packed tighter than the
    material's volume allows, so they spread out again (density correction;
    ``expansion`` = beta/dt). Only the excess counts: a deficit is what a node next to the
    free surface has by nature, and pulling particles into a deficit elsewhere packs their
    neighbours instead (measured: the wetted volume then drifts by 11% in the dam break).
    """
    n = row_nodes.shape[0]
    nchunks = min(CHUNKS, n)
    for chunk in prange(nchunks):
        _rhs_rows(chunk * n // nchunks, (chunk + 1) * n // nchunks, ncx, ncy, spacing,
                  cell_slot, C, V, node_vol, row_nodes, vstar, contact, wall_flux, expansion,
                  rho_over_dt, rhs)


@njit(cache=True)
def _rhs_rows(r0, r1, ncx, ncy, h, cell_slot, C, V, node_vol, row_nodes, vstar, contact,
              wall_flux, expansion, rho_over_dt, rhs):
    """Rows r0 to r1 - 1 of ``assemble_rhs_2d``."""
    nnx = ncx + 1
    slots = np.empty(4, dtype=np.int64)
    local = np.empty(4, dtype=np.int64)
    base = np.empty(4, dtype=np.int64)
    for r in range(r0, r1):
        i = row_nodes[r]
        ix = i % nnx
        iy = i // nnx
        b = 0.0
        vol = 0.0
        for k in range(_cells_of_node(ix, iy, ncx, ncy, cell_slot, slots, local, base)):
            s, a = slots[k], local[k]
            vol += V[s, a]
            for bb in range(4):
                j = base[k] + (bb & 1) + nnx * (bb >> 1)
                b -= C[s, a, bb, 0] * vstar[j, 0] + C[s, a, bb, 1] * vstar[j, 1]
        excess = node_vol[i] - vol
        if expansion > 0.0 and excess > 0.0:
            b += expansion * excess
        if wall_flux:
            b += _wall_integral(ix, iy, ncx, ncy, h, cell_slot, vstar, contact)
        rhs[r] = rho_over_dt * b


@njit(cache=True)
def _wall_integral(ix, iy, ncx, ncy, h, cell_slot, vstar, contact):
    """sum over wetted wall edges through node i of int N_i (v*.n) ds, nodes in contact only.

    Along an edge v*.n is interpolated linearly from its two nodes (1D mass matrix h/6 [2 1; 1 2]);
    a node whose wall released the material contributes zero (natural condition).
    """
    nnx = ncx + 1
    total = 0.0
    for k in range(2):
        pos = ix if k == 0 else iy
        top = ncx if k == 0 else ncy
        for side in range(2):
            if (side == 0 and pos != 0) or (side == 1 and pos != top):
                continue
            sign = -1.0 if side == 0 else 1.0
            i = ix + nnx * iy
            vi = sign * vstar[i, k] if contact[i, k] else 0.0
            for e in range(2):
                # neighbours along the wall: the other axis, one node down or up
                if k == 0:
                    jx, jy = ix, iy - 1 + 2 * e
                    cx, cy = (0 if side == 0 else ncx - 1), iy - 1 + e
                    if jy < 0 or jy > ncy:
                        continue
                else:
                    jx, jy = ix - 1 + 2 * e, iy
                    cx, cy = ix - 1 + e, (0 if side == 0 else ncy - 1)
                    if jx < 0 or jx > ncx:
                        continue
                if cell_slot[cx + ncx * cy] < 0:
                    continue
                j = jx + nnx * jy
                vj = sign * vstar[j, k] if contact[j, k] else 0.0
                total += h * (vi / 3.0 + vj / 6.0)
    return total


@njit(cache=True, parallel=True)
def ghost_pressures_2d(ncx, ncy, cell_slot, K, node_row, node_f, theta_min, p_node):
    """Pressure at nodes of the system that are not unknowns (in place, p_node of unknowns set).

    Each such node takes the coupling-weighted mean of the extrapolations from its unknown
    neighbours, the same extrapolations the assembly used; 0 where it has none.
    """
    nnx = ncx + 1
    nny = ncy + 1
    for t in prange(CHUNKS):
        S = np.empty((3, 3))
        slots = np.empty(4, dtype=np.int64)
        local = np.empty(4, dtype=np.int64)
        base = np.empty(4, dtype=np.int64)
        for iy in range(t, nny, CHUNKS):
            for ix in range(nnx):
                i = ix + nnx * iy
                if node_row[i] >= 0:
                    continue
                # no material around the node: none of its cells is in the system (a cell in
                # the system holds particles or is enclosed by nodes with f > 1/2)
                if node_f[i] == 0.0 or _stencil(ix, iy, ncx, ncy, cell_slot, K, S, slots, local,
                                                base) == 0:
                    p_node[i] = 0.0
                    continue
                num = 0.0
                den = 0.0
                for dy in range(3):
                    for dx in range(3):
                        sv = S[dy, dx]
                        if (dy == 1 and dx == 1) or sv >= 0.0:
                            continue
                        j = (ix + dx - 1) + nnx * (iy + dy - 1)
                        if node_row[j] < 0:
                            continue
                        num -= sv * _ghost_factor(node_f[j], node_f[i], theta_min) * p_node[j]
                        den -= sv
                p_node[i] = num / den if den > 0.0 else 0.0


@njit(cache=True, parallel=True)
def correct_velocity_2d(ncx, ncy, cell_slot, C, V, p_node, vstar, dt_over_rho, v_new):
    """Eq. (16) with the row-sum lumped volume matrix: v_i = v*_i - dt/rho (G p)_i / V_i.

    Nodes outside every cell of the system keep v* (they carry splashes only).
    """
    nnx = ncx + 1
    nny = ncy + 1
    for t in prange(CHUNKS):
        slots = np.empty(4, dtype=np.int64)
        local = np.empty(4, dtype=np.int64)
        base = np.empty(4, dtype=np.int64)
        for iy in range(t, nny, CHUNKS):
            for ix in range(nnx):
                i = ix + nnx * iy
                vol = 0.0
                g0 = 0.0
                g1 = 0.0
                for k in range(_cells_of_node(ix, iy, ncx, ncy, cell_slot, slots, local, base)):
                    s, a = slots[k], local[k]
                    vol += V[s, a]
                    for b in range(4):
                        pj = p_node[base[k] + (b & 1) + nnx * (b >> 1)]
                        g0 += C[s, a, b, 0] * pj
                        g1 += C[s, a, b, 1] * pj
                if vol > 0.0:
                    v_new[i, 0] = vstar[i, 0] - dt_over_rho * g0 / vol
                    v_new[i, 1] = vstar[i, 1] - dt_over_rho * g1 / vol
                else:
                    v_new[i, 0] = vstar[i, 0]
                    v_new[i, 1] = vstar[i, 1]
