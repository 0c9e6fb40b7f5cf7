"""One step of the projection scheme as compiled code, 2D and 3D (docs/method.md, steps 1-8).

``advance`` runs a chunk of steps without returning to Python; each phase of the method is
one named function below, so the step reads like the algorithm:

    bin_particles -> particles_to_grid -> cell_integrals -> classify_nodes
      -> viscous_predictor (viscous materials only)
      -> pressure_multigrid (contact walls, assembly, solve, release, ghost values)
      -> correct_velocity and apply_walls -> volume_correction (every few steps)
      -> grid_to_particles

The arrays come grouped in named tuples (``Grid``, ``Particles``, ``Options``, ``Work``),
built once by ``mpmflow.schemes.projection``; the dimension D is that of ``Grid.cells``.
Failures (a solve that does not converge, a pressure system without a free surface) stop
the chunk and come back as a status code in ``report``; Python turns them into messages.

The pressure solvers that are not compiled (``amg``, ``direct``) run the same phases one
step at a time with the solve in Python (``mpmflow.pressure``): ``predict``,
``pressure_matrix``, ``pressure_rhs``, ``release_walls``, ``extend_pressure``, ``finish``.
"""

from collections import namedtuple

import numba
import numpy as np
from numba import njit

from . import (assembly, binning, corrector, cutcells, ghost, multigrid, quadrature, surface,
               transfer, viscous, volume, walls)

# the obstacles' tables (``mpmflow.obstacles``): phi at the nodes (empty: none), the cells'
# fluid fraction and static slot, the static element integrals by slot (0: a whole cell),
# the obstacle nodes with their normals and no-slip flags; viscous_T: the full cell's
# gradient products (``viscous.gauss_gradients``; empty for inviscid material)
Grid = namedtuple(
    "Grid", "h cells cell_volume upper margin wall_node wall_axis wall_sign phi open "
    "static_slot K_static C_static V_static F_static Wf_static onode onormal ono_slip "
    "viscous_T")
Particles = namedtuple("Particles", "x v mass volume pressure")
# flip: the FLIP fraction of one step; volume_every: the volume correction runs on the steps
# whose number (counted from the start of the run) is a multiple of it, 0 = never
Options = namedtuple(
    "Options",
    "dt gravity rho flip full sparse partial_particles surface subcell wall_flux no_slip "
    "theta_min expansion tol max_iterations sweeps volume_rate volume_every volume_tol "
    "volume_max_iterations volume_dmax viscous model model_params")
Work = namedtuple(
    "Work",
    "cell start order theta node_mass node_mom node_vol v_old v_star v_c v_new node_f "
    "enclosed slot surface_slot node_row contact ocontact p_node cell_vol density "
    "cell_row vol_cols vol_vals vol_rhs vol_rows q faces no_faces eta eta_weight vrow vu "
    "voff")

# surface quadrature (solver.surface_quadrature)
GAUSS, DIVERGENCE, CONSISTENT = 0, 1, 2

# report: what a chunk of steps did (filled by advance; sums over its steps unless said)
R_UNKNOWNS = 0  # the largest number of pressure unknowns in a step
R_SOLVES = 1
R_ITERATIONS = 2
R_MAX_ITERATIONS = 3  # the most iterations in one step
R_RESIDUAL = 4  # the worst relative residual
R_RELEASED = 5
R_MOVED = 6
R_STATUS = 7  # OK or the failure below
R_STEP = 8  # the step (0-based, within the chunk) that failed or is running
R_FAIL_ITERATIONS = 9
R_FAIL_RESIDUAL = 10
R_FAIL_NODE = 11  # node (pressure, viscous) or cell (volume correction) of the largest residual
R_FAIL_SIZE = 12  # unknowns of the failed system
R_VOLUME_ITERATIONS = 13
R_LAST_UNKNOWNS = 14  # the unknowns of the last step
R_VISCOUS_ITERATIONS = 15
REPORT_SIZE = 16

OK, SINGULAR, PRESSURE_NOT_CONVERGED, VOLUME_NOT_CONVERGED, VISCOUS_NOT_CONVERGED = 0, 1, 2, 3, 4
WET = 0.5  # volume correction: a cell less than half full is surface (as front, height)


@njit(cache=True)
def _worst(cols, vals, x, b):
    """The row of the largest |b - A x| (NaN counts as largest)."""
    r = np.empty(b.shape[0])
    multigrid.residual(cols, vals, x, b, r)
    worst = 0
    big = -1.0
    for i in range(r.shape[0]):
        a = abs(r[i])
        if not a <= big:
            big = a
            worst = i
            if a != a:
                break
    return worst


