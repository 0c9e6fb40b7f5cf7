"""Particle-grid kernels called from Python: transfers, the corrector, the volume
correction, binning and cut cells, and the particles' totals at an output time
(src/core/transfer, corrector, volume_correction, binning, cut_cells, totals, strips.hpp)."""

import math
from collections.abc import Callable, Sequence
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from .. import _core, arrays
from ..arrays import Bools, Floats, Ints
from ..grid import Grid

# (src/core/transfer.*, corrector.*, volume_correction.*, strips.hpp.) ``grid`` is a
# ``mpmflow.grid.Grid``; arrays the kernels write must be C-contiguous of the right dtype
# (float64, int64, bool) and are written in place.


def flip_per_step(flip: float, dt: float) -> float:
    """The FLIP fraction of one step of dt (s): flip^(dt / 1 ms), the same PIC damping per
    second whatever the step (the core's, used by both schemes)."""
    return float(_core.flip_per_step(float(flip), float(dt)))


def particles_to_grid(
    grid: Grid,
    x: Floats,
    v: Floats,
    mass: Floats,
    volume: Floats,
    order: Ints,
    start: Ints,
    gravity: ArrayLike,
    dt: float,
    node_mass: Floats,
    node_mom: Floats,
    node_vol: Floats,
    v_old: Floats,
    v_star: Floats,
    cell_vol: Floats,
    affine: ArrayLike | None = None,
) -> None:
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
    grid: Grid,
    x: Floats,
    v: Floats,
    pressure: Floats,
    v_old: Floats,
    v_new: Floats,
    p_node: Floats,
    dt: float,
    flip: float,
    upper: ArrayLike,
    margin: float,
    faces: Sequence[Floats] = (),
    affine: Floats | None = None,
) -> int:
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


class Totals(NamedTuple):
    """The particles' totals at an output time (src/core/totals.hpp), in one pass."""

    kinetic: float  # J (J/m in 2D)
    potential: float  # J (J/m in 2D), -sum m g . x
    max_speed: float  # m/s, of the finite particles (nan: none)
    max_pressure: float  # Pa (nan: no particle)
    fastest: int  # the particle of max_speed (-1: none)
    nonfinite: int  # particles with a non-finite position or velocity
    first_nonfinite: int  # the first of those (-1: none)


def particle_totals(
    x: Floats, v: Floats, mass: Floats, pressure: Floats, gravity: Sequence[float]
) -> Totals:
    """Kinetic and potential energy, the fastest particle, the largest pressure and the
    non-finite particles of (x, v: n x D; mass, pressure: n) under ``gravity`` (D entries,
    m/s^2), in one pass over the particles (fixed chunks: the same bits on any number of
    threads). Non-finite particles are counted and left out of the rest."""
    g = np.ascontiguousarray(gravity, dtype=float)
    k, u, s2, pmax, fastest, bad, first = _core.particle_totals(x, v, mass, pressure, g)
    none = fastest < 0
    return Totals(
        float(k),
        float(u),
        math.nan if none else math.sqrt(s2),
        math.nan if x.shape[0] == 0 else float(pmax),
        int(fastest),
        int(bad),
        int(first),
    )


def pressure_noise(
    grid: Grid,
    x: Floats,
    mass: Floats,
    pressure: Floats,
    work_m: Floats | None = None,
    work_mp: Floats | None = None,
    add: Callable[[Floats], Floats] | None = None,
    order: Ints | None = None,
    start: Ints | None = None,
) -> float:
    """RMS over particles of p_p minus the mass-weighted grid-smoothed pressure at x_p (Pa);
    ``work_m``, ``work_mp``: scratch of one value per node (allocated if not given).
    ``add``: for particles held in parts (one per MPI rank), the sum of an array over the
    parts; the smoothing then reads every part's particles, the RMS runs over all of them
    and every part gets the whole run's value. ``order``, ``start``: the particles grouped
    by cell (``counting_sort``'s), binned here if not given."""
    if work_m is None:
        work_m = np.empty(grid.nnodes)
    if work_mp is None:
        work_mp = np.empty(grid.nnodes)
    h, cells = float(grid.spacing), arrays.cells(grid)
    if order is None or start is None:
        cell = np.empty(len(x), dtype=np.int64)
        order, start = np.empty(len(x), dtype=np.int64), np.empty(grid.ncells + 1, dtype=np.int64)
        cell_index(x, h, cells, cell)
        counting_sort(cell, grid.ncells, start, order)
    _core.scatter_mass_pressure(x, mass, pressure, order, start, h, cells, work_m, work_mp)
    if add is not None:
        work_m, work_mp = add(work_m), add(work_mp)
    total = float(_core.pressure_deviation(x, pressure, h, cells, work_m, work_mp))
    n = float(len(x))
    if add is not None:
        total, n = (float(v) for v in add(np.array([total, n])))
    return math.sqrt(total / max(n, 1.0))


