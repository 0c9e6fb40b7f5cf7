"""The volume correction (docs/method.md, "Volume correction") over MPI ranks: its
cell-centred system assembled per rank, solved by PETSc, applied per rank.

On a step that corrects, the compiled step (src/core/step.cpp, volume_correction) completes
the particle volume each cell holds (``cell_vol``, from ``scatter``) at the cells a rank
holds without owning them by their owners' values, and ``volume_system`` assembles the rows
of the local cells (the ghost layer's cells have every particle of theirs in the halo, so a
rank and the owner agree on which cells are rows); the ranks decide together whether the
system has rows and touches an empty cell. Here (the core's volume solver on a rank) the
owned rows are numbered after the ranks before, PETSc solves to
``solver.volume_correction_tolerance`` and the solution reaches the ghost layer; the
step's ``volume_apply`` moves the faces the particles are displaced by in
``to_particles``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from ..arrays import Floats, Ints
from ..errors import SolverError
from ..schemes import volume_correction
from .comm import Comm
from .exchange import NodeExchange, number_rows, spread
from .petsc import DistributedSystem, Preconditioner
from .pockets import sealed_pockets
from .subgrid import Subgrid

if TYPE_CHECKING:
    from ..state.step import CoreState


class DistributedVolume:
    """The volume correction's solve over the ranks (its own PETSc system): the core's
    volume solver on a rank (``State.use_solvers``); ``bind`` gives it a split's local
    state."""

    def __init__(self, comm: Comm, tolerance: float, preconditioner: Preconditioner) -> None:
        self.comm = comm
        self.system = DistributedSystem(tolerance, volume_correction.MAX_ITERATIONS, preconditioner)
        self.iterations = 0
        self.where: Callable[[], str] = lambda: ""

    def bind(
        self, core: CoreState, sub: Subgrid, cells: NodeExchange, where: Callable[[], str]
    ) -> None:
        self.core, self.sub, self.cells, self.where = core, sub, cells, where

    def setup(self, cols: Ints, vals: Floats, rows: Ints) -> None:
        """Number the owned rows (cells) over the ranks and hand PETSc this rank's block."""
        comm, sub = self.comm, self.sub
        owned = np.flatnonzero(sub.owned_cells[rows])
        count = sub.grid.ncells
        number, first, n = number_rows(comm, self.cells, (count,), rows[owned])
        mine = cols[owned]
        global_cols = np.where(mine >= 0, number[rows[np.maximum(mine, 0)]], -1)
        where = self.where()
        if comm.allreduce(int(np.any((mine >= 0) & (global_cols < 0)))):  # together
            raise SolverError(
                f"A volume-correction row{where} couples to a cell its owner does not count "
                "as wet: the ranks disagree on the ghost layer."
            )
        air = self.core.volume_air[owned]
        if sealed_pockets(comm, self.cells, cols, rows, owned, air, count):
            raise SolverError(
                f"Water sealed off from every empty cell{where} lies across ranks: its "
                "volume correction is held on one process only. Run this case on one process."
            )
        self.system.prepare(first, global_cols.astype(np.int64), vals[owned].copy(), n)
        self.owned, self.rows, self.n = owned, rows.copy(), n

    def solve(self, rhs: Floats, q: Floats) -> tuple[int, float]:
        """Solve for the owned rows; q (the last correction's solution in) takes the
        solution at every local row, the owners' values at the cells this rank does not
        own."""
        owned = self.owned
        result = self.system.solve(rhs[owned].copy(), q[owned].copy())
        self.iterations += result.iterations
        if not result.converged:  # the same verdict on every rank: the residual is global
            raise volume_correction.not_converged(
                self.where(), result.residual, result.iterations, self.n
            )
        q[:] = spread(self.cells, (self.sub.grid.ncells,), self.rows[owned], result.x)[self.rows]
        return result.iterations, result.residual
