"""The processes of a run: mpi4py's ``COMM_WORLD`` under ``mpirun``, or one process.

A run started by ``mpirun``/``mpiexec`` (its launcher sets the world size in the
environment) uses mpi4py; one started without it needs no MPI at all (``Single``).
Collective calls take and return NumPy arrays or Python numbers, as mpi4py's do.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from functools import cache
from typing import Any, Protocol, TypeVar

from ..errors import CaseError, MpmflowError

T = TypeVar("T")

# the world size as the launchers of Open MPI, MPICH (Hydra) and Slurm give it
_SIZE_VARIABLES = ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE", "SLURM_NTASKS")
_RANK_VARIABLES = ("OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK", "SLURM_PROCID")
# the processes of the run on this machine (they share its memory)
_LOCAL_VARIABLES = ("OMPI_COMM_WORLD_LOCAL_SIZE", "MPI_LOCALNRANKS", "SLURM_NTASKS_PER_NODE")

SETUP_HINT = (
    "run `make setup-mpi` (Open MPI, mpi4py and petsc4py from Debian's packages, into "
    ".venv-mpi) and start the run with .venv-mpi/bin/python or .venv-mpi/bin/mpmflow"
)


class Comm(Protocol):
    """What mpmflow asks of a communicator (mpi4py's ``Comm`` satisfies it)."""

    @property
    def rank(self) -> int: ...
    @property
    def size(self) -> int: ...
    def allreduce(self, value: Any, op: Any = ...) -> Any: ...
    def Allreduce(self, sendbuf: Any, recvbuf: Any, op: Any = ...) -> None: ...
    def allgather(self, value: Any) -> list[Any]: ...
    def bcast(self, value: Any, root: int = 0) -> Any: ...
    def alltoall(self, values: list[Any]) -> list[Any]: ...
    def Isend(self, buf: Any, dest: int, tag: int = ...) -> Any: ...
    def Irecv(self, buf: Any, source: int = ..., tag: int = ...) -> Any: ...
    def isend(self, obj: Any, dest: int, tag: int = ...) -> Any: ...
    def recv(self, buf: Any = ..., source: int = ..., tag: int = ...) -> Any: ...
    def Barrier(self) -> None: ...


class Single:
    """One process: every collective is the identity."""

    rank = 0
    size = 1

    def allreduce(self, value: Any, op: Any = None) -> Any:
        return value

    def Allreduce(self, sendbuf: Any, recvbuf: Any, op: Any = None) -> None:
        raise RuntimeError("one process reduces nothing (sum_in_place returns its input)")

    def allgather(self, value: Any) -> list[Any]:
        return [value]

    def bcast(self, value: Any, root: int = 0) -> Any:
        return value

    def alltoall(self, values: list[Any]) -> list[Any]:
        return list(values)

    def Isend(self, buf: Any, dest: int, tag: int = 0) -> Any:
        raise RuntimeError("one process sends nothing")

    def Irecv(self, buf: Any, source: int = 0, tag: int = 0) -> Any:
        raise RuntimeError("one process receives nothing")

    def isend(self, obj: Any, dest: int, tag: int = 0) -> Any:
        raise RuntimeError("one process sends nothing")

    def recv(self, buf: Any = None, source: int = 0, tag: int = 0) -> Any:
        raise RuntimeError("one process receives nothing")

    def Barrier(self) -> None:
        return None


def agreed(
    comm: Comm,
    work: Callable[[], T],
    root_only: bool = False,
    errors: tuple[type[Exception], ...] = (MpmflowError,),
) -> T:
    """``work()`` on every rank (``root_only``: its result is rank 0's, sent to all), and
    an error of ``errors`` (a refusal, MpmflowError, by default) on any rank raised on
    every rank, as the first rank that met it gives it (a rank that met one raises its
    own): a rank that stopped alone would leave the others waiting in their next
    collective call for ever."""
    result, error = None, None
    try:
        result = work()
    except errors as err:
        error = err
    said = None if error is None else (type(error), str(error))
    if root_only:
        said, result = comm.bcast((said, result), root=0)
        told = [said]
    else:
        told = comm.allgather(said)
    if error is not None:
        raise error
    first = next((t for t in told if t is not None), None)
    if first is not None:  # another rank's, as that rank gives it
        kind, text = first
        other = kind.__new__(kind)
        Exception.__init__(other, text)
        raise other
    return result  # type: ignore[return-value]


def launched_size() -> int:
    """The number of processes the launcher started (1 without a launcher)."""
    for name in _SIZE_VARIABLES:
        value = os.environ.get(name)
        if value and value.isdigit():
            return int(value)
    return 1


def launched_rank() -> int:
    """This process's rank as the launcher gave it (0 without a launcher)."""
    return _first_number(_RANK_VARIABLES, 0)


def ranks_here() -> int:
    """The run's processes on this machine, as the launcher tells (all of them when it
    does not)."""
    return _first_number(_LOCAL_VARIABLES, launched_size())


def _first_number(names: tuple[str, ...], default: int) -> int:
    for name in names:
        value = os.environ.get(name)
        if value and value.isdigit():
            return int(value)
    return default


def sum_in_place(comm: Comm, values: Any) -> Any:
    """``values`` (a contiguous NumPy array) summed entry by entry over the ranks, in place
    (MPI's buffer Allreduce with IN_PLACE: no copy of the array; mpi4py's ``allreduce``
    pickles each rank's and makes new arrays of the sums); returned. One process: as it
    is."""
    if comm.size == 1:
        return values
    from mpi4py import MPI

    comm.Allreduce(MPI.IN_PLACE, values, op=MPI.SUM)
    return values


@cache
def world() -> Comm:
    """The run's processes: mpi4py's COMM_WORLD when mpi4py is installed or the run was
    started by an MPI launcher, ``Single`` otherwise. Under a launcher without mpi4py every
    process would run the whole case alone and write the same files: refused."""
    try:
        from mpi4py import MPI
    except ImportError:
        if launched_size() > 1:
            raise CaseError(
                f"This run was started on {launched_size()} MPI processes, but mpi4py is not "
                f"installed in this environment: {SETUP_HINT}."
            ) from None
        return Single()
    comm: Comm = MPI.COMM_WORLD
    return comm
