"""The viscous predictor (docs/method.md, "Viscous materials") over MPI ranks: its system
assembled per rank, solved by PETSc, applied per rank.

The compiled step (src/core/step.cpp, viscous_predictor) does the rest on each rank: after
the classification (with the owners' say on the nodes round the box, so that the walls hold
the same nodes on every rank), ``viscous_start`` gives each rank the cells' viscosity (the
capped cells counted where it owns them) and the velocity the solve starts from (the
owners' values at the nodes round the box, where the local corrector lacks cells), and
``viscous_system`` the rows of its local nodes' velocity components, D x D blocks whose
columns are numbered within their component. The owned rows are numbered after the ranks before
(node by node, component by component), the ghost layer takes its owners' numbers, and the
blocks become one row of global columns per unknown: PETSc solves the coupled system to
``solver.tolerance`` by conjugate gradients (the core solves the same system with one
multigrid cycle per diagonal block as its preconditioner; both stop on the true residual).
Here the solution reaches the ghost layer; the step's ``viscous_apply`` writes it into v*,
and v* at the nodes round the box takes the owners' values again.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from ..arrays import Floats
from ..errors import SolverError
from .comm import Comm
from .exchange import NodeExchange, number_rows, spread
from .petsc import DistributedSystem, Preconditioner
from .subgrid import Subgrid

if TYPE_CHECKING:
    from ..state.step import CoreState


class DistributedViscous:
    """The viscous predictor's solve over the ranks (its own PETSc system): the core's
    viscous solver on a rank (``State.use_solvers``); ``bind`` gives it a split's local
    state."""

    def __init__(
        self, comm: Comm, tolerance: float, max_iterations: int, preconditioner: Preconditioner
    ) -> None:
        self.comm = comm
        self.system = DistributedSystem(tolerance, max_iterations, preconditioner)
        self.where: Callable[[], str] = lambda: ""

    def bind(
        self, core: CoreState, sub: Subgrid, nodes: NodeExchange, where: Callable[[], str]
    ) -> None:
        self.core, self.sub, self.nodes, self.where = core, sub, nodes, where

    def solve(self, x: Floats) -> tuple[int, float]:
        """Solve the last ``viscous_system`` (collective): x, the start at each local
        unknown, takes the solution, the owners' values at the nodes this rank does not
        own."""
        comm, sub, core = self.comm, self.sub, self.core
        rows = core.viscous_rows  # nn x D
        unknown = rows >= 0
        mine = unknown & sub.owned_nodes[:, None]
        number, first, total = number_rows(comm, self.nodes, rows.shape, mine)
        if total == 0:
            return 0, 0.0
        glob = np.full(x.size, -1, dtype=np.int64)
        glob[rows[unknown]] = number[unknown].astype(np.int64)
        # a ghost node the owner does not solve for, or the reverse, would couple the ranks'
        # systems wrongly: every rank decides together
        where = self.where()
        if comm.allreduce(int(np.any(glob < 0))):
            raise SolverError(
                f"A viscous unknown{where} lies on a node its owner holds: the ranks disagree "
                "on the walls' contact. Run this case on one process and report it."
            )
        owned = rows[mine]  # local rows, in global order
        off = core.viscous_off
        cols = core.viscous_cols  # D x n x slots
        vals = core.viscous_vals
        D = cols.shape[0]
        gcols = np.concatenate(
            [
                np.where(cols[m, owned] >= 0, glob[off[m] + np.maximum(cols[m, owned], 0)], -1)
                for m in range(D)
            ],
            axis=1,
        )
        gvals = np.concatenate([vals[m, owned] for m in range(D)], axis=1)
        self.system.prepare(first, gcols, gvals, total)
        result = self.system.solve(core.viscous_rhs[owned].copy(), x[owned].copy())
        if not result.converged:  # the same verdict on every rank: the residual is global
            raise SolverError(
                f"The viscous solve did not converge{where} over the MPI ranks: relative "
                f"residual {result.residual:.3e} after {result.iterations} iterations "
                f"(solver.tolerance = {self.system.tolerance:g}, solver.max_iterations = "
                f"{self.system.max_iterations}); {total} unknowns (velocity components). Try "
                "a smaller time.dt or a larger solver.max_iterations."
            )
        values = spread(self.nodes, rows.shape, mine, result.x)
        x[rows[unknown]] = values[unknown]
        return result.iterations, result.residual
