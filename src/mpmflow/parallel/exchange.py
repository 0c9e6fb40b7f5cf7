"""What the ranks send each other during a step (docs/design/mpi.md, section 2):

- ``NodeExchange.fill``: the values at the local nodes a rank does not own (its ghost
  ring and its box's upper planes), copied from their owners after each phase that makes
  them. The lists of who needs which node are made once per split.
- ``migrate``: the particles whose cell left a rank's box go to the rank that owns it.
- ``halo``: copies of a rank's particles in its neighbours' ghost layers, so that every
  node of a box sees all its particles.

Particles travel as a dict of arrays (one row per particle), to the neighbours only
(``subgrid.neighbours``: the ranks whose boxes meet this one's with its ghost layer), one
message to each of them and one from each, pickled by mpi4py (``swap``); node values
travel by its buffer sends. (Both used an all-to-all of every rank before, a message to
each rank of the run whatever its place: the cost the 64-rank model of
docs/notes/benchmarks-diary.md, "MPI", grows with N.)
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from .boxes import Boxes, cells_of
from .comm import Comm, sum_in_place
from .subgrid import Subgrid, extended

ParticleArrays = dict[str, NDArray[Any]]


class NodeExchange:
    """The owners' values at a rank's local nodes (or cells: ``cells=True``) that it does
    not own."""

    def __init__(self, comm: Comm, sub: Subgrid, cells: bool = False) -> None:
        self.comm = comm
        self.sent = 0  # bytes this rank has sent in fills
        size = comm.size
        owner = sub.cell_owner if cells else sub.node_owner
        number = sub.cell_global if cells else sub.node_global
        local_of = sub.local_cells if cells else sub.local_nodes
        foreign = np.flatnonzero(owner != sub.rank)
        owners = owner[foreign]
        # what this rank receives from each owner (local indices) and asks for (global)
        self.receive = {int(r): foreign[owners == r] for r in np.unique(owners)}
        asks: list[NDArray[np.int64]] = [
            number[self.receive[r]] if r in self.receive else np.zeros(0, np.int64)
            for r in range(size)
        ]
        asked = comm.alltoall(asks)
        self.send: dict[int, NDArray[np.int64]] = {}
        for r in range(size):
            if r != sub.rank and len(asked[r]):
                local = local_of(np.asarray(asked[r], dtype=np.int64))
                if np.any(local < 0) or np.any(owner[local] != sub.rank):
                    raise RuntimeError(f"rank {r} asked rank {sub.rank} for places it lacks")
                self.send[r] = local

    def fill(self, *arrays: NDArray[Any]) -> None:
        """Overwrite each array's rows (first axis: local nodes, or cells) where this rank
        does not own them with their owners' values. Collective."""
        if self.comm.size == 1:
            return
        from mpi4py import MPI

        widths = [int(np.prod(a.shape[1:])) for a in arrays]
        total = sum(widths)
        requests = []
        outgoing = {}
        for r, idx in self.send.items():
            buf = np.empty((idx.size, total))
            col = 0
            for a, w in zip(arrays, widths):
                buf[:, col : col + w] = a[idx].reshape(idx.size, w)
                col += w
            outgoing[r] = buf
            self.sent += buf.nbytes
            requests.append(self.comm.Isend(buf, dest=r, tag=11))
        incoming = {}
        for r, idx in self.receive.items():
            incoming[r] = np.empty((idx.size, total))
            requests.append(self.comm.Irecv(incoming[r], source=r, tag=11))
        MPI.Request.Waitall(requests)
        for r, idx in self.receive.items():
            col = 0
            for a, w in zip(arrays, widths):
                shape = (idx.size, *a.shape[1:])
                a[idx] = incoming[r][:, col : col + w].reshape(shape).astype(a.dtype)
                col += w


def number_rows(
    comm: Comm, exchange: NodeExchange, shape: tuple[int, ...], mine: NDArray[Any]
) -> tuple[NDArray[np.float64], int, int]:
    """The global numbers of a system's rows split over the ranks (the pressure's on nodes,
    the volume correction's on cells, the viscous predictor's on node components): this
    rank's own rows, ``mine`` (an index or a mask into an array of ``shape``, one entry per
    local node or cell and component), numbered in their order after those of the ranks
    before. Returns the numbers at every local place (-1: no row; the owners' numbers where
    this rank does not own the place), the first of this rank's and the total. Collective."""
    count = int(np.count_nonzero(mine)) if mine.dtype == bool else int(mine.size)
    counts = comm.allgather(count)
    first = int(sum(counts[: comm.rank]))
    number = np.full(shape, -1.0)
    number[mine] = first + np.arange(count)
    exchange.fill(number)
    return number, first, int(sum(counts))


def spread(
    exchange: NodeExchange, shape: tuple[int, ...], mine: NDArray[Any], values: NDArray[Any]
) -> NDArray[np.float64]:
    """A solution over the ranks at every local place: this rank's values at its own rows
    (``mine``, as ``number_rows`` took them), the owners' elsewhere, 0 off the rows.
    Collective."""
    whole = np.zeros(shape)
    whole[mine] = values
    exchange.fill(whole)
    return whole