@njit(cache=True)
def bin_particles(P, G, W):
    """Step 1a: particles sorted by cell and the cell volume fractions theta (eqs. 8, 9)."""
    binning.cell_index(P.x, G.h, G.cells, W.cell)
    binning.counting_sort(W.cell, W.theta.shape[0], W.start, W.order)
    binning.cell_volume_fraction(W.order, W.start, P.volume, G.cell_volume, G.open, W.theta)
    if G.phi.shape[0] > 0:
        cutcells.sliver_fractions(G.cells, G.open, W.theta)


@njit(cache=True)
def cell_integrals(P, G, O, W):
    """Step 3: which cells take part in the pressure system and their element integrals
    (``mpmflow.quadrature`` describes the rules). Returns (slot, K, rhs_slot, rhs_C,
    rhs_V, cor_slot, cor_C, cor_V): the Laplacian's, the right-hand side's and the
    corrector's slots and tensors (slot 0: the Gauss tensors, 1 to nstatic - 1: the cells
    obstacles cut, then the cells' own particle tensors; -1: left out)."""
    cells = G.cells
    D = len(cells)
    NC = 1 << D
    theta, enclosed, slot, static = W.theta, W.enclosed, W.slot, G.static_slot
    nc = theta.shape[0]
    ns = G.K_static.shape[0]
    npartial = 0
    nsurface = 0
    for c in range(nc):
        counted = theta[c] >= O.sparse
        slot[c] = static[c] if (counted or enclosed[c]) and static[c] >= 0 else -1
        if counted and theta[c] < O.full and static[c] >= 0:
            if O.partial_particles:
                npartial += 1
            elif not enclosed[c]:
                nsurface += 1
    partial = np.empty(npartial, dtype=np.int64)
    K = np.empty((npartial + ns, NC, NC))
    C = np.empty((npartial + ns, NC, NC, D))
    V = np.empty((npartial + ns, NC))
    K[:ns] = G.K_static
    C[:ns] = G.C_static
    V[:ns] = G.V_static
    if npartial:
        m = 0
        for c in range(nc):
            if theta[c] >= O.sparse and theta[c] < O.full and static[c] >= 0:
                slot[c] = ns + m
                partial[m] = c
                m += 1
        quadrature.particle_cell_tensors(P.x, P.volume, W.order, W.start, partial, G.h, cells,
                                         K[ns:], C[ns:], V[ns:])
    if O.surface == GAUSS or O.partial_particles:
        return slot, K, slot, C, V, slot, C, V
    surface_slot = W.surface_slot
    listed = np.empty(nsurface, dtype=np.int64)
    m = 0
    for c in range(nc):
        surface_slot[c] = slot[c]
        if (theta[c] >= O.sparse and theta[c] < O.full and not enclosed[c]
                and static[c] >= 0):
            surface_slot[c] = ns + m
            listed[m] = c
            m += 1
    Cs = np.empty((nsurface + ns, NC, NC, D))
    Vs = np.empty((nsurface + ns, NC))
    Vcells = np.empty((nsurface + ns, NC))
    Cs[:ns] = G.C_static
    Vs[:ns] = G.V_static
    Vcells[:ns] = G.V_static
    for s in range(ns, nsurface + ns):
        Vcells[s] = G.V_static[0]
    if nsurface:
        quadrature.particle_cell_tensors(P.x, P.volume, W.order, W.start, listed, G.h, cells,
                                         np.empty((0, NC, NC)), Cs[ns:], Vs[ns:])
    if O.surface == CONSISTENT:
        return slot, K, surface_slot, Cs, Vcells, surface_slot, Cs, Vs
    return slot, K, surface_slot, Cs, Vcells, slot, C, V


@njit(cache=True)
def classify_nodes(G, O, W, slot):
    """Step 4: the free surface. The nodal volume fraction is in ``W.node_f`` (computed
    before the integrals, which need the enclosed cells); numbers the pressure unknowns in
    ``W.node_row`` and returns their nodes."""
    n = surface.classify_nodes(G.cells, slot, G.static_slot, W.node_f, O.subcell, W.node_row)
    rows = np.empty(n, dtype=np.int64)
    for i in range(W.node_row.shape[0]):
        r = W.node_row[i]
        if r >= 0:
            rows[r] = i
    return rows


