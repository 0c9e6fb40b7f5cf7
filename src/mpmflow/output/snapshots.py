"""Particle snapshots as VTU files (meshio) indexed by a ParaView time series (particles.pvd).

Each snapshot file is written atomically. The index grows in place: its closing tags are
overwritten by the new entry and the closing tags again, in one ``os.pwrite``, so adding a
snapshot costs the same at the 10,000th as at the first, and the index is a whole XML file
after any kill of the process (a single write is never half done for another process). A
restart rewrites it (atomically) with the entries the checkpoint counts.
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import TYPE_CHECKING
from xml.sax.saxutils import quoteattr

import meshio
import numpy as np

from ..errors import CaseError
from .atomic import atomic_path, write_text

if TYPE_CHECKING:
    from ..particles import Particles

# an entry of the index: a snapshot's time (s) and file name
Entry = tuple[float, str]

HEADER = (
    '<?xml version="1.0"?>\n'
    '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n'
    "  <Collection>\n"
)
FOOTER = "  </Collection>\n</VTKFile>\n"
_ENTRY = re.compile(r'^\s*<DataSet timestep="([^"]*)" part="0" file="([^"]*)"\s*/>\s*$')


def _entry(time: float, name: str) -> str:
    return f'    <DataSet timestep="{time:.9g}" part="0" file={quoteattr(name)}/>\n'


def read_index(path: str | Path) -> tuple[list[Entry], bool]:
    """The (time, file name) entries of a particles.pvd written by mpmflow, in order; a
    damaged tail (a crash of the machine) ends the list. Returns (entries, complete)."""
    try:
        text = Path(path).read_text(errors="replace")
    except OSError as err:
        raise CaseError(f"{path} cannot be read: {err.strerror}.") from None
    entries: list[Entry] = []
    for line in text.splitlines():
        m = _ENTRY.match(line)
        if m:
            try:
                entries.append((float(m.group(1)), _unescape(m.group(2))))
            except ValueError:
                break
    return entries, text.endswith(FOOTER)


def _unescape(value: str) -> str:
    return (
        value.replace("&quot;", '"').replace("&lt;", "<").replace("&gt;", ">").replace("&amp;", "&")
    )


class SnapshotWriter:
    def __init__(
        self, folder: str | Path, stem: str = "particles", resume: int | None = None
    ) -> None:
        """``resume``: the number of snapshots the checkpoint counts: the index is cut back
        to them (CaseError when it holds fewer) and later snapshot files are deleted.
        Without it the index is started anew."""
        self.folder = Path(folder)
        self.stem = stem
        self.index = self.folder / f"{stem}.pvd"
        self.entries: list[Entry] = []
        if resume is not None:
            found, _ = read_index(self.index) if self.index.exists() else ([], False)
            if len(found) < resume:
                raise CaseError(
                    f"--restart: {self.index} lists {len(found)} snapshots, the checkpoint was "
                    f"written after {resume}: it was changed or cut short since. Start the run "
                    "again with --overwrite, or restore the file."
                )
            self.entries = found[: int(resume)]
            keep = {f for _, f in self.entries}
            for old in self.folder.glob(f"{self.stem}_*.vtu"):
                if old.name not in keep:
                    old.unlink()
        self._rewrite()

    def _rewrite(self) -> None:
        text = HEADER + "".join(_entry(t, f) for t, f in self.entries)
        self._end = len(text.encode())  # where the next entry goes
        write_text(self.index, text + FOOTER)

    def write(self, time: float, particles: Particles) -> str:
        name = f"{self.stem}_{len(self.entries):06d}.vtu"
        n, dim = particles.x.shape
        points = np.zeros((n, 3))
        points[:, :dim] = particles.x
        velocity = np.zeros((n, 3))
        velocity[:, :dim] = particles.v
        mesh = meshio.Mesh(
            points,
            [("vertex", np.arange(n, dtype=np.int64).reshape(-1, 1))],
            point_data={
                "velocity": velocity,
                "pressure": particles.pressure.copy(),
                "mass": particles.mass.copy(),
            },
        )
        with atomic_path(self.folder / name) as tmp:
            # binary, uncompressed: zlib took 55 ms of a 60 ms snapshot of 26k particles
            # (about 0.6 s of a 5 s dam-break run) for a file about a third smaller
            meshio.write(tmp, mesh, file_format="vtu", compression=None)
        del mesh, points, velocity
        entry = _entry(time, name).encode()
        fd = os.open(self.index, os.O_WRONLY | os.O_CLOEXEC)
        try:
            os.pwrite(fd, entry + FOOTER.encode(), self._end)
        finally:
            os.close(fd)
        self._end += len(entry)
        self.entries.append((time, name))
        return name

    def sync(self) -> None:
        fd = os.open(self.index, os.O_RDONLY | os.O_CLOEXEC)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
