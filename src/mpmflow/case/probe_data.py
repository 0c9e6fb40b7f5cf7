"""A probe's measured series (``probes.N.data``): the CSV file read and checked when the
case is loaded, so that `mpmflow plot` draws it over the probe's series as it is. A header
line names the columns; below it every row holds, in the two columns the probe reads, a
finite number, and the times do not decrease. A cell of text, nan or inf, or a time out of
order is refused with the file and the line (ValueError: the case's validation turns it
into the message), never dropped or plotted as it stands. Other columns are not read."""

import functools
import math
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from ..arrays import Floats


def _names(line: str) -> list[str]:
    return [c.strip().strip('"') for c in line.rstrip("\r\n").split(",")]


def read_series(
    path: str | Path, time_column: str, column: str, key: str = "probes.N.data", shown: str = ""
) -> tuple[Floats, Floats]:
    """(times, values) of the columns ``time_column`` and ``column`` of the CSV file
    ``path`` (absolute). ``key``: the case's key of the data, ``shown``: the path as the
    case gives it, for messages. ValueError naming the key, the file, its line and the
    fix."""
    path = Path(path)
    head = f"{key}.path = {shown or str(path)!r}: "
    try:
        with open(path, encoding="utf-8-sig") as f:
            lines = f.readlines()
    except OSError as err:
        raise ValueError(
            f"{head}the file {path} cannot be read ({err.strerror}); give "
            "the path of the measured series' CSV file, relative to the case file's folder"
        ) from None
    except UnicodeDecodeError:
        raise ValueError(
            f"{head}{path} is not a text file; give the path of the measured series' "
            "CSV file (a header line, then numbers)"
        ) from None
    names = _names(lines[0]) if lines else []
    for field, name in (("time_column", time_column), ("column", column)):
        if name not in names:
            raise ValueError(
                f"{key}.{field} = {name!r} is not a column of {path.name}, whose header names "
                + ", ".join(repr(n) for n in names[:20])
                + (" ..." if len(names) > 20 else "")
                + f"; set {key}.{field} to one of them, exactly as written"
            )
    cols = (names.index(time_column), names.index(column))
    fast = _parsed(path, cols)
    if fast is not None:
        return fast
    # the line-by-line reading, which names the line and cell at fault
    rows: list[tuple[float, float]] = []
    for n, line in enumerate(lines[1:], start=2):
        if not line.strip():
            continue  # a blank line (the one after the last row, say)
        cells = line.rstrip("\r\n").split(",")
        row = [_number(cells, c, names[c], f"{head}line {n} of {path}") for c in cols]
        if rows and row[0] < rows[-1][0]:
            raise ValueError(
                f"{head}line {n} of {path} is at {time_column!r} = {row[0]:g} s, before "
                f"the {rows[-1][0]:g} s of the row above it: the rows of a measured series go "
                "forward in time; sort the file by its time column"
            )
        rows.append((row[0], row[1]))
    if not rows:
        raise ValueError(
            f"{head}{path} holds no rows of numbers below its header; give the "
            "measured series' CSV file"
        )
    values = np.asarray(rows, dtype=float)
    return values[:, 0], values[:, 1]


def _parsed(path: Path, cols: tuple[int, int]) -> tuple[Floats, Floats] | None:
    """The two columns of a well-formed file (every row finite numbers, times not going
    back), read by NumPy's parser and kept for the file as it is now (its size and time of
    change: a case's probes share one file, and the case is checked again as a run starts:
    load_case of SPHERIC Test 2, 12 probes on one 7,400-line file, took 0.55 s line by line
    and takes 0.10 s so, medians of 3 on the 2-core machine); None where the file is not
    well formed, for the line-by-line reading to name what is wrong."""
    stat = path.stat()
    return _parse(str(path), stat.st_mtime_ns, stat.st_size, cols)


@functools.lru_cache(maxsize=64)
def _parse(
    path: str, mtime_ns: int, size: int, cols: tuple[int, int]
) -> tuple[Floats, Floats] | None:
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # an empty file's warning: None, read below
            table = np.loadtxt(
                path,
                delimiter=",",
                skiprows=1,
                usecols=cols,
                dtype=float,
                ndmin=2,
                quotechar='"',
                comments=None,  # a line of text is the reading's to refuse, not skipped
                encoding="utf-8-sig",
            )
    except (ValueError, OSError):
        return None
    if table.shape[0] == 0 or not np.isfinite(table).all() or np.any(np.diff(table[:, 0]) < 0):
        return None
    times, values = table[:, 0].copy(), table[:, 1].copy()
    times.setflags(write=False)
    values.setflags(write=False)
    return times, values


def _number(cells: list[str], c: int, name: str, line: str) -> float:
    """The cell of column c (named ``name``) of a line (``line``: where, for messages), a
    finite number; ValueError."""
    text = cells[c].strip().strip('"') if c < len(cells) else None
    where = f"{line}, column {name!r},"
    fix = "; the measured series holds numbers: correct or remove that line"
    if text is None:
        raise ValueError(f"{where} is missing (the line has {len(cells)} cells){fix}")
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"{where} holds {text!r}, which is not a number{fix}") from None
    if not math.isfinite(value):
        raise ValueError(f"{where} holds {text!r}, not a finite number{fix}")
    return value


def check(k: int, data: Any, folder: Path | None) -> None:
    """probes.k.data: its file exists and holds the series (``read_series``); ValueError
    otherwise. The path is made absolute (relative to ``folder``, the case file's, else the
    working folder), so that the resolved case in summary.json finds it from anywhere."""
    path = Path(data.path).expanduser()
    if not path.is_absolute():
        path = (Path(folder) if folder is not None else Path.cwd()) / path
    path = path.resolve()
    read_series(path, data.time_column, data.column, f"probes.{k}.data", data.path)
    object.__setattr__(data, "path", str(path))
