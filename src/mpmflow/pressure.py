"""The pressure step (docs/method.md, step 5) with a solver from Python, and the messages of
every pressure failure.

The default solver (``multigrid``) runs inside the compiled step (``kernels.step``). The
others (``amg``, ``direct``; for comparison and tests) run the same compiled phases one step
at a time, with this loop around the solve: assemble eq. (13) with the walls as contact
conditions, solve, release the wall nodes whose pressure comes out negative while v* leaves
the wall and solve again (the matrix and its preconditioner are kept), then extend the
pressure to the ghost nodes.
"""

import numpy as np

from .errors import SolverError
from .kernels import step
from .linsolve import LinearSolver, PressureMatrix

SETUP_ERRORS = (np.linalg.LinAlgError, RuntimeError, ValueError)


def singular(where):
    return SolverError(
        f"The pressure system is singular{where}: the material touches no free surface "
        "(it fills a closed container), so the pressure is defined only up to a "
        "constant. mpmflow needs a free surface; leave some empty space in the domain.")


def setup_failed(where, err, unknowns):
    return SolverError(f"The pressure solver could not be set up{where}: {err}. "
                       f"{unknowns} unknowns. Try solver.linear_solver = \"direct\" or "
                       "a smaller time.dt.")


def not_converged(where, residual, iterations, settings, unknowns, xyz):
    return SolverError(
        f"The pressure solve did not converge{where}: relative residual "
        f"{residual:.3e} after {iterations} iterations (solver.tolerance = "
        f"{settings.tolerance:g}, solver.max_iterations = {settings.max_iterations}); "
        f"{unknowns} unknowns, largest residual at node "
        f"({', '.join(f'{c:.4g}' for c in xyz)}) m. Try solver.linear_solver = \"direct\", "
        "a smaller time.dt, or a larger solver.max_iterations.")


class PythonPressure:
    """Step 5 with ``linsolve.LinearSolver`` (amg or direct); fills the step's report as the
    compiled ``kernels.step.pressure_multigrid`` does."""

    def __init__(self, grid, settings):
        self.grid = grid
        self.settings = settings
        self.solver = LinearSolver(settings.linear_solver, settings.tolerance,
                                   settings.max_iterations)

    def solve(self, G, O, W, integrals, rows, report, where):
        x = step.warm_start(W, rows)
        cols, vals, anchored = step.pressure_matrix(G, O, W, integrals, rows)
        n = rows.size
        if n == 0:
            return
        if not anchored:
            raise singular(where)
        try:
            self.solver.prepare(PressureMatrix(cols, vals, rows, self.grid.nodes))
        except SETUP_ERRORS as err:
            raise setup_failed(where, err, n) from None
        rhs = np.empty(n)
        iterations = 0
        while True:
            step.pressure_rhs(G, O, W, integrals, rows, rhs)
            result = self.solver.solve(rhs, x)
            report[step.R_SOLVES] += 1
            report[step.R_ITERATIONS] += result.iterations
            iterations += result.iterations
            report[step.R_RESIDUAL] = max(report[step.R_RESIDUAL], result.residual)
            if not result.converged:
                r = self.solver.residual_vector(rhs, result.x)
                worst = rows[int(np.nanargmax(np.abs(r)))]
                raise not_converged(where, result.residual, result.iterations, self.settings,
                                    n, self.grid.node_coordinates()[worst])
            x = result.x
            released = step.release_walls(G, W, rows, x)
            if not released:
                break
            report[step.R_RELEASED] += released
        report[step.R_MAX_ITERATIONS] = max(report[step.R_MAX_ITERATIONS], iterations)
        step.extend_pressure(G, O, W, integrals)
