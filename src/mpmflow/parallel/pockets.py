"""Water sealed off from the free surface, found across ranks (src/core/pockets.hpp finds it
on one process): a connected part of the pressure system with no row next to a free surface
has its pressure fixed only up to a constant.

Each rank labels the connected parts of its own rows (SciPy's connected components), the
labels reach the nodes round its box (the owners' labels), and rank 0 joins the parts that
meet across the boxes (a small graph: one vertex per part, one edge per pair that touch).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..state import CoreState
from ..state.arrays import Floats, Ints
from .comm import Comm
from .exchange import NodeExchange


def sealed_pockets(
    comm: Comm, nodes: NodeExchange, core: CoreState, owned: Ints, number: Floats
) -> bool:
    """True when some connected part of the distributed pressure system has no anchored
    row. ``owned``: this rank's rows (local row numbers); ``number``: each local row's
    global number. Collective."""
    cols = core.matrix_cols[owned]
    m = owned.size
    rows = core.rows
    position = np.full(rows.size, -1, dtype=np.int64)  # local row -> place among owned
    position[owned] = np.arange(m)
    r, s = np.nonzero(cols >= 0)
    c = cols[r, s]
    inside = position[c] >= 0
    graph = sp.coo_matrix(
        (np.ones(int(inside.sum())), (r[inside], position[c[inside]])), shape=(m, m)
    )
    parts, label = connected_components(graph, directed=False) if m else (0, np.zeros(0, int))
    anchored = np.zeros(parts, dtype=bool)
    np.logical_or.at(anchored, label, core.anchored[owned])
    # a part of the whole system joins parts of the ranks': when every rank's parts touch
    # a free surface, so do the whole system's
    if not comm.allreduce(int(not anchored.all())):
        return False
    counts = comm.allgather(int(parts))
    first = int(sum(counts[: comm.rank]))
    # each owned row's part, at its node, for the neighbours
    at_nodes = np.full(core.node_row.shape[0], -1.0)
    at_nodes[rows[owned]] = first + label
    nodes.fill(at_nodes)
    across = ~inside
    edges = np.stack([first + label[r[across]], at_nodes[rows[c[across]]]], axis=1)
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
