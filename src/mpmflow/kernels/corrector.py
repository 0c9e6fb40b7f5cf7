"""The corrector of the projection, eq. (16) with the row-sum lumped volume matrix (eq. 17),
2D and 3D: v_i = v*_i - dt/rho (G p)_i / V_i with (G p)_i = sum_e C_e[a_i, b, :] p_b and
V_i = sum_e V_e[a_i] over the node's cells in the system."""

import numpy as np
from numba import njit, prange

from .parallel import CHUNKS
from .stencil import first_of_slab, next_in_slab, node_cells, tables


@njit(cache=True, parallel=True)
def correct_velocity(cells, cell_slot, C, V, p_node, vstar, dt_over_rho, v_new):
    """v_new = v* - dt/rho (G p) / V at every node; nodes outside every cell of the system keep
    v* (they carry splashes only)."""
    D = len(cells)
    NC = 1 << D
    ns, cs, slot, offset = tables(cells)
    off = np.empty(NC, dtype=np.int64)
    for a in range(NC):
        o = 0
        for k in range(D):
            if (a >> k) & 1:
                o += ns[k]
        off[a] = o
    nslabs = cells[D - 1] + 1
    per = 1
    for k in range(D - 1):
        per *= cells[k] + 1
    for t in prange(CHUNKS):
        ix = np.empty(D, dtype=np.int64)
        g = np.empty(D)
        slots = np.empty(NC, dtype=np.int64)
        local = np.empty(NC, dtype=np.int64)
        base = np.empty(NC, dtype=np.int64)
        for sl in range(t, nslabs, CHUNKS):
            first_of_slab(sl, cells, ix)
            for i in range(sl * per, (sl + 1) * per):
                vol = 0.0
                for k in range(D):
                    g[k] = 0.0
                for m in range(node_cells(ix, cells, ns, cs, cell_slot, slots, local, base)):
                    s, a = slots[m], local[m]
                    vol += V[s, a]
                    for b in range(NC):
                        pj = p_node[base[m] + off[b]]
                        for k in range(D):
                            g[k] += C[s, a, b, k] * pj
                for k in range(D):
                    if vol > 0.0:
                        v_new[i, k] = vstar[i, k] - dt_over_rho * g[k] / vol
                    else:
                        v_new[i, k] = vstar[i, k]
                next_in_slab(ix, cells)
