"""Checkpoints: one .npz file per checkpoint holding the arrays of a run and its JSON meta.

A checkpoint holds everything a run needs to continue exactly as if it had not stopped: the
particle arrays, the scheme's state carried between steps (``scheme.state()``), and in the
meta the time, step, time step, output schedule, counters, the resolved case, and where
each output file ended when it was written (rows and bytes of timeseries.csv and
probes.csv, the number of snapshots): state, not history, so a checkpoint's size does not
grow with the run's length. A restart cuts the output files back to those positions. The meta also holds a content hash
(SHA-256) of every file the case reads (meshes, probes' data): a restart whose files differ
from those the run started with is refused, naming the file.
mpmflow draws no random numbers, so there is no random state to keep. Files are written
atomically (and fsynced) and the latest ``KEEP`` are kept. Format 2 (format 1 carried every
row written so far).

A run over MPI ranks writes a checkpoint in pieces (no rank holds the whole run): each rank
its own particles' arrays with their numbers in the run (``scheme.id``) into
``checkpoint_NNNNNNNNN_rRRRR.npz``, then rank 0 the main file with the meta (``pieces``:
how many; ``particles``: the run's count) and the arrays sized by the grid. The main file is
written last, so a checkpoint whose main file exists has all its pieces; one whose piece is
missing or damaged is a damaged checkpoint. ``read`` gives one process the whole run in its
order, as a one-process checkpoint holds it, and a rank (``part``) its share of the pieces.
"""

from __future__ import annotations

import hashlib
import json
import re
import zipfile
from collections.abc import Collection, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypedDict

import numpy as np
from numpy.typing import NDArray

from .errors import CaseError
from .output.atomic import atomic_path

if TYPE_CHECKING:
    from .case import Case

# a checkpoint's arrays by name: the particles' (float64) and the scheme's state (any dtype)
Arrays = dict[str, NDArray[np.generic]]
# its meta: JSON read back (a checkpoint of any version, checked key by key where used)
Meta = dict[str, Any]


class FileHash(TypedDict):
    """The content hash of one file the case reads, and where it was."""

    path: str
    sha256: str


FORMAT = 2
KEEP = 2
_NAME = re.compile(r"^checkpoint_(\d{9})\.npz$")
NUMBERS = "scheme.id"  # in a checkpoint's pieces: each particle's number in the run


class CheckpointError(CaseError):
    """A checkpoint file cannot be read (damaged, cut short, or missing an entry)."""

    def __init__(self, path: str | Path, why: str) -> None:
        self.path, self.why = Path(path), why
        super().__init__(
            f"Checkpoint {path} cannot be read ({why}); it is damaged, e.g. cut short by a "
            "crash. Delete it to restart from the checkpoint before it, or start the run "
            "again with --overwrite instead of --restart."
        )


def path_for(folder: str | Path, step: int) -> Path:
    return Path(folder) / f"checkpoint_{step:09d}.npz"


def piece_path(main: str | Path, rank: int) -> Path:
    """The piece of rank ``rank`` of the checkpoint whose main file is ``main``."""
    main = Path(main)
    return main.with_name(f"{main.stem}_r{rank:04d}.npz")


def checkpoints(folder: str | Path) -> list[Path]:
    """The checkpoint files in ``folder``, oldest first (by step)."""
    found = [
        (int(m.group(1)), p)
        for p in Path(folder).glob("checkpoint_*.npz")
        if (m := _NAME.match(p.name))
    ]
    return [p for _, p in sorted(found)]


def _save(path: Path, arrays: Mapping[str, NDArray[np.generic]], **extra: object) -> None:
    with atomic_path(path, durable=True) as tmp:
        with open(tmp, "wb") as f:  # a file object: np.savez would append .npz to a name
            # numpy's stub takes a **mapping's values for savez's allow_pickle (bool) too
            np.savez(f, **extra, **arrays)  # type: ignore[arg-type]


