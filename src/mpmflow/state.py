"""The scheme's state and the one door to the compiled core (``mpmflow._core``).

Nothing else in mpmflow imports the core: the rest of the package calls the functions
here, which take NumPy arrays and grids and call the C++ kernels (src/core, one header/
source pair per concept). The core is built once, at install (scikit-build-core, CMake);
nothing compiles at run time.
"""

import enum

import numpy as np

try:
    from . import _core
except ImportError as err:  # a source tree without the install's build
    raise ImportError(
        f"mpmflow's compiled core (mpmflow._core) could not be loaded ({err}). It is built "
        "when the package is installed: run `make setup`, or `pip install -e .` in the "
        "repository (needs a C++17 compiler with OpenMP and CMake >= 3.18).") from err

CHUNKS = _core.CHUNKS
POOL = _core.max_threads()  # the threads at import: OMP_NUM_THREADS, or the cores


def max_threads():
    """The threads the core's parallel loops use."""
    return _core.max_threads()


def set_threads(n):
    """Run the core's parallel loops on n threads."""
    _core.set_threads(int(n))


# --- pressure system: quadrature, walls (src/core/quadrature, walls) ---


def gauss_cell_tensors(h, K, C, V):
    """The element integrals K (2^D x 2^D), C (2^D x 2^D x D), V (2^D) of a full cell of side
    h from its 2^D Gauss points, into the arrays (float64; D from C's last axis)."""
    _core.gauss_cell_tensors(float(h), K, C, V)


def particle_cell_tensors(x, volume, order, start, cells_list, h, cells, K, C, V):
    """The element integrals of the cells ``cells_list`` with their material points as
    quadrature points into K[m], C[m], V[m] (K may have no rows: then C and V only); the
    particles of cell c are order[start[c]:start[c + 1]]."""
    _core.particle_cell_tensors(x, volume, order, start, cells_list, float(h),
                                [int(c) for c in cells], K, C, V)


def wall_pairs(cells, periodic=()):
    """(node, axis, sign) arrays of every wall node and wall of the grid ``cells``: the walls
    normal to axis 0 first, then axis 1, ...; the lower wall (sign -1) before the upper. A
    periodic axis (``periodic[k]``) has no walls."""
    cells = [int(c) for c in cells]
    periodic = [bool(p) for p in periodic]
    n = _core.wall_pair_count(cells, periodic)
    node = np.empty(n, dtype=np.int64)
    axis = np.empty(n, dtype=np.int64)
    sign = np.empty(n)
    _core.wall_pairs(cells, periodic, node, axis, sign)
    return node, axis, sign


def apply_walls(node, axis, sign, no_slip, v, contact):
    """Velocity conditions at the wall nodes, in place in v (nnodes x D): the normal velocity
    zeroed where the wall holds the material (``contact[i, k]``), elsewhere only a velocity
    into the wall; a no-slip pair (``no_slip``: a flag per pair, or one bool for all) zeroes
    the tangential velocity at its node in contact too."""
    _core.apply_walls(node, axis, sign, _pair_flags(no_slip, node), v, contact)


def _pair_flags(flags, node):
    """A bool per wall pair: ``flags`` as given, or one bool repeated."""
    return np.ascontiguousarray(np.broadcast_to(np.asarray(flags, dtype=np.bool_),
                                                np.shape(node)))


def start_contact(node, axis, sign, vstar, node_row, contact):
    """The wall contact as the pressure step starts, into ``contact`` (nnodes x D, bool): a
    wall node holds where it carries an unknown or v* presses into the wall."""
    _core.start_contact(node, axis, sign, vstar, node_row, contact)


def release_contact(node, axis, sign, vstar, node_row, p_node, contact):
    """Release the wall nodes in contact under tension that v* leaves (in place); returns
    how many (node, wall) pairs were released."""
    return _core.release_contact(node, axis, sign, vstar, node_row, p_node, contact)
# --- multigrid ---
COARSEST = _core.COARSEST  # unknowns at which the multigrid hierarchy stops (dense factor)
PARALLEL_ROWS = _core.PARALLEL_ROWS  # multigrid levels this large run on all threads


