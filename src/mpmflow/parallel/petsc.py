"""Distributed symmetric positive definite solves with PETSc (petsc4py): the pressure system
split by rows over the ranks, solved by conjugate gradients preconditioned by PETSc's
algebraic multigrid (GAMG) or hypre's BoomerAMG.

Each rank gives its own rows: a block of consecutive global row numbers (``first`` to
``first + m``), their columns as global row numbers in the core's ELL form (``cols``
m x slots, -1 where a slot is empty) and their values. ``DistributedSystem`` turns them
into PETSc's distributed AIJ matrix (rows sorted by column, as PETSc wants them) and keeps
the KSP and its preconditioner for several right-hand sides (the contact release solves
the same matrix again).

Convergence as the project's other solvers state it: the true relative residual
||b - A x|| / ||b|| at most ``tolerance``, measured after the solve (PETSc's own test is
run on the unpreconditioned residual, relative to ||b||). PETSc's options database
reaches the solver under the prefix ``mpmflow_pressure_`` (e.g. ``PETSC_OPTIONS=
"-mpmflow_pressure_ksp_view"``).

Every PETSc object is destroyed explicitly (``destroy``): left to Python's collector the
ranks free them in different orders, and PETSc's collective clean-up then hangs.
"""

from __future__ import annotations

import sys
from functools import cache
from typing import Any, Literal

import numpy as np

from ..arrays import Floats, Ints
from ..errors import CaseError
from ..linalg.result import SolveResult
from .comm import SETUP_HINT

Preconditioner = Literal["gamg", "hypre"]
RESTARTS = 3  # fresh starts from the true residual when PETSc's own test stopped early
OPTIONS_PREFIX = "mpmflow_pressure_"


@cache
def petsc() -> Any:
    """petsc4py's PETSc module, initialised once (petsc4py has no type information: Any)."""
    try:
        import petsc4py
    except ImportError:
        raise CaseError(
            f'solver.linear_solver = "petsc" needs petsc4py, which this environment lacks: '
            f"{SETUP_HINT}. Without MPI, use the default solver.linear_solver = "
            '"multigrid".'
        ) from None
    petsc4py.init(sys.argv[:1])
    from petsc4py import PETSc

    return PETSc


