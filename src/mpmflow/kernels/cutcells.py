"""Cells cut by fixed obstacles, 2D and 3D: their element integrals over the fluid part, and
the integrals over the obstacle's face that enter the pressure system.

The obstacles are given by their signed distance phi at the grid nodes (negative inside a
solid), interpolated multilinearly inside each cell, so the surface lies where the
interpolated phi is 0, off the grid lines. Each cut cell is divided into n^D sub-cells; a
sub-cell is fluid when phi at its centre is positive. On that staircase fluid region the
integrals are exact: 2^D Gauss points per fluid sub-cell give

* ``K[a, b]    = int grad N_a . grad N_b``,  ``C[a, b, k] = int N_a dN_b/dx_k``,
  ``V[a] = int N_a`` (as ``quadrature`` for a full cell, over the fluid part only),

and the divergence theorem on the staircase gives the obstacle's face term exactly,

* ``F[a, b, k] = int_{obstacle face in the cell} N_a N_b n_k ds``
  ``          = int (N_a dN_b/dx_k + N_b dN_a/dx_k) dV - sum over the cell's faces``,

where a face piece is subtracted when it is fluid on both sides (an inner face) or fluid on
this side and on the domain's boundary (a wall, whose own term is ``Wf``). n points out of
the fluid, into the solid. With these, the column at rest is exact around an obstacle: the
discrete Laplacian of a linear pressure equals the face terms of uniform gravity on the same
staircase (docs/method.md, "Obstacles"). The surface is placed to within h / n.

* ``Wf[f, a, b] = int_{fluid part of cell face f} N_a N_b ds`` for the faces f = 2 k + side
  on the domain's boundary (the walls' term of the right-hand side).
"""

import numpy as np
from numba import njit, prange

from .geometry import (cell_coords, cell_strides, corner_gradient, corner_offset,
                       corner_weight, locate, node_coords, node_strides)
from .quadrature import accumulate_point


@njit(cache=True)
def phi_at(phi_node, local, first, ns):
    """phi interpolated multilinearly at local coordinates ``local`` of the cell whose first
    node is ``first``."""
    val = 0.0
    for a in range(1 << local.shape[0]):
        val += corner_weight(a, local) * phi_node[first + corner_offset(a, ns)]
    return val


@njit(cache=True)
def _face_gauss_point(gp, k, side, centre, g, local):
    """Gauss point gp (of 2^(D-1)) of the face normal to axis k on ``side`` (0, 1) of the
    (sub-)cell with local centre ``centre`` (its offsets +-g already scaled), into
    ``local``."""
    bit = 0
    for kk in range(local.shape[0]):
        if kk == k:
            local[kk] = float(side)
        else:
            local[kk] = centre[kk] + (g if (gp >> bit) & 1 else -g)
            bit += 1


@njit(cache=True)
def _face_point(local, w, M, N):
    """Add a face quadrature point: M[a, b] += w N_a N_b."""
    NC = 1 << local.shape[0]
    for a in range(NC):
        N[a] = corner_weight(a, local)
    for a in range(NC):
        for b in range(NC):
            M[a, b] += w * N[a] * N[b]


