"""timeseries.csv (and probes.csv): one row per output time, appended as the run goes.

The file is append-only, so its cost is linear in the run's length: the header is written
once (atomically, when the run starts), and each row is one ``os.write`` of the whole line
on a file opened with O_APPEND. A row is in the operating system's hands as soon as it is
written (a killed process loses nothing written); before every checkpoint the file is
fsynced, so that the rows a checkpoint counts survive a power loss too. After a power loss
or a crash of the machine the last line may be cut short: ``read_table`` drops a last line
without its newline (and says so), and ``--restart`` cuts the file back to the length the
checkpoint recorded before appending.

The columns and their units: COLUMNS (and the README).
"""

import math
import os
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any, TypedDict

import numpy as np
from numpy.typing import NDArray

from ..errors import CaseError
from .atomic import write_text

# a row: a value by column (None: not measured, written as nan)
Row = Mapping[str, float | None]
# a table read back: a column of values by name
Table = dict[str, NDArray[np.float64]]


class Position(TypedDict):
    """Where a CSV file ended when a checkpoint was written: its rows and bytes."""

    rows: int
    bytes: int


COLUMNS = {
    "time": "s",
    "front": "m",
    "height": "m",
    "step": "-",
    "kinetic_energy": "J/m",
    "potential_energy": "J/m",
    "body_energy": "J/m",
    "max_speed": "m/s",
    "max_pressure": "Pa",
    "pressure_noise": "Pa",
    "volume_ratio": "-",
    "packed_share": "-",
    "max_particles_per_cell": "-",
    "pressure_unknowns": "-",
    "solver_iterations": "-",
}


def units(dim: int) -> dict[str, str]:
    """The columns' units for a run of dimension ``dim``: energies per metre of depth in 2D
    (J/m), absolute in 3D (J)."""
    if dim == 2:
        return dict(COLUMNS)
    return {c: ("J" if u == "J/m" else u) for c, u in COLUMNS.items()}


def _fmt(value: float | np.integer[Any] | None) -> str:
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "nan"
    return f"{value:.9g}"


def format_row(columns: Iterable[str], row: Row) -> str:
    """One CSV line (with its newline) of the values of ``row`` (a dict) in column order."""
    return ",".join(_fmt(row[c]) for c in columns) + "\n"


class CsvAppender:
    """An append-only CSV file with a fixed header.

    ``resume``: the position a checkpoint recorded ({"rows": n, "bytes": b}); the file is
    checked to hold at least that much (CaseError otherwise) and cut back to it, dropping
    the rows written after the checkpoint. Without it the file is created anew.
    ``labels``: the header's names of the columns when they differ from the row's keys
    (probes.csv: ``name [unit]``)."""

    def __init__(
        self,
        path: str | Path,
        columns: Iterable[str],
        resume: Position | None = None,
        labels: Iterable[str] | None = None,
    ) -> None:
        self._fd: int | None = None
        self.path = Path(path)
        self.columns = list(columns)
        header = ",".join(labels if labels is not None else self.columns) + "\n"
        if resume is None:
            write_text(self.path, header)
            self.rows, self.bytes = 0, len(header.encode())
        else:
            self.rows, self.bytes = int(resume["rows"]), int(resume["bytes"])
            self._check(header)
            os.truncate(self.path, self.bytes)
        self._fd = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CLOEXEC)

    def _check(self, header: str) -> None:
        name = self.path.name
        try:
            with open(self.path, "rb") as f:
                head = f.read(self.bytes)
        except OSError as err:
            raise CaseError(
                f"--restart: {self.path} cannot be read ({err.strerror}); the "
                "checkpoint needs the rows written before it. Start the run again "
                "with --overwrite."
            ) from None
        lines = head.count(b"\n")
        first = head.split(b"\n", 1)[0] + b"\n"
        if first != header.encode() and head.endswith(b"\n"):
            raise CaseError(
                f"--restart: {name} in {self.path.parent} has other columns than this run "
                f"writes (its header: {first.decode(errors='replace').strip()!r}; this run's: "
                f"{header.strip()!r}): it was written by another version of mpmflow (the time "
                "series gained body_energy on 2026-12-01) or for other probes. Start the run "
                "again with --overwrite."
            )
        if (
            len(head) < self.bytes
            or not head.endswith(b"\n")
            or lines != self.rows + 1
            or not head.startswith(header.encode())
        ):
            raise CaseError(
                f"--restart: {name} in {self.path.parent} does not hold the {self.rows} rows "
                f"the checkpoint was written after (it holds {max(lines - 1, 0)} complete rows "
                f"in its first {len(head)} bytes, or another header): it was changed or cut "
                "short since. Start the run again with --overwrite, or restore the file."
            )

    def append(self, row: Row) -> None:
        """Append one row (a dict with every column)."""
        data = format_row(self.columns, row).encode()
        assert self._fd is not None, "appending to a closed CSV file"
        written = os.write(self._fd, data)
        while written < len(data):  # a regular file takes it whole; a full disk raises
            written += os.write(self._fd, data[written:])
        self.rows += 1
        self.bytes += len(data)

    def position(self) -> Position:
        """What a checkpoint records to continue this file."""
        return {"rows": self.rows, "bytes": self.bytes}

    def sync(self) -> None:
        assert self._fd is not None, "syncing a closed CSV file"
        os.fsync(self._fd)

    def close(self) -> None:
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None

    def __del__(self) -> None:
        self.close()


