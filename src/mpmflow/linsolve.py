"""Sparse symmetric positive definite solves for the pressure system.

``amg``    conjugate gradients preconditioned by smoothed-aggregation algebraic multigrid
           (pyamg), warm-started from the previous pressure;
``direct`` sparse LU (SuperLU through SciPy).
``prepare`` sets up for one matrix (AMG hierarchy or factorisation); ``solve`` may then be
called for several right-hand sides. Every solve reports its true relative residual
||b - A x|| / ||b||; the caller decides what a failure means.
"""

from dataclasses import dataclass

import numpy as np
import pyamg
import scipy.sparse.linalg as spla


@dataclass
class SolveResult:
    x: np.ndarray
    iterations: int
    residual: float  # true relative residual
    converged: bool


class LinearSolver:
    def __init__(self, method, tolerance, max_iterations):
        self.method = method
        self.tolerance = tolerance
        self.max_iterations = max_iterations
        self._A = None
        self._setup = None

    def prepare(self, A):
        self._A = A
        if self.method == "direct":
            self._setup = spla.splu(A.tocsc())
        else:
            self._setup = pyamg.smoothed_aggregation_solver(
                A, symmetry="symmetric", max_coarse=400, coarse_solver="splu")

    def solve(self, b, x0=None):
        A = self._A
        bnorm = np.linalg.norm(b)
        if bnorm == 0.0:
            return SolveResult(np.zeros_like(b), 0, 0.0, True)
        if self.method == "direct":
            x = self._setup.solve(b)
            iterations = 1
        else:
            history = []
            x = self._setup.solve(b, x0=x0, tol=self.tolerance, maxiter=self.max_iterations,
                                  accel="cg", residuals=history)
            iterations = max(len(history) - 1, 0)
        residual = float(np.linalg.norm(b - A @ x) / bnorm)
        ok = bool(np.isfinite(residual) and residual <= self.tolerance)
        return SolveResult(x, iterations, residual, ok)
