"""What a linear solve returns, whichever solver made it (``solvers``, or PETSc's over MPI
ranks in ``parallel.petsc``): its own module, so that the solvers and the PETSc side each
import it without importing each other."""

from dataclasses import dataclass

from ..arrays import Floats


@dataclass
class SolveResult:
    x: Floats
    iterations: int
    residual: float  # true relative residual ||b - A x|| / ||b||
    converged: bool
