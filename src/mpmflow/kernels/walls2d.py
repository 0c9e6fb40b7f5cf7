"""Velocity conditions at the domain walls (2D), one-sided: a wall stops penetration only."""

from numba import njit


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
                pos = ix if k == 0 else iy
                top = ncx if k == 0 else ncy
                if pos != 0 and pos != top:
                    continue
                sign = -1.0 if pos == 0 else 1.0
                if contact[i, k] or sign * v[i, k] > 0.0:
                    v[i, k] = 0.0
                    if no_slip and contact[i, k]:
                        v[i, 1 - k] = 0.0
