"""Element integrals of the pressure system (eqs. 14, 15, 17, 18) from quadrature points (2D).

For one cell the kernels accumulate, over points with weights w:
* ``K[a, b]    = sum w grad N_a . grad N_b``          (Laplacian, eq. 14)
* ``C[a, b, k] = sum w N_a d/dx_k N_b``               (divergence, eq. 15, and gradient, eq. 18)
* ``V[a]       = sum w N_a``                          (row-sum lumped volume matrix, eq. 17)
The points are the 2x2 Gauss points of a full cell or the material points of a partial cell.
"""

import numpy as np
from numba import njit, prange


@njit(cache=True)
def accumulate_point(xi, eta, w, h, K, C, V):
    """Add one quadrature point at local coordinates (xi, eta) with weight w (m^2)."""
    N = np.empty(4)
    dN = np.empty((4, 2))
    inv_h = 1.0 / h
    for a in range(4):
        lx = a & 1
        ly = a >> 1
        fx = xi if lx == 1 else 1.0 - xi
        fy = eta if ly == 1 else 1.0 - eta
        sx = 1.0 if lx == 1 else -1.0
        sy = 1.0 if ly == 1 else -1.0
        N[a] = fx * fy
        dN[a, 0] = sx * fy * inv_h
        dN[a, 1] = sy * fx * inv_h
    for a in range(4):
        V[a] += w * N[a]
        for b in range(4):
            K[a, b] += w * (dN[a, 0] * dN[b, 0] + dN[a, 1] * dN[b, 1])
            C[a, b, 0] += w * N[a] * dN[b, 0]
            C[a, b, 1] += w * N[a] * dN[b, 1]


@njit(cache=True)
def gauss_cell_tensors_2d(h, K, C, V):
    """Element integrals of a full cell with 2x2 Gauss quadrature (exact for bilinear products)."""
    K[:] = 0.0
    C[:] = 0.0
    V[:] = 0.0
    g = 0.5 / np.sqrt(3.0)
    w = 0.25 * h * h
    for qx in (0.5 - g, 0.5 + g):
        for qy in (0.5 - g, 0.5 + g):
            accumulate_point(qx, qy, w, h, K, C, V)


@njit(cache=True)
def particle_cell_tensors_2d(x, volume, order, start, cells, h, ncx, K, C, V):
    """Element integrals of the listed cells with their material points as quadrature points.

    ``cells[k]`` is a flat cell index; its integrals go to ``K[k], C[k], V[k]``; the weights
    are the particle volumes V_p.
    """
    inv_h = 1.0 / h
    for k in range(cells.shape[0]):
        c = cells[k]
        cx = c % ncx
        cy = c // ncx
        K[k] = 0.0
        C[k] = 0.0
        V[k] = 0.0
        for s in range(start[c], start[c + 1]):
            p = order[s]
            xi = min(max(x[p, 0] * inv_h - cx, 0.0), 1.0)
            eta = min(max(x[p, 1] * inv_h - cy, 0.0), 1.0)
            accumulate_point(xi, eta, volume[p], h, K[k], C[k], V[k])


@njit(cache=True, parallel=True)
def particle_cell_divergence_2d(x, volume, order, start, cells, h, ncx, C, V):
    """C and V (not K) of the listed cells with their material points as quadrature points,
    as ``particle_cell_tensors_2d``; cells in parallel (each writes its own slot)."""
    inv_h = 1.0 / h
    n = cells.shape[0]
    for k in prange(n):
        c = cells[k]
        cx = c % ncx
        cy = c // ncx
        Ck = C[k]
        Vk = V[k]
        Ck[:] = 0.0
        Vk[:] = 0.0
        for s in range(start[c], start[c + 1]):
            p = order[s]
            xi = min(max(x[p, 0] * inv_h - cx, 0.0), 1.0)
            eta = min(max(x[p, 1] * inv_h - cy, 0.0), 1.0)
            w = volume[p]
            N0 = (1.0 - xi) * (1.0 - eta)
            N1 = xi * (1.0 - eta)
            N2 = (1.0 - xi) * eta
            N3 = xi * eta
            # dN_b/dx, dN_b/dy
            gx0 = -(1.0 - eta) * inv_h
            gx1 = (1.0 - eta) * inv_h
            gx2 = -eta * inv_h
            gx3 = eta * inv_h
            gy0 = -(1.0 - xi) * inv_h
            gy1 = -xi * inv_h
            gy2 = (1.0 - xi) * inv_h
            gy3 = xi * inv_h
            for a in range(4):
                Na = N0 if a == 0 else (N1 if a == 1 else (N2 if a == 2 else N3))
                wa = w * Na
                Vk[a] += wa
                Ck[a, 0, 0] += wa * gx0
                Ck[a, 1, 0] += wa * gx1
                Ck[a, 2, 0] += wa * gx2
                Ck[a, 3, 0] += wa * gx3
                Ck[a, 0, 1] += wa * gy0
                Ck[a, 1, 1] += wa * gy1
                Ck[a, 2, 1] += wa * gy2
                Ck[a, 3, 1] += wa * gy3
