"""The viscous predictor (docs/method.md, "Viscous materials") over MPI ranks: its system
assembled per rank, solved by PETSc, applied per rank.

After the classification (with the owners' say on the nodes round the box, so that the
walls hold the same nodes on every rank), ``viscous_start`` gives each rank the cells'
viscosity and the velocity the solve starts from (the owners' values at the nodes round the
box, where the local corrector lacks cells), and ``viscous_system`` the rows of its local
nodes' velocity components, D x D blocks whose columns
are numbered within their component. The owned rows are numbered after the ranks before
(node by node, component by component), the ghost layer takes its owners' numbers, and the
blocks become one row of global columns per unknown: PETSc solves the coupled system to
``solver.tolerance`` by conjugate gradients (the core solves the same system with one
multigrid cycle per diagonal block as its preconditioner; both stop on the true residual).
The solution reaches the ghost layer, ``viscous_apply`` writes it into v*, and v* at the
nodes round the box takes the owners' values again.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..arrays import Floats, Ints
from ..errors import SolverError
from .comm import Comm
from .exchange import NodeExchange
from .petsc import DistributedSystem, Preconditioner
from .subgrid import Subgrid

if TYPE_CHECKING:
    from ..state.step import CoreOptions, CoreReport, CoreState

# the parameter that holds a rheology's max_viscosity, by its code (src/core/rheology.hpp:
# Herschel-Bulkley 2, mu(I) 3)
MODEL_CAP = {2: 3, 3: 5}


class DistributedViscous:
    """The viscous predictor's solve over the ranks (its own PETSc system)."""

    def __init__(
        self, comm: Comm, tolerance: float, max_iterations: int, preconditioner: Preconditioner
    ) -> None:
        self.comm = comm
        self.system = DistributedSystem(tolerance, max_iterations, preconditioner)

    def predict(
        self,
        core: CoreState,
        sub: Subgrid,
        nodes: NodeExchange,
        options: CoreOptions,
        report: CoreReport,
        where: str,
    ) -> None:
        """One viscous predictor (collective): v* of the local nodes updated in the core."""
        comm = self.comm
        capped = int(report.capped)
        core.viscous_start(options, report)
        report.capped = capped + self._capped(core, sub, options)
        # the corrector at the nodes on the local grid's edge reaches past its cells: the
        # owners' values (the held components of the rows beside them take theirs)
        nodes.fill(core.viscous_base)
        n = core.viscous_system(options)
        rows = core.viscous_rows  # nn x D
        unknown = rows >= 0
        mine = unknown & sub.owned_nodes[:, None]
        count = int(mine.sum())
        counts = comm.allgather(count)
        first = int(sum(counts[: comm.rank]))
        total = int(sum(counts))
        if total == 0:
            core.viscous_apply(np.zeros(n))
            nodes.fill(core.v_star)
            return
        number = np.full(rows.shape, -1.0)
        number[mine] = first + np.arange(count)
        nodes.fill(number)
        glob = np.full(n, -1, dtype=np.int64)
        glob[rows[unknown]] = number[unknown].astype(np.int64)
        # a ghost node the owner does not solve for, or the reverse, would couple the ranks'
        # systems wrongly: every rank decides together
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
        result = self.system.solve(core.viscous_rhs[owned].copy(), core.viscous_x[owned].copy())
        report.viscous_iterations += result.iterations
        if not result.converged:
            raise SolverError(
                f"The viscous solve did not converge{where} over the MPI ranks: relative "
                f"residual {result.residual:.3e} after {result.iterations} iterations "
                f"(solver.tolerance = {self.system.tolerance:g}, solver.max_iterations = "
                f"{self.system.max_iterations}); {total} unknowns (velocity components). Try "
                "a smaller time.dt or a larger solver.max_iterations."
            )
        values = np.zeros(rows.shape)
        values[mine] = result.x
        nodes.fill(values)
        x = np.empty(n)
        x[rows[unknown]] = values[unknown]
        core.viscous_apply(x)
        nodes.fill(core.v_star)

    @staticmethod
    def _capped(core: CoreState, sub: Subgrid, options: CoreOptions) -> int:
        """The owned cells held at the rheology's max_viscosity (the core counts the ghost
        layer's too, which their owners count)."""
        slot = MODEL_CAP.get(int(options.model))
        if slot is None:
            return 0
        eta: Floats = core.eta
        owned: Ints = np.flatnonzero(sub.owned_cells)
        return int(np.count_nonzero(eta[owned] >= options.model_params[slot]))