def write_piece(
    folder: str | Path, step: int, rank: int, arrays: Mapping[str, NDArray[np.generic]]
) -> Path:
    """Write rank ``rank``'s piece of the checkpoint at ``step`` atomically (its particles'
    arrays, with ``NUMBERS``); the main file (``write`` with ``pieces``) follows once
    every rank's is written."""
    path = piece_path(path_for(folder, step), rank)
    _save(path, arrays)
    return path


def write(
    folder: str | Path,
    step: int,
    arrays: Mapping[str, NDArray[np.generic]],
    meta: Mapping[str, object],
) -> Path:
    """Write one checkpoint atomically and delete all but the latest ``KEEP`` (with their
    pieces); returns its path. A ``meta`` with ``pieces`` names a checkpoint in pieces,
    which ``write_piece`` has written."""
    path = path_for(folder, step)
    _save(path, arrays, meta=np.array(json.dumps({"format": FORMAT, **meta})))
    for old in checkpoints(folder)[:-KEEP]:
        old.unlink(missing_ok=True)
        for piece in old.parent.glob(f"{old.stem}_r*.npz"):
            piece.unlink(missing_ok=True)
    return path


def _load(path: Path, main: Path) -> Arrays:
    """The arrays of one .npz file (``main``: the checkpoint it belongs to, named when it
    cannot be read)."""
    try:
        data = np.load(path, allow_pickle=False)
        if not hasattr(data, "files"):
            raise ValueError("not an .npz archive")
        with data:
            return {k: data[k] for k in data.files}
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as err:
        # an empty file gives EOFError, a truncated one BadZipFile (a crash before the data
        # reached the disk)
        why = f"{type(err).__name__}: {err}" if str(err) else type(err).__name__
        raise CheckpointError(
            main, why if path == main else f"its piece {path.name}: {why}"
        ) from None


def read(path: str | Path, part: tuple[int, int] | None = None) -> tuple[Arrays, Meta]:
    """(arrays, meta) of a checkpoint file. Of one in pieces: without ``part`` the whole
    run's particles in their order (as a one-process checkpoint holds them, without
    ``NUMBERS``); with ``part`` = (rank, ranks) the pieces rank, rank + ranks, ... joined,
    with ``NUMBERS`` (the ranks part them again at their first split). A checkpoint of one
    process is read whole either way."""
    path = Path(path)
    arrays = _load(path, path)
    try:
        meta = json.loads(str(arrays.pop("meta")))
    except (KeyError, ValueError) as err:
        raise CheckpointError(path, f"{type(err).__name__}: {err}") from None
    if not isinstance(meta, dict):
        raise CheckpointError(path, "its meta entry is not a JSON object")
    if meta.get("format") != FORMAT:
        raise CaseError(
            f"Checkpoint {path} has format {meta.get('format')}, this mpmflow reads "
            f"format {FORMAT}; start the run again with --overwrite instead of "
            "--restart."
        )
    pieces = int(meta.get("pieces", 0))
    if pieces:
        ranks = range(pieces) if part is None else range(part[0], pieces, part[1])
        loaded = [_load(piece_path(path, r), path) for r in ranks]
        if not loaded:  # more ranks than pieces: none of the particles, in their shapes
            loaded = [{k: a[:0] for k, a in _load(piece_path(path, 0), path).items()}]
        joined = _joined(loaded, path)
        if NUMBERS not in joined:
            raise CheckpointError(path, f"its pieces lack {NUMBERS}")
        if part is None:
            numbers = joined.pop(NUMBERS)
            order = np.argsort(numbers, kind="stable")
            if not np.array_equal(numbers[order], np.arange(numbers.size)):
                raise CheckpointError(path, "its pieces do not hold each particle once")
            joined = {k: a[order] for k, a in joined.items()}
        arrays.update(joined)
    return arrays, meta


def _joined(pieces: list[Arrays], main: Path) -> Arrays:
    """The pieces' arrays joined, row by row, in the pieces' order."""
    names = set(pieces[0])
    if any(set(p) != names for p in pieces):
        raise CheckpointError(main, "its pieces hold different arrays")
    return {k: np.concatenate([p[k] for p in pieces]) for k in pieces[0]}


