"""PETSc's distributed solve of the pressure system (issue 28, first slice): on one process
and under ``mpirun -n 2`` (``make test-mpi``). Skipped where petsc4py is not installed
(the one-process environment); CI runs them in the MPI environment.

Every rank runs the same case and holds the same system; PETSc splits its rows over the
ranks. The tolerances follow from the solver's: the pressure solves converge to a relative
residual of 1e-8, so two solvers' particles differ by far less than 1e-8 m after 300 steps
(each step moves a particle by dt times a velocity corrected by dt grad p / rho)."""

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from conftest import EXAMPLES

from mpmflow import load_case
from mpmflow.errors import SolverError
from mpmflow.geometry.seeding import build_particles
from mpmflow.grid import Grid
from mpmflow.schemes.projection import ProjectionScheme

pytest.importorskip("petsc4py")
pytest.importorskip("mpi4py")

from mpmflow.parallel.comm import world  # noqa: E402
from mpmflow.parallel.petsc import DistributedSystem, block  # noqa: E402


def laplacian(n: int) -> sp.csr_matrix:
    """The 5-point Laplacian of an n x n grid with Dirichlet sides (SPD)."""
    one = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(n, n))
    eye = sp.identity(n)
    return (sp.kron(one, eye) + sp.kron(eye, one)).tocsr()


def ell(A: sp.csr_matrix, slots: int = 5) -> tuple[np.ndarray, np.ndarray]:
    """A in the core's ELL form: columns (-1: empty) and values, ``slots`` a row."""
    n = A.shape[0]
    cols = -np.ones((n, slots), np.int64)
    vals = np.zeros((n, slots))
    for r in range(n):
        lo, hi = A.indptr[r], A.indptr[r + 1]
        cols[r, : hi - lo] = A.indices[lo:hi][::-1]  # unsorted: the solver sorts them
        vals[r, : hi - lo] = A.data[lo:hi][::-1]
    return cols, vals


@pytest.mark.parametrize("preconditioner", ["gamg", "hypre"])
def test_a_split_system_solves_to_its_tolerance(preconditioner):
    comm = world()
    A = laplacian(24)
    n = A.shape[0]
    b = np.sin(np.arange(n) * 0.37) + 1.0
    exact = spla.spsolve(A.tocsc(), b)
    cols, vals = ell(A)
    lo, hi = block(n, comm.rank, comm.size)
    system = DistributedSystem(1e-10, 200, preconditioner)
    try:
        system.prepare(lo, cols[lo:hi], vals[lo:hi], n)
        result = system.solve(b[lo:hi].copy(), np.zeros(hi - lo))
        x = system.gather(result.x)
    finally:
        system.destroy()
    assert result.converged and result.residual <= 1e-10
    # the condition number of this Laplacian is about 240: the error within 1e-10 x 240
    assert np.linalg.norm(x - exact) / np.linalg.norm(exact) < 3e-8
    assert 0 < result.iterations < 40  # multigrid-preconditioned: independent of the split


def test_a_solve_that_cannot_reach_its_tolerance_says_so():
    comm = world()
    A = laplacian(24)
    n = A.shape[0]
    cols, vals = ell(A)
    lo, hi = block(n, comm.rank, comm.size)
    system = DistributedSystem(1e-14, 1, "gamg")
    try:
        system.prepare(lo, cols[lo:hi], vals[lo:hi], n)
        result = system.solve(np.ones(hi - lo), np.zeros(hi - lo))
    finally:
        system.destroy()
    assert not result.converged and result.residual > 1e-14 and result.iterations == 1


class Run:
    """The dam break stepped by the one-process scheme (on every rank alike: each holds the
    whole case, and only the pressure solve is split)."""

    def __init__(self, solver: str, steps: int = 300, **settings: str) -> None:
        overrides = [f"solver.linear_solver={solver}", "time.end=0.3"]
        overrides += [f"solver.{k}={v}" for k, v in settings.items()]
        case = load_case(str(EXAMPLES / "dam_break.toml"), overrides)
        grid = Grid.of_case(case)
        self.scheme = ProjectionScheme(case, grid, build_particles(case, grid))
        self.particles = self.scheme.particles
        self.report = self.scheme.advance(float(case.time.dt), steps)


def run(solver: str, steps: int = 300, **settings: str) -> Run:
    return Run(solver, steps, **settings)


@pytest.fixture(scope="module")
def multigrid() -> Run:
    return run("multigrid")


# one process only: on several ranks each would step the whole case (the split scheme's
# tests, test_scheme.py, run the distributed solve on real cases there)
@pytest.mark.skipif(world().size > 1, reason="the whole case on every rank: one process")
@pytest.mark.parametrize("preconditioner", ["gamg", "hypre"])
def test_the_dam_break_with_petsc_matches_the_core_multigrid(multigrid, preconditioner):
    sim = run("petsc", petsc_preconditioner=preconditioner)
    assert np.abs(sim.particles.x - multigrid.particles.x).max() < 1e-8  # m
    assert np.abs(sim.particles.v - multigrid.particles.v).max() < 1e-6  # m/s
    # the contact release sees the same pressures: the same walls let go
    assert sim.report.released == multigrid.report.released > 0
    assert sim.report.solves == multigrid.report.solves
    assert sim.report.residual <= 1e-8


def test_a_pressure_solve_that_fails_stops_every_rank_with_its_message():
    with pytest.raises(SolverError, match="did not converge"):
        run("petsc", steps=5, max_iterations="1", tolerance="1e-12")
