"""Water sealed off from the free surface, found across ranks (src/core/pockets.hpp finds it
on one process): a connected part of the pressure system with no row next to a free surface
has its pressure fixed only up to a constant.

First the cheap test, every step: each rank walks its local system (its own rows and those
round its box) from its own rows next to a free surface (``state.reach``, compiled). When
every rank reaches all its own rows, every part of the whole system touches a free surface
(each part holds some rank's own row, and that rank's walk stayed inside the part), and the
step goes on after one reduction. Otherwise the exact test: each rank labels the connected
parts of its own rows (SciPy's connected components), the labels reach the nodes round its
box (the owners' labels), and rank 0 joins the parts that meet across the boxes (a small
graph: one vertex per part, one edge per pair that touch).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from .. import state
from ..arrays import Bools, Ints
from .comm import Comm
from .exchange import NodeExchange


def sealed_pockets(
    comm: Comm,
    exchange: NodeExchange,
    cols: Ints,
    places: Ints,
    owned: Ints,
    open_: Bools,
    count: int,
) -> bool:
    """True when some connected part of a distributed system (the pressure's on nodes, the
    volume correction's on cells) has no row next to an empty cell. ``cols``: the local
    rows' columns (local row numbers, -1: empty); ``places``: each local row's node or cell;
    ``owned``: this rank's rows; ``open_``: whether each owned row touches a free surface;
    ``exchange``: the owners' values at the nodes or cells this rank does not own;
    ``count``: the local nodes or cells. Collective."""
    seed = np.zeros(places.size, dtype=bool)
    seed[owned] = open_
    if not comm.allreduce(int(not state.reach(cols, seed)[owned].all())):
        return False
    cols = cols[owned]
    m = owned.size
    position = np.full(places.size, -1, dtype=np.int64)  # local row -> place among owned
    position[owned] = np.arange(m)
    r, s = np.nonzero(cols >= 0)
    c = cols[r, s]
    inside = position[c] >= 0
    graph = sp.coo_matrix(
        (np.ones(int(inside.sum())), (r[inside], position[c[inside]])), shape=(m, m)
    )
    parts, label = connected_components(graph, directed=False) if m else (0, np.zeros(0, int))
    anchored = np.zeros(parts, dtype=bool)
    np.logical_or.at(anchored, label, open_)
    # a part of the whole system joins parts of the ranks': when every rank's parts touch
    # a free surface, so do the whole system's
    if not comm.allreduce(int(not anchored.all())):
        return False
    counts = comm.allgather(int(parts))
    first = int(sum(counts[: comm.rank]))
    # each owned row's part, at its node or cell, for the neighbours
    at = np.full(count, -1.0)
    at[places[owned]] = first + label
    exchange.fill(at)
    across = ~inside
    edges = np.stack([first + label[r[across]], at[places[c[across]]]], axis=1)
    pieces = comm.allgather((np.unique(edges.astype(np.int64), axis=0), anchored))
    if comm.rank == 0:
        total = int(sum(counts))
        pairs = np.concatenate([e for e, _ in pieces]) if pieces else np.zeros((0, 2), int)
        flags = np.concatenate([a for _, a in pieces])
        joined = sp.coo_matrix(
            (np.ones(pairs.shape[0]), (pairs[:, 0], pairs[:, 1])), shape=(total, total)
        )
        _, whole = connected_components(joined, directed=False)
        reached = np.zeros(int(whole.max()) + 1 if total else 0, dtype=bool)
        np.logical_or.at(reached, whole, flags)
        sealed = bool(total and not reached.all())
    else:
        sealed = False
    return bool(comm.bcast(sealed, root=0))
