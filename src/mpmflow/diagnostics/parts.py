"""Measures of a run whose particles are held in parts, one part per MPI rank (issue 42,
item 3: no rank holds the whole run).

Each rank measures its own particles; these combine the parts, so that every rank holds the
whole run's value: the ranks take the same decisions from them (a blow-up, a stop, the
next output). The per-cell and per-node sums are exact: a cell's particles are all on the
rank that owns it, so the other ranks add zeros. Sums over the particles (energies) add the
ranks' partial sums, so their last bits depend on the split. With one process
(``parallel.comm.Single``) every function returns its input: the one-process measures are
unchanged to the bit.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..arrays import Floats, Ints
from ..parallel.comm import Comm, Single, sum_in_place
from ..state import Totals

ALONE: Comm = Single()  # one process: the whole run in one part


def count(comm: Comm, n: int) -> int:
    """The particles of the whole run, from each rank's ``n``."""
    return n if comm.size == 1 else int(comm.allreduce(int(n)))


def add(comm: Comm, values: NDArray[Any]) -> NDArray[Any]:
    """``values`` (an array) summed entry by entry over the ranks: in place where it is
    contiguous (the callers replace their array by the sum), into a contiguous copy
    otherwise."""
    if comm.size == 1:
        return values
    total: NDArray[Any] = sum_in_place(comm, np.ascontiguousarray(values))
    return total


def largest(comm: Comm, value: float) -> float:
    """The largest of the ranks' values (nan where no rank has one)."""
    if comm.size == 1:
        return value
    return largest_of(comm.allgather(float(value)))


def totals(comm: Comm, t: Totals, ids: Ints | None) -> Totals:
    """The whole run's totals from each rank's (``diagnostics.measures.totals``):
    ``fastest`` and ``first_nonfinite`` become the particles' numbers in the run (``ids``:
    each own particle's), the first of equal speeds the one of the lowest number, as one
    process takes the first."""
    if comm.size == 1:
        return t
    assert ids is not None
    mine = (
        t.kinetic,
        t.potential,
        t.max_speed,
        t.max_pressure,
        int(ids[t.fastest]) if t.fastest >= 0 else -1,
        t.nonfinite,
        int(ids[t.first_nonfinite]) if t.first_nonfinite >= 0 else -1,
    )
    parts = comm.allgather(mine)
    speeds = [(p[2], -p[4]) for p in parts if p[4] >= 0]
    fastest = -max(speeds)[1] if speeds else -1
    bad = [p[6] for p in parts if p[6] >= 0]
    return Totals(
        math.fsum(p[0] for p in parts),
        math.fsum(p[1] for p in parts),
        max(s for s, _ in speeds) if speeds else math.nan,
        largest_of([p[3] for p in parts]),
        fastest,
        sum(p[5] for p in parts),
        min(bad) if bad else -1,
    )


def largest_of(values: list[float]) -> float:
    """The largest of ``values`` that are numbers (nan: none is)."""
    seen = [v for v in values if not math.isnan(v)]
    return max(seen) if seen else math.nan


def position(comm: Comm, ids: Ints | None, x: Floats, number: int) -> Floats:
    """The position (m) of the particle numbered ``number`` in the run (one process: the
    index), from the rank that holds it."""
    if comm.size == 1:
        here: Floats = x[number]
        return here
    mine = np.flatnonzero(ids == number) if ids is not None else np.zeros(0, np.int64)
    found = [p for p in comm.allgather(x[mine[0]] if mine.size else None) if p is not None]
    return np.asarray(found[0]) if found else np.full(x.shape[1], math.nan)


def joined(comm: Comm, x: Floats, values: Floats) -> tuple[Floats, Floats]:
    """Positions (n x D) and values (n) of a few particles (a probe's window) from every
    rank, joined in the ranks' order."""
    if comm.size == 1:
        return x, values
    parts = comm.allgather((x, values))
    return np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])