def cell_volume(grid: Grid, x: Floats, volume: Floats, out: Floats) -> None:
    """sum_p N_c(x_p) V_p on every cell centre (m^3) into ``out`` (walls mirror)."""
    _core.cell_volume(x, volume, float(grid.spacing), arrays.cells(grid), out)


def correct_velocity(
    grid: Grid,
    cell_slot: Ints,
    C: Floats,
    V: Floats,
    p_node: Floats,
    vstar: Floats,
    dt_over_rho: float,
    v_new: Floats,
) -> None:
    """The corrector v_new = v* - dt/rho (G p) / V at every node (eq. 16); nodes outside every
    cell of the system keep v*."""
    _core.correct_velocity(
        arrays.cells(grid), cell_slot, C, V, p_node, vstar, float(dt_over_rho), v_new
    )


def assemble_volume(
    grid: Grid,
    theta: Floats,
    density: Floats,
    wet: float,
    contact: Bools,
    static_slot: Ints,
    cell_row: Ints,
    cols: Ints,
    vals: Floats,
    rhs: Floats,
    rows: Ints,
) -> tuple[int, bool]:
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


def face_displacements(
    grid: Grid,
    cell_row: Ints,
    static_slot: Ints,
    q: Floats,
    scale: float,
    dmax: float,
    faces: Sequence[Floats],
) -> None:
    """d = -scale grad q on the inner cell faces normal to each axis (m), limited to dmax;
    ``faces[k]``: the faces normal to axis k, written."""
    _core.face_displacements(
        arrays.cells(grid), cell_row, static_slot, q, float(scale), float(dmax), list(faces)
    )


def strips(row_cum: ArrayLike, nstrips: int, min_rows: int, bounds: Ints) -> int:
    """Cut rows into at most ``nstrips`` strips of at least ``min_rows`` rows holding about
    equal work (``row_cum``: the work before each row, n + 1 entries); strip t is rows
    bounds[t] to bounds[t + 1] - 1. Returns the number of strips."""
    return int(
        _core.strips(
            np.ascontiguousarray(row_cum, dtype=np.int64), int(nstrips), int(min_rows), bounds
        )
    )


def cell_index(x: Floats, h: float, cells: Sequence[int], out: Ints) -> None:
    """Flat cell index of every particle (x: n x D, m) into ``out`` (int64)."""
    _core.cell_index(x, float(h), [int(c) for c in cells], out)


def counting_sort(cell: Ints, ncells: int, start: Ints, order: Ints) -> None:
    """Particles grouped by cell: cell c holds ``order[start[c]:start[c + 1]]``."""
    _core.counting_sort(cell, int(ncells), start, order)


def cell_volume_fraction(
    order: Ints, start: Ints, volume: Floats, cell_volume: float, open_: Floats, theta: Floats
) -> None:
    """theta per cell: particle volume / cell volume, over the fluid part ``open_``."""
    _core.cell_volume_fraction(order, start, volume, float(cell_volume), open_, theta)


# Cells cut by fixed obstacles (src/core/cut_cells.hpp; ``mpmflow.boundaries.obstacles``).

SLIVER: float = _core.SLIVER  # a cut cell with less fluid takes its volume fraction from beside


def cut_cell_tensors(
    phi_node: ArrayLike,
    h: float,
    cells: Sequence[int],
    candidates: ArrayLike,
    nsub: int,
    K: Floats,
    C: Floats,
    V: Floats,
    F: Floats,
    Wf: Floats,
    solid_parts: Ints,
) -> None:
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


def face_mass(h: float, dim: int, Wf: Floats) -> None:
    """``Wf[f, a, b]`` (2 dim x 2^dim x 2^dim) of a whole cell: int N_a N_b over face f."""
    _core.face_mass(float(h), int(dim), Wf)


def push_out(
    x: Floats, v: Floats, phi_node: Floats, h: float, cells: Sequence[int], margin: float
) -> int:
    """Particles inside an obstacle moved out to phi = margin (x, v in place); returns how
    many were moved."""
    return int(_core.push_out(x, v, phi_node, float(h), [int(c) for c in cells], float(margin)))


def sliver_fractions(cells: Sequence[int], open_: Floats, theta: Floats) -> None:
    """theta of sliver cut cells (0 < open < SLIVER) from their face neighbours (in place)."""
    _core.sliver_fractions([int(c) for c in cells], open_, theta)


def extend_velocity(
    onode: Ints, cells: Sequence[int], node_mass: Floats, v_old: Floats, v_star: Floats
) -> None:
    """Velocities of the massless obstacle nodes from their neighbours' (in place)."""
    _core.extend_velocity(onode, [int(c) for c in cells], node_mass, v_old, v_star)