def latest(folder: str | Path) -> Path:
    """The path of the latest checkpoint in ``folder``; CaseError if there is none."""
    found = checkpoints(folder)
    if not found:
        raise CaseError(
            f"--restart: {folder} holds no checkpoint (checkpoint_*.npz) to "
            "continue from. Run without --restart to start the run."
        )
    return found[-1]


def _flatten(data: object, prefix: str = "") -> dict[str, object]:
    if isinstance(data, dict):
        out: dict[str, object] = {}
        for key, value in data.items():
            out.update(_flatten(value, f"{prefix}{key}."))
        return out
    if isinstance(data, list) and data and isinstance(data[0], dict):
        out = {}
        for k, value in enumerate(data):
            out.update(_flatten(value, f"{prefix}{k}."))
        return out
    return {prefix[:-1]: data}


def check_same_case(
    saved: Mapping[str, object],
    current: Mapping[str, object],
    path: str | Path,
    may_change: Collection[str] = ("time.end", "execution.threads"),
) -> None:
    """Refuse to continue a checkpoint with other settings than it was written with (only
    ``may_change`` may differ): CaseError naming the first differing key."""
    old, new = _flatten(saved), _flatten(current)
    for key in sorted(set(old) | set(new)):
        if key in may_change or old.get(key) == new.get(key):
            continue
        saved_value = old.get(key, "(not set)")
        raise CaseError(
            f"--restart: the case differs from the one checkpoint {path} was written with: "
            f"`{key}` = {json.dumps(new.get(key, '(not set)'))} now, "
            f"{json.dumps(saved_value)} in the checkpoint. A restart must use the same "
            f"settings except time.end (which may be later, to extend the run) and "
            f"execution.threads. Use "
            f"--set {key}={json.dumps(saved_value)}, or start a new run in another folder."
        )


def case_files(case: Case) -> dict[str, str]:
    """{case key: absolute path} of every file the case reads: the meshes of bodies and
    obstacles, the probes' data."""
    files = {}
    for group in ("bodies", "obstacles"):
        for k, spec in enumerate(getattr(case, group)):
            if spec.type == "mesh":
                files[f"{group}.{k}.path"] = str(Path(spec.path).expanduser())
    for k, probe in enumerate(case.probes):
        if probe.data is not None:
            files[f"probes.{k}.data.path"] = str(Path(probe.data.path).expanduser())
    return files


def file_hashes(case: Case) -> dict[str, FileHash]:
    """{case key: {"path", "sha256"}} of the files the case reads, as they are now."""
    out: dict[str, FileHash] = {}
    for key, path in case_files(case).items():
        digest = hashlib.sha256()
        with open(path, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                digest.update(block)
        out[key] = {"path": path, "sha256": digest.hexdigest()}
    return out


def check_same_files(
    saved: Mapping[str, FileHash] | None, current: Mapping[str, FileHash], path: str | Path
) -> None:
    """Refuse to continue a checkpoint whose case files changed since the run started
    (CaseError naming the file). ``saved``: the checkpoint's ``files`` (None in checkpoints
    written before they were recorded: nothing to compare)."""
    if saved is None:
        return
    for key, old in sorted(saved.items()):
        new = current.get(key)
        if new is not None and new["sha256"] == old["sha256"]:
            continue
        where = new["path"] if new is not None else old["path"]
        raise CaseError(
            f"--restart: the file `{key}` = {where} is not the one checkpoint {path} was "
            f"written with: its content changed since the run started (SHA-256 "
            f"{old['sha256'][:12]}... then, "
            f"{new['sha256'][:12] + '...' if new is not None else 'no such entry'} now). The "
            "particles moved in the old geometry and data; continuing with the new would mix "
            "the two without a word. Put the original file back, or start a new run in "
            "another folder (or with --overwrite)."
        )