class DistributedSystem:
    """This rank's rows of a distributed SPD matrix, its KSP and preconditioner."""

    def __init__(
        self,
        tolerance: float,
        max_iterations: int,
        preconditioner: Preconditioner = "hypre",
        comm: Any = None,
    ) -> None:
        self.PETSc = petsc()
        self.comm = comm if comm is not None else self.PETSc.COMM_WORLD
        self.tolerance = float(tolerance)
        self.max_iterations = int(max_iterations)
        self.preconditioner = preconditioner
        self._A: Any = None
        self._ksp: Any = None
        self._b: Any = None
        self._x: Any = None
        self._r: Any = None

    @property
    def rank(self) -> int:
        return int(self.comm.getRank())

    @property
    def ranks(self) -> int:
        return int(self.comm.getSize())

    def prepare(self, first: int, cols: Ints, vals: Floats, size: int) -> None:
        """Rows first .. first + m - 1 of a size x size matrix: ``cols`` (m x slots, global
        column numbers, -1: empty) and ``vals``. Replaces an earlier matrix; the KSP and
        its options are made once and take each new matrix (the preconditioner is set up
        for it anew)."""
        P = self.PETSc
        m = cols.shape[0]
        if self.preconditioner == "gamg":
            # GAMG's levels keep the old matrix's sizes through KSPReset (PETSc 3.18: "Cannot
            # change local size of Amat after use"): a KSP of its own for each matrix
            self.destroy()
        if self._ksp is None:
            self._ksp = self._make_ksp()
        # PETSc's CSR wants each row's columns in increasing order: the core's slots are
        # in the order of the nodes, so only rows with columns of other ranks may need it
        r, s = np.nonzero(cols >= 0)
        c, v = cols[r, s], vals[r, s]
        if np.any((r[1:] == r[:-1]) & (c[1:] <= c[:-1])):
            order = np.argsort(r * np.int64(size) + c, kind="stable")
            c, v = c[order], v[order]
        indptr = np.zeros(m + 1, dtype=P.IntType)
        np.cumsum(np.bincount(r, minlength=m), out=indptr[1:])
        A = P.Mat().createAIJ(
            size=((m, size), (m, size)),
            csr=(indptr, c.astype(P.IntType), np.ascontiguousarray(v)),
            comm=self.comm,
        )
        A.setOption(P.Mat.Option.SPD, True)
        A.assemble()
        # a KSP kept keeps its type and options, not its work vectors and preconditioner,
        # which were of the old matrix (size and pattern change as the water moves): made
        # once, it saves 0.2 ms a step of 4.7 on the split dam break's one rank
        self._ksp.reset()
        self._ksp.setOperators(A)
        self._ksp.setUp()
        for name in ("_A", "_b", "_x", "_r"):  # the old matrix's (the KSP let go of it)
            obj = getattr(self, name)
            if obj is not None:
                obj.destroy()
        self._A = A
        self._b, self._x = A.createVecs()
        self._r = A.createVecLeft()
        self.first, self.rows, self.size = int(first), m, int(size)
        # the other ranks' unknowns a product with A reads (each CG iteration's exchange)
        outside = c[(c < first) | (c >= first + m)]
        self.ghost_columns = int(np.unique(outside).size)

    def _make_ksp(self) -> Any:
        """PETSc's CG with the preconditioner and the options database's settings."""
        P = self.PETSc
        ksp = P.KSP().create(comm=self.comm)
        ksp.setOptionsPrefix(OPTIONS_PREFIX)
        ksp.setType(P.KSP.Type.CG)
        ksp.setNormType(P.KSP.NormType.UNPRECONDITIONED)
        ksp.setTolerances(rtol=self.tolerance, atol=0.0, max_it=self.max_iterations)
        ksp.setInitialGuessNonzero(True)
        pc = ksp.getPC()
        if self.preconditioner == "hypre":
            try:
                pc.setType(P.PC.Type.HYPRE)
                pc.setHYPREType("boomeramg")
            except P.Error:
                ksp.destroy()
                raise CaseError(
                    "This PETSc was built without hypre, so solver.petsc_preconditioner = "
                    '"hypre" (the default) is not available: set it to "gamg".'
                ) from None
        else:
            pc.setType(P.PC.Type.GAMG)
        ksp.setFromOptions()
        return ksp

    def solve(self, b: Floats, x0: Floats, tolerance: float | None = None) -> SolveResult:
        """Solve for this rank's block of x (warm-started from ``x0``, its block of the
        last solution) to ``tolerance`` (default: the system's). Collective: every rank
        calls it."""
        if self._ksp is None:
            raise RuntimeError("DistributedSystem.solve before prepare")
        tol = self.tolerance if tolerance is None else float(tolerance)
        self._ksp.setTolerances(rtol=tol)
        self._b.setArray(b)
        bnorm = self._b.norm()
        if bnorm == 0.0:
            return SolveResult(np.zeros_like(b), 0, 0.0, True)
        self._x.setArray(x0)
        iterations = 0
        # PETSc stops on its recursive residual; where the true one then misses the
        # tolerance (by rounding, in the last digit), it goes on from the true residual with a
        # fresh start, as the core's conjugate gradients do, within the same iteration limit
        for _ in range(RESTARTS + 1):
            self._ksp.setTolerances(max_it=max(self.max_iterations - iterations, 1))
            self._ksp.solve(self._b, self._x)
            iterations += int(self._ksp.getIterationNumber())
            self._A.mult(self._x, self._r)
            self._r.aypx(-1.0, self._b)  # r = b - A x
            residual = float(self._r.norm() / bnorm)
            ok = bool(np.isfinite(residual) and residual <= tol)
            if ok or iterations >= self.max_iterations or not np.isfinite(residual):
                break
        return SolveResult(self._x.getArray().copy(), iterations, residual, ok)

    def residual(self, b: Floats, x: Floats) -> Floats:
        """This rank's block of b - A x (collective)."""
        self._b.setArray(b)
        self._x.setArray(x)
        self._A.mult(self._x, self._r)
        self._r.aypx(-1.0, self._b)
        out: Floats = self._r.getArray().copy()
        return out

    def gather(self, local: Floats) -> Floats:
        """The whole vector on every rank, from each rank's block (collective)."""
        self._x.setArray(local)
        scatter, whole = self.PETSc.Scatter.toAll(self._x)
        try:
            scatter.scatter(self._x, whole)
            out: Floats = whole.getArray().copy()
        finally:
            scatter.destroy()
            whole.destroy()
        return out

    def destroy(self) -> None:
        """Free the PETSc objects (collective: every rank calls it, in the same order)."""
        for name in ("_ksp", "_A", "_b", "_x", "_r"):
            obj = getattr(self, name)
            if obj is not None:
                obj.destroy()
                setattr(self, name, None)


def block(n: int, rank: int, size: int) -> tuple[int, int]:
    """Rank ``rank``'s block [first, last) of n rows split into ``size`` near-equal blocks."""
    return n * rank // size, n * (rank + 1) // size