def multigrid(cols, vals, node, dims, coarsest=COARSEST, hierarchy=None):
    """A multigrid hierarchy (``_core.Multigrid2``/``Multigrid3``) set up for the ELL matrix
    (cols, vals: n x 3^D) whose row r is grid point node[r] of a grid of ``dims`` points per
    axis: ``hierarchy`` (an earlier one, whose storage is reused) when given, else a new one.
    It holds the arrays until its next setup; its ``pcg(rhs, x, tol, maxiter, sweeps)``
    updates x in place and returns (iterations, true relative residual); ``vcycle(b, x,
    sweeps)`` applies the preconditioner."""
    dims = tuple(int(d) for d in dims)
    kind = _core.Multigrid2 if len(dims) == 2 else _core.Multigrid3
    mg = hierarchy if isinstance(hierarchy, kind) else kind()
    mg.setup(np.ascontiguousarray(cols, dtype=np.int64), np.ascontiguousarray(vals, dtype=float),
             np.ascontiguousarray(node, dtype=np.int64), dims, int(coarsest))
    return mg


def matvec(cols, vals, x, y):
    """y = A x (A in ELL form); y: float64, written in place."""
    _core.matvec(cols, vals, x, y)


def residual(cols, vals, x, b, out):
    """out = b - A x (A in ELL form); out: float64, written in place."""
    _core.residual(cols, vals, x, b, out)


def dot(a, b):
    """a . b summed chunk by chunk when long: the same bits on any thread count."""
    return _core.dot(a, b)


def worst_row(cols, vals, x, b):
    """The row of the largest |b - A x| (NaN counts as largest)."""
    return _core.worst_row(cols, vals, x, b, np.empty(len(b)))
# --- transfer, corrector, volume correction ---
# (src/core/transfer.*, corrector.*, volume_correction.*, strips.hpp.) ``grid`` is a
# ``mpmflow.grid.Grid``; arrays the kernels write must be C-contiguous of the right dtype
# (float64, int64, bool) and are written in place.


def _cells(grid):
    return [int(c) for c in grid.cells]


def flip_per_step(flip, dt):
    """The FLIP fraction of one step of dt (s): flip^(dt / 1 ms), the same PIC damping per
    second whatever the step (the core's, used by both schemes)."""
    return float(_core.flip_per_step(float(flip), float(dt)))


def particles_to_grid(grid, x, v, mass, volume, order, start, gravity, dt, node_mass, node_mom,
                      node_vol, v_old, v_star, cell_vol, affine=None):
    """Particle-to-grid (eqs. 10-12): nodal mass, momentum, material volume, velocity v_old
    and predictor v_star = v_old + dt g where there is mass (0 elsewhere); with ``cell_vol``
    non-empty also the particles' volume on the cell centres. Particles binned by cell
    (``order``, ``start``). ``affine`` (n x D x D, APIC): the momentum carries each
    particle's affine field, m_p (v_p + C_p (x_i - x_p)); None: FLIP/PIC."""
    _core.particles_to_grid(x, v, mass, volume, order, start, float(grid.spacing), _cells(grid),
                            np.ascontiguousarray(gravity, dtype=float), float(dt), node_mass,
                            node_mom, node_vol, v_old, v_star, cell_vol,
                            None if affine is None else np.ascontiguousarray(affine, dtype=float))


def grid_to_particles(grid, x, v, pressure, v_old, v_new, p_node, dt, flip, upper, margin,
                      faces=(), affine=None):
    """Grid-to-particle (eqs. 19-21): FLIP/PIC velocity, positions moved with v_new plus the
    volume correction's displacement (``faces``: one array per axis; empty: none), pressure;
    particles that left the box [0, upper] put back inside. Returns how many were put back.
    ``affine`` (n x D x D, float64, written in place): APIC instead of FLIP/PIC, the particle
    velocity the PIC one and C_p the gradient of the interpolated v_new (``flip`` unused)."""
    if len(faces) == 0:
        faces = [np.zeros(0)] * grid.dim
    return int(_core.grid_to_particles(x, v, pressure, float(grid.spacing), _cells(grid), v_old,
                                       v_new, p_node, float(dt), float(flip),
                                       np.ascontiguousarray(upper, dtype=float), float(margin),
                                       list(faces), affine))


def pressure_noise(grid, x, mass, pressure, work_m=None, work_mp=None):
    """RMS over particles of p_p minus the mass-weighted grid-smoothed pressure at x_p (Pa);
    ``work_m``, ``work_mp``: scratch of one value per node (allocated if not given)."""
    if work_m is None:
        work_m = np.empty(grid.nnodes)
    if work_mp is None:
        work_mp = np.empty(grid.nnodes)
    return float(_core.pressure_noise(x, mass, pressure, float(grid.spacing), _cells(grid),
                                      work_m, work_mp))


def cell_volume(grid, x, volume, out):
    """sum_p N_c(x_p) V_p on every cell centre (m^3) into ``out`` (walls mirror)."""
    _core.cell_volume(x, volume, float(grid.spacing), _cells(grid), out)


