"""The pressure system (docs/method.md, steps 4-5) over MPI ranks: the core's pressure
solver on a rank (``State.use_solvers``, src/core/step.hpp's LinearSolver).

The compiled step assembles each rank's rows (its nodes' after the owners' say on the
unknowns round its box; a solid's, its cells' with material: ``cells``) and calls ``setup``
and ``solve`` on every rank, rows or none. Here
the owned rows are numbered after those of the ranks before, their columns take the global
numbers (the ghost layer's from their owners), PETSc solves to ``solver.tolerance``, and
the solution reaches the rows a rank holds without owning them; the step's wall release
then decides on each rank, and the ranks together whether to solve again.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from ..arrays import Floats, Ints
from ..errors import SolverError
from ..schemes import pressure
from .comm import Comm
from .exchange import NodeExchange, number_rows, spread
from .petsc import DistributedSystem, Preconditioner
from .pockets import sealed_pockets
from .subgrid import Subgrid

if TYPE_CHECKING:
    from ..case.solver import Solver
    from ..state.step import CoreState


class DistributedPressure:
    """The pressure solve over the ranks (its own PETSc system); ``bind`` gives it a
    split's local state."""

    def __init__(
        self,
        comm: Comm,
        settings: Solver,
        preconditioner: Preconditioner,
        traffic: dict[str, int],
        cells: bool = False,
    ) -> None:
        self.comm = comm
        # a solid's pressure, one per cell (src/core/cell_pressure.hpp): rows on cells, its
        # surface natural (no row is held, so no part of it can be sealed off)
        self.cells = cells
        self.settings = settings
        self.system = DistributedSystem(settings.tolerance, settings.max_iterations, preconditioner)
        self.traffic = traffic
        self.seconds = 0.0  # in PETSc's set-up and solves
        self.last_owned = 0  # this rank's unknowns in the last step
        self.where: Callable[[], str] = lambda: ""

    def bind(
        self, core: CoreState, sub: Subgrid, places: NodeExchange, where: Callable[[], str]
    ) -> None:
        """The split's local state; ``places``: the exchange of the rows' places (the
        nodes', or with ``cells`` the cells')."""
        self.core, self.sub, self.nodes, self.where = core, sub, places, where
        self.count = sub.grid.ncells if self.cells else sub.grid.nnodes
        self.owned_places = sub.owned_cells if self.cells else sub.owned_nodes

    def setup(self, cols: Ints, vals: Floats, rows: Ints) -> None:
        """Number the owned rows over the ranks and hand PETSc this rank's block."""
        comm = self.comm
        owned = np.flatnonzero(self.owned_places[rows])
        number, first, n = number_rows(comm, self.nodes, (self.count,), rows[owned])
        number = number[rows]
        self.owned, self.rows = owned, rows.copy()
        self.last_owned = int(owned.size)
        mine = cols[owned]
        global_cols = np.where(mine >= 0, number[np.maximum(mine, 0)], -1).astype(np.int64)
        where = self.where()
        # every rank decides together: one rank raising alone would leave the others
        # waiting in the next exchange
        if comm.allreduce(int(np.any((mine >= 0) & (global_cols < 0)))):
            raise SolverError(f"A pressure row{where} couples to a node no rank numbered.")
        air = None if self.cells else self.core.anchored[owned]  # rows next to a free surface
        if air is not None and sealed_pockets(comm, self.nodes, cols, rows, owned, air, self.count):
            raise SolverError(
                f"Water sealed off from the free surface{where} lies across ranks: such "
                "pockets are held at their top on one process only. Run this case on one "
                "process."
            )
        clock = time.perf_counter()
        self.system.prepare(first, global_cols, vals[owned].copy(), n)
        self.seconds += time.perf_counter() - clock
        self.traffic["ghost columns"] += self.system.ghost_columns
        self.n = n

    def solve(self, rhs: Floats, x: Floats) -> tuple[int, float]:
        """Solve for the owned rows; x (the warm start in) takes the solution at every
        local row, the owners' values at the rows this rank does not own."""
        owned = self.owned
        b = rhs[owned].copy()
        clock = time.perf_counter()
        result = self.system.solve(b, x[owned].copy())
        self.seconds += time.perf_counter() - clock
        self.traffic["iterations"] += result.iterations
        if not result.converged:  # the same verdict on every rank: the residual is global
            raise pressure.not_converged(
                self.where(),
                result.residual,
                result.iterations,
                self.settings,
                self.n,
                self._worst(b, result.x),
            )
        x[:] = spread(self.nodes, (self.count,), self.rows[owned], result.x)[self.rows]
        return result.iterations, result.residual

    def _worst(self, b: Floats, x: Floats) -> Floats:
        """The position of the largest residual over all ranks (collective)."""
        r = np.abs(self.system.residual(b, x))
        mine = (-1.0, np.zeros(self.sub.grid.dim))
        if r.size:
            k = int(np.argmax(r))
            place = int(self.rows[self.owned[k]])
            mine = (
                float(r[k]),
                self.sub.cell_centre(place) if self.cells else self.sub.node_position(place),
            )
        worst: Floats = max(self.comm.allgather(mine), key=lambda item: item[0])[1]
        return worst
