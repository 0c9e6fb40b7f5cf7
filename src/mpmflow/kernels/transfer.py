"""Particle-grid transfers with multilinear shape functions, for 2D and 3D.

The grid comes as ``cells``, the tuple of cell counts (``geometry``): its length D is part
of the kernels' types, so each compiles once per dimension, with per-particle sums in
D-tuples (``geometry.zeros_of``) that live in registers.

particle-to-grid: nodal mass, momentum and material volume, the velocity and the predictor
with gravity, and (for the volume correction) the particles' volume on the cell centres;
grid-to-particle: the FLIP/PIC velocity, the position moved with the new grid velocity plus
the volume correction's displacement, the pressure, and the wall put-back.
"""

import numpy as np
from numba import njit, prange
from numba.cpython.unsafe.tuple import tuple_setitem

from .geometry import cell_strides, corner_offsets, node_strides, weights_at, zeros_of
from .parallel import CHUNKS, strips

STRIPS = 16  # particle-to-grid cuts the slabs of cells into 2 STRIPS strips


@njit(cache=True, inline="always")
def scatter_cell_volume(x, p, volume, inv_h, cells, cs, frac, first, cell_vol):
    """Add ``volume`` at particle p to the cell centres with the multilinear hat of the
    cell-centred grid. A wall mirrors the particles next to it: a ghost cell's weight goes to
    its mirror, the cell against the wall, so a uniform material reads full up to the walls.
    Points beyond the grid (and NaN) count at its edge. ``frac``, ``first``: scratch arrays of
    length D."""
    D = len(cells)
    for k in range(D):
        s = x[p, k] * inv_h
        if not s >= 0.0:
            s = 0.0
        elif s > cells[k]:
            s = float(cells[k])
        s -= 0.5
        i0 = int(s + 1.0) - 1  # floor: s >= -1/2
        frac[k] = s - i0
        first[k] = i0
    for a in range(1 << D):
        c = 0
        w = volume
        for k in range(D):
            i = first[k] + ((a >> k) & 1)
            w *= frac[k] if (a >> k) & 1 else 1.0 - frac[k]
            if i < 0:
                i = 0
            elif i > cells[k] - 1:
                i = cells[k] - 1
            c += i * cs[k]
        cell_vol[c] += w


@njit(cache=True, inline="always")
def face_samples(x, p, inv_h, cells, normal, nlo, tangent, tlo, thi):
    """Where particle p samples the face values of the volume correction: along an axis j
    whose faces it interpolates across (normal to them), between faces nlo[j] and nlo[j] + 1
    with the weight ``normal[j]`` of the upper one; along an axis whose faces lie at cell
    centres, between tlo[j] and thi[j] (clamped to the outermost) with weight tangent[j].
    Points beyond the grid count at its edge."""
    for j in range(len(cells)):
        s = x[p, j] * inv_h
        if not s >= 0.0:
            s = 0.0
        elif s > cells[j]:
            s = float(cells[j])
        i0 = int(s)
        if i0 > cells[j] - 1:
            i0 = cells[j] - 1
        nlo[j] = i0
        normal[j] = s - i0
        s -= 0.5
        i0 = int(s + 1.0) - 1  # floor: s >= -1/2
        tangent[j] = s - i0
        tlo[j] = max(i0, 0)
        thi[j] = min(i0 + 1, cells[j] - 1)