def correct_velocity(grid, cell_slot, C, V, p_node, vstar, dt_over_rho, v_new):
    """The corrector v_new = v* - dt/rho (G p) / V at every node (eq. 16); nodes outside every
    cell of the system keep v*."""
    _core.correct_velocity(_cells(grid), cell_slot, C, V, p_node, vstar, float(dt_over_rho),
                           v_new)


def assemble_volume(grid, theta, density, wet, contact, static_slot, cell_row, cols, vals, rhs,
                    rows):
    """The volume correction's Poisson system on the cells holding material; returns
    (number of rows, whether any row touches air)."""
    n, anchored = _core.assemble_volume(_cells(grid), theta, density, float(wet), contact,
                                        static_slot, cell_row, cols, vals, rhs, rows)
    return int(n), bool(anchored)


def face_displacements(grid, cell_row, static_slot, q, scale, dmax, faces):
    """d = -scale grad q on the inner cell faces normal to each axis (m), limited to dmax;
    ``faces[k]``: the faces normal to axis k, written."""
    _core.face_displacements(_cells(grid), cell_row, static_slot, q, float(scale), float(dmax),
                             list(faces))


def strips(row_cum, nstrips, min_rows, bounds):
    """Cut rows into at most ``nstrips`` strips of at least ``min_rows`` rows holding about
    equal work (``row_cum``: the work before each row, n + 1 entries); strip t is rows
    bounds[t] to bounds[t + 1] - 1. Returns the number of strips."""
    return int(_core.strips(np.ascontiguousarray(row_cum, dtype=np.int64), int(nstrips),
                            int(min_rows), bounds))


# --- step ---


class Status(enum.IntEnum):
    """How a step ended (``Report.status``; the core's ``Status``, src/core/step.hpp)."""

    OK = _core.OK
    SINGULAR = _core.SINGULAR
    PRESSURE_NOT_CONVERGED = _core.PRESSURE_NOT_CONVERGED
    VOLUME_NOT_CONVERGED = _core.VOLUME_NOT_CONVERGED
    VISCOUS_NOT_CONVERGED = _core.VISCOUS_NOT_CONVERGED
    INTERRUPTED = _core.INTERRUPTED  # a signal asked the chunk to stop between steps


OK = Status.OK
SURFACE_QUADRATURE = {"gauss": _core.GAUSS, "divergence": _core.DIVERGENCE,
                      "consistent": _core.CONSISTENT}
Report = _core.Report


def _ints(a):
    return np.ascontiguousarray(a, dtype=np.int64)


def _floats(a):
    return np.ascontiguousarray(a, dtype=np.float64)


def step_state(grid, walls, solids, viscous_T, margin, volume_correction, viscous):
    """The compiled step's state for a grid (``mpmflow.grid.Grid``): ``walls`` = (node,
    axis, sign, no_slip) of the domain walls (``wall_pairs`` and a flag per pair), ``solids`` the obstacles' tables
    (``mpmflow.boundaries.obstacles.Tables``), ``viscous_T`` the full cell's gradient products (empty
    for inviscid material), ``margin`` (m) how far inside the walls particles are put back.
    The state keeps its own work arrays from step to step."""
    D = grid.dim
    cls = _core.State2 if D == 2 else _core.State3
    node, axis, sign, no_slip = walls
    o = solids
    return cls(float(grid.spacing), [int(c) for c in grid.cells], float(grid.cell_volume),
               [float(u) for u in grid.size], float(margin), _ints(node), _ints(axis),
               _floats(sign), _pair_flags(no_slip, node), _floats(o.phi), _floats(o.open), _ints(o.static_slot),
               _floats(o.K), _floats(o.C), _floats(o.V), _floats(o.F), _floats(o.Wf),
               _ints(o.node), _floats(np.reshape(o.normal, (-1, D))),
               np.ascontiguousarray(o.no_slip, dtype=np.bool_),
               _floats(viscous_T),
               bool(volume_correction), bool(viscous), [bool(p) for p in grid.periodic])


def step_options(dim, **settings):
    """The compiled step's settings (``Options2``/``Options3``) from keyword values."""
    opt = _core.Options2() if dim == 2 else _core.Options3()
    for key, value in settings.items():
        setattr(opt, key, value)
    return opt
# --- binning ---

def cell_index(x, h, cells, out):
    """Flat cell index of every particle (x: n x D, m) into ``out`` (int64)."""
    _core.cell_index(x, float(h), [int(c) for c in cells], out)


