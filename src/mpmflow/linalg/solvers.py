"""Sparse symmetric positive definite solves for the pressure system.

``multigrid`` conjugate gradients preconditioned by a geometric multigrid V-cycle on the
            node grid (compiled: the core's Multigrid, through ``state``); warm-started.
``amg``     conjugate gradients preconditioned by smoothed-aggregation algebraic multigrid
            (pyamg); warm-started.
``direct``  sparse LU (SuperLU through SciPy).
``petsc``   PETSc's conjugate gradients with GAMG or BoomerAMG (``parallel.petsc``), the
            rows split over the run's MPI processes (every process holds the whole
            system and gets the whole solution); warm-started.
``prepare`` sets up for one matrix (hierarchy or factorisation); ``solve`` may then be
called for several right-hand sides. Every solve reports its true relative residual
||b - A x|| / ||b||; the caller decides what a failure means.
"""

from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from .. import state
from ..arrays import Floats, Ints
from .result import SolveResult

SMOOTHING_SWEEPS = 1  # Gauss-Seidel sweeps before and after each coarse correction


@dataclass
class PressureMatrix:
    """The pressure matrix in ELL form with its place on the node grid."""

    cols: Ints  # (n, 9) column of each stencil slot, -1 where empty
    vals: Floats  # (n, 9)
    nodes: Ints  # (n,) node of each row
    grid_nodes: tuple[int, ...]  # nodes per axis

    def csr(self) -> Any:
        """The matrix as a SciPy CSR matrix (SciPy has no type information here: Any)."""
        import scipy.sparse as sp  # here: the default solver never needs SciPy (50 ms import)

        mask = self.cols >= 0
        indptr = np.concatenate(([0], np.cumsum(mask.sum(axis=1))))
        n = self.cols.shape[0]
        return sp.csr_matrix((self.vals[mask], self.cols[mask], indptr), shape=(n, n))


Method = Literal["multigrid", "amg", "direct", "petsc"]


class LinearSolver:
    def __init__(
        self,
        method: Method,
        tolerance: float,
        max_iterations: int,
        preconditioner: Literal["gamg", "hypre"] = "hypre",
    ) -> None:
        self.method = method
        self.preconditioner = preconditioner
        if method == "petsc":  # a missing petsc4py is told before the run starts
            from ..parallel.petsc import petsc

            petsc()
        self.tolerance = tolerance
        self.max_iterations = max_iterations
        self._hierarchy: state.Multigrid | None = None  # multigrid
        # direct: SuperLU's factorisation; amg: pyamg's hierarchy (libraries without type
        # information here)
        self._setup: Any = None

    def prepare(self, matrix: PressureMatrix) -> None:
        self.matrix = matrix
        if self.method == "multigrid":
            # an earlier hierarchy's storage is reused
            self._hierarchy = state.multigrid(
                matrix.cols, matrix.vals, matrix.nodes, matrix.grid_nodes, hierarchy=self._hierarchy
            )
            return
        if self.method == "petsc":
            self._prepare_petsc(matrix)
            return
        self._A = matrix.csr()
        if self.method == "direct":
            import scipy.sparse.linalg as spla

            self._setup = spla.splu(self._A.tocsc())
        else:
            import pyamg

            self._setup = pyamg.smoothed_aggregation_solver(
                self._A, symmetry="symmetric", max_coarse=400, coarse_solver="splu"
            )

    def solve(
        self, b: Floats, x0: Floats | None = None, tolerance: float | None = None
    ) -> SolveResult:
        """Solve the prepared system to ``tolerance`` (default: the solver's own)."""
        tol = self.tolerance if tolerance is None else tolerance
        bnorm = np.linalg.norm(b)
        if bnorm == 0.0:
            return SolveResult(np.zeros_like(b), 0, 0.0, True)
        if self.method == "multigrid":
            if self._hierarchy is None:
                raise RuntimeError("LinearSolver.solve before prepare")
            x = np.zeros_like(b) if x0 is None else x0.copy()
            iterations, residual = self._hierarchy.pcg(
                b, x, tol, self.max_iterations, SMOOTHING_SWEEPS
            )
        elif self.method == "petsc":
            return self._solve_petsc(b, np.zeros_like(b) if x0 is None else x0, tol)
        else:
            if self.method == "direct":
                x = self._setup.solve(b)
                iterations = 1
            else:
                history: list[float] = []
                x = self._setup.solve(
                    b, x0=x0, tol=tol, maxiter=self.max_iterations, accel="cg", residuals=history
                )
                iterations = max(len(history) - 1, 0)
            residual = float(np.linalg.norm(b - self._A @ x) / bnorm)
        ok = bool(np.isfinite(residual) and residual <= tol)
        return SolveResult(x, int(iterations), float(residual), ok)

    def _prepare_petsc(self, matrix: PressureMatrix) -> None:
        """This rank's block of rows into PETSc (every rank holds the whole matrix)."""
        from ..parallel.petsc import DistributedSystem, block

        if self._setup is None:
            self._setup = DistributedSystem(
                self.tolerance, self.max_iterations, self.preconditioner
            )
        system: DistributedSystem = self._setup
        n = matrix.cols.shape[0]
        self._block = block(n, system.rank, system.ranks)
        lo, hi = self._block
        system.prepare(lo, matrix.cols[lo:hi], matrix.vals[lo:hi], n)

    def _solve_petsc(self, b: Floats, x0: Floats, tol: float) -> SolveResult:
        system = self._setup
        lo, hi = self._block
        part = system.solve(np.ascontiguousarray(b[lo:hi]), np.ascontiguousarray(x0[lo:hi]), tol)
        x = system.gather(part.x)
        return SolveResult(x, part.iterations, part.residual, part.converged)

    def residual_vector(self, b: Floats, x: Floats) -> Floats:
        """b - A x for the prepared matrix."""
        out = np.empty_like(b)
        state.residual(self.matrix.cols, self.matrix.vals, x, b, out)
        return out
