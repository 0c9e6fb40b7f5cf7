"""The sub-cell free surface's ghost values (2D and 3D): the pressure extrapolated from the
unknowns to the nodes just outside the material, p = 0 at the f = 1/2 surface.

Along the edge from an unknown node i to a node g outside, theta = (f_i - 1/2)/(f_i - f_g) is
the fractional distance from i to the surface and p_g = (1 - 1/theta) p_i the linear
extrapolation to p = 0 there (the ghost-fluid method of Gibou et al. 2002).
"""

import numpy as np
from numba import njit, prange

from .parallel import CHUNKS
from .stencil import first_of_slab, next_in_slab, node_stencil, tables


@njit(cache=True)
def ghost_factor(f_i, f_g, theta_min):
    """(1 - 1/theta): p_g = factor * p_i, linear extrapolation to p = 0 at f = 1/2; theta is
    kept at or above ``theta_min``."""
    if f_i - f_g <= 0.0:
        return 0.0
    t = (f_i - 0.5) / (f_i - f_g)
    if t >= 1.0:
        return 0.0
    if t < theta_min:
        t = theta_min
    return 1.0 - 1.0 / t


@njit(cache=True, parallel=True)
def ghost_values(cells, cell_slot, K, node_row, node_f, theta_min, p_node):
    """Values at the nodes of the system that are not unknowns (in place; the unknowns' values
    are set): each takes the coupling-weighted mean of the extrapolations from its unknown
    neighbours, the same extrapolations the assembly used; 0 where it has none."""
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
                if node_row[i] < 0:
                    # no material around the node: none of its cells is in the system (a
                    # cell in the system holds particles or is enclosed by f > 1/2 nodes)
                    if node_f[i] == 0.0 or node_stencil(ix, cells, ns, cs, cell_slot, K, slot,
                                                        S, slots, local, base) == 0:
                        p_node[i] = 0.0
                    else:
                        num = 0.0
                        den = 0.0
                        for s in range(NS):
                            sv = S[s]
                            if s == centre or sv >= 0.0:
                                continue
                            j = i + offset[s]
                            if node_row[j] < 0:
                                continue
                            num -= sv * ghost_factor(node_f[j], node_f[i], theta_min) * p_node[j]
                            den -= sv
                        p_node[i] = num / den if den > 0.0 else 0.0
                next_in_slab(ix, cells)
