"""Particle-grid kernels called from Python: transfers, the corrector, the volume
correction, binning and cut cells (src/core/transfer, corrector, volume_correction,
binning, cut_cells, strips.hpp)."""

import numpy as np

from .. import _core
from ..grid import Grid
from . import arrays

# (src/core/transfer.*, corrector.*, volume_correction.*, strips.hpp.) ``grid`` is a
# ``mpmflow.grid.Grid``; arrays the kernels write must be C-contiguous of the right dtype
# (float64, int64, bool) and are written in place.


def flip_per_step(flip, dt):
    """The FLIP fraction of one step of dt (s): flip^(dt / 1 ms), the same PIC damping per
    second whatever the step (the core's, used by both schemes)."""
    return float(_core.flip_per_step(float(flip), float(dt)))


def particles_to_grid(
    grid,
    x,
    v,
    mass,
    volume,
    order,
    start,
    gravity,
    dt,
    node_mass,
    node_mom,
    node_vol,
    v_old,
    v_star,
    cell_vol,
    affine=None,
):
    """Particle-to-grid (eqs. 10-12): nodal mass, momentum, material volume, velocity v_old
    and predictor v_star = v_old + dt g where there is mass (0 elsewhere); with ``cell_vol``
    non-empty also the particles' volume on the cell centres. Particles binned by cell
    (``order``, ``start``). ``affine`` (n x D x D, APIC): the momentum carries each
    particle's affine field, m_p (v_p + C_p (x_i - x_p)); None: FLIP/PIC."""
    _core.particles_to_grid(
        x,
        v,
        mass,
        volume,
        order,
        start,
        float(grid.spacing),
        arrays.cells(grid),
        np.ascontiguousarray(gravity, dtype=float),
        float(dt),
        node_mass,
        node_mom,
        node_vol,
        v_old,
        v_star,
        cell_vol,
        None if affine is None else np.ascontiguousarray(affine, dtype=float),
    )


def grid_to_particles(
    grid, x, v, pressure, v_old, v_new, p_node, dt, flip, upper, margin, faces=(), affine=None
):
    """Grid-to-particle (eqs. 19-21): FLIP/PIC velocity, positions moved with v_new plus the
    volume correction's displacement (``faces``: one array per axis; empty: none), pressure;
    particles that left the box [0, upper] put back inside. Returns how many were put back.
    ``affine`` (n x D x D, float64, written in place): APIC instead of FLIP/PIC, the particle
    velocity the PIC one and C_p the gradient of the interpolated v_new (``flip`` unused)."""
    if len(faces) == 0:
        faces = [np.zeros(0)] * grid.dim
    return int(
        _core.grid_to_particles(
            x,
            v,
            pressure,
            float(grid.spacing),
            arrays.cells(grid),
            v_old,
            v_new,
            p_node,
            float(dt),
            float(flip),
            np.ascontiguousarray(upper, dtype=float),
            float(margin),
            list(faces),
            affine,
        )
    )


def pressure_noise(
    grid: Grid,
    x: np.ndarray,
    mass: np.ndarray,
    pressure: np.ndarray,
    work_m: np.ndarray | None = None,
    work_mp: np.ndarray | None = None,
) -> float:
    """RMS over particles of p_p minus the mass-weighted grid-smoothed pressure at x_p (Pa);
    ``work_m``, ``work_mp``: scratch of one value per node (allocated if not given)."""
    if work_m is None:
        work_m = np.empty(grid.nnodes)
    if work_mp is None:
        work_mp = np.empty(grid.nnodes)
    return float(
        _core.pressure_noise(
            x, mass, pressure, float(grid.spacing), arrays.cells(grid), work_m, work_mp
        )
    )


def cell_volume(grid, x, volume, out):
    """sum_p N_c(x_p) V_p on every cell centre (m^3) into ``out`` (walls mirror)."""
    _core.cell_volume(x, volume, float(grid.spacing), arrays.cells(grid), out)


def correct_velocity(grid, cell_slot, C, V, p_node, vstar, dt_over_rho, v_new):
    """The corrector v_new = v* - dt/rho (G p) / V at every node (eq. 16); nodes outside every
    cell of the system keep v*."""
    _core.correct_velocity(
        arrays.cells(grid), cell_slot, C, V, p_node, vstar, float(dt_over_rho), v_new
    )


def assemble_volume(
    grid, theta, density, wet, contact, static_slot, cell_row, cols, vals, rhs, rows
):
    """The volume correction's Poisson system on the cells holding material; returns
    (number of rows, whether any row touches air)."""
    n, anchored = _core.assemble_volume(
        arrays.cells(grid),
        theta,
        density,
        float(wet),
        contact,
        static_slot,
        cell_row,
        cols,
        vals,
        rhs,
        rows,
    )
    return int(n), bool(anchored)


def face_displacements(grid, cell_row, static_slot, q, scale, dmax, faces):
    """d = -scale grad q on the inner cell faces normal to each axis (m), limited to dmax;
    ``faces[k]``: the faces normal to axis k, written."""
    _core.face_displacements(
        arrays.cells(grid), cell_row, static_slot, q, float(scale), float(dmax), list(faces)
    )


def strips(row_cum, nstrips, min_rows, bounds):
    """Cut rows into at most ``nstrips`` strips of at least ``min_rows`` rows holding about
    equal work (``row_cum``: the work before each row, n + 1 entries); strip t is rows
    bounds[t] to bounds[t + 1] - 1. Returns the number of strips."""
    return int(
        _core.strips(
            np.ascontiguousarray(row_cum, dtype=np.int64), int(nstrips), int(min_rows), bounds
        )
    )


def cell_index(x, h, cells, out):
    """Flat cell index of every particle (x: n x D, m) into ``out`` (int64)."""
    _core.cell_index(x, float(h), [int(c) for c in cells], out)


def counting_sort(cell, ncells, start, order):
    """Particles grouped by cell: cell c holds ``order[start[c]:start[c + 1]]``."""
    _core.counting_sort(cell, int(ncells), start, order)


def cell_volume_fraction(order, start, volume, cell_volume, open_, theta):
    """theta per cell: particle volume / cell volume, over the fluid part ``open_``."""
    _core.cell_volume_fraction(order, start, volume, float(cell_volume), open_, theta)


# Cells cut by fixed obstacles (src/core/cut_cells.hpp; ``mpmflow.boundaries.obstacles``).

SLIVER = _core.SLIVER  # a cut cell with less fluid takes its volume fraction from beside


def cut_cell_tensors(phi_node, h, cells, candidates, nsub, K, C, V, F, Wf, solid_parts):
    """The element integrals K, C, V, the obstacle face term F and the wall face term Wf of
    the candidate cells (flat indices), with nsub sub-cells per axis; ``solid_parts[m]``:
    solid sub-cells and sub-faces of candidate m (0: not cut). Outputs are filled."""
    _core.cut_cell_tensors(
        np.ascontiguousarray(phi_node, dtype=float),
        float(h),
        [int(c) for c in cells],
        np.ascontiguousarray(candidates, dtype=np.int64),
        int(nsub),
        K,
        C,
        V,
        F,
        Wf,
        solid_parts,
    )


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
