"""The scheme's state and the one door to the compiled core (``mpmflow._core``).

Nothing else in mpmflow imports the core: the rest of the package calls the functions
here, which take NumPy arrays and grids and call the C++ kernels (src/core, one header/
source pair per concept). The core is built once, at install (scikit-build-core, CMake);
nothing compiles at run time.
"""

import numpy as np

from . import _core

CHUNKS = _core.CHUNKS


def max_threads():
    """The threads the core's parallel loops use."""
    return _core.max_threads()


def set_threads(n):
    """Run the core's parallel loops on n threads."""
    _core.set_threads(int(n))


# --- transfer, corrector, volume correction ---
# (src/core/transfer.*, corrector.*, volume_correction.*, strips.hpp.) ``grid`` is a
# ``mpmflow.grid.Grid``; arrays the kernels write must be C-contiguous of the right dtype
# (float64, int64, bool) and are written in place.


def _cells(grid):
    return [int(c) for c in grid.cells]


def particles_to_grid(grid, x, v, mass, volume, order, start, gravity, dt, node_mass, node_mom,
                      node_vol, v_old, v_star, cell_vol):
    """Particle-to-grid (eqs. 10-12): nodal mass, momentum, material volume, velocity v_old
    and predictor v_star = v_old + dt g where there is mass (0 elsewhere); with ``cell_vol``
    non-empty also the particles' volume on the cell centres. Particles binned by cell
    (``order``, ``start``)."""
    _core.particles_to_grid(x, v, mass, volume, order, start, float(grid.spacing), _cells(grid),
                            np.ascontiguousarray(gravity, dtype=float), float(dt), node_mass,
                            node_mom, node_vol, v_old, v_star, cell_vol)


def grid_to_particles(grid, x, v, pressure, v_old, v_new, p_node, dt, flip, upper, margin,
                      faces=()):
    """Grid-to-particle (eqs. 19-21): FLIP/PIC velocity, positions moved with v_new plus the
    volume correction's displacement (``faces``: one array per axis; empty: none), pressure;
    particles that left the box [0, upper] put back inside. Returns how many were put back."""
    if len(faces) == 0:
        faces = [np.zeros(0)] * grid.dim
    return int(_core.grid_to_particles(x, v, pressure, float(grid.spacing), _cells(grid), v_old,
                                       v_new, p_node, float(dt), float(flip),
                                       np.ascontiguousarray(upper, dtype=float), float(margin),
                                       list(faces)))


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