@njit(cache=True)
def node_fractions(G, O, W):
    """Step 3a: the nodal volume fraction and, with the sub-cell free surface, the cells
    enclosed by the material."""
    surface.nodal_fraction(G.cells, W.theta, G.open, W.node_f)
    if O.subcell:
        surface.enclosed_cells(G.cells, W.node_f, W.enclosed)
    else:
        W.enclosed[:] = False


@njit(cache=True)
def pressure_matrix(G, O, W, integrals, rows):
    """Step 5a: the wall contact the step starts with and the matrix of eq. (13) in ELL
    form. Returns (cols, vals, anchored): ``anchored`` is False for a system that touches no
    free surface (singular)."""
    slot, K = integrals[0], integrals[1]
    walls.start_contact(G.wall_node, G.wall_axis, G.wall_sign, W.v_star, W.node_row, W.contact)
    walls.start_obstacles(G.onode, G.onormal, W.v_star, W.node_row, W.ocontact)
    n = rows.shape[0]
    NS = 1
    for k in range(len(G.cells)):
        NS *= 3
    cols = np.empty((n, NS), dtype=np.int64)
    vals = np.empty((n, NS))
    anchored = np.empty(n, dtype=np.bool_)
    if n == 0:
        return cols, vals, False
    assembly.assemble_matrix(G.cells, slot, K, W.node_row, W.node_f, O.subcell, O.theta_min,
                             cols, vals, anchored)
    return cols, vals, anchored.any()


@njit(cache=True)
def pressure_rhs(G, O, W, integrals, rows, rhs):
    """Step 5b: the right-hand side of eq. (13) for the current wall contact."""
    v_c = W.v_star
    if not O.wall_flux:  # the paper: the divergence of the wall-constrained v*
        v_c = W.v_c
        v_c[:] = W.v_star
        walls.apply_walls(G.wall_node, G.wall_axis, G.wall_sign, v_c, W.contact, O.no_slip)
        walls.apply_obstacles(G.onode, G.onormal, G.ono_slip, v_c, W.ocontact)
    assembly.assemble_rhs(G.cells, G.h, integrals[2], integrals[3], integrals[4], W.node_vol,
                          rows, v_c, W.contact, O.wall_flux, O.expansion / O.dt,
                          O.rho / O.dt, G.static_slot, G.F_static, G.Wf_static, W.ocontact,
                          rhs)


@njit(cache=True)
def release_walls(G, W, rows, x):
    """Step 5c: the solution into the nodal pressure, and the wall nodes released where
    holding the material would need a negative pressure; returns how many."""
    for r in range(rows.shape[0]):
        W.p_node[rows[r]] = x[r]
    return (walls.release_contact(G.wall_node, G.wall_axis, G.wall_sign, W.v_star,
                                  W.node_row, W.p_node, W.contact)
            + walls.release_obstacles(G.onode, G.onormal, W.v_star, W.node_row, W.p_node,
                                      W.ocontact))


@njit(cache=True)
def extend_pressure(G, O, W, integrals):
    """Step 5d: the pressure at the ghost nodes (sub-cell free surface)."""
    if O.subcell:
        ghost.ghost_values(G.cells, integrals[0], integrals[1], W.node_row, W.node_f,
                           O.theta_min, W.p_node)


@njit(cache=True)
def warm_start(W, rows):
    """The last step's pressure at this step's unknowns (the first guess of the solve); the
    nodal pressure is then cleared for this step's."""
    x = np.empty(rows.shape[0])
    for r in range(rows.shape[0]):
        x[r] = W.p_node[rows[r]]
    W.p_node[:] = 0.0
    return x


@njit(cache=True)
def pressure_multigrid(G, O, W, integrals, rows, report):
    """Step 5: eq. (13) with the walls as contact conditions, solved by multigrid-
    preconditioned CG (``multigrid``), again after each release of wall nodes; then the
    ghost values. Returns a status code."""
    x = warm_start(W, rows)
    cols, vals, anchored = pressure_matrix(G, O, W, integrals, rows)
    n = rows.shape[0]
    if n == 0:
        return OK
    if not anchored:
        return SINGULAR
    dims = np.empty(len(G.cells), dtype=np.int64)
    for k in range(len(G.cells)):
        dims[k] = G.cells[k] + 1
    setup = multigrid.build_hierarchy(cols, vals, rows, dims, multigrid.COARSEST)
    rhs = np.empty(n)
    step_iterations = 0
    while True:
        pressure_rhs(G, O, W, integrals, rows, rhs)
        it, res = multigrid.pcg(setup[0], setup[1], setup[2], setup[3], setup[4], setup[5],
                                setup[6], setup[7], rhs, x, O.tol, O.max_iterations, O.sweeps)
        report[R_SOLVES] += 1
        report[R_ITERATIONS] += it
        step_iterations += it
        report[R_RESIDUAL] = max(report[R_RESIDUAL], res)
        if not res <= O.tol:
            report[R_FAIL_ITERATIONS] = it
            report[R_FAIL_RESIDUAL] = res
            report[R_FAIL_NODE] = rows[_worst(cols, vals, x, rhs)]
            report[R_FAIL_SIZE] = n
            return PRESSURE_NOT_CONVERGED
        released = release_walls(G, W, rows, x)
        if released == 0:
            break
        report[R_RELEASED] += released
    report[R_MAX_ITERATIONS] = max(report[R_MAX_ITERATIONS], step_iterations)
    extend_pressure(G, O, W, integrals)
    return OK