def _take(arrays: ParticleArrays, mask: NDArray[Any]) -> ParticleArrays:
    return {k: a[mask] for k, a in arrays.items()}


def _join(parts: list[ParticleArrays], like: ParticleArrays) -> ParticleArrays:
    return {k: np.concatenate([p[k] for p in parts] or [like[k][:0]]) for k in like}


def owners(boxes: Boxes, sub: Subgrid, x: NDArray[np.float64]) -> NDArray[np.int64]:
    """The rank owning the cell of each point (global coordinates, m): this rank where the
    cell lies in its box (after a step, almost every particle of the rank), else looked up
    in the local grid's table where the point lies in it, by the boxes elsewhere."""
    me = sub.rank
    owner = np.full(x.shape[0], me, dtype=np.int64)
    if not x.shape[0]:
        return owner
    # a point's cell is monotone in each coordinate: when the cells of the least and the
    # largest coordinates lie in the box, so do all (the usual step: none left it)
    # (by column: NumPy reduces an n x D array along its long axis many times slower)
    ends = [(x[:, k].min(), x[:, k].max()) for k in range(x.shape[1])]
    corners = cells_of(np.array(ends).T, sub.grid.spacing, boxes.cells)
    if np.all((corners >= boxes.lo[me]) & (corners < boxes.hi[me])):
        return owner
    ijk = cells_of(x, sub.grid.spacing, boxes.cells)
    away = ~np.all((ijk >= boxes.lo[me]) & (ijk < boxes.hi[me]), axis=1)
    if not away.any():
        return owner
    rel = ijk[away] - sub.origin
    inside = np.all((rel >= 0) & (rel < np.asarray(sub.grid.cells)), axis=1)
    found = np.empty(rel.shape[0], dtype=np.int64)
    flat = np.ravel_multi_index(tuple(rel[inside].T), sub.grid.cells, order="F")
    found[inside] = sub.cell_owner[flat]
    if not inside.all():
        found[~inside] = boxes.owner_of_cells(rel[~inside] + sub.origin)
    owner[away] = found
    return owner


MIGRATE, HALO = 21, 22  # the tags of the two particle exchanges


def swap(comm: Comm, neighbours: list[int], out: dict[int, Any], tag: int) -> dict[int, Any]:
    """Send ``out[r]`` (None when absent) to each neighbour r and receive one object from
    each; returns them by sending rank. The neighbour relation is symmetric, so every
    send has its receive. Collective over the neighbours."""
    from mpi4py import MPI

    requests = [comm.isend(out.get(r), dest=r, tag=tag) for r in neighbours]
    got = {r: comm.recv(source=r, tag=tag) for r in neighbours}
    MPI.Request.waitall(requests)
    return got


def migrate(
    comm: Comm, owner: NDArray[np.int64], arrays: ParticleArrays, neighbours: list[int]
) -> ParticleArrays:
    """The particles this rank owns after they moved (``owner``: each one's rank now):
    those that stayed, then those that arrived, by sending rank. A particle goes to a
    neighbour only (``subgrid.neighbours``); one whose new owner is not a neighbour moved
    farther than the ghost layer in a step, which no step allows: RuntimeError. Collective
    over the neighbours."""
    if comm.size == 1:
        return arrays
    me = comm.rank
    leaving = owner != me
    if leaving.any():
        beyond = np.setdiff1d(np.unique(owner[leaving]), neighbours)
        if beyond.size:
            raise RuntimeError(
                f"rank {me}: particles moved in one step to rank(s) {beyond.tolist()}, beyond "
                f"its neighbours {neighbours}: farther than the ghost layer"
            )
    out = {r: _take(arrays, owner == r) for r in neighbours} if leaving.any() else {}
    got = swap(comm, neighbours, out, MIGRATE)
    arrived = [got[r] for r in neighbours if got[r] is not None]
    if not leaving.any() and not arrived:
        return arrays
    kept = _take(arrays, ~leaving) if leaving.any() else arrays
    return _join([kept, *arrived], arrays)


class Halo:
    """Copies of the neighbours' particles in a rank's ghost layer: which of this rank's
    cells lie in each other rank's ghost layer is listed once per split."""

    def __init__(self, comm: Comm, boxes: Boxes, sub: Subgrid, neighbours: list[int]) -> None:
        self.comm, self.sub, self.boxes = comm, sub, boxes
        self.neighbours = neighbours
        cells = (
            np.stack(
                np.unravel_index(np.arange(sub.grid.ncells), sub.grid.cells, order="F"), axis=1
            )
            + sub.origin
        )
        mine = sub.owned_cells
        self.wanted: dict[int, NDArray[np.bool_]] = {}
        for r in neighbours:  # only a neighbour's ghost layer meets this rank's box
            lo, hi = extended(boxes, r)
            wanted = mine & np.all((cells >= lo) & (cells < hi), axis=1)
            if wanted.any():
                self.wanted[r] = wanted

    def __call__(self, arrays: ParticleArrays) -> ParticleArrays:
        """The halo of this rank's (owned) particles' neighbours, by sending rank.
        Collective."""
        comm = self.comm
        if comm.size == 1:
            return {k: a[:0] for k, a in arrays.items()}
        sub = self.sub
        ijk = cells_of(arrays["x"], sub.grid.spacing, self.boxes.cells) - sub.origin
        local = np.ravel_multi_index(tuple(ijk.T), sub.grid.cells, order="F")
        out = {r: _take(arrays, wanted[local]) for r, wanted in self.wanted.items()}
        got = swap(comm, self.neighbours, out, HALO)
        return _join([got[r] for r in self.neighbours if got[r] is not None], arrays)


