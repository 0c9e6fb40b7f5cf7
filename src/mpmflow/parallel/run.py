"""A run started by ``mpirun -n N mpmflow run CASE``: one Simulation per rank, stepping the
case together (``parallel.scheme``), rank 0 alone writing the run's folder.

Every rank builds the same case and, between chunks, holds the same particles (gathered at
the output times), so the Simulation's loop, measures and decisions agree on every rank;
the other ranks run it without an output folder. A restart reads the checkpoint rank 0
names (the folder's latest) on every rank: a checkpoint of a run on any number of ranks,
or of one process, continues on any other number.
"""

from __future__ import annotations

from pathlib import Path

from .. import checkpoint
from ..case import Case
from ..output.folder import Hints
from ..simulation import Simulation, checkpointer
from .comm import world


def start(case: Case, out: Path, restart: bool, overwrite: bool, hints: Hints) -> Simulation:
    """This rank's Simulation of a run on several ranks (rank 0's claims ``out``)."""
    comm = world()
    root = comm.rank == 0
    if restart:
        path = comm.bcast(checkpoint.latest(out) if root else None, root=0)
        if root:
            return Simulation.resume(case, out, path=path, hints=hints)
        sim = checkpointer.resume_from(Simulation, case, out, path, None)
        sim.out_dir = None  # read from the folder; rank 0 alone writes to it
        return sim
    if root:
        sim = Simulation(case, out, overwrite=overwrite)
        sim.claim(hints)
        return sim
    return Simulation(case, None)
