"""Element integrals of the pressure system (eqs. 14, 15, 17, 18) from quadrature points,
for 2D and 3D (``geometry`` for the corner numbering).

For one cell the kernels accumulate, over points with weights w:
* ``K[a, b]    = sum w grad N_a . grad N_b``          (Laplacian, eq. 14)
* ``C[a, b, k] = sum w N_a d/dx_k N_b``               (divergence, eq. 15, and gradient, eq. 18)
* ``V[a]       = sum w N_a``                          (row-sum lumped volume matrix, eq. 17)
The points are the 2^D Gauss points of a full cell or the material points of a partial cell.

Which cells get which points: the mixed quadrature of the paper (section 2.2), applied by
``kernels.step.cell_integrals``.

Cells are classified by their volume fraction theta:
* theta >= full threshold (0.9): full cell, 2^D Gauss points;
* sparse threshold (0.2) <= theta < full threshold: partial cell, integrated with its
  material points (solver.partial_cell_quadrature = "particles", the paper) or, like a full cell, with Gauss
  points ("gauss": the free surface is then placed inside the cell by the
  sub-cell free-surface treatment, see ``surface``);
* theta < sparse threshold: left out of the pressure system, unless the free-surface
  treatment says the cell lies inside the fluid (``enclosed``): then it is a gap between
  particle lines in continuous material, integrated like a full cell.
The element integrals of the cells in the system come as stacked arrays with a slot per cell;
slot 0 holds the Gauss-point integrals shared by all Gauss cells.

With Gauss partial cells, solver.surface_quadrature chooses how the cells the free surface passes
through (partial and not enclosed) are integrated besides the Laplacian, which keeps Gauss
points: "gauss" (all of them), "divergence" (the divergence of the predicted velocity,
eq. 15, over their material points: the velocity the grid carries in the air part of such
a cell is an extrapolation that no equation constrains, and integrated over the whole cell
its divergence did work against the extrapolated (ghost) pressure that nothing balanced, so
a standing wave gained energy) or "consistent" (the corrector's gradient and volumes, eqs.
16-18, too: divergence and gradient are then adjoint and the projection takes energy out
only, at the price of more damping). docs/method.md, "Energy".
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
