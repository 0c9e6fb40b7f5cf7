"""Velocity conditions at the domain walls, 2D and 3D: one-sided contact, a wall stops
penetration only. The wall nodes come as (node, axis of the wall's normal, outward sign)
triples from ``wall_pairs``: the walls normal to axis 0 first, then axis 1, ...; along each,
the nodes in node order with the lower wall before the upper; a node on an edge or a corner
appears once for each of its walls."""

import numpy as np
from numba import njit

from .geometry import node_strides


@njit(cache=True)
def wall_pairs(cells):
    """(node, axis, sign) arrays of every wall node and wall."""
    D = len(cells)
    ns = np.empty(D, dtype=np.int64)
    nn = node_strides(cells, ns)
    total = 0
    for k in range(D):
        total += 2 * (nn // (cells[k] + 1))
    node = np.empty(total, dtype=np.int64)
    axis = np.empty(total, dtype=np.int64)
    sign = np.empty(total)
    e = 0
    ix = np.empty(D, dtype=np.int64)
    for k in range(D):
        for i in range(nn):
            r = i
            for m in range(D):
                ix[m] = r % (cells[m] + 1)
                r //= cells[m] + 1
            if ix[k] != 0:
                continue
            for side in range(2):
                node[e] = i + side * cells[k] * ns[k]
                axis[e] = k
                sign[e] = -1.0 if side == 0 else 1.0
                e += 1
    return node, axis, sign


@njit(cache=True)
def apply_walls(node, axis, sign, v, contact, no_slip):
    """Velocity conditions at wall nodes (in place). Where the wall holds the material
    (``contact[i, k]``) the normal velocity is zero; elsewhere on the wall only a velocity into
    the wall is removed, so material leaves a wall freely. No-slip also zeroes the tangential
    velocity at nodes in contact."""
    for e in range(node.shape[0]):
        i, k = node[e], axis[e]
        if contact[i, k] or sign[e] * v[i, k] > 0.0:
            v[i, k] = 0.0
            if no_slip and contact[i, k]:
                for m in range(v.shape[1]):
                    if m != k:
                        v[i, m] = 0.0


@njit(cache=True)
def start_contact(node, axis, sign, vstar, node_row, contact):
    """The wall nodes that hold the material when the pressure step starts (in place):
    ``contact[i, k]`` is set where the node carries a pressure unknown or v* presses into that
    wall; every other entry is cleared."""
    contact[:] = False
    for e in range(node.shape[0]):
        i, k = node[e], axis[e]
        contact[i, k] = node_row[i] >= 0 or sign[e] * vstar[i, k] > 0.0


@njit(cache=True)
def release_contact(node, axis, sign, vstar, node_row, p_node, contact):
    """Release the wall nodes in contact whose pressure came out negative while v* leaves the
    wall (in place); returns how many (node, wall) pairs were released."""
    released = 0
    for e in range(node.shape[0]):
        i, k = node[e], axis[e]
        if (node_row[i] >= 0 and p_node[i] < 0.0 and contact[i, k]
                and sign[e] * vstar[i, k] < 0.0):
            contact[i, k] = False
            released += 1
    return released


# Obstacles (``mpmflow.obstacles``): the same contact conditions at the obstacle nodes, each
# with its unit normal into the solid; ``ocontact`` is per node.


@njit(cache=True, inline="always")
def normal_velocity(v, i, onormal, e):
    """v_i . n_e: the velocity of node i into the solid along obstacle entry e's normal."""
    vn = 0.0
    for k in range(v.shape[1]):
        vn += v[i, k] * onormal[e, k]
    return vn


@njit(cache=True)
def apply_obstacles(onode, onormal, no_slip, v, ocontact):
    """Velocity conditions at the obstacle nodes (in place), as ``apply_walls``: the normal
    velocity is removed where the obstacle holds the material, elsewhere only a velocity into
    the solid; a no-slip obstacle zeroes the whole velocity where it holds."""
    D = v.shape[1]
    for e in range(onode.shape[0]):
        i = onode[e]
        vn = normal_velocity(v, i, onormal, e)
        if ocontact[i] and no_slip[e]:
            for k in range(D):
                v[i, k] = 0.0
        elif ocontact[i] or vn > 0.0:
            for k in range(D):
                v[i, k] -= vn * onormal[e, k]


@njit(cache=True)
def start_obstacles(onode, onormal, vstar, node_row, ocontact):
    """The obstacle nodes that hold the material as the pressure step starts (in place): a
    pressure unknown, or v* pressing into the solid."""
    for e in range(onode.shape[0]):
        i = onode[e]
        vn = normal_velocity(vstar, i, onormal, e)
        ocontact[i] = node_row[i] >= 0 or vn > 0.0


@njit(cache=True)
def release_obstacles(onode, onormal, vstar, node_row, p_node, ocontact):
    """Release the obstacle nodes in contact whose pressure came out negative while v* leaves
    the solid (in place); returns how many."""
    released = 0
    for e in range(onode.shape[0]):
        i = onode[e]
        vn = normal_velocity(vstar, i, onormal, e)
        if node_row[i] >= 0 and p_node[i] < 0.0 and ocontact[i] and vn < 0.0:
            ocontact[i] = False
            released += 1
    return released