@njit(cache=True)
def viscous_predictor(G, O, W, integrals, report):
    """Step 2a, viscous materials only: the implicit viscous step (``viscous``) with each
    cell's viscosity at the step's start, in incremental form: it acts on v* less the last
    step's pressure gradient, dt/rho (G p)/V, which is added back after, so material held
    by its pressure (a column at rest) meets no-slip walls without a spurious shear layer.
    Returns a status code."""
    if not O.viscous:
        return OK
    viscous.cell_viscosity(G.cells, G.h, W.theta, G.open, W.enclosed, O.full, W.v_old,
                           W.p_node, O.model, O.model_params, W.eta, W.eta_weight)
    base = W.v_c
    corrector.correct_velocity(G.cells, integrals[5], integrals[6], integrals[7], W.p_node,
                               W.v_star, O.dt / O.rho, base)
    n = viscous.number_unknowns(W.node_mass, G.wall_node, G.wall_axis, G.wall_sign,
                                O.no_slip, G.onode, G.onormal, G.ono_slip, base, W.vu,
                                W.vrow, W.voff)
    if n == 0:
        return OK
    D = len(G.cells)
    NS = 1
    for k in range(D):
        NS *= 3
    cols = np.empty((D, n, NS), dtype=np.int64)
    vals = np.empty((D, n, NS))
    rhs = np.empty(n)
    node = np.empty(n, dtype=np.int64)
    viscous.assemble(G.cells, G.viscous_T, W.eta_weight, W.node_mass, O.dt, W.vu, W.vrow,
                     W.voff, cols, vals, rhs, node)
    x = np.empty(n)
    nn = W.vrow.shape[0]
    for i in range(nn):
        for k in range(D):
            if W.vrow[i, k] >= 0:
                x[W.vrow[i, k]] = W.vu[i, k]
    it, res = viscous.solve(cols, vals, node, W.voff, G.cells, rhs, x, O.tol,
                            O.max_iterations, O.sweeps)
    report[R_VISCOUS_ITERATIONS] += it
    if not res <= O.tol:
        report[R_FAIL_ITERATIONS] = it
        report[R_FAIL_RESIDUAL] = res
        report[R_FAIL_NODE] = node[viscous.worst_row(cols, vals, W.voff, x, rhs)]
        report[R_FAIL_SIZE] = n
        return VISCOUS_NOT_CONVERGED
    for i in range(nn):
        for k in range(D):
            r = W.vrow[i, k]
            W.v_star[i, k] += (x[r] if r >= 0 else W.vu[i, k]) - base[i, k]
    return OK


@njit(cache=True)
def volume_correction(G, O, W, report):
    """Step 7 (every ``volume_every`` steps): the displacement that moves the particles back
    to the material's volume (``mpmflow.volume_correction``), into ``W.faces``. Returns a
    status code."""
    cells = G.cells
    inv = 1.0 / G.cell_volume
    for c in range(W.density.shape[0]):
        W.density[c] = W.cell_vol[c] * inv
    n, anchored = volume.assemble(cells, W.theta, W.density, WET, W.contact, G.static_slot,
                                  W.cell_row, W.vol_cols, W.vol_vals, W.vol_rhs, W.vol_rows)
    if n == 0 or not anchored:
        # nothing, or material filling the whole domain: its volume cannot change
        for k in range(len(cells)):
            W.faces[k][:] = 0.0
        return OK
    rows = W.vol_rows[:n]
    cols = W.vol_cols[:n]
    vals = W.vol_vals[:n]
    rhs = W.vol_rhs[:n]
    q = np.empty(n)
    for r in range(n):
        q[r] = W.q[rows[r]]
    dims = np.empty(len(cells), dtype=np.int64)
    for k in range(len(cells)):
        dims[k] = cells[k]
    setup = multigrid.build_hierarchy(cols, vals, rows, dims, multigrid.COARSEST)
    it, res = multigrid.pcg(setup[0], setup[1], setup[2], setup[3], setup[4], setup[5],
                            setup[6], setup[7], rhs, q, O.volume_tol, O.volume_max_iterations,
                            1)
    report[R_VOLUME_ITERATIONS] += it
    if not res <= O.volume_tol:
        report[R_FAIL_ITERATIONS] = it
        report[R_FAIL_RESIDUAL] = res
        report[R_FAIL_NODE] = rows[_worst(cols, vals, q, rhs)]
        report[R_FAIL_SIZE] = n
        return VOLUME_NOT_CONVERGED
    W.q[:] = 0.0
    for r in range(n):
        W.q[rows[r]] = q[r]
    volume.face_displacements(cells, W.cell_row, G.static_slot, q, O.volume_rate * G.h,
                              O.volume_dmax * G.h, W.faces)
    return OK


