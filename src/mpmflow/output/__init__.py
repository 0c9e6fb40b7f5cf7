"""Writers for run outputs: time series (CSV), particle snapshots (VTU + PVD), summary (JSON).

Every file is written atomically (to a temporary file in the same folder, then renamed),
so a run that is killed never leaves a half-written output behind.
"""

import errno
import os
import sys
from pathlib import Path

from ..errors import CaseError


def check_out_dir(out: str | Path, create: bool = True, name: str = "--out") -> None:
    """CaseError when the output folder ``out`` (``name`` in messages: the option or
    argument that gave it) is empty, a file, a path the system refuses (too long a name,
    no permission) or (with ``create``) cannot be created."""
    if isinstance(out, str) and not out:
        raise CaseError(
            f'{name} "" is empty, which would write into the current folder; give the '
            f"output folder, e.g. {name} runs/my_case."
        )
    out = Path(out)
    try:
        if out.exists() and not out.is_dir():
            raise CaseError(f"{name} {out} exists and is not a folder; give a folder path.")
        if create:
            out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        verb = "created" if create else "used"
        raise CaseError(f"{name} {out} cannot be {verb}: {fix(err)}") from None


def fix(err: OSError, elsewhere: str = "give a folder on another one") -> str:
    """What the system said of a path (``err``) and what to do, as a message's end
    (``elsewhere``: the fix of a full disk besides freeing space)."""
    said = err.strerror or str(err)
    if err.errno == errno.ENAMETOOLONG:
        return (
            f"{said}. Shorten it: each name in a path may have at most 255 bytes, "
            "the whole path 4096."
        )
    if err.errno == errno.ENOSPC:
        return f"{said}. Free some space on that disk, or {elsewhere}."
    return f"{said}. Give a folder you can write to."


def os_error(err: OSError) -> str:
    """The message of an OSError that reached the command line (writing an output file, or
    standard output on a full disk): the path when the system names one, and what it said.
    Standard output is pointed at /dev/null, so that the interpreter's last flush does not
    fail again with a traceback when it was what failed (a write to an open file names no
    path either, so it cannot be told apart; the command ends here anyway)."""
    paths = [str(p) for p in (err.filename, err.filename2) if p is not None]
    if paths:
        return f"{' and '.join(paths)}: {fix(err)}"
    silence_stdout()
    return (
        f"writing the command's output (standard output, or a file in its output folder) "
        f"failed: {fix(err, 'write it to another disk')}"
    )


def silence_stdout() -> None:
    """Point standard output at /dev/null (its reader went away, or its disk is full)."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())
