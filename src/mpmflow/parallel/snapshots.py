"""Particle snapshots of a run over ranks, in pieces (issue 42, item 3): at each snapshot
time every rank writes its own particles as one VTU piece,
``particles_NNNNNN_rRRRR.vtu`` (with each particle's number in the run, ``id``), and rank 0
writes ``particles_NNNNNN.pvtu`` naming the pieces and adds it to ``particles.pvd``, the
index a one-process run keeps (``output.snapshots``). ParaView opens the .pvd as one time
series; ``mpmflow.open_run`` reads a .pvtu's pieces back in the particles' order.

No rank writes or gathers another rank's particles for a snapshot; the pieces' particles
are the rank's own (the scheme's ``owned_particles``). A one-process run keeps its single
VTU file a snapshot, byte for byte as before.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import CaseError
from ..output.snapshots import SnapshotWriter, piece_name, write_pvtu, write_vtu
from ..simulation.writers import Snapshots
from .comm import Comm

if TYPE_CHECKING:
    from ..simulation import Simulation


class RankSnapshots(Snapshots):
    """The ``snapshots`` writer of a run over ranks, in place of ``writers.Snapshots``
    (``open``, ``__call__``, ``position``, ``sync``). Every call is collective."""

    def __init__(self, comm: Comm, folder: Path, stem: str = "particles") -> None:
        super().__init__()
        self.comm = comm
        self.folder = folder
        self.stem = stem
        self.index: SnapshotWriter | None = None  # rank 0's
        self.count = 0  # snapshots written, on every rank
        self.active = False

    def open(self, sim: Simulation, resume: int | None) -> None:
        """Rank 0 opens (or cuts back, on a restart) the index and deletes later files,
        before any rank writes a piece; a refusal there is every rank's."""
        self.active = bool(sim.case.output.snapshots)
        if not self.active:
            return
        error = None
        if self.comm.rank == 0:
            try:
                self.index = SnapshotWriter(self.folder, self.stem, resume=resume)
            except CaseError as err:
                error = str(err)
        error = self.comm.bcast(error, root=0)  # also: no piece before the clean-up
        if error is not None:
            raise CaseError(error)
        self.count = int(resume or 0)

    def __call__(self, sim: Simulation) -> None:
        sim.forget_bins()
        if not self.active:
            return
        mine: dict[str, Any] = sim.scheme.owned_particles()  # type: ignore[attr-defined]
        rank = self.comm.rank
        counts = self.comm.allgather(int(mine["id"].size))
        if counts[rank] or (rank == 0 and not any(counts)):  # no empty pieces but one
            write_vtu(
                self.folder / piece_name(self.stem, self.count, rank),
                mine["x"],
                mine["v"],
                mine["pressure"],
                mine["mass"],
                mine["id"],
                # a solid's history, as one process writes it
                {k: mine[k] for k in ("stress", "plastic_strain", "yielding") if k in mine},
            )
        self.comm.Barrier()  # every piece is written before the .pvtu names it
        if rank == 0:
            assert self.index is not None
            # the pieces that hold particles (rank 0's when none does: a valid empty set)
            pieces = [piece_name(self.stem, self.count, r) for r, c in enumerate(counts) if c]
            pvtu = f"{self.stem}_{self.count:06d}.pvtu"
            write_pvtu(self.folder / pvtu, pieces or [piece_name(self.stem, self.count, 0)])
            self.index.add(sim.time, pvtu)
        self.count += 1

    def position(self) -> int | None:
        return self.count if self.active else None

    def sync(self) -> None:
        if self.index is not None:
            self.index.sync()
