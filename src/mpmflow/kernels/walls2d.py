"""Velocity conditions at the domain walls (2D), one-sided: a wall stops penetration only."""

import numpy as np
from numba import njit


@njit(cache=True)
def wall_pairs(ncx, ncy):
    """Every wall node with the wall it lies on: (node, axis k of the wall's normal, outward
    normal sign -1.0 or +1.0). The left and right walls (k = 0) come first, then the bottom
    and top walls (k = 1); a corner node appears once for each of its two walls."""
    nnx = ncx + 1
    n = 2 * (ncy + 1) + 2 * (ncx + 1)
    node = np.empty(n, dtype=np.int64)
    axis = np.empty(n, dtype=np.int64)
    sign = np.empty(n, dtype=np.float64)
    e = 0
    for iy in range(ncy + 1):
        for ix, s in ((0, -1.0), (ncx, 1.0)):
            node[e], axis[e], sign[e] = ix + nnx * iy, 0, s
            e += 1
    for ix in range(ncx + 1):
        for iy, s in ((0, -1.0), (ncy, 1.0)):
            node[e], axis[e], sign[e] = ix + nnx * iy, 1, s
            e += 1
    return node, axis, sign


@njit(cache=True)
def apply_walls_2d(ncx, ncy, v, contact, no_slip):
    """Velocity conditions at wall nodes (in place).

    Where the wall holds the material (``contact[i, k]``) the normal velocity is zero;
    elsewhere on the wall only a velocity into the wall is removed, so material leaves a
    wall freely. No-slip also zeroes the tangential velocity at nodes in contact.
    """
    node, axis, sign = wall_pairs(ncx, ncy)
    for e in range(node.shape[0]):
        i, k = node[e], axis[e]
        if contact[i, k] or sign[e] * v[i, k] > 0.0:
            v[i, k] = 0.0
            if no_slip and contact[i, k]:
                v[i, 1 - k] = 0.0


@njit(cache=True)
def start_contact_2d(ncx, ncy, vstar, node_row, contact):
    """The wall nodes that hold the material when the pressure step starts (in place):
    ``contact[i, k]`` for the wall normal to axis k through node i is set where the node
    carries a pressure unknown (``node_row[i] >= 0``) or v* presses into that wall; every
    other entry is cleared."""
    contact[:] = False
    node, axis, sign = wall_pairs(ncx, ncy)
    for e in range(node.shape[0]):
        i, k = node[e], axis[e]
        contact[i, k] = node_row[i] >= 0 or sign[e] * vstar[i, k] > 0.0


@njit(cache=True)
def release_contact_2d(ncx, ncy, vstar, node_row, p_node, contact):
    """Release the wall nodes in contact whose pressure unknown came out negative while v*
    leaves the wall (in place); returns how many (node, wall) pairs were released."""
    released = 0
    node, axis, sign = wall_pairs(ncx, ncy)
    for e in range(node.shape[0]):
        i, k = node[e], axis[e]
        if (node_row[i] >= 0 and p_node[i] < 0.0 and contact[i, k]
                and sign[e] * vstar[i, k] < 0.0):
            contact[i, k] = False
            released += 1
    return released
