"""A run over MPI ranks stops together (``parallel.run``): a signal that reaches one rank
first is the ranks' signal after the chunk it arrived in. On one process and under
``mpirun -n 2`` (make test-mpi)."""

import signal

import pytest
from conftest import EXAMPLES

from mpmflow import load_case
from mpmflow.errors import CaseError
from mpmflow.output.folder import API_HINTS

pytest.importorskip("petsc4py")
pytest.importorskip("mpi4py")

from mpmflow.parallel.comm import world  # noqa: E402
from mpmflow.parallel.run import start  # noqa: E402


def test_a_signal_on_the_last_rank_stops_every_rank_at_the_same_output(tmp_path):
    comm = world()
    case = load_case(EXAMPLES / "hydrostatic.toml", ["time.end=0.1", "output.snapshots=false"])
    out = comm.bcast(tmp_path / "run")  # one folder: every rank writes a checkpoint piece
    with start(case, out, restart=False, overwrite=False, hints=API_HINTS) as sim:

        def signal_on_the_last_rank(sim):
            if comm.rank == comm.size - 1 and sim.time >= 0.03 - 1e-9:
                sim.stop_signal = signal.SIGTERM

        sim.add_callback(signal_on_the_last_rank)
        summary = sim.run()
    assert summary["status"] == "interrupted"
    times = comm.allgather(sim.time)
    assert times == [pytest.approx(0.03)] * comm.size
    assert summary["last_checkpoint"] == "checkpoint_000000030.npz"  # each rank's piece in it


def test_a_wall_budget_over_several_ranks_is_refused(tmp_path):
    """Each rank would stop on its own clock, at its own output time, and the others would
    wait for it in the next exchange: refused before the run starts."""
    comm = world()
    if comm.size == 1:
        pytest.skip("one rank: the budget is the one process's (tests/simulation)")
    case = load_case(EXAMPLES / "hydrostatic.toml", ["time.end=0.1", "output.snapshots=false"])
    with start(case, tmp_path / "run", restart=False, overwrite=False, hints=API_HINTS) as sim:
        with pytest.raises(CaseError, match=r"wall_budget"):
            sim.run(wall_budget=10.0)
