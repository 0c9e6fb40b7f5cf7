"""The implicit viscous predictor (docs/method.md, "Viscous materials"), 2D and 3D.

Before the pressure step, the predicted velocity v* (gravity only) becomes the solution u of

    M/dt (u - v*) = -K_visc u,   (K_visc u)_(i,k) = sum_e c_e int dN_i/dx_m (du_k/dx_m + du_m/dx_k)

the backward-Euler step of the full deviatoric stress tau = 2 eta D(u) (not the Laplacian
eta lap u, which is the same only for constant viscosity in the interior; at a free surface
the two differ by the term that carries half of a standing wave's damping). M is the lumped
nodal mass, c_e = eta_e w_e with eta_e the cell's viscosity (``rheology``, at the strain rate
and pressure of the step's start) and w_e its fluid fraction (1 for full and enclosed cells,
theta for partial ones, times the part an obstacle leaves open); the element integrals are
the full-cell Gauss tensors T[a, b, m, k] = int dN_a/dx_m dN_b/dx_k. The free surface is
traction-free (the natural condition). Walls: the normal component of a wall node keeps v*
(the pressure step's contact condition decides it); a no-slip wall, and a no-slip obstacle,
hold the tangential velocity at 0 where the material presses on them or rests.

The system is symmetric positive definite; it is stored as D x D blocks in ELL form (block
(k, m): rows of component k, columns of component m; 3^D slots as in ``assembly``) and
solved by conjugate gradients preconditioned with one multigrid V-cycle (``multigrid``) of
each diagonal block (the separate-component preconditioner of elasticity solvers).
"""

import numpy as np
from numba import njit, prange
from numba.typed import List

from . import multigrid, rheology
from .geometry import corner_gradient, corner_offsets, node_strides
from .parallel import CHUNKS
from .stencil import first_of_slab, next_in_slab, node_cell, tables
from .walls import normal_velocity

# the rows of the system: row[i, k] >= 0 numbers the unknown component k of node i
FREE, HELD = 0, -1  # before numbering: an unknown; a component kept at its value in u


@njit(cache=True)
def gauss_gradients(cells, h):
    """T[a, b, m, k] = int over a full cell of dN_a/dx_m dN_b/dx_k (2^D Gauss points, exact
    for multilinear N)."""
    D = len(cells)
    NC = 1 << D
    T = np.zeros((NC, NC, D, D))
    g = 0.5 / np.sqrt(3.0)
    frac = np.empty(D)
    w = h ** D / NC
    inv_h = 1.0 / h
    for q in range(NC):
        for k in range(D):
            frac[k] = 0.5 + g if (q >> k) & 1 else 0.5 - g
        for a in range(NC):
            for b in range(NC):
                for m in range(D):
                    ga = corner_gradient(a, m, frac, inv_h)
                    for k in range(D):
                        T[a, b, m, k] += w * ga * corner_gradient(b, k, frac, inv_h)
    return T


