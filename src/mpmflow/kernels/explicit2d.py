"""Explicit weakly compressible MPM (2D, update stress last): whole steps in one compiled call.

The time loop inside ``explicit_steps_2d`` runs the steps between two output times without
returning to Python; one explicit step is cheap and there are many of them. A step makes
two passes over the particles (P2G; G2P with the volume update and the cell sums) and a
few over the grid.
"""

import numpy as np
from numba import njit

from .geometry import cell_of
from .transfer import put_inside
from .walls import apply_walls, wall_pairs

# The bilinear weights and the FLIP/PIC update are written out for 2D here (the explicit
# step is cheap and runs hundreds of thousands of times); the cell index, the wall pairs and
# conditions and the put-back are the projection scheme's own kernels.


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
def _walls(node, axis, sign, v, contact, no_slip):
    """Wall nodes where the velocity points into the wall are in contact: normal velocity 0
    (and tangential too for no-slip); elsewhere the material leaves the wall freely."""
    contact[:] = False
    for e in range(node.shape[0]):
        contact[node[e], axis[e]] = sign[e] * v[node[e], axis[e]] > 0.0
    apply_walls(node, axis, sign, v, contact, no_slip)


@njit(cache=True, inline="always")
def _cell_grads(cx, cy, xi, eta, inv_h, ncx):
    """The four nodes of cell (cx, cy) and dN/dx, dN/dy at its local point (xi, eta)."""
    nnx = ncx + 1
    base = cx + nnx * cy
    nodes = (base, base + 1, base + nnx, base + nnx + 1)
    gx = (-(1.0 - eta) * inv_h, (1.0 - eta) * inv_h, -eta * inv_h, eta * inv_h)
    gy = (-(1.0 - xi) * inv_h, -xi * inv_h, (1.0 - xi) * inv_h, xi * inv_h)
    return nodes, gx, gy


@njit(cache=True, inline="always")
def _add_to_cell(x0, x1, v0, vol, inv_h, ncx, ncy, sum_v, sum_v0, sum_xi):
    """Add one particle (reference volume v0, current volume vol) to its cell's sums."""
    sx = x0 * inv_h
    sy = x1 * inv_h
    cx = cell_of(sx, ncx)
    cy = cell_of(sy, ncy)
    c = cx + ncx * cy
    sum_v[c] += vol
    sum_v0[c] += v0
    sum_xi[c, 0] += v0 * (sx - cx)
    sum_xi[c, 1] += v0 * (sy - cy)


@njit(cache=True)
def _finish_cells(bulk, tension, full_volume, sparse_volume, cell_j, cell_vol, cell_v0,
                  cell_xi, cell_p):
    """From the sums (cell_j: current volume, cell_v0: reference volume V0_c, cell_xi:
    V0-weighted local coordinates) to the cell state: J_c = V/V0_c capped at
    1 + tension / K, the current volume J_c V0_c (cell_vol), the pressure K (1 - J_c) and
    the cell's quadrature point: its centre if the cell is full (V0_c >= full_volume), else
    the centroid of its particles, so that a partly filled cell pushes where its material
    is. A cell with material below ``sparse_volume`` holds too little to define a volumetric
    strain: J_c = 1, no pressure, and it takes no part in the step (cell_vol = 0)."""
    jmax = 1.0 + tension / bulk
    for c in range(cell_v0.shape[0]):
        v0 = cell_v0[c]
        if v0 > 0.0 and v0 >= sparse_volume:
            j = min(cell_j[c] / v0, jmax)
            if v0 >= full_volume:
                cell_xi[c, 0] = 0.5
                cell_xi[c, 1] = 0.5
            else:
                cell_xi[c, 0] /= v0
                cell_xi[c, 1] /= v0
            cell_j[c] = j
            cell_vol[c] = v0 * j
            cell_p[c] = bulk * (1.0 - j)
        else:
            cell_j[c] = 1.0
            cell_vol[c] = 0.0
            cell_p[c] = 0.0


