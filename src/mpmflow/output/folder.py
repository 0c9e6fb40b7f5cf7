"""The output folder of a run: one run at a time, by an advisory lock held for the run's life.

A run claims its folder before it reads or writes anything there: it creates (if needed)
and locks ``.mpmflow.lock`` in the folder with ``fcntl.flock`` and writes its PID, host,
start time and command line into it. A second run or restart into the same folder, from
the command line or the Python API, in this process or another, finds the lock taken and
is refused (``FolderBusy``, exit code 2) with the holder's PID. The kernel drops the lock
when the holder exits, however it exits (kill -9 included), so a lock is never stale; the
lock file itself stays (deleting it would let two runs lock two different files).

Under the lock the folder is checked and tidied:

- a new run refuses a folder that already holds the outputs of a run (unless told to
  overwrite, which deletes them first);
- temporary files left by a killed run's atomic writes (``.NAME.XXXX.tmp``) are deleted:
  no run of ours is writing there, so they are leftovers (reported as notes).

Locks need a POSIX system (Linux, macOS); on NFS, Linux maps flock to fcntl locks, which
work between machines when the server supports locking.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import json
import os
import re
import socket
import sys
import time
from pathlib import Path
from typing import Any, Literal, TypedDict

from ..errors import CaseError
from . import check_out_dir

LOCK_NAME = ".mpmflow.lock"

# the outputs of a run (outputs, checkpoints, snapshots): their presence means the folder
# holds a run; --overwrite deletes exactly these
OUTPUT_NAMES = ("timeseries.csv", "probes.csv", "summary.json", "particles.pvd")
OUTPUT_PATTERNS = ("particles_*.vtu", "particles_*.pvtu", "checkpoint_*.npz")
# a temporary file of output/atomic.py: ".<target name>.<random>.tmp" (a run over ranks
# writes particles_NNNNNN.pvtu and one piece a rank, particles_NNNNNN_rRRRR.vtu, and its
# checkpoints in pieces, checkpoint_NNNNNNNNN_rRRRR.npz)
_LEFTOVER = re.compile(
    r"^\.(timeseries\.csv|probes\.csv|summary\.json|particles\.pvd|"
    r"particles_\d+(_r\d+)?\.vtu|particles_\d+\.pvtu|checkpoint_\d+(_r\d+)?\.npz)\..+\.tmp$"
)


class Hints(TypedDict):
    """How refusals tell the user what to do: the command line's words or the API's."""

    busy: str  # when another run holds the folder ({pid}: its PID)
    holds: str  # when the folder holds another run's outputs
    name: str  # what gave the folder: the option or the argument


# how a run claims its folder: a new run, one that replaces the outputs there, a restart
Mode = Literal["new", "overwrite", "restart"]

CLI_HINTS: Hints = {
    "busy": "Wait for it to finish (or stop it: kill -TERM {pid}), or give another --out.",
    "holds": "Choose another folder, add --restart to continue it from its latest checkpoint, "
    "or add --overwrite to replace it.",
    "name": "--out",
}
API_HINTS: Hints = {
    "busy": "Wait for it to finish (or stop it: kill -TERM {pid}), or give another out_dir.",
    "holds": "Choose another folder, continue it with Simulation.resume(case, out_dir), or "
    "pass overwrite=True to replace it.",
    "name": "out_dir",
}


class FolderBusy(CaseError):
    """The output folder is locked by another run."""

    def __init__(self, message: str, pid: int | None) -> None:
        super().__init__(message)
        self.pid = pid


def output_files(folder: str | Path) -> list[Path]:
    """The run outputs present in ``folder`` (see OUTPUT_NAMES / OUTPUT_PATTERNS)."""
    folder = Path(folder)
    found = [folder / n for n in OUTPUT_NAMES if (folder / n).exists()]
    for pattern in OUTPUT_PATTERNS:
        found += sorted(folder.glob(pattern))
    return found


def leftovers(folder: str | Path) -> list[Path]:
    """Temporary files of atomic writes that a killed run left behind."""
    return sorted(p for p in Path(folder).iterdir() if _LEFTOVER.match(p.name))


def holder(folder: str | Path) -> dict[str, Any]:  # JSON: what the holder wrote
    """What the lock file says about the run holding it (dict, possibly empty)."""
    for _ in range(20):  # the holder writes it right after locking: a moment to appear
        try:
            text = (Path(folder) / LOCK_NAME).read_text()
        except OSError:
            return {}
        try:
            info = json.loads(text)
            if isinstance(info, dict):
                return info
        except ValueError:
            pass
        time.sleep(0.01)
    return {}


def _describe(info: dict[str, Any]) -> str:
    pid = info.get("pid")
    who = f"PID {pid}" if pid is not None else "PID unknown"
    if info.get("host") and info.get("host") != socket.gethostname():
        who += f" on host {info['host']}"
    if info.get("started"):
        who += f", started {info['started']}"
    if info.get("command"):
        who += f": {info['command']}"
    return who


class RunFolder:
    """A claimed (locked) output folder; ``release()`` (or the process's exit) frees it."""

    def __init__(self, path: str | Path, fd: int, notes: list[str], created: bool) -> None:
        self.path = Path(path)
        self._fd: int | None = fd
        self.notes = notes
        self.created = created

    @classmethod
    def claim(cls, path: str | Path, mode: Mode = "new", hints: Hints = API_HINTS) -> RunFolder:
        """Lock ``path`` for one run and prepare it.

        ``mode``: "new" (refuse a folder that holds a run's outputs), "overwrite" (delete
        them) or "restart" (the folder must exist; its outputs are the run to continue).
        Raises FolderBusy when another run holds the folder, CaseError for the other
        refusals."""
        path = Path(path)
        name = hints["name"]
        if mode == "restart":
            if not path.is_dir():
                raise CaseError(
                    f"{name} {path} does not exist; give the folder of the run to "
                    "continue, or start a new run."
                )
            created = False
        else:
            created = not path.exists()
            check_out_dir(path, create=True, name=name)
        try:
            fd = os.open(path / LOCK_NAME, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o666)
        except OSError as err:
            raise CaseError(
                f"{name} {path} cannot be written: {err.strerror} (creating its "
                f"lock file {LOCK_NAME}). Give a folder you can write to."
            ) from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as err:
            os.close(fd)
            if err.errno in (errno.EAGAIN, errno.EWOULDBLOCK, errno.EACCES):  # taken
                info = holder(path)
                raise FolderBusy(
                    f"{name} {path} is in use by another mpmflow run ({_describe(info)}). "
                    "Two runs in one folder would mix their outputs. "
                    + hints["busy"].format(pid=info.get("pid", "PID")),
                    info.get("pid"),
                ) from None
            raise CaseError(
                f"{name} {path}: its lock file cannot be locked ({err.strerror}); "
                "the file system may not support locks. Give a folder on a local "
                "disk."
            ) from None
        folder = cls(path, fd, [], created)
        try:
            folder._write_holder()
            folder._prepare(mode, hints)
        except BaseException:
            folder.release()
            raise
        return folder

    def _write_holder(self) -> None:
        info = {
            "pid": os.getpid(),
            "host": socket.gethostname(),
            "started": time.strftime("%Y-%m-%d %H:%M:%S"),
            "command": " ".join(sys.argv) if sys.argv and sys.argv[0] else "python",
        }
        data = (json.dumps(info) + "\n").encode()
        assert self._fd is not None  # right after the claim: not released yet
        os.ftruncate(self._fd, 0)
        os.pwrite(self._fd, data, 0)

    def _prepare(self, mode: Mode, hints: Hints) -> None:
        if mode == "new" and output_files(self.path):
            raise CaseError(
                f"{hints['name']} {self.path} already holds the results of a run. " + hints["holds"]
            )
        if mode == "overwrite":
            for old in output_files(self.path):
                old.unlink(missing_ok=True)
        stale = leftovers(self.path)
        for tmp in stale:
            tmp.unlink(missing_ok=True)
        if stale:
            self.notes.append(
                f"deleted {len(stale)} temporary file(s) left in {self.path} by a run that was "
                f"killed while writing ({', '.join(p.name for p in stale[:3])}"
                + (", ..." if len(stale) > 3 else "")
                + ")"
            )

    @property
    def held(self) -> bool:
        return self._fd is not None

    def release(self) -> None:
        """Unlock (idempotent). A temporary file of an atomic write still in the folder is
        this run's (a killed run's were deleted at the claim): one whose write a second
        signal cut short in the moment between creating it and guarding it. It goes first."""
        if self._fd is not None:
            with contextlib.suppress(OSError):  # (a folder removed under the run)
                for tmp in leftovers(self.path):
                    tmp.unlink(missing_ok=True)
            fd, self._fd = self._fd, None
            try:
                fcntl.flock(fd, fcntl.LOCK_UN)
            finally:
                os.close(fd)

    def __del__(self) -> None:
        self.release()
