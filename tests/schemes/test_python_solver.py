"""A pressure solver from Python inside the core's step (State.use_solvers,
schemes/pressure.py's PythonSolver): its failures reach the user as the multigrid's do."""

import numpy as np
import pytest
from conftest import EXAMPLES

from mpmflow import Simulation, load_case
from mpmflow.errors import SolverError
from mpmflow.linalg.solvers import LinearSolver


def case(*settings):
    return load_case(
        EXAMPLES / "hydrostatic.toml", ["output.snapshots=false", "time.end=0.01", *settings]
    )


def test_a_python_solver_that_does_not_converge_is_told_with_its_worst_node():
    sim = Simulation(
        case("solver.linear_solver=amg", "solver.max_iterations=1", "solver.tolerance=1e-14")
    )
    with pytest.raises(SolverError, match=r"did not converge.*largest residual at node \("):
        sim.run()


def test_a_python_solver_whose_setup_fails_is_told(monkeypatch):
    def broken(self, matrix):
        raise np.linalg.LinAlgError("singular factor")

    monkeypatch.setattr(LinearSolver, "prepare", broken)
    sim = Simulation(case("solver.linear_solver=direct"))
    with pytest.raises(SolverError, match=r"could not be set up at step 1 .*: singular factor"):
        sim.run()


def test_the_column_at_rest_stays_at_rest_with_a_python_solver():
    """The hydrostatic column is exact at rest with the core's multigrid (test_hydrostatic);
    SciPy's direct solve plugged into the same step keeps it there too."""
    sim = Simulation(case("solver.linear_solver=direct"))
    sim.run()
    assert np.abs(sim.particles.v).max() < 1e-9  # m/s
