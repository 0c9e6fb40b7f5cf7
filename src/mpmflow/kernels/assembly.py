"""The pressure Poisson system of eq. (13) on the node grid, 2D and 3D: the matrix rows in
ELL form with the sub-cell (ghost-fluid) free surface, and the right-hand side with the
wall term. Element integrals come as stacked arrays ``K[s], C[s], V[s]`` (``quadrature``)
and ``cell_slot[c]`` says which slot cell c uses: -1 = left out of the system, 0 = the
full-cell Gauss tensors, s > 0 = the cell's own material-point tensors.

Free-surface treatment (``subcell``): the coupling of an unknown node i to a node g outside
the unknowns uses the pressure extrapolated linearly along the edge i-g to p = 0 at the
surface (``ghost.ghost_factor``); it changes only the diagonal, so the matrix stays symmetric
positive definite. Without ``subcell`` nodes outside the unknowns have p = 0.
"""

import numpy as np
from numba import njit, prange

from .geometry import corner_offset
from .ghost import ghost_factor
from .parallel import CHUNKS
from .stencil import (coords, first_of_slab, next_in_slab, node_cell, node_cells, node_stencil,
                      tables)


@njit(cache=True, parallel=True)
def assemble_matrix(cells, cell_slot, K, node_row, node_f, subcell, theta_min, cols, vals,
                    anchored):
    """Assemble L of eq. (14) row by row in ELL form.

    Row r (the unknown at node i) holds its coupling to the neighbour at offset d in slot
    sum_k (d_k + 1) 3^k (column -1 where there is none); with rows numbered in node order the
    slots are in increasing column order. Couplings to nodes that are not unknowns go to the
    diagonal through the ghost extrapolation (``subcell``) or vanish (p = 0 there).
    ``anchored[r]`` tells whether row r couples to such a node (a system with no anchored row
    is pure Neumann, hence singular). Slabs of nodes (one index along the last axis) are dealt
    round the chunks, so every chunk gets rows wherever the water is.
    """
    D = len(cells)
    ns, cs, slot, offset = tables(cells)
    NS = offset.shape[0]
    centre = NS // 2
    nslabs = cells[D - 1] + 1
    per = 1
    for k in range(D - 1):
        per *= cells[k] + 1
    for t in prange(CHUNKS):
        S = np.empty(NS)
        ix = np.empty(D, dtype=np.int64)
        slots = np.empty(1 << D, dtype=np.int64)
        local = np.empty(1 << D, dtype=np.int64)
        base = np.empty(1 << D, dtype=np.int64)
        for sl in range(t, nslabs, CHUNKS):
            first_of_slab(sl, cells, ix)
            for i in range(sl * per, (sl + 1) * per):
                r = node_row[i]
                if r >= 0:
                    node_stencil(ix, cells, ns, cs, cell_slot, K, slot, S, slots, local, base)
                    anchored[r] = False
                    for s in range(NS):
                        sv = S[s]
                        if s == centre or sv == 0.0:
                            continue
                        j = i + offset[s]
                        if node_row[j] < 0:
                            anchored[r] = True
                            if subcell and sv < 0.0:
                                S[centre] += sv * ghost_factor(node_f[i], node_f[j], theta_min)
                            S[s] = 0.0
                    for s in range(NS):
                        sv = S[s]
                        if sv == 0.0:
                            cols[r, s] = -1
                            vals[r, s] = 0.0
                        else:
                            cols[r, s] = node_row[i + offset[s]]
                            vals[r, s] = sv
                next_in_slab(ix, cells)


@njit(cache=True)
def wall_integral(ix, i, cells, ns, cs, h, cell_slot, static_slot, Wf, vstar, contact):
    """sum over the wetted wall faces through node i of int N_i (v*.n) ds, counting only the
    nodes in contact (a node whose wall released the material contributes zero: natural
    condition). On a face v*.n is interpolated multilinearly from its 2^(D-1) nodes, whose
    mass matrix has h^(D-1) / prod(3 or 6) entries (the corner itself: 3 per axis, a
    neighbour along the face: 6). In a cell an obstacle cuts (``static_slot`` >= 1) only the
    fluid part of the face counts: ``Wf[s, 2 k + side]`` is its mass matrix
    (``cutcells``)."""
    D = len(cells)
    total = 0.0
    for k in range(D):
        for side in range(2):
            wall = 0 if side == 0 else cells[k]
            if ix[k] != wall:
                continue
            sign = -1.0 if side == 0 else 1.0
            on = 0 if side == 0 else 1  # corner bit along k of the nodes on this wall
            for b in range(1 << D):
                if ((b >> k) & 1) == on:
                    continue  # not a cell on this wall
                c, first, a = node_cell(ix, b, cells, ns, cs)
                if c < 0 or cell_slot[c] < 0:
                    continue
                ss = static_slot[c]
                if ss >= 1:
                    face = 0.0
                    for corner in range(1 << D):
                        jn = first + corner_offset(corner, ns)
                        if contact[jn, k]:
                            face += Wf[ss, 2 * k + side, a, corner] * sign * vstar[jn, k]
                    total += face
                    continue
                face = 0.0
                for corner in range(1 << D):
                    if ((corner >> k) & 1) != on:
                        continue
                    jn = first
                    denom = 1.0
                    for m in range(D):
                        if (corner >> m) & 1:
                            jn += ns[m]
                        if m != k:
                            denom *= 3.0 if ((corner >> m) & 1) == ((a >> m) & 1) else 6.0
                    vn = sign * vstar[jn, k] if contact[jn, k] else 0.0
                    face += vn / denom
                total += h ** (D - 1) * face
    return total