@njit(cache=True, parallel=True)
def cut_cell_tensors(phi_node, h, cells, candidates, nsub, K, C, V, F, Wf, solid_parts):
    """The integrals of the candidate cells (flat indices ``candidates[m]``) into K[m], C[m],
    V[m], F[m], Wf[m] (module docstring); ``solid_parts[m]``: the number of solid sub-cells
    plus the solid sub-faces seen across the cell's inner faces (0: the cell is not cut)."""
    D = len(cells)
    NC = 1 << D
    ns = np.empty(D, dtype=np.int64)
    node_strides(cells, ns)
    g = 0.5 / np.sqrt(3.0)
    sub = h / nsub
    for m in prange(candidates.shape[0]):
        cx = np.empty(D, dtype=np.int64)
        cell_coords(candidates[m], cells, cx)
        first = 0
        for k in range(D):
            first += cx[k] * ns[k]
        local = np.empty(D)
        centre = np.empty(D)
        N = np.empty(NC)
        dN = np.empty((NC, D))
        M = np.empty((NC, NC))
        K[m] = 0.0
        C[m] = 0.0
        V[m] = 0.0
        F[m] = 0.0
        Wf[m] = 0.0
        solid = 0
        si = np.empty(D, dtype=np.int64)
        total = 1
        for k in range(D):
            total *= nsub
        # volume: 2^D Gauss points in each fluid sub-cell
        for q in range(total):
            rq = q
            for k in range(D):
                si[k] = rq % nsub
                rq //= nsub
                centre[k] = (si[k] + 0.5) / nsub
            if not phi_at(phi_node, centre, first, ns) > 0.0:
                solid += 1
                continue
            for gp in range(NC):
                for k in range(D):
                    local[k] = centre[k] + (g if (gp >> k) & 1 else -g) / nsub
                accumulate_point(local, sub**D / NC, h, K[m], C[m], V[m], N, dN)
        # faces: 2^(D-1) Gauss points on each sub-face
        nface = total // nsub
        for k in range(D):
            for side in range(2):
                j = cx[k] + (1 if side == 1 else -1)
                wall = j < 0 or j >= cells[k]
                other_first = first + (ns[k] if side == 1 else -ns[k])
                sign = 1.0 if side == 1 else -1.0
                for q in range(nface):
                    rq = q
                    for kk in range(D):
                        if kk == k:
                            centre[kk] = 0.5 / nsub if side == 0 else 1.0 - 0.5 / nsub
                        else:
                            centre[kk] = (rq % nsub + 0.5) / nsub
                            rq //= nsub
                    if not phi_at(phi_node, centre, first, ns) > 0.0:
                        continue  # solid on this side: part of the obstacle's face, or no face
                    if not wall:
                        centre[k] = 1.0 - centre[k]  # the mirrored sub-cell across the face
                        fluid_other = phi_at(phi_node, centre, other_first, ns) > 0.0
                        if not fluid_other:
                            solid += 1
                            continue  # fluid here, solid there: a piece of obstacle face
                    M[:] = 0.0
                    for gp in range(1 << (D - 1)):
                        _face_gauss_point(gp, k, side, centre, g / nsub, local)
                        _face_point(local, sub ** (D - 1) / (1 << (D - 1)), M, N)
                    for a in range(NC):
                        for b in range(NC):
                            F[m, a, b, k] -= sign * M[a, b]
                            if wall:
                                Wf[m, 2 * k + side, a, b] += M[a, b]
        for a in range(NC):
            for b in range(NC):
                for k in range(D):
                    F[m, a, b, k] += C[m, a, b, k] + C[m, b, a, k]
        solid_parts[m] = solid


@njit(cache=True)
def face_mass(h, D, Wf):
    """``Wf[f, a, b]`` of a whole cell (every face fluid): int N_a N_b over face f."""
    NC = 1 << D
    Wf[:] = 0.0
    g = 0.5 / np.sqrt(3.0)
    local = np.empty(D)
    centre = np.full(D, 0.5)
    N = np.empty(NC)
    for k in range(D):
        for side in range(2):
            for gp in range(1 << (D - 1)):
                _face_gauss_point(gp, k, side, centre, g, local)
                _face_point(local, h ** (D - 1) / (1 << (D - 1)), Wf[2 * k + side], N)


@njit(cache=True)
def interpolate_phi(phi_node, x, p, inv_h, cells, ns, grad):
    """phi and its gradient (into ``grad``) at particle p, multilinear in its cell."""
    D = len(cells)
    local = np.empty(D)
    first = locate(x, p, inv_h, cells, ns, local)
    val = 0.0
    for k in range(D):
        grad[k] = 0.0
    for a in range(1 << D):
        phi = phi_node[first + corner_offset(a, ns)]
        val += corner_weight(a, local) * phi
        for k in range(D):
            grad[k] += corner_gradient(a, k, local, inv_h) * phi
    return val