def counting_sort(cell, ncells, start, order):
    """Particles grouped by cell: cell c holds ``order[start[c]:start[c + 1]]``."""
    _core.counting_sort(cell, int(ncells), start, order)


def cell_volume_fraction(order, start, volume, cell_volume, open_, theta):
    """theta per cell: particle volume / cell volume, over the fluid part ``open_``."""
    _core.cell_volume_fraction(order, start, volume, float(cell_volume), open_, theta)


# --- cut_cells ---
# Cells cut by fixed obstacles (src/core/cut_cells.hpp; ``mpmflow.boundaries.obstacles``).

SLIVER = _core.SLIVER  # a cut cell with less fluid takes its volume fraction from beside


def cut_cell_tensors(phi_node, h, cells, candidates, nsub, K, C, V, F, Wf, solid_parts):
    """The element integrals K, C, V, the obstacle face term F and the wall face term Wf of
    the candidate cells (flat indices), with nsub sub-cells per axis; ``solid_parts[m]``:
    solid sub-cells and sub-faces of candidate m (0: not cut). Outputs are filled."""
    _core.cut_cell_tensors(np.ascontiguousarray(phi_node, dtype=float), float(h),
                           [int(c) for c in cells],
                           np.ascontiguousarray(candidates, dtype=np.int64), int(nsub), K, C,
                           V, F, Wf, solid_parts)


def face_mass(h, dim, Wf):
    """``Wf[f, a, b]`` (2 dim x 2^dim x 2^dim) of a whole cell: int N_a N_b over face f."""
    _core.face_mass(float(h), int(dim), Wf)


def push_out(x, v, phi_node, h, cells, margin):
    """Particles inside an obstacle moved out to phi = margin (x, v in place); returns how
    many were moved."""
    return _core.push_out(x, v, phi_node, float(h), [int(c) for c in cells], float(margin))


def sliver_fractions(cells, open_, theta):
    """theta of sliver cut cells (0 < open < SLIVER) from their face neighbours (in place)."""
    _core.sliver_fractions([int(c) for c in cells], open_, theta)


def extend_velocity(onode, cells, node_mass, v_old, v_star):
    """Velocities of the massless obstacle nodes from their neighbours' (in place)."""
    _core.extend_velocity(onode, [int(c) for c in cells], node_mass, v_old, v_star)
# --- viscous ---
# the rheology's model codes (``mpmflow.materials``) and the implicit viscous predictor
# (src/core/rheology.hpp, src/core/viscous.hpp)
WATER, NEWTONIAN, HERSCHEL_BULKLEY, MU_I = (_core.WATER, _core.NEWTONIAN,
                                            _core.HERSCHEL_BULKLEY, _core.MU_I)


def viscosity(model, par, rate, p):
    """The effective viscosity (Pa s) of rheology ``model`` with parameters ``par`` at strain
    rate ``rate`` (1/s) and pressure ``p`` (Pa)."""
    return _core.viscosity(int(model), np.ascontiguousarray(par, dtype=float), float(rate),
                           float(p))


def _viscous_out(a):
    """``a`` itself when C-contiguous (the core writes into it), else a C-contiguous copy to
    be copied back with ``_viscous_back``."""
    return a if a.flags.c_contiguous else np.ascontiguousarray(a)


def _viscous_back(a, c):
    if c is not a:
        a[...] = c


def gauss_gradients(cells, h):
    """T[a, b, m, k] = int over a full cell of dN_a/dx_m dN_b/dx_k (2^D x 2^D x D x D)."""
    D = len(cells)
    T = np.empty((1 << D, 1 << D, D, D))
    _core.gauss_gradients([int(c) for c in cells], float(h), T)
    return T


def cell_viscosity(cells, h, theta, open_, enclosed, full, v, p_node, model, par, eta, weight):
    """Each cell's viscosity ``eta`` and ``weight`` = eta x its fluid fraction (in place)."""
    etac, weightc = _viscous_out(eta), _viscous_out(weight)
    _core.cell_viscosity([int(c) for c in cells], float(h), theta, open_, enclosed, float(full),
                         v, p_node, int(model), np.ascontiguousarray(par, dtype=float), etac,
                         weightc)
    _viscous_back(eta, etac)
    _viscous_back(weight, weightc)


