"""Which particles lie in which cell, and the cell volume fractions theta (eqs. 8, 9)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from . import state
from .arrays import Floats, Ints
from .grid import Grid
from .particles import Particles


@dataclass
class CellBins:
    """Particles grouped by cell: cell ``c`` holds ``order[start[c]:start[c+1]]``."""

    cell: Ints  # (n,) flat cell index of each particle
    start: Ints  # (ncells+1,)
    order: Ints  # (n,)
    theta: Floats  # (ncells,) particle volume / cell volume

    def counts(self) -> Ints:
        return np.diff(self.start)


def bin_particles(
    grid: Grid,
    particles: Particles,
    bins: CellBins | None = None,
    open_: Floats | None = None,
    add: Callable[[Floats], Floats] | None = None,
) -> CellBins:
    """Bin the particles (reusing ``bins``' arrays when given) and compute theta per cell
    (over the fluid part of cells that obstacles cut: ``open_``, ``mpmflow.boundaries.obstacles``).
    ``add``: for particles held in parts (one per MPI rank), the sum of an array over the
    parts: theta is then the whole run's (the bins stay the part's own particles)."""
    n = particles.count
    if bins is None or bins.cell.shape[0] != n:
        bins = CellBins(
            cell=np.empty(n, dtype=np.int64),
            start=np.empty(grid.ncells + 1, dtype=np.int64),
            order=np.empty(n, dtype=np.int64),
            theta=np.empty(grid.ncells),
        )
    state.cell_index(particles.x, grid.spacing, grid.cells, bins.cell)
    state.counting_sort(bins.cell, grid.ncells, bins.start, bins.order)
    if open_ is None:
        open_ = np.ones(grid.ncells)
    state.cell_volume_fraction(
        bins.order, bins.start, particles.volume, grid.cell_volume, open_, bins.theta
    )
    if add is not None:
        bins.theta = add(bins.theta)
    if (open_ < 1.0).any():
        state.sliver_fractions(grid.cells, open_, bins.theta)
    return bins