@njit(cache=True, inline="always")
def face_displacement(cells, k, f, normal, nlo, tangent, tlo, thi):
    """Component k of the volume correction's displacement at a particle (m), interpolated
    multilinearly from ``f``, the values on the cell faces normal to axis k (face (i_0, ...)
    at i_k h along axis k, i_k = 0 to cells[k], and at (i_j + 1/2) h along the others, flat
    index with axis 0 fastest), at the samples ``face_samples`` found."""
    D = len(cells)
    acc = 0.0
    for a in range(1 << D):
        w = 1.0
        idx = 0
        stride = 1
        for j in range(D):
            up = (a >> j) & 1
            if j == k:
                w *= normal[j] if up else 1.0 - normal[j]
                idx += (nlo[j] + up) * stride
                stride *= cells[j] + 1
            else:
                w *= tangent[j] if up else 1.0 - tangent[j]
                idx += (thi[j] if up else tlo[j]) * stride
                stride *= cells[j]
        acc += w * f[idx]
    return acc


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
def pressure_noise(x, mass, pressure, h, cells, work_m, work_mp):
    """RMS over particles of p_p minus the mass-weighted grid-smoothed pressure at x_p (Pa).

    The smoothed field is the particle-to-grid sum of m_p p_p divided by the nodal mass,
    interpolated back: a smooth pressure field is kept (up to interpolation), a checkerboard
    is not. ``work_m``, ``work_mp``: scratch of one value per node."""
    D = len(cells)
    ns = np.empty(D, dtype=np.int64)
    node_strides(cells, ns)
    off = np.empty(1 << D, dtype=np.int64)
    corner_offsets(ns, off)
    w = np.empty(1 << D)
    work_m[:] = 0.0
    work_mp[:] = 0.0
    inv_h = 1.0 / h
    for p in range(x.shape[0]):
        base = weights_at(x, p, inv_h, cells, ns, w)
        for a in range(1 << D):
            work_m[base + off[a]] += w[a] * mass[p]
            work_mp[base + off[a]] += w[a] * mass[p] * pressure[p]
    total = 0.0
    for p in range(x.shape[0]):
        base = weights_at(x, p, inv_h, cells, ns, w)
        smooth = 0.0
        for a in range(1 << D):
            if w[a] > 0.0:  # then the node has mass from this particle at least
                smooth += w[a] * work_mp[base + off[a]] / work_m[base + off[a]]
        d = pressure[p] - smooth
        total += d * d
    return np.sqrt(total / max(x.shape[0], 1))


@njit(cache=True)
def scatter_slabs(r0, r1, x, v, mass, volume, order, start, inv_h, cells, ns, cs, node_mass,
                  node_mom, node_vol, cell_vol):
    """P2G of the particles of cell slabs r0 to r1 - 1 (a slab: the cells with one index
    along the last axis), cell by cell."""
    D = len(cells)
    NC = 1 << D
    ZERO = zeros_of(cells)
    w = np.empty(NC)
    off = np.empty(NC, dtype=np.int64)
    corner_offsets(ns, off)
    cfrac = np.empty(D)
    first = np.empty(D, dtype=np.int64)
    slab = cs[D - 1]
    cells_too = cell_vol.shape[0] > 0
    for s in range(start[r0 * slab], start[r1 * slab]):
        p = order[s]
        base = weights_at(x, p, inv_h, cells, ns, w)
        m = mass[p]
        vp = ZERO
        for k in range(D):
            vp = tuple_setitem(vp, k, v[p, k])
        for a in range(NC):
            i = base + off[a]
            wm = w[a] * m
            node_mass[i] += wm
            node_vol[i] += w[a] * volume[p]
            for k in range(D):
                node_mom[i, k] += wm * vp[k]
        if cells_too:
            scatter_cell_volume(x, p, volume[p], inv_h, cells, cs, cfrac, first, cell_vol)


