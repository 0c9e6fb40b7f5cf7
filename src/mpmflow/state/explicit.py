"""The weakly compressible comparator's kernels (src/core/explicit_scheme)."""

import numpy as np

from .. import _core
from . import arrays

# The weakly compressible explicit scheme (src/core/explicit_scheme.hpp), 2D and 3D. ``grid``
# is a ``mpmflow.grid.Grid``; arrays are C-contiguous float64 (``contact``: bool), vectors
# (count, dim); the cell and node work arrays are the scheme's (``schemes.explicit``).


def explicit_cell_state(
    grid,
    x,
    mass,
    volume,
    density,
    bulk,
    tension,
    full,
    sparse,
    cell_j,
    cell_vol,
    cell_v0,
    cell_xi,
    cell_p,
):
    """Volumetric strain J and pressure once per cell from the particles in it (in place)."""
    _core.cell_state(
        x,
        mass,
        volume,
        density,
        bulk,
        tension,
        grid.spacing,
        list(grid.cells),
        full,
        sparse,
        cell_j,
        cell_vol,
        cell_v0,
        cell_xi,
        cell_p,
    )


def explicit_particle_state(
    grid, x, mass, volume, pressure, density, smoothing, cell_j, cell_vol, cell_p, node_w, node_p
):
    """Each particle's volume (its cell's J) and pressure (smoothed through the nodes or its
    cell's), in place."""
    _core.particle_state(
        x,
        mass,
        volume,
        pressure,
        density,
        grid.spacing,
        list(grid.cells),
        bool(smoothing),
        cell_j,
        cell_vol,
        cell_p,
        node_w,
        node_p,
    )


def explicit_max_speed(v):
    """The largest particle speed (m/s); NaN if any speed is NaN."""
    return _core.max_speed(v)


def explicit_steps(
    grid,
    span,
    nsteps,
    safety,
    x,
    v,
    pressure,
    mass,
    volume,
    density,
    bulk,
    gravity,
    flip_ms,
    no_slip,
    smoothing,
    full,
    sparse,
    mass_cut,
    q_lin,
    q_quad,
    tension,
    max_speed,
    upper,
    margin,
    node_mass,
    node_mom,
    v_old,
    v_new,
    contact,
    cell_j,
    cell_vol,
    cell_v0,
    cell_xi,
    cell_p,
    cell_q,
    node_w,
    node_p,
    stats,
):
    """Explicit steps over ``span`` seconds (in place); ``no_slip``: a flag per side (x_min,
    x_max, y_min, ...) or one bool for all; ``stats`` gets [steps taken, time
    advanced (s), smallest step (s), particles put back inside, 1 if stopped on
    ``max_speed`` else 0, largest particle speed (m/s) at the end]."""
    _core.explicit_steps(
        span,
        int(nsteps),
        safety,
        x,
        v,
        pressure,
        mass,
        volume,
        density,
        bulk,
        np.ascontiguousarray(gravity, dtype=float),
        grid.spacing,
        list(grid.cells),
        flip_ms,
        arrays.pair_flags(no_slip, np.empty(2 * len(grid.cells))),
        bool(smoothing),
        full,
        sparse,
        mass_cut,
        q_lin,
        q_quad,
        tension,
        max_speed,
        np.ascontiguousarray(upper, dtype=float),
        margin,
        node_mass,
        node_mom,
        v_old,
        v_new,
        contact,
        cell_j,
        cell_vol,
        cell_v0,
        cell_xi,
        cell_p,
        cell_q,
        node_w,
        node_p,
        stats,
    )