@njit(cache=True, parallel=True)
def push_out(x, v, phi_node, h, cells, margin):
    """Particles inside an obstacle (interpolated phi < margin) moved out along the gradient
    of phi to phi = margin (a few Newton steps), their velocity into the solid removed.
    Returns how many were moved."""
    D = len(cells)
    ns = np.empty(D, dtype=np.int64)
    node_strides(cells, ns)
    inv_h = 1.0 / h
    moved = 0
    for p in prange(x.shape[0]):
        grad = np.empty(D)
        phi = interpolate_phi(phi_node, x, p, inv_h, cells, ns, grad)
        if phi >= margin:
            continue
        moved += 1
        for it in range(4):
            g2 = 0.0
            for k in range(D):
                g2 += grad[k] * grad[k]
            if g2 == 0.0:
                break
            step = (margin - phi) / g2
            for k in range(D):
                x[p, k] += step * grad[k]
            phi = interpolate_phi(phi_node, x, p, inv_h, cells, ns, grad)
            if phi >= margin:
                break
        g2 = 0.0
        vn = 0.0
        for k in range(D):
            g2 += grad[k] * grad[k]
            vn += v[p, k] * grad[k]
        if g2 > 0.0 and vn < 0.0:
            for k in range(D):
                v[p, k] -= vn * grad[k] / g2
    return moved


SLIVER = 0.5  # a cut cell with less fluid than this takes its volume fraction from beside


@njit(cache=True, parallel=True)
def sliver_fractions(cells, open_, theta):
    """The volume fraction of a cut cell whose fluid part is a sliver (open < SLIVER): the
    largest of its face neighbours' with open >= SLIVER (in place; unchanged without one).
    A sliver thinner than the particle spacing holds no particle centre even in still water,
    and read as empty it would put a free surface against the obstacle."""
    D = len(cells)
    cs = np.empty(D, dtype=np.int64)
    n = cell_strides(cells, cs)
    for c in prange(n):
        if not 0.0 < open_[c] < SLIVER:
            continue
        best = -1.0
        cx = np.empty(D, dtype=np.int64)
        cell_coords(c, cells, cx)
        for k in range(D):
            for step in (-1, 1):
                j = cx[k] + step
                if j < 0 or j >= cells[k]:
                    continue
                nb = c + step * cs[k]
                if open_[nb] >= SLIVER and theta[nb] > best:
                    best = theta[nb]
        if best >= 0.0:
            theta[c] = best


@njit(cache=True)
def extend_velocity(onode, cells, node_mass, v_old, v_star):
    """The velocities of obstacle nodes no particle reaches (zero mass): the mass-weighted
    mean of their neighbours' that carry mass (in place). Such a node sits inside the solid
    at a corner of a cut cell, whose integrals still read its velocity."""
    D = len(cells)
    ns = np.empty(D, dtype=np.int64)
    node_strides(cells, ns)
    NS = 1
    for k in range(D):
        NS *= 3
    ix = np.empty(D, dtype=np.int64)
    for e in range(onode.shape[0]):
        i = onode[e]
        if node_mass[i] > 0.0:
            continue
        node_coords(i, cells, ix)
        total = 0.0
        for k in range(D):
            v_old[i, k] = 0.0
            v_star[i, k] = 0.0
        for s in range(NS):
            j = i
            rs = s
            inside = True
            for k in range(D):
                d = rs % 3 - 1
                rs //= 3
                if ix[k] + d < 0 or ix[k] + d > cells[k]:
                    inside = False
                    break
                j += d * ns[k]
            if not inside or node_mass[j] <= 0.0:
                continue
            m = node_mass[j]
            total += m
            for k in range(D):
                v_old[i, k] += m * v_old[j, k]
                v_star[i, k] += m * v_star[j, k]
        if total > 0.0:
            for k in range(D):
                v_old[i, k] /= total
                v_star[i, k] /= total