@njit(cache=True, parallel=True)
def particles_to_grid(x, v, mass, volume, order, start, h, cells, gravity, dt, node_mass,
                      node_mom, node_vol, v_old, v_star, cell_vol):
    """Lumped nodal mass M_i = sum_p N_i(x_p) m_p, momentum sum_p N_i m_p v_p, material
    volume sum_p N_i V_p, velocity v_i = momentum / M_i and the predictor without pressure
    v*_i = v_i + dt g (eqs. 10-12) where M_i > 0 (both 0 elsewhere); with ``cell_vol``
    (non-empty) also the particles' volume on the cell centres (``scatter_cell_volume``).

    The particles come binned by cell (``order``, ``start``: see ``binning``). The slabs
    of cells along the last axis are cut into 2 STRIPS strips of at least 2 slabs holding
    equal numbers of particles; strips 0, 2, 4, ... share no node (nor cell centre), so
    they are scattered in parallel, then strips 1, 3, 5, .... Every sum is taken in the
    same order whatever the thread count, so results do not depend on it.
    """
    D = len(cells)
    ns = np.empty(D, dtype=np.int64)
    cs = np.empty(D, dtype=np.int64)
    nn = node_strides(cells, ns)
    cell_strides(cells, cs)
    for i in prange(nn):
        node_mass[i] = 0.0
        node_vol[i] = 0.0
        for k in range(D):
            node_mom[i, k] = 0.0
    for c in prange(cell_vol.shape[0]):
        cell_vol[c] = 0.0
    inv_h = 1.0 / h
    bounds = np.empty(2 * STRIPS + 1, dtype=np.int64)
    nstrips = strips(start[::cs[D - 1]], 2 * STRIPS, 2, bounds)
    for parity in range(2):
        for t in prange((nstrips - parity + 1) // 2):
            u = 2 * t + parity
            scatter_slabs(bounds[u], bounds[u + 1], x, v, mass, volume, order, start, inv_h,
                          cells, ns, cs, node_mass, node_mom, node_vol, cell_vol)
    for i in prange(nn):
        m = node_mass[i]
        for k in range(D):
            if m > 0.0:
                v_old[i, k] = node_mom[i, k] / m
                v_star[i, k] = v_old[i, k] + dt * gravity[k]
            else:
                v_old[i, k] = 0.0
                v_star[i, k] = 0.0


@njit(cache=True)
def gather(lo, hi, x, v, pressure, inv_h, cells, ns, v_old, v_new, p_node, dt, flip, upper,
           margin, faces):
    """G2P of particles lo to hi - 1 (``grid_to_particles``); returns how many were put
    back inside."""
    D = len(cells)
    NC = 1 << D
    ZERO = zeros_of(cells)
    w = np.empty(NC)
    off = np.empty(NC, dtype=np.int64)
    corner_offsets(ns, off)
    normal = np.empty(D)
    tangent = np.empty(D)
    nlo = np.empty(D, dtype=np.int64)
    tlo = np.empty(D, dtype=np.int64)
    thi = np.empty(D, dtype=np.int64)
    correct = faces[0].shape[0] > 0
    moved = 0
    for p in range(lo, hi):
        base = weights_at(x, p, inv_h, cells, ns, w)
        pic = ZERO
        dv = ZERO
        pp = 0.0
        for a in range(NC):
            i = base + off[a]
            for k in range(D):
                pic = tuple_setitem(pic, k, pic[k] + w[a] * v_new[i, k])
                dv = tuple_setitem(dv, k, dv[k] + w[a] * (v_new[i, k] - v_old[i, k]))
            pp += w[a] * p_node[i]
        disp = ZERO
        if correct:
            face_samples(x, p, inv_h, cells, normal, nlo, tangent, tlo, thi)
            for k in range(D):
                disp = tuple_setitem(disp, k, face_displacement(cells, k, faces[k], normal,
                                                                nlo, tangent, tlo, thi))
        for k in range(D):
            v[p, k] = flip * (v[p, k] + dv[k]) + (1.0 - flip) * pic[k]
            x[p, k] += dt * pic[k]
            if correct:
                x[p, k] += disp[k]
        pressure[p] = pp
        if put_inside(x, v, p, upper, margin):
            moved += 1
    return moved


@njit(cache=True, parallel=True)
def grid_to_particles(x, v, pressure, h, cells, v_old, v_new, p_node, dt, flip, upper,
                      margin, faces):
    """Eqs. (19)-(21): FLIP/PIC velocity update (``flip``: the FLIP fraction of this
    step), position update with v^{t+1} evaluated at x_p^t plus the volume correction's
    displacement (``faces``: one array per axis, see ``face_displacement``; empty arrays:
    none), pressure; then particles that left the box [0, upper] are put back inside
    (``put_inside``). Returns how many were put back."""
    D = len(cells)
    ns = np.empty(D, dtype=np.int64)
    node_strides(cells, ns)
    inv_h = 1.0 / h
    n = x.shape[0]
    nchunks = min(CHUNKS, max(n, 1))
    moved = 0
    for chunk in prange(nchunks):
        moved += gather(chunk * n // nchunks, (chunk + 1) * n // nchunks, x, v, pressure,
                        inv_h, cells, ns, v_old, v_new, p_node, dt, flip, upper, margin,
                        faces)
    return moved
