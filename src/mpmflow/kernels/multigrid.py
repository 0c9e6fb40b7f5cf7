"""Geometric multigrid-preconditioned conjugate gradients on the node grid (2D).

Matrices are in ELL form: row r has up to 9 entries ``cols[r, s], vals[r, s]`` (col -1 =
empty), slot ``s = 3*(dy+1) + (dx+1)`` for the neighbour at node offset (dx, dy), so the
structure of the grid is kept at every level. ``node[r]`` is the node of row r on its
level's node grid (``nnx`` nodes per row of nodes).

Levels: a coarse node is an unknown when the fine node it coincides with (2I, 2J) is one;
prolongation is bilinear interpolation from the coarse unknowns (missing ones count as
zero), so P has full column rank and the Galerkin operator P^T A P stays symmetric
positive definite. Smoothing is four-colour Gauss-Seidel (colour = node parity in x and y;
in a 9-point stencil rows of one colour do not couple, so each colour is updated in
parallel), colours 0-3 before and 3-0 after the coarse correction, which makes the
V-cycle a symmetric preconditioner; the coarsest level is solved with a dense Cholesky
factor. Levels of at least ``PARALLEL_ROWS`` rows run their row loops and dot products in
parallel; the arithmetic is the same whatever the thread count, so the results are too. (McAdams, Sifakis & Teran 2010 use the same structure
with rediscretised coarse operators.)
"""

import numpy as np
from numba import njit, prange

from .parallel import CHUNKS, strips

COARSEST = 64  # unknowns at which the hierarchy stops and a dense factor takes over
PARALLEL_ROWS = 4096  # levels at least this large run their loops on all threads
STRIPS = 16  # Galerkin products of large levels: strips of node rows