class RankExchange:
    """The core's exchange seam on one rank (src/core/exchange.hpp; ``State.use_exchange``):
    the compiled step calls these methods where a step meets the other ranks. It holds the
    rank's own particles between steps (global coordinates, with their numbers ``id``) and
    the local set of a step (its own, then the halo, in the local grid's coordinates)."""

    def __init__(
        self,
        comm: Comm,
        boxes: Boxes,
        sub: Subgrid,
        neighbours: list[int],
        fields: tuple[str, ...],
        traffic: dict[str, int],
    ) -> None:
        self.comm, self.boxes, self.sub = comm, boxes, sub
        self.neighbours = neighbours
        self.fields = fields
        self.traffic = traffic
        self.nodes = NodeExchange(comm, sub)
        self.cells = NodeExchange(comm, sub, cells=True)
        self.halo = Halo(comm, boxes, sub, neighbours)
        self.foreign = ~sub.owned_nodes
        self.owned: ParticleArrays = {}
        self.local: ParticleArrays = {}
        self.step = 0  # the steps begun in this chunk (where the solvers' messages point)

    def start(self, owned: ParticleArrays) -> None:
        """A chunk's start: the rank's own particles."""
        self.owned = owned
        self.step = 0

    # the seam's calls, in the order of a step
    def particles(self) -> tuple[int, Any, Any, Any, Any, Any, Any, Any, Any, Any]:
        """The step's particles: the owned ones, then the halo (local coordinates); with
        APIC their affine matrices, a solid's history (None where not carried)."""
        ghosts = self.halo(self.owned)
        self.traffic["halo particles"] += int(ghosts["id"].size)
        # without a halo (one rank; a box away from the others) the owned arrays serve
        arrays = {
            f: np.concatenate([self.owned[f], ghosts[f]]) if len(ghosts[f]) else self.owned[f]
            for f in self.fields
        }
        arrays["x"] = arrays["x"] - self.sub.offset
        self.local = {f: np.ascontiguousarray(a) for f, a in arrays.items()}
        self.step += 1
        a = self.local
        m = int(self.owned["x"].shape[0])
        return (
            m,
            a["x"],
            a["v"],
            a["mass"],
            a["volume"],
            a["pressure"],
            a.get("affine"),
            a.get("stress"),
            a.get("plastic_strain"),
            a.get("yielding"),
        )

    def fill_nodes(self, *arrays: NDArray[Any]) -> None:
        self.nodes.fill(*arrays)

    def fill_cells(self, *arrays: NDArray[Any]) -> None:
        self.cells.fill(*arrays)

    def own_unknowns(self, node_row: NDArray[np.int64]) -> None:
        """The owners say which nodes round the box are unknowns (0: one, -1: not; the core
        numbers its rows again)."""
        unknown = (node_row >= 0).astype(float)
        self.nodes.fill(unknown)
        node_row[self.foreign] = np.where(unknown[self.foreign] > 0, 0, -1)

    def max(self, x: float) -> float:
        return float(max(self.comm.allgather(float(x))))

    def sum(self, n: int) -> int:
        return int(self.comm.allreduce(int(n)))

    def sum_values(self, values: NDArray[np.float64]) -> None:
        """Each value summed over the ranks, in place (the bodies' forces and torques)."""
        if values.flags.c_contiguous:
            sum_in_place(self.comm, values)
        else:
            values[:] = sum_in_place(self.comm, values.copy())

    def refresh_halo(self) -> None:
        """The halo's stress history made its owners' again (a solid's, after the owners
        updated it: the step's tools read every particle's round a node). The owned
        particles have not moved since ``particles``, so the halo is the same particles in
        the same order."""
        m = int(self.owned["x"].shape[0])
        names = [f for f in ("stress", "plastic_strain", "yielding") if f in self.local]
        mine: ParticleArrays = {f: self.local[f][:m] for f in names}
        mine["x"] = self.owned["x"]
        ghosts = self.halo(mine)
        for f in names:
            self.local[f][m:] = ghosts[f]

    def migrate(self) -> None:
        """The owned particles, moved by the step, to the ranks that own their cells."""
        m = int(self.owned["x"].shape[0])
        moved = {f: a[:m] for f, a in self.local.items()}
        moved["x"] = moved["x"] + self.sub.offset
        moved["id"] = self.owned["id"]
        owner = owners(self.boxes, self.sub, moved["x"])
        self.traffic["migrated particles"] += int((owner != self.comm.rank).sum())
        self.traffic["steps"] += 1
        self.owned = migrate(self.comm, owner, moved, self.neighbours)
        self.local = {}