class TimeSeriesWriter(CsvAppender):
    def __init__(self, path: str | Path, resume: Position | None = None) -> None:
        super().__init__(path, COLUMNS, resume)


class SeriesBuffer:
    """The rows of a run in memory, as one float array that doubles when full (8 bytes per
    value: ``Simulation.series`` and the rows of a resumed run)."""

    def __init__(self, columns: Iterable[str]) -> None:
        self.columns = list(columns)
        self._index = {c: k for k, c in enumerate(self.columns)}
        self._data = np.empty((64, len(self.columns)))
        self._n = 0

    def __len__(self) -> int:
        return self._n

    def append(self, row: Row) -> None:
        if self._n == self._data.shape[0]:
            self._data = np.concatenate([self._data, np.empty_like(self._data)])
        self._data[self._n] = [np.nan if row[c] is None else row[c] for c in self.columns]
        self._n += 1

    def extend(self, table: Mapping[str, NDArray[np.float64]]) -> None:
        """Append the rows of a table read by ``read_table`` (a dict of columns)."""
        n = len(table[self.columns[0]]) if table else 0
        for k in range(n):
            self.append({c: table[c][k] for c in self.columns})

    def column(self, name: str) -> NDArray[np.float64]:
        values: NDArray[np.float64] = self._data[: self._n, self._index[name]].copy()
        return values

    def rows(self) -> list[dict[str, float]]:
        """The rows as dicts (integer columns as int)."""
        out = []
        for values in self._data[: self._n]:
            row: dict[str, float] = {}
            for c, v in zip(self.columns, values):
                row[c] = int(v) if c in _INTEGER and v == v else float(v)
            out.append(row)
        return out


_INTEGER = {"step", "max_particles_per_cell", "pressure_unknowns", "solver_iterations"}


def read_table(path: str | Path, required: Iterable[str] = ("time",)) -> tuple[Table, list[str]]:
    """Read an mpmflow CSV (timeseries.csv, probes.csv) as {column: array}, the columns named
    without the units a header gives (``time [s]`` -> ``time``), tolerating what a
    crash can leave: a last line without its newline is dropped. Returns (table, notes).
    CaseError when the file is not such a table (binary, another header, a damaged row)."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as err:
        raise CaseError(f"{path} cannot be read: {err.strerror}.") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise CaseError(
            f"{path} is not a text file (it holds binary data), so it is not an "
            "mpmflow table; the run that wrote it may have been damaged. Run the "
            "case again."
        ) from None
    notes: list[str] = []
    lines = text.split("\n")
    if lines and lines[-1] == "":
        lines.pop()  # the newline that ends the last complete row
    elif len(lines) > 1:
        notes.append(
            f"the last line of {path.name} is cut short (a crash while writing it); it is left out"
        )
        lines.pop()
    elif lines:
        lines = lines[:1]
    header = [_strip_unit(c) for c in lines[0].split(",")] if lines else []
    missing = [c for c in required if c not in header]
    if not header or missing or any(not c.isidentifier() and not _probe_name(c) for c in header):
        first = (
            (lines[0][:60] + "...") if lines and len(lines[0]) > 60 else (lines[0] if lines else "")
        )
        raise CaseError(
            f"{path} is not an mpmflow table: its first line should name the "
            f"columns (time, ...), it reads {first!r}. Give the folder of an "
            "mpmflow run, or run the case again."
        )
    values = np.empty((len(lines) - 1, len(header)))
    for k, line in enumerate(lines[1:]):
        cells = line.split(",")
        try:
            if len(cells) != len(header):
                raise ValueError(f"{len(cells)} values for {len(header)} columns")
            values[k] = [float(c) for c in cells]
        except ValueError as err:
            raise CaseError(
                f"{path}, line {k + 2}, is damaged ({err}); the file was changed "
                "or damaged after the run wrote it. Run the case again."
            ) from None
    return {c: values[:, j].copy() for j, c in enumerate(header)}, notes


def header_units(path: str | Path) -> dict[str, str]:
    """The units a CSV's header gives its columns ({name: unit}, ``wall_p [Pa]`` -> "Pa");
    {} when it cannot be read. probes.csv states them, so a run still going (no summary.json
    yet) has them too."""
    try:
        with open(path, encoding="utf-8") as f:
            first = f.readline().rstrip("\n")
    except (OSError, UnicodeDecodeError):
        return {}
    out: dict[str, str] = {}
    for label in first.split(","):
        name = _strip_unit(label)
        if name != label:
            out[name] = label[len(name) + 2 : -1]
    return out


def _strip_unit(label: str) -> str:
    """A column's name without the unit its header may give: ``wall_p [Pa]`` -> ``wall_p``."""
    name, sep, unit = label.partition(" [")
    return name if sep and unit.endswith("]") and "[" not in unit else label


def _probe_name(name: str) -> bool:
    return bool(name) and all(ch.isalnum() or ch in "_.+-" for ch in name)
