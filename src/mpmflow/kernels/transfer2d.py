"""Particle-grid transfers with bilinear shape functions (2D)."""

import numpy as np
from numba import njit, prange

from .parallel import CHUNKS, strips
from .volume2d import displacement_at, scatter_cell_volume

STRIPS = 16  # P2G cuts the grid into 2 STRIPS strips of cell rows


@njit(cache=True, inline="always")
def cell_of(s, n):
    """The cell (0 to n - 1) holding grid coordinate s = x / h; points beyond the grid go to
    the nearest cell. Clamped before the conversion to an integer, so NaN goes to cell 0
    instead of an undefined index."""
    if not s > 0.0:  # also NaN
        return 0
    if s >= n - 1.0:
        return n - 1
    return int(s)


@njit(cache=True, inline="always")
def _weights(x0, x1, inv_h, ncx, ncy):
    """The four nodes of the cell holding a point and their bilinear weights N_a."""
    sx = x0 * inv_h
    sy = x1 * inv_h
    cx = cell_of(sx, ncx)
    cy = cell_of(sy, ncy)
    xi = sx - cx
    eta = sy - cy
    nnx = ncx + 1
    base = cx + nnx * cy
    nodes = (base, base + 1, base + nnx, base + nnx + 1)
    w = ((1.0 - xi) * (1.0 - eta), xi * (1.0 - eta), (1.0 - xi) * eta, xi * eta)
    return nodes, w


@njit(cache=True)
def _scatter_rows(cy0, cy1, x, v, mass, volume, order, start, h, ncx, ncy, node_mass, node_mom,
                  node_vol, cell_vol):
    """P2G of the particles of cell rows cy0 to cy1 - 1, cell by cell; with ``cell_vol``
    (non-empty) also their volume onto the cell centres (``volume2d.scatter_cell_volume``)."""
    inv_h = 1.0 / h
    cells = cell_vol.shape[0] > 0
    for s in range(start[cy0 * ncx], start[cy1 * ncx]):
        p = order[s]
        nodes, w = _weights(x[p, 0], x[p, 1], inv_h, ncx, ncy)
        for a in range(4):
            i = nodes[a]
            wm = w[a] * mass[p]
            node_mass[i] += wm
            node_vol[i] += w[a] * volume[p]
            node_mom[i, 0] += wm * v[p, 0]
            node_mom[i, 1] += wm * v[p, 1]
        if cells:
            scatter_cell_volume(x[p, 0] * inv_h, x[p, 1] * inv_h, volume[p], ncx, ncy,
                                cell_vol)


@njit(cache=True, parallel=True)
def particles_to_grid_2d(x, v, mass, volume, order, start, h, ncx, ncy, gravity, dt, node_mass,
                         node_mom, node_vol, v_old, v_star, cell_vol):
    """Lumped nodal mass M_i = sum_p N_i(x_p) m_p, momentum sum_p N_i m_p v_p, material
    volume sum_p N_i V_p, velocity v_i = momentum / M_i and the predictor without pressure
    v*_i = v_i + dt g (eqs. 10-12) where M_i > 0 (both 0 elsewhere); with ``cell_vol``
    (non-empty) also the particles' volume on the cell centres for the volume correction.

    The particles come binned by cell (``order``, ``start``: see ``binning``). The cell rows
    are cut into 2 STRIPS strips of at least 2 rows holding equal numbers of particles;
    strips 0, 2, 4, ... share no node (nor cell centre), so they are scattered in parallel,
    then strips 1, 3, 5, .... Every sum is taken in the same order whatever the thread count,
    so results do not depend on it.
    """
    nn = node_mass.shape[0]
    for i in prange(nn):
        node_mass[i] = 0.0
        node_vol[i] = 0.0
        node_mom[i, 0] = 0.0
        node_mom[i, 1] = 0.0
    for c in prange(cell_vol.shape[0]):
        cell_vol[c] = 0.0
    bounds = np.empty(2 * STRIPS + 1, dtype=np.int64)
    k = strips(start[::ncx], 2 * STRIPS, 2, bounds)  # start[r * ncx]: particles below row r
    for parity in range(2):
        for t in prange((k - parity + 1) // 2):
            u = 2 * t + parity
            _scatter_rows(bounds[u], bounds[u + 1], x, v, mass, volume, order, start, h, ncx,
                          ncy, node_mass, node_mom, node_vol, cell_vol)
    for i in prange(nn):
        m = node_mass[i]
        for d in range(2):
            if m > 0.0:
                v_old[i, d] = node_mom[i, d] / m
                v_star[i, d] = v_old[i, d] + dt * gravity[d]
            else:
                v_old[i, d] = 0.0
                v_star[i, d] = 0.0


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
def _gather_particles(lo, hi, x, v, pressure, h, ncx, ncy, v_old, v_new, p_node, dt, flip,
                      upper, margin, dx_face, dy_face):
    """G2P of particles lo to hi - 1 (see ``grid_to_particles_2d``); returns how many were
    put back inside."""
    inv_h = 1.0 / h
    moved = 0
    correct = dx_face.shape[0] > 0
    for p in range(lo, hi):
        nodes, w = _weights(x[p, 0], x[p, 1], inv_h, ncx, ncy)
        if correct:
            d0, d1 = displacement_at(x[p, 0], x[p, 1], inv_h, ncx, ncy, dx_face, dy_face)
        flip_update(x, v, p, nodes, w, v_old, v_new, dt, flip)
        if correct:
            x[p, 0] += d0
            x[p, 1] += d1
        pp = 0.0
        for a in range(4):
            pp += w[a] * p_node[nodes[a]]
        pressure[p] = pp
        if put_inside(x, v, p, upper, margin):
            moved += 1
    return moved


@njit(cache=True, parallel=True)
def grid_to_particles_2d(x, v, pressure, h, ncx, ncy, v_old, v_new, p_node, dt, flip, upper,
                         margin, dx_face, dy_face):
    """Eqs. (19)-(21): FLIP/PIC velocity update, position update with v^{t+1}, pressure;
    then particles that left the box [0, upper] are put back inside (``put_inside``).
    Returns how many were put back.

    ``flip`` is the FLIP fraction of this step: 1 = pure FLIP (the paper), 0 = pure PIC.
    Positions move with the interpolated new grid velocity (eq. 21), evaluated at x_p^t,
    plus the volume correction's displacement interpolated from ``dx_face, dy_face`` (see
    ``volume2d``; empty arrays: none).
    """
    n = x.shape[0]
    nchunks = min(CHUNKS, n)
    moved = 0
    for chunk in prange(nchunks):
        moved += _gather_particles(chunk * n // nchunks, (chunk + 1) * n // nchunks, x, v,
                                   pressure, h, ncx, ncy, v_old, v_new, p_node, dt, flip,
                                   upper, margin, dx_face, dy_face)
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
