"""The volume correction (docs/method.md, "Volume correction") over MPI ranks: its
cell-centred system assembled per rank, solved by PETSc, applied per rank.

On a step that corrects, the particle volume each cell holds (``cell_vol``, from
``scatter``) is completed at the cells a rank holds without owning them by their owners'
values; ``volume_system`` assembles the rows of the local cells (the ghost layer's cells
have every particle of theirs in the halo, so a rank and the owner agree on which cells are
rows); the owned rows are numbered after the ranks before, PETSc solves to
``solver.tolerance``, the solution reaches the ghost layer, and ``volume_apply`` moves the
faces the particles are displaced by in ``to_particles``.
"""

from __future__ import annotations

import numpy as np

from ..errors import SolverError
from ..schemes import volume_correction
from ..state import CoreOptions, CoreReport, CoreState
from .comm import Comm
from .exchange import NodeExchange
from .petsc import DistributedSystem, Preconditioner
from .pockets import sealed_pockets
from .subgrid import Subgrid


class DistributedVolume:
    """The volume correction's solve over the ranks (its own PETSc system)."""

    def __init__(self, comm: Comm, tolerance: float, preconditioner: Preconditioner) -> None:
        self.comm = comm
        self.system = DistributedSystem(tolerance, volume_correction.MAX_ITERATIONS, preconditioner)
        self.iterations = 0

    def correct(
        self,
        core: CoreState,
        sub: Subgrid,
        cells: NodeExchange,
        options: CoreOptions,
        report: CoreReport,
        where: str,
    ) -> None:
        """One volume correction (collective); the faces are left in the core."""
        comm = self.comm
        core.volume_system(options)
        rows = core.volume_rows
        owned = np.flatnonzero(sub.owned_cells[rows])
        counts = comm.allgather(int(owned.size))
        first = int(sum(counts[: comm.rank]))
        n = int(sum(counts))
        number = np.full(sub.grid.ncells, -1.0)
        number[rows[owned]] = first + np.arange(owned.size)
        cells.fill(number)
        air = core.volume_air[owned]
        core.volume_anchored = bool(comm.allreduce(int(air.any())))
        if n == 0 or not core.volume_anchored:
            # nothing, or material filling the whole domain: its volume cannot change
            core.volume_apply(options, np.zeros(rows.size))
            return
        cols = core.volume_cols[owned]
        global_cols = np.where(cols >= 0, number[rows[np.maximum(cols, 0)]], -1)
        if comm.allreduce(int(np.any((cols >= 0) & (global_cols < 0)))):  # together
            raise SolverError(
                f"A volume-correction row{where} couples to a cell its owner does not count "
                "as wet: the ranks disagree on the ghost layer."
            )
        count = sub.grid.ncells
        if sealed_pockets(comm, cells, core.volume_cols, rows, owned, air, count):
            raise SolverError(
                f"Water sealed off from every empty cell{where} lies across ranks: its "
                "volume correction is held on one process only. Run this case on one process."
            )
        self.system.prepare(first, global_cols.astype(np.int64), core.volume_vals[owned].copy(), n)
        q0 = np.ascontiguousarray(core.volume_q[rows[owned]])
        result = self.system.solve(core.volume_rhs[owned].copy(), q0)
        self.iterations += result.iterations
        report.volume_iterations += result.iterations
        if not result.converged:
            raise volume_correction.not_converged(where, result.residual, result.iterations, n)
        q = np.zeros(count)
        q[rows[owned]] = result.x
        cells.fill(q)
        report.clamped += core.volume_apply(options, np.ascontiguousarray(q[rows]))
