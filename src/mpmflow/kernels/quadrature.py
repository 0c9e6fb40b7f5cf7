"""Element integrals of the pressure system (eqs. 14, 15, 17, 18) from quadrature points,
for 2D and 3D (``geometry`` for the corner numbering).

For one cell the kernels accumulate, over points with weights w:
* ``K[a, b]    = sum w grad N_a . grad N_b``          (Laplacian, eq. 14)
* ``C[a, b, k] = sum w N_a d/dx_k N_b``               (divergence, eq. 15, and gradient, eq. 18)
* ``V[a]       = sum w N_a``                          (row-sum lumped volume matrix, eq. 17)
The points are the 2^D Gauss points of a full cell or the material points of a partial cell.
"""

import numpy as np
from numba import njit, prange


@njit(cache=True)
def accumulate_point(local, w, h, K, C, V, N, dN):
    """Add one quadrature point at local coordinates ``local`` (length D, in [0, 1]) with
    weight w (m^D). ``N`` (2^D) and ``dN`` (2^D, D): scratch arrays."""
    D = local.shape[0]
    NC = 1 << D
    inv_h = 1.0 / h
    for a in range(NC):
        n = 1.0
        for k in range(D):
            n *= local[k] if (a >> k) & 1 else 1.0 - local[k]
        N[a] = n
        for k in range(D):
            g = 1.0 if (a >> k) & 1 else -1.0
            for j in range(D):
                if j != k:
                    g *= local[j] if (a >> j) & 1 else 1.0 - local[j]
            dN[a, k] = g * inv_h
    for a in range(NC):
        V[a] += w * N[a]
        for b in range(NC):
            kk = 0.0
            for k in range(D):
                kk += dN[a, k] * dN[b, k]
            K[a, b] += w * kk
            for k in range(D):
                C[a, b, k] += w * N[a] * dN[b, k]


@njit(cache=True)
def gauss_cell_tensors(h, K, C, V):
    """Element integrals of a full cell with 2^D Gauss points (exact for multilinear
    products). The dimension D is that of ``V`` (2^D entries)."""
    NC = V.shape[0]
    D = 0
    while (1 << D) < NC:
        D += 1
    K[:] = 0.0
    C[:] = 0.0
    V[:] = 0.0
    g = 0.5 / np.sqrt(3.0)
    w = h**D / NC
    local = np.empty(D)
    N = np.empty(NC)
    dN = np.empty((NC, D))
    for q in range(NC):  # the last axis fastest
        for k in range(D):
            local[k] = 0.5 + g if (q >> (D - 1 - k)) & 1 else 0.5 - g
        accumulate_point(local, w, h, K, C, V, N, dN)


@njit(cache=True, parallel=True)
def particle_cell_tensors(x, volume, order, start, cells_list, h, cells, K, C, V):
    """Element integrals of the listed cells with their material points as quadrature points:
    ``cells_list[k]`` is a flat cell index, its integrals go to ``K[k], C[k], V[k]`` (K may
    have no entries: then only C and V); the weights are the particle volumes V_p. Cells in
    parallel (each writes its own slot)."""
    D = len(cells)
    NC = 1 << D
    inv_h = 1.0 / h
    with_k = K.shape[0] > 0
    for m in prange(cells_list.shape[0]):
        c = cells_list[m]
        local = np.empty(D)
        first = np.empty(D)
        N = np.empty(NC)
        dN = np.empty((NC, D))
        r = c
        for k in range(D):
            first[k] = r % cells[k]
            r //= cells[k]
        Kk = K[m] if with_k else np.empty((NC, NC))
        Kk[:] = 0.0
        C[m] = 0.0
        V[m] = 0.0
        for s in range(start[c], start[c + 1]):
            p = order[s]
            for k in range(D):
                local[k] = min(max(x[p, k] * inv_h - first[k], 0.0), 1.0)
            accumulate_point(local, volume[p], h, Kk, C[m], V[m], N, dN)