@njit(cache=True)
def cell_state_2d(x, mass, volume, density, bulk, tension, h, ncx, ncy, full, sparse, cell_j,
                  cell_vol, cell_v0, cell_xi, cell_p):
    """Volumetric strain and pressure once per cell (in place), see ``_finish_cells``.

    Per cell c: reference volume V0_c = sum m_p / rho and current volume V_c = sum V_p of
    its particles, J_c = V_c / V0_c, and pressure K (1 - J_c).
    """
    cell_j[:] = 0.0
    cell_v0[:] = 0.0
    cell_xi[:] = 0.0
    inv_h = 1.0 / h
    for p in range(x.shape[0]):
        _add_to_cell(x[p, 0], x[p, 1], mass[p] / density, volume[p], inv_h, ncx, ncy,
                     cell_j, cell_v0, cell_xi)
    _finish_cells(bulk, tension, full * h * h, sparse * h * h, cell_j, cell_vol, cell_v0,
                  cell_xi, cell_p)


@njit(cache=True)
def particle_state_2d(x, mass, volume, pressure, density, h, ncx, ncy, smoothing, cell_j,
                      cell_vol, cell_p, node_w, node_p):
    """Each particle takes its cell's J (volume J_c m_p / rho) and its pressure: with
    ``smoothing`` the interpolation of the node pressures, each the volume-weighted average
    of the pressures of the cells around the node; else its cell's pressure."""
    inv_h = 1.0 / h
    nnx = ncx + 1
    if smoothing:
        node_w[:] = 0.0
        node_p[:] = 0.0
        for cy in range(ncy):
            for cx in range(ncx):
                c = cx + ncx * cy
                if cell_vol[c] > 0.0:
                    base = cx + nnx * cy
                    for i in (base, base + 1, base + nnx, base + nnx + 1):
                        node_w[i] += cell_vol[c]
                        node_p[i] += cell_vol[c] * cell_p[c]
        for i in range(node_w.shape[0]):
            if node_w[i] > 0.0:
                node_p[i] /= node_w[i]
    for p in range(x.shape[0]):
        nodes, w = _weights(x[p, 0], x[p, 1], inv_h, ncx, ncy)
        c = cell_of(x[p, 0] * inv_h, ncx) + ncx * cell_of(x[p, 1] * inv_h, ncy)
        volume[p] = cell_j[c] * mass[p] / density
        if smoothing:
            s = 0.0
            for a in range(4):
                s += w[a] * node_p[nodes[a]]
            pressure[p] = s
        else:
            pressure[p] = cell_p[c]


@njit(cache=True)
def max_speed_2d(v):
    """The largest particle speed (m/s); NaN if any speed is NaN."""
    top = 0.0
    for p in range(v.shape[0]):
        s = np.sqrt(v[p, 0] * v[p, 0] + v[p, 1] * v[p, 1])
        if not s <= top:
            top = s
            if s != s:
                return s
    return top


