"""The pressure step (docs/method.md, step 5) with a solver from Python, and the messages of
every pressure failure.

The default solver (``multigrid``) runs inside the compiled step (the core's State). The
others (``amg``, ``direct``; for comparison and tests) run the same compiled phases one step
at a time, with this loop around the solve: assemble eq. (13) with the walls as contact
conditions, solve, release the wall nodes whose pressure comes out negative while v* leaves
the wall and solve again (the matrix and its preconditioner are kept), then extend the
pressure to the ghost nodes.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .. import state
from ..arrays import Floats
from ..errors import SolverError
from ..grid import Grid
from ..linalg.solvers import LinearSolver, PressureMatrix

if TYPE_CHECKING:  # the case's schema asks the scheme registry what each scheme supports
    from ..case.solver import Solver

SETUP_ERRORS = (np.linalg.LinAlgError, RuntimeError, ValueError)


def singular(where: str) -> SolverError:
    return SolverError(
        f"The pressure system is singular{where}: the material touches no free surface "
        "(it fills a closed container), so the pressure is defined only up to a "
        "constant. mpmflow needs a free surface; leave some empty space in the domain."
    )


def setup_failed(where: str, err: Exception, unknowns: int) -> SolverError:
    return SolverError(
        f"The pressure solver could not be set up{where}: {err}. "
        f'{unknowns} unknowns. Try solver.linear_solver = "direct" or '
        "a smaller time.dt."
    )


def not_converged(
    where: str, residual: float, iterations: int, settings: Solver, unknowns: int, xyz: Floats
) -> SolverError:
    return SolverError(
        f"The pressure solve did not converge{where}: relative residual "
        f"{residual:.3e} after {iterations} iterations (solver.tolerance = "
        f"{settings.tolerance:g}, solver.max_iterations = {settings.max_iterations}); "
        f"{unknowns} unknowns, largest residual at node "
        f'({", ".join(f"{c:.4g}" for c in xyz)}) m. Try solver.linear_solver = "direct", '
        "a smaller time.dt, or a larger solver.max_iterations."
    )


class PythonPressure:
    """Step 5 with ``linsolve.LinearSolver`` (amg or direct) around the compiled phases of
    the core's State; fills the step's report as the compiled multigrid step does."""

    def __init__(self, grid: Grid, settings: Solver) -> None:
        self.grid = grid
        self.settings = settings
        self.solver = LinearSolver(
            settings.linear_solver,
            settings.tolerance,
            settings.max_iterations,
            settings.petsc_preconditioner,
        )

    def solve(
        self, core: state.CoreState, O: state.CoreOptions, report: state.CoreReport, where: str
    ) -> None:
        core.warm_start()
        x = core.x0.copy()
        anchored = core.pressure_matrix(O)
        rows = core.rows.copy()
        n = rows.size
        if n == 0:
            return
        if not anchored:
            raise singular(where)
        try:
            self.solver.prepare(
                PressureMatrix(
                    core.matrix_cols.copy(), core.matrix_vals.copy(), rows, self.grid.nodes
                )
            )
        except SETUP_ERRORS as err:
            raise setup_failed(where, err, n) from None
        iterations = 0
        while True:
            core.pressure_rhs(O)
            rhs = core.rhs.copy()
            result = self.solver.solve(rhs, x)
            report.solves += 1
            report.iterations += result.iterations
            iterations += result.iterations
            report.residual = max(report.residual, result.residual)
            if not result.converged:
                r = self.solver.residual_vector(rhs, result.x)
                worst = rows[int(np.nanargmax(np.abs(r)))]
                raise not_converged(
                    where,
                    result.residual,
                    result.iterations,
                    self.settings,
                    n,
                    self.grid.node_coordinates()[worst],
                )
            x = result.x
            released = core.release_walls(np.ascontiguousarray(x))
            if not released:
                break
            report.released += released
        report.max_iterations = max(report.max_iterations, iterations)
        core.extend_pressure(O)
