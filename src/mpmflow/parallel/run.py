"""A run started by ``mpirun -n N mpmflow run CASE``: one Simulation per rank, stepping the
case together (``parallel.scheme``), rank 0 alone writing the run's folder.

Every rank builds the same case and holds its own part of the particles
(``parallel.scheme``); the Simulation's measures combine the parts (``diagnostics.parts``),
so its loop and decisions agree on every rank. The other ranks run it without an output
folder, but write their pieces of the snapshots and checkpoints into it. A restart reads
the checkpoint rank 0 names (the folder's latest) on every rank, each its share of the
pieces: a checkpoint of a run on any number of ranks, or of one process, continues on any
other number.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

from .. import checkpoint
from ..case import Case
from ..errors import MpmflowError
from ..output.folder import Hints
from ..simulation import Simulation, checkpointer
from .comm import Comm, agreed, world
from .snapshots import RankSnapshots


def start(case: Case, out: Path, restart: bool, overwrite: bool, hints: Hints) -> Simulation:
    """This rank's Simulation of a run on several ranks (rank 0's claims ``out``)."""
    comm = world()
    root = comm.rank == 0
    path = None
    if restart:  # rank 0 finds the checkpoint, or the refusal every rank gives
        path = agreed(comm, lambda: checkpoint.latest(out) if root else None, root_only=True)
    sim: Simulation | None = None

    def build() -> None:
        nonlocal sim
        if restart:
            assert path is not None
            if root:
                sim = Simulation.resume(case, out, path=path, hints=hints)
            else:
                sim = checkpointer.resume_from(Simulation, case, out, path, None)
                sim.out_dir = None  # read from the folder; rank 0 alone writes to it
        elif root:
            sim = Simulation(case, out, overwrite=overwrite)
            sim.claim(hints)
        else:
            sim = Simulation(case, None)

    try:
        agreed(comm, build)
    except MpmflowError:
        if sim is not None:
            sim.close()  # rank 0's folder lock
        raise
    assert sim is not None
    agree_on_stops(sim, comm)
    snapshots_in_pieces(sim, comm, out)
    sim.checkpoint_dir = out  # every rank writes its piece of each checkpoint
    return sim


def snapshots_in_pieces(sim: Simulation, comm: Comm, out: Path) -> None:
    """Every rank writes its own particles as a piece of each snapshot, rank 0 the .pvtu
    that names them (``parallel.snapshots``), in place of one file of all of them."""
    pieces = RankSnapshots(comm, out)
    sim.builtin_writers["snapshots"] = pieces
    for k, action in enumerate(sim.actions):
        if action.name == "snapshots":
            sim.actions[k] = replace(action, func=pieces)


def agree_on_stops(sim: Simulation, comm: Comm) -> None:
    """A signal reaches the ranks at different moments (mpirun forwards SIGINT and SIGTERM
    to each): the ranks agree on it after every chunk, before the run acts on it, so that
    they stop at the same output time instead of one leaving the others waiting."""
    for k, action in enumerate(sim.actions):
        if action.name == "stop_on_signal":
            sim.actions[k] = replace(action, func=_agreed(comm, action.func))


def _agreed(comm: Comm, stop: Callable[[Simulation], None]) -> Callable[[Simulation], None]:
    def act(sim: Simulation) -> None:
        signals = comm.allgather(sim.stop_signal)
        sim.stop_signal = next((s for s in signals if s is not None), None)
        stop(sim)

    return act
