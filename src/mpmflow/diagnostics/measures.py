"""Quantities measured on a running simulation (SI units).

``front`` and ``height`` follow the definition used for the VOF reference data: on the
per-cell particle volume fraction f (clipped to [0, 1]), along each row of cells, the x
where f last crosses 1/2 going right (linear interpolation between cell centres; the wall
position if the last cell is at least half full); ``front`` is the largest over rows.
``height`` is the same in y along the column of cells touching the left wall (x = 0). In 3D
the vertical is z, and both run over every row (column) of cells across the width.
"""

from collections.abc import Callable, Sequence

import numpy as np

from .. import state
from ..arrays import Floats
from ..cells import CellBins
from ..grid import Grid
from ..particles import Particles

# A cell at least this full is half full, to rounding, as the volume correction takes it
# (src/core/volume_correction.hpp): read exactly, the 3D dam break with slip walls and no
# volume correction (every slice the 2D flow, the cells' fractions equal to 1e-16) read its
# front a cell behind the 2D run's at 0.15 s, 0.07 a.
HALF_FULL = state.HALF_FULL


def last_crossings(f: Floats, centres: Floats, wall: float) -> Floats:
    """For every column j of f (one value per cell along axis 0), the position where f[:, j]
    last drops below 1/2; ``wall`` if the last cell is at least half full; nan if never."""
    above = f >= HALF_FULL
    n = f.shape[0]
    k = n - 1 - np.argmax(above[::-1], axis=0)
    out = np.full(f.shape[1], np.nan)
    seen = above.any(axis=0)
    out[seen & (k == n - 1)] = wall
    j = np.flatnonzero(seen & (k < n - 1))
    k = k[j]
    f0, f1 = f[k, j], f[k + 1, j]
    out[j] = centres[k] + (centres[k + 1] - centres[k]) * (f0 - 0.5) / (f0 - f1)
    return out


def last_crossing(f: Floats, centres: Floats, wall: float) -> float:
    """Position where the profile f (one value per cell) last drops below 1/2; nan if never above."""
    return float(last_crossings(f[:, None], centres, wall)[0])


def volume_fraction_field(grid: Grid, theta: Floats, clip: bool = True) -> Floats:
    """Cell volume fractions as an array indexed [cx, cy] ([cx, cy, cz] in 3D), clipped to
    [0, 1] (``clip``; else only to >= 0: the particles' volume over the cell's, which
    exceeds 1 where the lattice is strained)."""
    f: Floats = np.clip(theta, 0.0, 1.0 if clip else None).reshape(grid.cells[::-1]).T
    return f


def front_and_height(grid: Grid, theta: Floats) -> tuple[float, float]:
    """(front, height) in metres from the cell volume fractions theta (flat cell order).
    In 3D the front is the largest over all rows of cells along x, and the height the mean
    over the vertical columns of cells along the wall x = 0 (the vertical is the last axis)."""
    f = volume_fraction_field(grid, theta)  # [c_0, ..., c_{D-1}]
    fronts = last_crossings(f.reshape(f.shape[0], -1), grid.cell_centres(0), grid.size[0])
    front = np.nanmax(fronts) if np.isfinite(fronts).any() else np.nan
    wall = np.moveaxis(f[0], -1, 0)  # the cells against x = 0, vertical axis first
    heights = last_crossings(
        wall.reshape(wall.shape[0], -1), grid.cell_centres(grid.dim - 1), grid.size[-1]
    )
    height = np.nanmean(heights) if np.isfinite(heights).any() else np.nan
    return float(front), float(height)


WET = HALF_FULL  # a cell at least half full is wetted (as for front and height)
PACKED = 1.2  # a cell more than 20% over full is packed


def volume_measures(
    theta: Floats, cell_volume: float, material_volume: float, open_: Floats | None = None
) -> dict[str, float]:
    """``volume_ratio``: the volume of the wetted cells (f >= 1/2) over the material's volume,
    uncapped (loosening shows as > 1, packing as < 1), counting the fluid part of cells that
    obstacles cut (``open_``); ``packed_share``: the share of the cells holding material
    with f > 1.2."""
    holding = int(np.count_nonzero(theta > 0.0))
    wet = theta >= WET
    wetted = np.count_nonzero(wet) if open_ is None else float(open_[wet].sum())
    return {
        "volume_ratio": float(wetted * cell_volume / material_volume),
        "packed_share": float(np.count_nonzero(theta > PACKED) / max(holding, 1)),
    }


def totals(particles: Particles, gravity: Sequence[float]) -> state.Totals:
    """Kinetic and potential energy (J; J/m in 2D), the fastest particle and its speed
    (m/s), the largest pressure (Pa) and the particles that are not finite, in one pass of
    the core over the particles (``state.particle_totals``)."""
    P = particles
    return state.particle_totals(P.x, P.v, P.mass, P.pressure, gravity)


def pressure_noise(
    grid: Grid,
    particles: Particles,
    add: Callable[[Floats], Floats] | None = None,
    bins: CellBins | None = None,
) -> float:
    """RMS difference between particle pressure and its grid-smoothed value (Pa); ``add``:
    the sum over the parts of particles held in parts (``state.pressure_noise``); ``bins``:
    the particles binned by cell at this time, if at hand."""
    P = particles
    if bins is None:
        return state.pressure_noise(grid, P.x, P.mass, P.pressure, add=add)
    return state.pressure_noise(
        grid, P.x, P.mass, P.pressure, add=add, order=bins.order, start=bins.start
    )
