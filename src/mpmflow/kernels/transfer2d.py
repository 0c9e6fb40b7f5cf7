"""Particle-grid transfers with bilinear shape functions (2D)."""

import numpy as np
from numba import njit


@njit(cache=True, inline="always")
def _weights(x0, x1, inv_h, ncx, ncy):
    """The four nodes of the cell holding a point and their bilinear weights N_a."""
    sx = x0 * inv_h
    sy = x1 * inv_h
    cx = min(max(int(np.floor(sx)), 0), ncx - 1)
    cy = min(max(int(np.floor(sy)), 0), ncy - 1)
    xi = sx - cx
    eta = sy - cy
    nnx = ncx + 1
    base = cx + nnx * cy
    nodes = (base, base + 1, base + nnx, base + nnx + 1)
    w = ((1.0 - xi) * (1.0 - eta), xi * (1.0 - eta), (1.0 - xi) * eta, xi * eta)
    return nodes, w


@njit(cache=True)
def particles_to_grid_2d(x, v, mass, volume, h, ncx, ncy, node_mass, node_mom, node_vol):
    """Lumped nodal mass M_i = sum_p N_i(x_p) m_p, momentum sum_p N_i m_p v_p and
    material volume sum_p N_i V_p."""
    node_mass[:] = 0.0
    node_mom[:] = 0.0
    node_vol[:] = 0.0
    inv_h = 1.0 / h
    for p in range(x.shape[0]):
        nodes, w = _weights(x[p, 0], x[p, 1], inv_h, ncx, ncy)
        for a in range(4):
            i = nodes[a]
            wm = w[a] * mass[p]
            node_mass[i] += wm
            node_vol[i] += w[a] * volume[p]
            node_mom[i, 0] += wm * v[p, 0]
            node_mom[i, 1] += wm * v[p, 1]


@njit(cache=True)
def nodal_velocity(node_mass, node_mom, out):
    """v_i = momentum_i / M_i where M_i > 0, else 0."""
    for i in range(node_mass.shape[0]):
        m = node_mass[i]
        if m > 0.0:
            for k in range(node_mom.shape[1]):
                out[i, k] = node_mom[i, k] / m
        else:
            for k in range(node_mom.shape[1]):
                out[i, k] = 0.0


@njit(cache=True, inline="always")
def flip_update(x, v, p, nodes, w, v_old, v_new, dt, flip):
    """Particle p's FLIP/PIC velocity (FLIP fraction ``flip``) and its position moved with
    the interpolated new grid velocity, from its four nodes and weights."""
    pic0 = 0.0
    pic1 = 0.0
    dv0 = 0.0
    dv1 = 0.0
    for a in range(4):
        i = nodes[a]
        pic0 += w[a] * v_new[i, 0]
        pic1 += w[a] * v_new[i, 1]
        dv0 += w[a] * (v_new[i, 0] - v_old[i, 0])
        dv1 += w[a] * (v_new[i, 1] - v_old[i, 1])
    v[p, 0] = flip * (v[p, 0] + dv0) + (1.0 - flip) * pic0
    v[p, 1] = flip * (v[p, 1] + dv1) + (1.0 - flip) * pic1
    x[p, 0] += dt * pic0
    x[p, 1] += dt * pic1


@njit(cache=True)
def grid_to_particles_2d(x, v, pressure, h, ncx, ncy, v_old, v_new, p_node, dt, flip):
    """Eqs. (19)-(21): FLIP/PIC velocity update, position update with v^{t+1}, pressure.

    ``flip`` is the FLIP fraction: 1 = pure FLIP (the paper), 0 = pure PIC.
    Positions move with the interpolated new grid velocity (eq. 21), evaluated at x_p^t.
    """
    inv_h = 1.0 / h
    for p in range(x.shape[0]):
        nodes, w = _weights(x[p, 0], x[p, 1], inv_h, ncx, ncy)
        flip_update(x, v, p, nodes, w, v_old, v_new, dt, flip)
        pp = 0.0
        for a in range(4):
            pp += w[a] * p_node[nodes[a]]
        pressure[p] = pp


@njit(cache=True, inline="always")
def put_inside(x, v, p, upper, margin):
    """Put particle p back inside the box [0, upper] if it left it; True if it was moved.

    A particle beyond a wall is mirrored back across it (so it keeps its distance from the
    wall) and at least ``margin`` inside; its velocity component into the wall is removed.
    """
    out = False
    for k in range(x.shape[1]):
        lo = margin
        hi = upper[k] - margin
        if x[p, k] < 0.0:
            x[p, k] = min(max(-x[p, k], lo), hi)
            if v[p, k] < 0.0:
                v[p, k] = 0.0
            out = True
        elif x[p, k] > upper[k]:
            x[p, k] = max(min(2.0 * upper[k] - x[p, k], hi), lo)
            if v[p, k] > 0.0:
                v[p, k] = 0.0
            out = True
    return out


@njit(cache=True)
def keep_inside(x, v, upper, margin):
    """Put particles that left the box [0, upper] back inside (``put_inside``); return how
    many were moved."""
    moved = 0
    for p in range(x.shape[0]):
        if put_inside(x, v, p, upper, margin):
            moved += 1
    return moved


@njit(cache=True)
def pressure_noise_2d(x, mass, pressure, h, ncx, ncy, work_m, work_mp):
    """RMS over particles of p_p minus the mass-weighted grid-smoothed pressure at x_p (Pa).

    The smoothed field is the P2G of m_p p_p divided by the nodal mass, interpolated back:
    a smooth pressure field is kept (up to interpolation), a checkerboard is not.
    """
    work_m[:] = 0.0
    work_mp[:] = 0.0
    inv_h = 1.0 / h
    for p in range(x.shape[0]):
        nodes, w = _weights(x[p, 0], x[p, 1], inv_h, ncx, ncy)
        for a in range(4):
            work_m[nodes[a]] += w[a] * mass[p]
            work_mp[nodes[a]] += w[a] * mass[p] * pressure[p]
    total = 0.0
    for p in range(x.shape[0]):
        nodes, w = _weights(x[p, 0], x[p, 1], inv_h, ncx, ncy)
        smooth = 0.0
        for a in range(4):
            if w[a] > 0.0:  # then the node has mass from this particle at least
                smooth += w[a] * work_mp[nodes[a]] / work_m[nodes[a]]
        d = pressure[p] - smooth
        total += d * d
    return np.sqrt(total / max(x.shape[0], 1))