def launch_threads():
    """Launch Numba's threading layer (call before the first step): a function loaded from
    the cache that calls parallel kernels needs the layer's scheduler symbols, and loading
    it before any parallel kernel ran aborts the process ("LLVM ERROR: Symbol not found:
    allocate_sched", e.g. a restart whose first compiled call is advance)."""
    numba.get_num_threads()


@njit(cache=True)
def predict(P, G, O, W, correct):
    """Steps 1-4: binning, particle-to-grid with the predictor (eqs. 10-12; the particles'
    volume on the cell centres too when the volume correction runs this step), cell
    integrals, free surface. Returns (integrals, rows of the pressure unknowns)."""
    bin_particles(P, G, W)
    transfer.particles_to_grid(P.x, P.v, P.mass, P.volume, W.order, W.start, G.h, G.cells,
                               O.gravity, O.dt, W.node_mass, W.node_mom, W.node_vol, W.v_old,
                               W.v_star, W.cell_vol if correct else W.cell_vol[:0])
    if G.phi.shape[0] > 0:
        cutcells.extend_velocity(G.onode, G.cells, W.node_mass, W.v_old, W.v_star)
    node_fractions(G, O, W)
    integrals = cell_integrals(P, G, O, W)
    rows = classify_nodes(G, O, W, integrals[0])
    return integrals, rows


@njit(cache=True)
def finish(P, G, O, W, integrals, correct, report):
    """Steps 6-8: corrector (eq. 16) and wall conditions, volume correction, grid-to-
    particle (eqs. 19-21). Returns a status code."""
    corrector.correct_velocity(G.cells, integrals[5], integrals[6], integrals[7], W.p_node,
                               W.v_star, O.dt / O.rho, W.v_new)
    walls.apply_walls(G.wall_node, G.wall_axis, G.wall_sign, W.v_new, W.contact,
                      O.no_slip)
    walls.apply_obstacles(G.onode, G.onormal, G.ono_slip, W.v_new, W.ocontact)
    faces = W.no_faces
    if correct:
        status = volume_correction(G, O, W, report)
        if status != OK:
            return status
        faces = W.faces
    report[R_MOVED] += transfer.grid_to_particles(P.x, P.v, P.pressure, G.h, G.cells, W.v_old,
                                                  W.v_new, W.p_node, O.dt, O.flip, G.upper,
                                                  G.margin, faces)
    if G.phi.shape[0] > 0:
        report[R_MOVED] += cutcells.push_out(P.x, P.v, G.phi, G.h, G.cells, G.margin)
    return OK


@njit(cache=True)
def advance(P, G, O, W, first, nsteps, report):
    """``nsteps`` steps of size O.dt; ``first``: the number of the first (1-based, counted
    from the start of the run). Stops at the first failure; returns the steps done."""
    for k in range(nsteps):
        report[R_STEP] = k
        correct = O.volume_every > 0 and (first + k) % O.volume_every == 0
        integrals, rows = predict(P, G, O, W, correct)
        report[R_UNKNOWNS] = max(report[R_UNKNOWNS], rows.shape[0])
        report[R_LAST_UNKNOWNS] = rows.shape[0]
        status = viscous_predictor(G, O, W, integrals, report)
        if status == OK:
            status = pressure_multigrid(G, O, W, integrals, rows, report)
        if status == OK:
            status = finish(P, G, O, W, integrals, correct, report)
        if status != OK:
            report[R_STATUS] = status
            return k
    return nsteps
