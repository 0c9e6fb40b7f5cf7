"""The pressure step's solvers from Python, and the messages of every pressure failure.

The step (docs/method.md, step 5: assemble eq. (13) with the walls as contact conditions,
solve, release the wall nodes whose pressure comes out negative while v* leaves the wall
and solve again, extend the pressure to the ghost nodes) runs in the compiled core for every
solver. The default solver (``multigrid``) is the core's own; the others (``amg``,
``direct``, ``petsc``; for comparison and tests) plug into the same step through
``State.use_solvers``: ``PythonSolver`` sets the linear solver up for each step's matrix and
solves for each right-hand side the wall release asks for.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .. import state
from ..arrays import Floats, Ints
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


class PythonSolver:
    """``linalg.solvers.LinearSolver`` (amg, direct or petsc) as the core's pressure solver:
    ``use(core)`` plugs it into the step (``State.use_solvers``), which calls ``setup`` and
    ``solve`` with views of its own storage (valid during the call only)."""

    def __init__(self, grid: Grid, settings: Solver) -> None:
        self.grid = grid
        self.solver = LinearSolver(
            settings.linear_solver,
            settings.tolerance,
            settings.max_iterations,
            settings.petsc_preconditioner,
        )

    def use(self, core: state.CoreState) -> None:
        core.use_solvers(pressure=self)

    def setup(self, cols: Ints, vals: Floats, rows: Ints) -> None:
        self.solver.prepare(PressureMatrix(cols.copy(), vals.copy(), rows.copy(), self.grid.nodes))

    def solve(self, rhs: Floats, x: Floats) -> tuple[int, float]:
        result = self.solver.solve(rhs.copy(), x.copy())
        x[...] = result.x
        return result.iterations, result.residual
