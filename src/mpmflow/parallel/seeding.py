"""Each rank's own particles of a case, seeded without any rank holding the whole run
(issue 42, item 3).

Every rank walks the bodies' lattice in chunks (``geometry.seeding.body_pieces`` with
``lattice.CHUNK`` points a chunk) twice: first counting the particles of each cell, from
which the ranks' boxes follow (``boxes.bisect``, the split the scheme makes at its start),
then keeping the particles whose cell its box holds, with their numbers in the run (their
places in the order one process seeds them). A rank holds a chunk and its own particles at
once, never the whole set; it does the whole seeding's arithmetic, once per pass.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ..arrays import Ints
from ..geometry.lattice import CHUNK
from ..geometry.seeding import body_pieces, check_packing, obstacle_shapes
from ..grid import Grid
from ..particles import Particles, subset
from .boxes import bisect, cell_weights
from .comm import Comm, agreed

if TYPE_CHECKING:
    from ..case import Case


def seed_part(case: Case, grid: Grid, comm: Comm) -> tuple[Particles, Ints]:
    """This rank's particles of the case and their numbers in the run (ascending). The
    packing check (``seeding.check_packing``) runs on each rank's cells, which hold all
    their particles; a refusal on any rank is every rank's CaseError."""
    obstacles = obstacle_shapes(case)
    bodies = range(len(case.bodies))
    weights: Any = 0
    for k in bodies:
        for piece in body_pieces(case, grid, k, obstacles, CHUNK):
            weights = weights + cell_weights(piece.x, grid.spacing, grid.cells)
    if isinstance(weights, int):  # no lattice point in any body
        weights = np.zeros(tuple(int(c) for c in grid.cells), dtype=np.int64)
    boxes = bisect(weights, comm.size)
    D = grid.dim
    kept = [Particles(np.zeros((0, D)), np.zeros((0, D)), np.zeros(0), np.zeros(0), np.zeros(0))]
    numbers = [np.zeros(0, dtype=np.int64)]
    counts = []
    first = 0
    for k in bodies:
        count = 0
        for piece in body_pieces(case, grid, k, obstacles, CHUNK):
            mine = boxes.owner_of_points(piece.x, grid.spacing) == comm.rank
            kept.append(subset(piece, mine))
            numbers.append(first + np.flatnonzero(mine))
            first += piece.count
            count += int(mine.sum())
        counts.append(count)
    part = Particles.concatenate(kept)
    agreed(comm, lambda: check_packing(case, grid, part, counts))
    return part, np.concatenate(numbers)


def renumbered(comm: Comm, numbers: Ints, left_out: Any) -> Ints:
    """The numbers in the run of this rank's particles after those ``left_out`` (a mask of
    this rank's) are taken out of the run on every rank: each one's less the particles
    taken out before it."""
    out = np.sort(np.concatenate(comm.allgather(numbers[left_out])))
    kept = numbers[~left_out]
    renumbered: Ints = kept - np.searchsorted(out, kept)
    return renumbered