@njit(cache=True)
def obstacle_integral(ix, cells, ns, cs, cell_slot, static_slot, F, vstar, ocontact):
    """sum over the node's cut cells in the system of int N_i (v*.n) ds over the obstacle's
    face, counting the obstacle nodes in contact (``F``: ``cutcells``)."""
    D = len(cells)
    total = 0.0
    for b in range(1 << D):
        c, first, a = node_cell(ix, b, cells, ns, cs)
        if c < 0 or cell_slot[c] < 0 or static_slot[c] < 1:
            continue
        s = static_slot[c]
        for corner in range(1 << D):
            jn = first + corner_offset(corner, ns)
            if ocontact[jn]:
                for k in range(D):
                    total += F[s, a, corner, k] * vstar[jn, k]
    return total


@njit(cache=True)
def _rhs_rows(r0, r1, cells, h, cell_slot, C, V, node_vol, row_nodes, vstar, contact,
              wall_flux, expansion, rho_over_dt, static_slot, F, Wf, ocontact, rhs):
    """Rows r0 to r1 - 1 of ``assemble_rhs``."""
    D = len(cells)
    ns, cs, slot, offset = tables(cells)
    NC = 1 << D
    off = np.empty(NC, dtype=np.int64)
    for a in range(NC):
        o = 0
        for k in range(D):
            if (a >> k) & 1:
                o += ns[k]
        off[a] = o
    ix = np.empty(D, dtype=np.int64)
    slots = np.empty(NC, dtype=np.int64)
    local = np.empty(NC, dtype=np.int64)
    base = np.empty(NC, dtype=np.int64)
    for r in range(r0, r1):
        i = row_nodes[r]
        coords(i, cells, ix)
        b = 0.0
        vol = 0.0
        for m in range(node_cells(ix, cells, ns, cs, cell_slot, slots, local, base)):
            s, a = slots[m], local[m]
            vol += V[s, a]
            for bb in range(NC):
                j = base[m] + off[bb]
                acc = 0.0
                for k in range(D):
                    acc += C[s, a, bb, k] * vstar[j, k]
                b -= acc
        excess = node_vol[i] - vol
        if expansion > 0.0 and excess > 0.0:
            b += expansion * excess
        if wall_flux:
            b += wall_integral(ix, i, cells, ns, cs, h, cell_slot, static_slot, Wf, vstar,
                               contact)
            if F.shape[0] > 1:
                b += obstacle_integral(ix, cells, ns, cs, cell_slot, static_slot, F, vstar,
                                       ocontact)
        rhs[r] = rho_over_dt * b


@njit(cache=True, parallel=True)
def assemble_rhs(cells, h, cell_slot, C, V, node_vol, row_nodes, vstar, contact, wall_flux,
                 expansion, rho_over_dt, static_slot, F, Wf, ocontact, rhs):
    """Right-hand side of eq. (13) for every unknown (``row_nodes[r]``: the node of row r).

    rhs_i = -(rho/dt) sum_e C_e[a_i, b, k] v*_{b,k}                (divergence, eq. 15)
            + (rho/dt) int_{wetted walls in contact} N_i v*.n ds   (if wall_flux)
            + (rho/dt) int_{obstacle faces in contact} N_i v*.n ds (if wall_flux)
            + (rho/dt) expansion * max(vol_i - V_i, 0)
    ``contact[i, k]`` marks wall nodes whose wall normal to axis k holds the material,
    ``ocontact[i]`` obstacle nodes that hold it; ``static_slot``, ``F``, ``Wf``: the cut
    cells' slots and face terms (``mpmflow.obstacles``).
    ``vol_i`` = sum_p N_i V_p is the material volume the particles give node i and
    V_i = sum_e V_e[a_i] the node's volume in the system: the last term is the earlier
    (velocity) density correction, div v = expansion (vol_i/V_i - 1) where particles are
    packed (``expansion`` = beta/dt; 0 = off).
    """
    n = row_nodes.shape[0]
    nchunks = min(CHUNKS, max(n, 1))
    for chunk in prange(nchunks):
        _rhs_rows(chunk * n // nchunks, (chunk + 1) * n // nchunks, cells, h, cell_slot, C, V,
                  node_vol, row_nodes, vstar, contact, wall_flux, expansion, rho_over_dt,
                  static_slot, F, Wf, ocontact, rhs)
