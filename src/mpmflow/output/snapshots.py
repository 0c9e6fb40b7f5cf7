"""Particle snapshots as VTU files (meshio) indexed by a ParaView time series (particles.pvd)."""

from pathlib import Path
from xml.sax.saxutils import quoteattr

import meshio
import numpy as np

from .atomic import atomic_path, write_text


class SnapshotWriter:
    def __init__(self, folder, stem="particles", entries=()):
        """``entries``: the (time, file name) pairs already written by the run being
        continued (from a checkpoint); later snapshot files are deleted and the index is
        rewritten at once."""
        self.folder = Path(folder)
        self.stem = stem
        self.entries = [(float(t), str(f)) for t, f in entries]  # (time, file name)
        if self.entries:
            keep = {f for _, f in self.entries}
            for old in self.folder.glob(f"{self.stem}_*.vtu"):
                if old.name not in keep:
                    old.unlink()
            self._write_index()

    def write(self, time, particles):
        name = f"{self.stem}_{len(self.entries):06d}.vtu"
        n, dim = particles.x.shape
        points = np.zeros((n, 3))
        points[:, :dim] = particles.x
        velocity = np.zeros((n, 3))
        velocity[:, :dim] = particles.v
        mesh = meshio.Mesh(
            points,
            [("vertex", np.arange(n, dtype=np.int64).reshape(-1, 1))],
            point_data={"velocity": velocity, "pressure": particles.pressure.copy(),
                        "mass": particles.mass.copy()},
        )
        with atomic_path(self.folder / name) as tmp:
            # binary, uncompressed: zlib took 55 ms of a 60 ms snapshot of 26k particles
            # (about 0.6 s of a 5 s dam-break run) for a file about a third smaller
            meshio.write(tmp, mesh, file_format="vtu", compression=None)
        self.entries.append((time, name))
        self._write_index()
        return name

    def _write_index(self):
        datasets = "\n".join(
            f'    <DataSet timestep="{t:.9g}" part="0" file={quoteattr(f)}/>'
            for t, f in self.entries)
        write_text(self.folder / f"{self.stem}.pvd",
                   '<?xml version="1.0"?>\n'
                   '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n'
                   "  <Collection>\n" + datasets + "\n  </Collection>\n</VTKFile>\n")
