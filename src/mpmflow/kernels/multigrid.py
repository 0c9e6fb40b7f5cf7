"""Geometric multigrid-preconditioned conjugate gradients on the node grid (2D and 3D).

Matrices are in ELL form: row r has up to 3^D entries ``cols[r, s], vals[r, s]`` (col -1 =
empty), slot ``s = sum_k (d_k + 1) 3^k`` for the neighbour at node offset d, so the
structure of the grid is kept at every level. ``node[r]`` is the node of row r on its
level's node grid, whose numbers of nodes per axis are ``dims`` (axis 0 fastest).

Levels: a coarse node is an unknown when the fine node it coincides with (at twice its
coordinates) is one; prolongation is multilinear interpolation from the coarse unknowns
(missing ones count as zero), so P has full column rank and the Galerkin operator P^T A P
stays symmetric positive definite. Smoothing is 2^D-colour Gauss-Seidel (colour = node
parity along each axis; in a 3^D stencil rows of one colour do not couple, so each colour is
updated in parallel), colours in order before and in reverse after the coarse correction,
which makes the V-cycle a symmetric preconditioner; the coarsest level is solved with a
dense Cholesky factor. Levels of at least ``PARALLEL_ROWS`` rows run their row loops and dot products in
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
def _coords(i, dims, out):
    for k in range(dims.shape[0]):
        out[k] = i % dims[k]
        i //= dims[k]


@njit(cache=True)
def coarse_level(node, dims):
    """Coarse unknowns of a level: returns (coarse node per coarse row, coarse dims, row of
    each coarse node or -1, coarse coordinates per row (n_c, D), P columns (n, 2^D) and
    weights (n, 2^D)). D is a constant of each branch, so that the loops over axes unroll."""
    if dims.shape[0] == 2:
        return _coarse_level_of(node, dims, 2)
    return _coarse_level_of(node, dims, 3)


@njit(cache=True, inline="always")
def _coarse_level_of(node, dims, D):
    NC = 1 << D
    cdims = dims // 2 + 1
    ncn = 1
    for k in range(D):
        ncn *= cdims[k]
    crow = -np.ones(ncn, dtype=np.int64)
    n = node.shape[0]
    ix = np.empty(D, dtype=np.int64)
    for r in range(n):
        _coords(node[r], dims, ix)
        even = True
        c = 0
        stride = 1
        for k in range(D):
            if ix[k] % 2 != 0:
                even = False
            c += (ix[k] // 2) * stride
            stride *= cdims[k]
        if even:
            crow[c] = 0
    cnode = np.empty(ncn, dtype=np.int64)
    nc = 0
    for i in range(ncn):
        if crow[i] == 0:
            crow[i] = nc
            cnode[nc] = i
            nc += 1
    pcols = -np.ones((n, NC), dtype=np.int64)
    pw = np.zeros((n, NC))
    for r in range(n):
        _coords(node[r], dims, ix)
        m = 0
        for combo in range(NC):  # axis 0 fastest, the order of the 2D kernel
            c = 0
            stride = 1
            w = 1.0
            ok = True
            for k in range(D):
                up = (combo >> k) & 1
                if ix[k] % 2 == 0:
                    if up:
                        ok = False
                        break
                    ck = ix[k] // 2
                else:
                    ck = ix[k] // 2 + up
                    w *= 0.5
                if ck >= cdims[k]:
                    ok = False
                    break
                c += ck * stride
                stride *= cdims[k]
            if not ok:
                continue
            if crow[c] >= 0:
                pcols[r, m] = crow[c]
                pw[r, m] = w
                m += 1
    ccoord = np.empty((nc, D), dtype=np.int64)
    for I in range(nc):
        _coords(cnode[I], cdims, ix)
        for k in range(D):
            ccoord[I, k] = ix[k]
    return cnode[:nc].copy(), cdims, crow, ccoord, pcols, pw


@njit(cache=True)
def slot_table(dims):
    """The stencil slot of a neighbour from the difference of flat node numbers on a grid of
    ``dims`` nodes: table[diff + (len - 1) / 2]. Empty when two offsets share a difference
    (an axis of fewer than 3 nodes): then the slots come from the coordinates."""
    D = dims.shape[0]
    stride = np.empty(D, dtype=np.int64)
    m = 0
    n = 1
    for k in range(D):
        stride[k] = n
        m += n
        n *= dims[k]
    table = -np.ones(2 * m + 1, dtype=np.int64)
    ns = 1
    for k in range(D):
        ns *= 3
    for s in range(ns):
        off = 0
        r = s
        for k in range(D):
            off += (r % 3 - 1) * stride[k]
            r //= 3
        if table[off + m] >= 0:
            return table[:0]
        table[off + m] = s
    return table


@njit(cache=True)
def galerkin(cols, vals, pcols, pw, ccoord, cnode, table, node, dims):
    """Coarse operator P^T A P in ELL form (3^D slots per row).

    Fine row r adds only to the coarse rows it interpolates from, which lie within half a
    slab of node (one index along the last axis) of it; so on large levels the fine rows are
    cut into strips of whole slabs (at least 2 each), and strips 0, 2, 4, ... are summed in
    parallel, then 1, 3, 5, ... (``node``, ``dims``: the fine rows' nodes, ascending). The
    strips depend on the level only, so the sums do not depend on the thread count.
    ``table``: the coarse grid's ``slot_table`` (the slots from ``ccoord`` if empty)."""
    nc = ccoord.shape[0]
    NS = cols.shape[1]
    ccols = -np.ones((nc, NS), dtype=np.int64)
    cvals = np.zeros((nc, NS))
    n = cols.shape[0]
    if n < PARALLEL_ROWS:
        _galerkin_rows(0, n, cols, vals, pcols, pw, ccoord, cnode, table, ccols, cvals)
        return ccols, cvals
    D = dims.shape[0]
    per = 1
    for k in range(D - 1):
        per *= dims[k]
    y0 = node[0] // per
    y1 = node[n - 1] // per + 1
    row_cum = np.searchsorted(node, (y0 + np.arange(y1 - y0 + 1)) * per)
    strip = np.empty(STRIPS + 1, dtype=np.int64)
    k = strips(row_cum, STRIPS, 2, strip)
    bounds = row_cum[strip[:k + 1]]
    for parity in range(2):
        _galerkin_strips(parity, bounds, k, cols, vals, pcols, pw, ccoord, cnode, table, ccols,
                         cvals)
    return ccols, cvals


@njit(cache=True, parallel=True)
def _galerkin_strips(parity, bounds, k, cols, vals, pcols, pw, ccoord, cnode, table, ccols,
                     cvals):
    for t in prange((k - parity + 1) // 2):
        u = 2 * t + parity
        _galerkin_rows(bounds[u], bounds[u + 1], cols, vals, pcols, pw, ccoord, cnode, table,
                       ccols, cvals)


@njit(cache=True)
def _galerkin_rows(r0, r1, cols, vals, pcols, pw, ccoord, cnode, table, ccols, cvals):
    """The contributions of fine rows r0 to r1 - 1 to P^T A P (the sizes of P's rows and of
    the stencil constants of each branch, so that their loops unroll)."""
    if cols.shape[1] == 9:
        _galerkin_rows_of(r0, r1, cols, vals, pcols, pw, ccoord, cnode, table, ccols, cvals,
                          4, 9, 2)
    else:
        _galerkin_rows_of(r0, r1, cols, vals, pcols, pw, ccoord, cnode, table, ccols, cvals,
                          8, 27, 3)


@njit(cache=True, inline="always")
def _galerkin_rows_of(r0, r1, cols, vals, pcols, pw, ccoord, cnode, table, ccols, cvals, NP,
                      NS, D):
    lookup = table.shape[0] > 0
    mid = (table.shape[0] - 1) // 2
    for r in range(r0, r1):
        for a in range(NP):
            I = pcols[r, a]
            if I < 0:
                break  # P's entries of a row come first, then -1
            wa = pw[r, a]
            for s in range(NS):
                j = cols[r, s]
                if j < 0:
                    continue
                v = wa * vals[r, s]
                for b in range(NP):
                    J = pcols[j, b]
                    if J < 0:
                        break
                    if lookup:
                        slot = table[cnode[J] - cnode[I] + mid]
                    else:
                        slot = 0
                        p3 = 1
                        for k in range(D):
                            slot += (ccoord[J, k] - ccoord[I, k] + 1) * p3
                            p3 *= 3
                    ccols[I, slot] = J
                    cvals[I, slot] += v * pw[j, b]


@njit(cache=True)
def dense(cols, vals):
    n = cols.shape[0]
    A = np.zeros((n, n))
    for r in range(n):
        for s in range(cols.shape[1]):
            if cols[r, s] >= 0:
                A[r, cols[r, s]] += vals[r, s]
    return A


@njit(cache=True, inline="always")
def _matvec_rows_of(cols, vals, x, b, y, lo, hi, subtract, NS):
    for r in range(lo, hi):
        acc = 0.0
        for s in range(NS):
            c = cols[r, s]
            if c >= 0:
                acc += vals[r, s] * x[c]
        y[r] = b[r] - acc if subtract else acc


@njit(cache=True)
def _matvec_rows(cols, vals, x, b, y, lo, hi, subtract):
    """y = A x (or b - A x when ``subtract``) for rows lo to hi - 1 (the stencil's size a
    constant of each branch, as in ``_gs_rows``)."""
    if cols.shape[1] == 9:
        _matvec_rows_of(cols, vals, x, b, y, lo, hi, subtract, 9)
    else:
        _matvec_rows_of(cols, vals, x, b, y, lo, hi, subtract, 27)


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


@njit(cache=True, inline="always")
def _gs_rows_of(cols, vals, b, x, rows, lo, hi, NS):
    centre = NS // 2
    for k in range(lo, hi):
        r = rows[k]
        acc = b[r]
        for s in range(NS):
            c = cols[r, s]
            if c >= 0 and s != centre:
                acc -= vals[r, s] * x[c]
        x[r] = acc / vals[r, centre]


@njit(cache=True)
def _gs_rows(cols, vals, b, x, rows, lo, hi):
    """Gauss-Seidel update of rows[lo:hi] (rows of one colour: they do not couple); the
    diagonal of every row is in the middle slot (offset 0). The stencil's size is a
    constant of each branch (9 in 2D, 27 in 3D), so that its loop is unrolled: the hot loop
    of the pressure solve."""
    if cols.shape[1] == 9:
        _gs_rows_of(cols, vals, b, x, rows, lo, hi, 9)
    else:
        _gs_rows_of(cols, vals, b, x, rows, lo, hi, 27)


@njit(cache=True, parallel=True)
def _gs_rows_parallel(cols, vals, b, x, rows, lo, hi):
    n = hi - lo
    for t in prange(CHUNKS):
        _gs_rows(cols, vals, b, x, rows, lo + t * n // CHUNKS, lo + (t + 1) * n // CHUNKS)


@njit(cache=True)
def _gauss_seidel(cols, vals, b, x, rows, cstart, forward):
    """One 2^D-colour Gauss-Seidel sweep: colours in order (forward) or in reverse; ``rows``
    lists the rows by colour, colour k is rows[cstart[k]:cstart[k+1]]."""
    parallel = cols.shape[0] >= PARALLEL_ROWS
    ncol = cstart.shape[0] - 1
    for k in range(ncol):
        colour = k if forward else ncol - 1 - k
        lo, hi = cstart[colour], cstart[colour + 1]
        if parallel:
            _gs_rows_parallel(cols, vals, b, x, rows, lo, hi)
        else:
            _gs_rows(cols, vals, b, x, rows, lo, hi)


@njit(cache=True)
def _colour(i, dims):
    """The colour of node i: sum_k (i_k mod 2) 2^k."""
    c = 0
    for k in range(dims.shape[0]):
        c += ((i % dims[k]) % 2) << k
        i //= dims[k]
    return c


@njit(cache=True)
def _colour_rows(node, dims, rows, cstart):
    """Rows sorted by the colour of their node; cstart: 2^D + 1 offsets."""
    n = node.shape[0]
    ncol = cstart.shape[0] - 1
    cstart[:] = 0
    for r in range(n):
        cstart[_colour(node[r], dims) + 1] += 1
    for k in range(ncol):
        cstart[k + 1] += cstart[k]
    fill = cstart[:ncol].copy()
    for r in range(n):
        k = _colour(node[r], dims)
        rows[fill[k]] = r
        fill[k] += 1


@njit(cache=True, inline="always")
def _restrict_of(pcols, pw, r_f, r_c, NP):
    r_c[:] = 0.0
    for r in range(pcols.shape[0]):
        for a in range(NP):
            c = pcols[r, a]
            if c >= 0:
                r_c[c] += pw[r, a] * r_f[r]


@njit(cache=True)
def _restrict(pcols, pw, r_f, r_c):
    """r_c = P^T r_f (P's 2^D entries per row a constant of each branch)."""
    if pcols.shape[1] == 4:
        _restrict_of(pcols, pw, r_f, r_c, 4)
    else:
        _restrict_of(pcols, pw, r_f, r_c, 8)


@njit(cache=True, inline="always")
def _prolong_add_of(pcols, pw, e_c, x_f, NP):
    for r in range(pcols.shape[0]):
        acc = 0.0
        for a in range(NP):
            c = pcols[r, a]
            if c >= 0:
                acc += pw[r, a] * e_c[c]
        x_f[r] += acc


@njit(cache=True)
def _prolong_add(pcols, pw, e_c, x_f):
    """x_f += P e_c."""
    if pcols.shape[1] == 4:
        _prolong_add_of(pcols, pw, e_c, x_f, 4)
    else:
        _prolong_add_of(pcols, pw, e_c, x_f, 8)


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
def build_hierarchy(cols, vals, node, dims, coarsest):
    """All levels, flattened: level l has rows off[l]:off[l+1] of Acols/Avals (column indices
    local to the level) and, for l < nlev-1, the same rows of Pcols/Pw (columns local to
    level l+1). Returns (off, Acols, Avals, Pcols, Pw, L, rows, cstart) with L the Cholesky
    factor of the coarsest operator and rows[off[l]:off[l+1]] level l's rows by colour, colour
    k from cstart[l, k] to cstart[l, k+1]."""
    D = dims.shape[0]
    NS = cols.shape[1]
    NP = 1 << D
    cols_l = [cols]
    vals_l = [vals]
    node_l = [node]
    dims_l = [dims]
    pc_l = [np.empty((0, NP), dtype=np.int64)]
    pw_l = [np.empty((0, NP))]
    pc_l.pop()
    pw_l.pop()
    while cols_l[-1].shape[0] > coarsest:
        cnode, cdims, crow, ccoord, pcols, pw = coarse_level(node, dims)
        if cnode.shape[0] == 0:
            break
        ccols, cvals = galerkin(cols_l[-1], vals_l[-1], pcols, pw, ccoord, cnode,
                                slot_table(cdims), node, dims)
        pc_l.append(pcols)
        pw_l.append(pw)
        cols_l.append(ccols)
        vals_l.append(cvals)
        node_l.append(cnode)
        dims_l.append(cdims)
        node = cnode
        dims = cdims
    nlev = len(cols_l)
    off = np.zeros(nlev + 1, dtype=np.int64)
    for lv in range(nlev):
        off[lv + 1] = off[lv] + cols_l[lv].shape[0]
    Acols = np.empty((off[nlev], NS), dtype=np.int64)
    Avals = np.empty((off[nlev], NS))
    Pcols = -np.ones((off[nlev], NP), dtype=np.int64)
    Pw = np.zeros((off[nlev], NP))
    for lv in range(nlev):
        Acols[off[lv]:off[lv + 1]] = cols_l[lv]
        Avals[off[lv]:off[lv + 1]] = vals_l[lv]
        if lv < nlev - 1:
            Pcols[off[lv]:off[lv + 1]] = pc_l[lv]
            Pw[off[lv]:off[lv + 1]] = pw_l[lv]
    rows = np.empty(off[nlev], dtype=np.int64)
    cstart = np.empty((nlev, NP + 1), dtype=np.int64)
    for lv in range(nlev):
        _colour_rows(node_l[lv], dims_l[lv], rows[off[lv]:off[lv + 1]], cstart[lv])
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