def number_unknowns(node_mass, wall_node, wall_axis, wall_no_slip, contact, onode, ocontact,
                    ono_slip, vstar, u, row, off):
    """Number the viscous system's unknowns (``u``, ``row``, ``off`` in place); returns
    their count. ``wall_no_slip``: a flag per wall pair (or one bool for all); ``contact``
    (nodes x D) and ``ocontact`` (nodes) say where the walls and obstacles hold the material
    (the pressure step's starting contact)."""
    uc, rowc = _viscous_out(u), _viscous_out(row)
    n = _core.number_unknowns(node_mass, wall_node, wall_axis,
                              _pair_flags(wall_no_slip, wall_node), contact, onode, ocontact,
                              ono_slip, vstar, uc, rowc, off)
    _viscous_back(u, uc)
    _viscous_back(row, rowc)
    return n


def viscous_assemble(cells, T, weight, node_mass, dt, u, row, off, cols, vals, rhs, node):
    """The viscous system's blocks, right-hand side and the node of each row (in place)."""
    out = [_viscous_out(a) for a in (cols, vals, rhs, node)]
    _core.viscous_assemble([int(c) for c in cells], T, weight, node_mass, float(dt), u, row, off,
                           *out)
    for a, c in zip((cols, vals, rhs, node), out):
        _viscous_back(a, c)


def viscous_worst_row(cols, vals, off, x, rhs):
    """The row of the largest |rhs - A x| of the viscous system (NaN counts as largest)."""
    return _core.viscous_worst_row(cols, vals, off, x, rhs)


def viscous_solve(cols, vals, node, off, cells, rhs, x, tol, maxiter, sweeps):
    """Block-preconditioned CG of the viscous system from the guess in ``x`` (in place).
    Returns (iterations, relative residual)."""
    xc = _viscous_out(x)
    result = _core.viscous_solve(cols, vals, node, off, [int(c) for c in cells], rhs, xc,
                                 float(tol), int(maxiter), int(sweeps))
    _viscous_back(x, xc)
    return result


# --- explicit scheme ---
# The weakly compressible explicit scheme (src/core/explicit_scheme.hpp), 2D and 3D. ``grid``
# is a ``mpmflow.grid.Grid``; arrays are C-contiguous float64 (``contact``: bool), vectors
# (count, dim); the cell and node work arrays are the scheme's (``schemes.explicit``).


def explicit_cell_state(grid, x, mass, volume, density, bulk, tension, full, sparse, cell_j,
                        cell_vol, cell_v0, cell_xi, cell_p):
    """Volumetric strain J and pressure once per cell from the particles in it (in place)."""
    _core.cell_state(x, mass, volume, density, bulk, tension, grid.spacing, list(grid.cells),
                     full, sparse, cell_j, cell_vol, cell_v0, cell_xi, cell_p)


def explicit_particle_state(grid, x, mass, volume, pressure, density, smoothing, cell_j,
                            cell_vol, cell_p, node_w, node_p):
    """Each particle's volume (its cell's J) and pressure (smoothed through the nodes or its
    cell's), in place."""
    _core.particle_state(x, mass, volume, pressure, density, grid.spacing, list(grid.cells),
                         bool(smoothing), cell_j, cell_vol, cell_p, node_w, node_p)


def explicit_max_speed(v):
    """The largest particle speed (m/s); NaN if any speed is NaN."""
    return _core.max_speed(v)


def explicit_steps(grid, span, nsteps, safety, x, v, pressure, mass, volume, density, bulk,
                   gravity, flip_ms, no_slip, smoothing, full, sparse, mass_cut, q_lin, q_quad,
                   tension, max_speed, upper, margin, node_mass, node_mom, v_old, v_new,
                   contact, cell_j, cell_vol, cell_v0, cell_xi, cell_p, cell_q, node_w, node_p,
                   stats):
    """Explicit steps over ``span`` seconds (in place); ``no_slip``: a flag per side (x_min,
    x_max, y_min, ...) or one bool for all; ``stats`` gets [steps taken, time
    advanced (s), smallest step (s), particles put back inside, 1 if stopped on
    ``max_speed`` else 0, largest particle speed (m/s) at the end]."""
    _core.explicit_steps(
        span, int(nsteps), safety, x, v, pressure, mass, volume, density, bulk,
        np.ascontiguousarray(gravity, dtype=float), grid.spacing, list(grid.cells), flip_ms,
        _pair_flags(no_slip, np.empty(2 * len(grid.cells))), bool(smoothing), full, sparse, mass_cut, q_lin, q_quad, tension,
        max_speed, np.ascontiguousarray(upper, dtype=float), margin, node_mass, node_mom,
        v_old, v_new, contact, cell_j, cell_vol, cell_v0, cell_xi, cell_p, cell_q, node_w,
        node_p, stats)


PHASES = tuple(_core.PHASES)  # the phases a step's State times (``phase_seconds``)