@njit(cache=True)
def coarse_level(node, nnx, nny):
    """Coarse unknowns of a level: returns (coarse node per coarse row, nnx_c, nny_c,
    row of each coarse node or -1, P columns (n, 4) and weights (n, 4))."""
    nnx_c = nnx // 2 + 1
    nny_c = nny // 2 + 1
    crow = -np.ones(nnx_c * nny_c, dtype=np.int64)
    n = node.shape[0]
    nc = 0
    for r in range(n):
        ix = node[r] % nnx
        iy = node[r] // nnx
        if ix % 2 == 0 and iy % 2 == 0:
            crow[(ix // 2) + nnx_c * (iy // 2)] = 0
    cnode = np.empty(nnx_c * nny_c, dtype=np.int64)
    for i in range(nnx_c * nny_c):
        if crow[i] == 0:
            crow[i] = nc
            cnode[nc] = i
            nc += 1
    pcols = -np.ones((n, 4), dtype=np.int64)
    pw = np.zeros((n, 4))
    for r in range(n):
        ix = node[r] % nnx
        iy = node[r] // nnx
        k = 0
        for ey in range(2):
            if iy % 2 == 0 and ey == 1:
                break
            cy = iy // 2 + ey
            wy = 1.0 if iy % 2 == 0 else 0.5
            for ex in range(2):
                if ix % 2 == 0 and ex == 1:
                    break
                cx = ix // 2 + ex
                wx = 1.0 if ix % 2 == 0 else 0.5
                if cx < nnx_c and cy < nny_c:
                    c = crow[cx + nnx_c * cy]
                    if c >= 0:
                        pcols[r, k] = c
                        pw[r, k] = wx * wy
                        k += 1
    return cnode[:nc].copy(), nnx_c, nny_c, crow, pcols, pw


@njit(cache=True)
def galerkin(cols, vals, pcols, pw, cnode, nnx_c, node, nnx):
    """Coarse operator P^T A P in ELL form (9 slots per row).

    Fine row r adds only to the coarse rows it interpolates from, which lie within half a
    node row of it; so on large levels the fine rows are cut into strips of whole node rows
    (at least 2 each), and strips 0, 2, 4, ... are summed in parallel, then 1, 3, 5, ...
    (``node``, ``nnx``: the fine rows' nodes, ascending). The strips depend on the level
    only, so the sums do not depend on the thread count."""
    nc = cnode.shape[0]
    ccols = -np.ones((nc, 9), dtype=np.int64)
    cvals = np.zeros((nc, 9))
    cx = np.empty(nc, dtype=np.int64)
    cy = np.empty(nc, dtype=np.int64)
    for I in range(nc):
        cx[I] = cnode[I] % nnx_c
        cy[I] = cnode[I] // nnx_c
    n = cols.shape[0]
    if n < PARALLEL_ROWS:
        _galerkin_rows(0, n, cols, vals, pcols, pw, cx, cy, ccols, cvals)
        return ccols, cvals
    # strips of whole node rows, 2 at least: fine rows 2 node rows apart reach no common
    # coarse row; the work of a node row is its number of fine rows
    y0 = node[0] // nnx
    y1 = node[n - 1] // nnx + 1
    row_cum = np.searchsorted(node, (y0 + np.arange(y1 - y0 + 1)) * nnx)
    strip = np.empty(STRIPS + 1, dtype=np.int64)
    k = strips(row_cum, STRIPS, 2, strip)
    bounds = row_cum[strip[:k + 1]]
    for parity in range(2):
        _galerkin_strips(parity, bounds, k, cols, vals, pcols, pw, cx, cy, ccols, cvals)
    return ccols, cvals


@njit(cache=True, parallel=True)
def _galerkin_strips(parity, bounds, k, cols, vals, pcols, pw, cx, cy, ccols, cvals):
    for t in prange((k - parity + 1) // 2):
        u = 2 * t + parity
        _galerkin_rows(bounds[u], bounds[u + 1], cols, vals, pcols, pw, cx, cy, ccols, cvals)


@njit(cache=True)
def _galerkin_rows(r0, r1, cols, vals, pcols, pw, cx, cy, ccols, cvals):
    """The contributions of fine rows r0 to r1 - 1 to P^T A P."""
    for r in range(r0, r1):
        for a in range(4):
            I = pcols[r, a]
            if I < 0:
                break  # P's entries of a row come first, then -1
            wa = pw[r, a]
            for s in range(9):
                j = cols[r, s]
                if j < 0:
                    continue
                v = wa * vals[r, s]
                for b in range(4):
                    J = pcols[j, b]
                    if J < 0:
                        break
                    slot = 3 * (cy[J] - cy[I] + 1) + (cx[J] - cx[I] + 1)
                    ccols[I, slot] = J
                    cvals[I, slot] += v * pw[j, b]


@njit(cache=True)
def dense(cols, vals):
    n = cols.shape[0]
    A = np.zeros((n, n))
    for r in range(n):
        for s in range(9):
            if cols[r, s] >= 0:
                A[r, cols[r, s]] += vals[r, s]
    return A


@njit(cache=True)
def _matvec_rows(cols, vals, x, b, y, lo, hi, subtract):
    """y = A x (or b - A x when ``subtract``) for rows lo to hi - 1."""
    for r in range(lo, hi):
        acc = 0.0
        for s in range(9):
            c = cols[r, s]
            if c >= 0:
                acc += vals[r, s] * x[c]
        y[r] = b[r] - acc if subtract else acc


@njit(cache=True, parallel=True)
def _matvec_parallel(cols, vals, x, b, y, subtract):
    n = cols.shape[0]
    for t in prange(CHUNKS):
        _matvec_rows(cols, vals, x, b, y, t * n // CHUNKS, (t + 1) * n // CHUNKS, subtract)


@njit(cache=True)
def matvec(cols, vals, x, y):
    """y = A x."""
    if cols.shape[0] >= PARALLEL_ROWS:
        _matvec_parallel(cols, vals, x, y, y, False)
    else:
        _matvec_rows(cols, vals, x, y, y, 0, cols.shape[0], False)


@njit(cache=True)
def residual(cols, vals, x, b, out):
    """out = b - A x."""
    if cols.shape[0] >= PARALLEL_ROWS:
        _matvec_parallel(cols, vals, x, b, out, True)
    else:
        _matvec_rows(cols, vals, x, b, out, 0, cols.shape[0], True)


@njit(cache=True)
def _cg_rows(x, r, p, q, z, alpha, beta, lo, hi, step):
    """CG vector updates of entries lo to hi - 1: x += alpha p, r -= alpha q (``step``),
    or p = z + beta p."""
    if step:
        for i in range(lo, hi):
            x[i] += alpha * p[i]
            r[i] -= alpha * q[i]
    else:
        for i in range(lo, hi):
            p[i] = z[i] + beta * p[i]


@njit(cache=True, parallel=True)
def _cg_parallel(x, r, p, q, z, alpha, beta, step):
    n = r.shape[0]
    for t in prange(CHUNKS):
        _cg_rows(x, r, p, q, z, alpha, beta, t * n // CHUNKS, (t + 1) * n // CHUNKS, step)


@njit(cache=True)
def _cg_update(x, r, p, q, z, alpha, beta, step):
    if r.shape[0] >= PARALLEL_ROWS:
        _cg_parallel(x, r, p, q, z, alpha, beta, step)
    else:
        _cg_rows(x, r, p, q, z, alpha, beta, 0, r.shape[0], step)


@njit(cache=True)
def dot(a, b):
    """a . b, summed in CHUNKS runs (in parallel) when long: the same sum on any thread count."""
    n = a.shape[0]
    if n < PARALLEL_ROWS:
        return np.dot(a, b)
    part = np.empty(CHUNKS)
    _dot_parts(a, b, part)
    total = 0.0
    for t in range(CHUNKS):
        total += part[t]
    return total


@njit(cache=True, parallel=True)
def _dot_parts(a, b, part):
    n = a.shape[0]
    for t in prange(CHUNKS):
        acc = 0.0
        for i in range(t * n // CHUNKS, (t + 1) * n // CHUNKS):
            acc += a[i] * b[i]
        part[t] = acc


@njit(cache=True)
def _gs_rows(cols, vals, b, x, rows, lo, hi):
    """Gauss-Seidel update of rows[lo:hi] (rows of one colour: they do not couple); the
    diagonal of every row is in slot 4 (offset 0, 0)."""
    for k in range(lo, hi):
        r = rows[k]
        acc = b[r]
        for s in range(9):
            c = cols[r, s]
            if c >= 0 and s != 4:
                acc -= vals[r, s] * x[c]
        x[r] = acc / vals[r, 4]


@njit(cache=True, parallel=True)
def _gs_rows_parallel(cols, vals, b, x, rows, lo, hi):
    n = hi - lo
    for t in prange(CHUNKS):
        _gs_rows(cols, vals, b, x, rows, lo + t * n // CHUNKS, lo + (t + 1) * n // CHUNKS)


@njit(cache=True)
def _gauss_seidel(cols, vals, b, x, rows, cstart, forward):
    """One four-colour Gauss-Seidel sweep: colours 0-3 (forward) or 3-0; ``rows`` lists the
    rows by colour, colour k is rows[cstart[k]:cstart[k+1]]."""
    parallel = cols.shape[0] >= PARALLEL_ROWS
    for k in range(4):
        colour = k if forward else 3 - k
        lo, hi = cstart[colour], cstart[colour + 1]
        if parallel:
            _gs_rows_parallel(cols, vals, b, x, rows, lo, hi)
        else:
            _gs_rows(cols, vals, b, x, rows, lo, hi)


@njit(cache=True)
def _colour_rows(node, nnx, rows, cstart):
    """Rows sorted by colour (ix mod 2) + 2 (iy mod 2) of their node; cstart: 5 offsets."""
    n = node.shape[0]
    cstart[:] = 0
    for r in range(n):
        cstart[(node[r] % nnx) % 2 + 2 * ((node[r] // nnx) % 2) + 1] += 1
    for k in range(4):
        cstart[k + 1] += cstart[k]
    fill = cstart[:4].copy()
    for r in range(n):
        k = (node[r] % nnx) % 2 + 2 * ((node[r] // nnx) % 2)
        rows[fill[k]] = r
        fill[k] += 1


@njit(cache=True)
def _restrict(pcols, pw, r_f, r_c):
    r_c[:] = 0.0
    for r in range(pcols.shape[0]):
        for a in range(4):
            c = pcols[r, a]
            if c >= 0:
                r_c[c] += pw[r, a] * r_f[r]


@njit(cache=True)
def _prolong_add(pcols, pw, e_c, x_f):
    for r in range(pcols.shape[0]):
        acc = 0.0
        for a in range(4):
            c = pcols[r, a]
            if c >= 0:
                acc += pw[r, a] * e_c[c]
        x_f[r] += acc


@njit(cache=True)
def _cholesky_solve(L, b, x):
    n = L.shape[0]
    for i in range(n):
        acc = b[i]
        for k in range(i):
            acc -= L[i, k] * x[k]
        x[i] = acc / L[i, i]
    for i in range(n - 1, -1, -1):
        acc = x[i]
        for k in range(i + 1, n):
            acc -= L[k, i] * x[k]
        x[i] = acc / L[i, i]


@njit(cache=True)
def build_hierarchy(cols, vals, node, nnx, nny, coarsest):
    """All levels, flattened: level l has rows off[l]:off[l+1] of Acols/Avals (column indices
    local to the level) and, for l < nlev-1, the same rows of Pcols/Pw (columns local to
    level l+1). Returns (off, Acols, Avals, Pcols, Pw, L, rows, cstart) with L the Cholesky
    factor of the coarsest operator and rows[off[l]:off[l+1]] level l's rows by colour, colour
    k from cstart[l, k] to cstart[l, k+1]."""
    cols_l = [cols]
    vals_l = [vals]
    node_l = [node]
    nnx_l = [nnx]
    pc_l = [np.empty((0, 4), dtype=np.int64)]
    pw_l = [np.empty((0, 4))]
    pc_l.pop()
    pw_l.pop()
    while cols_l[-1].shape[0] > coarsest:
        cnode, nnx_c, nny_c, crow, pcols, pw = coarse_level(node, nnx, nny)
        if cnode.shape[0] == 0:
            break
        ccols, cvals = galerkin(cols_l[-1], vals_l[-1], pcols, pw, cnode, nnx_c, node, nnx)
        pc_l.append(pcols)
        pw_l.append(pw)
        cols_l.append(ccols)
        vals_l.append(cvals)
        node_l.append(cnode)
        nnx_l.append(nnx_c)
        node = cnode
        nnx = nnx_c
        nny = nny_c
    nlev = len(cols_l)
    off = np.zeros(nlev + 1, dtype=np.int64)
    for lv in range(nlev):
        off[lv + 1] = off[lv] + cols_l[lv].shape[0]
    Acols = np.empty((off[nlev], 9), dtype=np.int64)
    Avals = np.empty((off[nlev], 9))
    Pcols = -np.ones((off[nlev], 4), dtype=np.int64)
    Pw = np.zeros((off[nlev], 4))
    for lv in range(nlev):
        Acols[off[lv]:off[lv + 1]] = cols_l[lv]
        Avals[off[lv]:off[lv + 1]] = vals_l[lv]
        if lv < nlev - 1:
            Pcols[off[lv]:off[lv + 1]] = pc_l[lv]
            Pw[off[lv]:off[lv + 1]] = pw_l[lv]
    rows = np.empty(off[nlev], dtype=np.int64)
    cstart = np.empty((nlev, 5), dtype=np.int64)
    for lv in range(nlev):
        _colour_rows(node_l[lv], nnx_l[lv], rows[off[lv]:off[lv + 1]], cstart[lv])
    L = np.linalg.cholesky(dense(cols_l[-1], vals_l[-1]))
    return off, Acols, Avals, Pcols, Pw, L, rows, cstart


@njit(cache=True)
def vcycle(off, Acols, Avals, Pcols, Pw, L, rows, cstart, b, x, r, sweeps):
    """One V-cycle with zero initial guess: b[off[0]:off[1]] in, x[off[0]:off[1]] out.

    b, x, r are work vectors over all levels (length off[-1])."""
    nlev = off.shape[0] - 1
    for lv in range(nlev - 1):
        lo, hi = off[lv], off[lv + 1]
        cols, vals = Acols[lo:hi], Avals[lo:hi]
        bl, xl, rl = b[lo:hi], x[lo:hi], r[lo:hi]
        xl[:] = 0.0
        for _ in range(sweeps):
            _gauss_seidel(cols, vals, bl, xl, rows[lo:hi], cstart[lv], True)
        residual(cols, vals, xl, bl, rl)
        _restrict(Pcols[lo:hi], Pw[lo:hi], rl, b[hi:off[lv + 2]])
    lo, hi = off[nlev - 1], off[nlev]
    _cholesky_solve(L, b[lo:hi], x[lo:hi])
    for lv in range(nlev - 2, -1, -1):
        lo, hi = off[lv], off[lv + 1]
        _prolong_add(Pcols[lo:hi], Pw[lo:hi], x[hi:off[lv + 2]], x[lo:hi])
        for _ in range(sweeps):
            _gauss_seidel(Acols[lo:hi], Avals[lo:hi], b[lo:hi], x[lo:hi], rows[lo:hi],
                          cstart[lv], False)


@njit(cache=True)
def pcg(off, Acols, Avals, Pcols, Pw, L, rows, cstart, rhs, x, tol, maxiter, sweeps):
    """Multigrid-preconditioned CG from the initial guess in x (updated in place).

    Stops when ||rhs - A x|| <= tol ||rhs||; returns (iterations, relative residual)."""
    n = rhs.shape[0]
    cols = Acols[:n]
    vals = Avals[:n]
    total = off[-1]
    b = np.zeros(total)
    z = np.zeros(total)
    w = np.zeros(total)
    bnorm = np.sqrt(dot(rhs, rhs))
    if bnorm == 0.0:
        x[:] = 0.0
        return 0, 0.0
    r = np.empty(n)
    residual(cols, vals, x, rhs, r)
    rnorm = np.sqrt(dot(r, r))
    if rnorm > bnorm:
        # a warm start worse than zero (the right-hand side changed a lot) would only cost
        # accuracy: the residual would have to fall far below round-off of A x0
        x[:] = 0.0
        r[:] = rhs
        rnorm = bnorm
    if rnorm <= tol * bnorm:
        return 0, rnorm / bnorm
    b[:n] = r
    vcycle(off, Acols, Avals, Pcols, Pw, L, rows, cstart, b, z, w, sweeps)
    p = z[:n].copy()
    rz = dot(r, z[:n])
    q = np.empty(n)
    it = 0
    while it < maxiter:
        it += 1
        matvec(cols, vals, p, q)
        alpha = rz / dot(p, q)
        _cg_update(x, r, p, q, z, alpha, 0.0, True)
        rnorm = np.sqrt(dot(r, r))
        if rnorm <= tol * bnorm:
            break
        b[:n] = r
        vcycle(off, Acols, Avals, Pcols, Pw, L, rows, cstart, b, z, w, sweeps)
        rz_new = dot(r, z[:n])
        beta = rz_new / rz
        rz = rz_new
        _cg_update(x, r, p, q, z[:n], 0.0, beta, False)
    # the recursive residual can drift from the true one: report the true residual
    residual(cols, vals, x, rhs, q)
    return it, np.sqrt(dot(q, q)) / bnorm