@njit(cache=True)
def explicit_steps_2d(span, nsteps, safety, x, v, pressure, mass, volume, density, bulk, gx,
                      gy, h, ncx, ncy, flip_ms, no_slip, smoothing, full, sparse, mass_cut,
                      q_lin, q_quad, tension, max_speed, upper, margin, node_mass, node_mom,
                      v_old, v_new, contact, cell_j, cell_vol, cell_v0, cell_xi, cell_p,
                      cell_q, node_w, node_p, stats):
    """Explicit steps over ``span`` seconds (in place). With ``safety`` > 0 each step is
    re-evaluated from the current state: the span's remainder is cut into equal steps of at
    most safety * h / (|v|max + Q + sqrt(Q^2 + c^2)) (c the sound speed, Q the artificial
    viscosity's signal speed); with ``safety`` = 0, ``nsteps`` equal steps. Stops early when
    a particle is faster than ``max_speed`` (or NaN).

    ``stats`` returns [steps taken, time advanced (s), smallest step (s), particles put back
    inside, 1 if stopped on ``max_speed`` else 0, largest particle speed (m/s) at the end].
    Expects the cell state of the current particles (``cell_state_2d``), keeps it up to
    date, and sets the particles' volume and pressure at the end (``particle_state_2d``).

    One step: (1) P2G of mass and momentum, nodal velocity v_old; the artificial bulk
    viscosity q_c = rho_c (q_lin c h |D| + q_quad h^2 D^2) of each compressing cell
    (D = div v_old < 0 at its quadrature point); (2) nodal force: gravity, and from each cell
    its pressure and viscosity on its current volume, f_i = sum_c V_c (p_c + q_c) grad N_i;
    nodes lighter than ``mass_cut`` rho h^2 take gravity only; grid velocity after the step
    (v_new), wall contact; the strain rate of v_new as div v at each cell's quadrature point
    (the transpose of the force), giving the cell's new J; (3) G2P: the particle takes its
    cell's new J, FLIP/PIC velocity (FLIP fraction ``flip_ms`` per millisecond), position
    x += dt * sum N v_new, put back inside if it crossed a wall, added to its new cell's
    sums; (4) the cells' J and pressure from those sums (``_finish_cells``).
    """
    inv_h = 1.0 / h
    full_volume = full * h * h
    sparse_volume = sparse * h * h
    light = mass_cut * density * h * h
    c = np.sqrt(bulk / density)
    n = x.shape[0]
    nnode = node_mass.shape[0]
    ncell = ncx * ncy
    moved = 0
    wnode, waxis, wsign = wall_pairs((ncx, ncy))
    done = 0.0
    steps = 0
    smallest = np.inf
    stopped = 0
    vmax = max_speed_2d(v)
    if not vmax <= max_speed:
        stopped = 1
    while stopped == 0 and (steps < nsteps if safety <= 0.0 else done < span):
        # (1) particle to grid, nodal velocity
        node_mass[:] = 0.0
        node_mom[:] = 0.0
        for p in range(n):
            nodes, w = _weights(x[p, 0], x[p, 1], inv_h, ncx, ncy)
            for a in range(4):
                i = nodes[a]
                wm = w[a] * mass[p]
                node_mass[i] += wm
                node_mom[i, 0] += wm * v[p, 0]
                node_mom[i, 1] += wm * v[p, 1]
        for i in range(nnode):
            if node_mass[i] > 0.0:
                v_old[i, 0] = node_mom[i, 0] / node_mass[i]
                v_old[i, 1] = node_mom[i, 1] / node_mass[i]
            else:
                v_old[i, 0] = 0.0
                v_old[i, 1] = 0.0
        # artificial bulk viscosity from the current strain rate
        qmax = 0.0
        for cc in range(ncell):
            cell_q[cc] = 0.0
        if q_lin > 0.0 or q_quad > 0.0:
            for cy in range(ncy):
                for cx in range(ncx):
                    cc = cx + ncx * cy
                    if cell_vol[cc] > 0.0:
                        nodes, dx, dy = _cell_grads(cx, cy, cell_xi[cc, 0], cell_xi[cc, 1],
                                                    inv_h, ncx)
                        d = 0.0
                        for a in range(4):
                            d += dx[a] * v_old[nodes[a], 0] + dy[a] * v_old[nodes[a], 1]
                        if d < 0.0:
                            sig = q_lin * c + q_quad * h * (-d)
                            cell_q[cc] = density / cell_j[cc] * h * (-d) * sig
                            if sig > qmax:
                                qmax = sig
        # the step
        if safety > 0.0:
            limit = h / (vmax + qmax + np.sqrt(qmax * qmax + c * c))
            left = span - done
            k = max(1, int(np.ceil(left / (safety * limit) - 1e-9)))
            dt = left / k
            if k == 1:
                dt = left
        else:
            dt = span / nsteps
        if dt < smallest:
            smallest = dt
        flip = flip_ms ** (dt / 1e-3)
        # (2) nodal forces (v_new holds them first), grid update, walls, cell strain rate
        for i in range(nnode):
            v_new[i, 0] = 0.0
            v_new[i, 1] = 0.0
        for cy in range(ncy):
            for cx in range(ncx):
                cc = cx + ncx * cy
                vp = cell_vol[cc] * (cell_p[cc] + cell_q[cc])
                if vp != 0.0:
                    nodes, dx, dy = _cell_grads(cx, cy, cell_xi[cc, 0], cell_xi[cc, 1],
                                                inv_h, ncx)
                    for a in range(4):
                        v_new[nodes[a], 0] += vp * dx[a]
                        v_new[nodes[a], 1] += vp * dy[a]
        for i in range(nnode):
            m = node_mass[i]
            if m > 0.0:
                if m >= light:
                    v_new[i, 0] = v_old[i, 0] + dt * (gx + v_new[i, 0] / m)
                    v_new[i, 1] = v_old[i, 1] + dt * (gy + v_new[i, 1] / m)
                else:
                    v_new[i, 0] = v_old[i, 0] + dt * gx
                    v_new[i, 1] = v_old[i, 1] + dt * gy
            else:
                v_old[i, 0] = 0.0
                v_old[i, 1] = 0.0
                v_new[i, 0] = 0.0
                v_new[i, 1] = 0.0
        _walls(wnode, waxis, wsign, v_new, contact, no_slip)
        for cy in range(ncy):
            for cx in range(ncx):
                cc = cx + ncx * cy
                if cell_vol[cc] > 0.0:
                    nodes, dx, dy = _cell_grads(cx, cy, cell_xi[cc, 0], cell_xi[cc, 1],
                                                inv_h, ncx)
                    d = 0.0
                    for a in range(4):
                        d += dx[a] * v_new[nodes[a], 0] + dy[a] * v_new[nodes[a], 1]
                    cell_p[cc] = cell_j[cc] * (1.0 + dt * d)  # the new J, until (4)
                else:
                    cell_p[cc] = 1.0
        # (3) grid to particle; the cell sums of the moved particles
        cell_j[:] = 0.0
        cell_v0[:] = 0.0
        cell_xi[:] = 0.0
        vmax = 0.0
        for p in range(n):
            nodes, w = _weights(x[p, 0], x[p, 1], inv_h, ncx, ncy)
            cx = nodes[0] % (ncx + 1)
            cy = nodes[0] // (ncx + 1)
            v0 = mass[p] / density
            vol = cell_p[cx + ncx * cy] * v0
            flip_update(x, v, p, nodes, w, v_old, v_new, dt, flip)
            if put_inside(x, v, p, upper, margin):
                moved += 1
            s = np.sqrt(v[p, 0] * v[p, 0] + v[p, 1] * v[p, 1])
            if not s <= vmax:
                vmax = s
            volume[p] = vol
            _add_to_cell(x[p, 0], x[p, 1], v0, vol, inv_h, ncx, ncy, cell_j, cell_v0,
                         cell_xi)
        # (4) the cell state of the moved particles
        _finish_cells(bulk, tension, full_volume, sparse_volume, cell_j, cell_vol, cell_v0,
                      cell_xi, cell_p)
        steps += 1
        done = span if (safety > 0.0 and dt == span - done) else done + dt
        if not vmax <= max_speed:
            stopped = 1
    particle_state_2d(x, mass, volume, pressure, density, h, ncx, ncy, smoothing, cell_j,
                      cell_vol, cell_p, node_w, node_p)
    stats[0] = steps
    stats[1] = done if safety > 0.0 else steps * (span / nsteps)
    stats[2] = smallest
    stats[3] = moved
    stats[4] = stopped
    stats[5] = vmax
