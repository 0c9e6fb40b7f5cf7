"""Velocity conditions at the domain walls (2D), one-sided: a wall stops penetration only."""

from numba import njit


@njit(cache=True, inline="always")
def outward(ix, iy, k, ncx, ncy):
    """The outward normal (-1.0 or +1.0) of the wall normal to axis k through node (ix, iy),
    0.0 if the node is not on such a wall."""
    pos = ix if k == 0 else iy
    top = ncx if k == 0 else ncy
    if pos == 0:
        return -1.0
    if pos == top:
        return 1.0
    return 0.0


@njit(cache=True)
def apply_walls_2d(ncx, ncy, v, contact, no_slip):
    """Velocity conditions at wall nodes (in place).

    Where the wall holds the material (``contact[i, k]``) the normal velocity is zero;
    elsewhere on the wall only a velocity into the wall is removed, so material leaves a
    wall freely. No-slip also zeroes the tangential velocity at nodes in contact.
    """
    nnx = ncx + 1
    nny = ncy + 1
    for iy in range(nny):
        for ix in range(nnx):
            if 0 < ix < ncx and 0 < iy < ncy:
                continue
            i = ix + nnx * iy
            for k in range(2):
                sign = outward(ix, iy, k, ncx, ncy)
                if sign == 0.0:
                    continue
                if contact[i, k] or sign * v[i, k] > 0.0:
                    v[i, k] = 0.0
                    if no_slip and contact[i, k]:
                        v[i, 1 - k] = 0.0


@njit(cache=True)
def start_contact_2d(ncx, ncy, vstar, node_row, contact):
    """The wall nodes that hold the material when the pressure step starts (in place):
    ``contact[i, k]`` for the wall normal to axis k through node i is set where the node
    carries a pressure unknown (``node_row[i] >= 0``) or v* presses into that wall; every
    other entry is cleared."""
    nnx = ncx + 1
    nny = ncy + 1
    contact[:] = False
    for iy in range(nny):
        for ix in range(nnx):
            if 0 < ix < ncx and 0 < iy < ncy:
                continue
            i = ix + nnx * iy
            for k in range(2):
                sign = outward(ix, iy, k, ncx, ncy)
                if sign == 0.0:
                    continue
                contact[i, k] = node_row[i] >= 0 or sign * vstar[i, k] > 0.0


@njit(cache=True)
def release_contact_2d(ncx, ncy, vstar, node_row, p_node, contact):
    """Release the wall nodes in contact whose pressure unknown came out negative while v*
    leaves the wall (in place); returns how many (node, wall) pairs were released."""
    nnx = ncx + 1
    nny = ncy + 1
    released = 0
    for iy in range(nny):
        for ix in range(nnx):
            if 0 < ix < ncx and 0 < iy < ncy:
                continue
            i = ix + nnx * iy
            if node_row[i] < 0 or p_node[i] >= 0.0:
                continue
            for k in range(2):
                sign = outward(ix, iy, k, ncx, ncy)
                if sign == 0.0:
                    continue
                if contact[i, k] and sign * vstar[i, k] < 0.0:
                    contact[i, k] = False
                    released += 1
    return released