@njit(cache=True, parallel=True)
def cell_viscosity(cells, h, theta, open_, enclosed, full, v, p_node, model, par, eta,
                   weight):
    """Each cell's viscosity eta (Pa s) at the strain rate of the nodal velocity ``v`` at its
    centre and the mean of its corners' pressure (negative counts as 0), and
    ``weight`` = eta x its fluid fraction; 0 in cells without material."""
    D = len(cells)
    NC = 1 << D
    ns = np.empty(D, dtype=np.int64)
    node_strides(cells, ns)
    off = np.empty(NC, dtype=np.int64)
    corner_offsets(ns, off)
    nc = theta.shape[0]
    inv_h = 1.0 / h
    for t in prange(CHUNKS):
        grad = np.empty((D, D))
        centre = np.full(D, 0.5)
        for c in range(t * nc // CHUNKS, (t + 1) * nc // CHUNKS):
            if not (theta[c] > 0.0 or enclosed[c]):
                eta[c] = 0.0
                weight[c] = 0.0
                continue
            r = c
            first = 0
            for k in range(D):
                first += (r % cells[k]) * ns[k]
                r //= cells[k]
            grad[:] = 0.0
            p = 0.0
            for a in range(NC):
                i = first + off[a]
                p += max(p_node[i], 0.0)
                for m in range(D):
                    g = corner_gradient(a, m, centre, inv_h)
                    for k in range(D):
                        grad[m, k] += g * v[i, k]
            rate2 = 0.0
            for m in range(D):
                for k in range(D):
                    d = 0.5 * (grad[m, k] + grad[k, m])
                    rate2 += 2.0 * d * d
            e = rheology.viscosity(model, par, np.sqrt(rate2), p / NC)
            fraction = 1.0 if (theta[c] >= full or enclosed[c]) else theta[c]
            eta[c] = e
            weight[c] = e * fraction * open_[c]


@njit(cache=True)
def number_unknowns(node_mass, wall_node, wall_axis, wall_sign, no_slip, onode, onormal,
                    ono_slip, vstar, u, row, off):
    """The unknowns and held values of the system: ``u`` = v* with the held tangential
    components of no-slip contacts set to 0; ``row[i, k]`` the unknown's number (component
    by component, each in node order), -1 where held or massless; ``off`` (D + 1) the first
    row of each component. Returns the number of unknowns."""
    nn, D = u.shape
    u[:] = vstar
    for i in range(nn):
        for k in range(D):
            row[i, k] = FREE if node_mass[i] > 0.0 else HELD
    for e in range(wall_node.shape[0]):
        i, k = wall_node[e], wall_axis[e]
        if node_mass[i] <= 0.0:
            continue
        row[i, k] = HELD
        if no_slip and wall_sign[e] * vstar[i, k] >= 0.0:
            for m in range(D):
                if m != k:
                    row[i, m] = HELD
                    u[i, m] = 0.0
    for e in range(onode.shape[0]):
        i = onode[e]
        if not ono_slip[e] or node_mass[i] <= 0.0:
            continue
        if normal_velocity(vstar, i, onormal, e) >= 0.0:
            for k in range(D):
                row[i, k] = HELD
                u[i, k] = 0.0
    n = 0
    for k in range(D):
        off[k] = n
        for i in range(nn):
            if row[i, k] == FREE:
                row[i, k] = n
                n += 1
    off[D] = n
    return n


@njit(cache=True)
def _node_rows(i, ix, cells, ns, cs, slot, offset, T, Kg, weight, node_mass, dt, u, row, off,
               cols, vals, rhs, node, S):
    """The rows of node i (one per unknown component)."""
    D = len(cells)
    NC = 1 << D
    NS = offset.shape[0]
    centre = NS // 2
    for k in range(D):
        r = row[i, k]
        if r < 0:
            continue
        S[:] = 0.0
        for b in range(NC):
            c, first, a = node_cell(ix, b, cells, ns, cs)
            if c < 0:
                continue
            w = weight[c]
            if w == 0.0:
                continue
            for bb in range(NC):
                s = slot[a, bb]
                for m in range(D):
                    val = T[a, bb, m, k]
                    if m == k:
                        val += Kg[a, bb]
                    S[m, s] += w * val
        S[k, centre] += node_mass[i] / dt
        rhs[r] = node_mass[i] / dt * u[i, k]
        node[r] = i
        for m in range(D):
            for s in range(NS):
                sv = S[m, s]
                j = i + offset[s]
                if sv != 0.0 and row[j, m] >= 0:
                    cols[m, r, s] = row[j, m] - off[m]
                    vals[m, r, s] = sv
                else:
                    cols[m, r, s] = -1
                    vals[m, r, s] = 0.0
                    if sv != 0.0:
                        rhs[r] -= sv * u[j, m]


@njit(cache=True, parallel=True)
def assemble(cells, T, weight, node_mass, dt, u, row, off, cols, vals, rhs, node):
    """The system's blocks (``cols[m], vals[m]``: the couplings of every row to component m,
    columns numbered within component m), right-hand side (the held values moved to it) and
    the node of each row. Slabs of nodes are dealt round the chunks as in ``assembly``."""
    D = len(cells)
    ns, cs, slot, offset = tables(cells)
    NC = 1 << D
    Kg = np.zeros((NC, NC))
    for a in range(NC):
        for b in range(NC):
            for m in range(D):
                Kg[a, b] += T[a, b, m, m]
    nslabs = cells[D - 1] + 1
    per = 1
    for k in range(D - 1):
        per *= cells[k] + 1
    for t in prange(CHUNKS):
        ix = np.empty(D, dtype=np.int64)
        S = np.empty((D, offset.shape[0]))
        for sl in range(t, nslabs, CHUNKS):
            first_of_slab(sl, cells, ix)
            for i in range(sl * per, (sl + 1) * per):
                _node_rows(i, ix, cells, ns, cs, slot, offset, T, Kg, weight, node_mass, dt, u,
                           row, off, cols, vals, rhs, node, S)
                next_in_slab(ix, cells)


@njit(cache=True)
def _apply(cols, vals, off, x, y, tmp):
    """y = A x, block by block."""
    D = cols.shape[0]
    for k in range(D):
        lo, hi = off[k], off[k + 1]
        y[lo:hi] = 0.0
        for m in range(D):
            if hi > lo and off[m + 1] > off[m]:
                multigrid.matvec(cols[m, lo:hi], vals[m, lo:hi], x[off[m]:off[m + 1]],
                                 tmp[:hi - lo])
                y[lo:hi] += tmp[:hi - lo]


@njit(cache=True)
def worst_row(cols, vals, off, x, rhs):
    """The row of the largest |rhs - A x| (NaN counts as largest)."""
    n = rhs.shape[0]
    r = np.empty(n)
    _apply(cols, vals, off, x, r, np.empty(n))
    worst = 0
    big = -1.0
    for i in range(n):
        a = abs(rhs[i] - r[i])
        if not a <= big:
            big = a
            worst = i
            if a != a:
                break
    return worst


@njit(cache=True)
def solve(cols, vals, node, off, cells, rhs, x, tol, maxiter, sweeps):
    """Block-preconditioned CG from the initial guess in x (updated in place); stops when
    ||rhs - A x|| <= tol ||rhs||. Returns (iterations, relative residual)."""
    D = len(cells)
    n = rhs.shape[0]
    dims = np.empty(D, dtype=np.int64)
    for k in range(D):
        dims[k] = cells[k] + 1
    setups = List()
    work = 0
    NS = cols.shape[2]
    for k in range(D):
        lo, hi = off[k], off[k + 1]
        if hi > lo:
            setup = multigrid.build_hierarchy(cols[k, lo:hi], vals[k, lo:hi], node[lo:hi],
                                              dims, multigrid.COARSEST)
        else:  # no unknown of this component: a 1 x 1 stand-in, never applied
            one = np.full((1, NS), -1, dtype=np.int64)
            one[0, NS // 2] = 0
            ones = np.zeros((1, NS))
            ones[0, NS // 2] = 1.0
            setup = multigrid.build_hierarchy(one, ones, np.zeros(1, dtype=np.int64), dims,
                                              multigrid.COARSEST)
        setups.append(setup)
        work = max(work, setup[0][-1])
    b = np.zeros(work)
    z = np.zeros(work)
    w = np.zeros(work)
    tmp = np.empty(n)
    bnorm = np.sqrt(multigrid.dot(rhs, rhs))
    if bnorm == 0.0:
        x[:] = 0.0
        return 0, 0.0
    r = np.empty(n)
    _apply(cols, vals, off, x, r, tmp)
    r[:] = rhs - r
    rnorm = np.sqrt(multigrid.dot(r, r))
    if rnorm <= tol * bnorm:
        return 0, rnorm / bnorm
    zz = np.empty(n)
    p = np.empty(n)
    q = np.empty(n)
    it = 0
    rz = 0.0
    while True:
        for k in range(D):
            lo, hi = off[k], off[k + 1]
            if hi == lo:
                continue
            s = setups[k]
            b[:hi - lo] = r[lo:hi]
            multigrid.vcycle(s[0], s[1], s[2], s[3], s[4], s[5], s[6], s[7], b, z, w, sweeps)
            zz[lo:hi] = z[:hi - lo]
        rz_new = multigrid.dot(r, zz)
        if it == 0:
            p[:] = zz
        else:
            p[:] = zz + (rz_new / rz) * p
        rz = rz_new
        if it >= maxiter:
            break
        it += 1
        _apply(cols, vals, off, p, q, tmp)
        alpha = rz / multigrid.dot(p, q)
        x += alpha * p
        r -= alpha * q
        if np.sqrt(multigrid.dot(r, r)) <= tol * bnorm:
            break
    _apply(cols, vals, off, x, q, tmp)
    q[:] = rhs - q
    return it, np.sqrt(multigrid.dot(q, q)) / bnorm
