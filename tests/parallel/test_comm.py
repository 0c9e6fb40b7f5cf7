"""The run's processes without MPI, and what a run that asks for PETSc is told where the
MPI environment is missing."""

import importlib.util

import pytest

from mpmflow.errors import CaseError
from mpmflow.linalg.solvers import LinearSolver
from mpmflow.parallel import comm


def test_one_process_without_mpi_is_a_world_of_one(monkeypatch):
    for name in ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE", "SLURM_NTASKS"):
        monkeypatch.delenv(name, raising=False)
    single = comm.Single()
    assert (single.rank, single.size) == (0, 1)
    assert single.allreduce(3.5) == 3.5 and single.allgather(2) == [2]
    assert comm.launched_size() == 1
    monkeypatch.setenv("OMPI_COMM_WORLD_SIZE", "4")
    assert comm.launched_size() == 4


@pytest.mark.skipif(
    importlib.util.find_spec("petsc4py") is not None, reason="petsc4py is installed here"
)
def test_petsc_without_petsc4py_names_the_setup():
    with pytest.raises(CaseError, match="make setup-mpi"):
        LinearSolver("petsc", 1e-8, 100)
