"""Writers: what the loop writes at its output times, each on a schedule.

- ``TimeSeries``: a row of ``Simulation.measure()`` into timeseries.csv and into memory
  (``sim.series``), at the output times (``output.interval``) and at ``time.end``;
- ``Probes``: the case's probes into probes.csv and memory (``sim.probe_series``), at the
  same times;
- ``Bodies``: the moving obstacles' pose, velocity, force and torque into bodies.csv, at
  the same times;
- ``Snapshots``: the particles into particles_NNNNNN.vtu and particles.pvd, at the first
  output time at or after each multiple of ``output.snapshot_interval`` and at the end; with
  moving obstacles, their surfaces where they are into bodies_NNNNNN.vtu and bodies.pvd;
- the checkpointer (``checkpointer.Checkpointer``), at the first output time at or after
  each multiple of ``checkpoint.interval``.

A writer is a callable(sim) with, optionally, ``open(sim, resume)`` (when the run starts;
``resume``: what a checkpoint recorded of it, None for a new run), ``position()`` (what a
checkpoint records of it), ``sync()`` (flush to the disk before a checkpoint) and
``close()``. The formats themselves are in ``mpmflow.output``.
"""

from __future__ import annotations

from collections.abc import Iterable
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .. import materials
from ..arrays import Floats
from ..boundaries import moving
from ..diagnostics import parts, probes
from ..geometry.rotation import quaternion_matrix
from ..output.snapshots import SnapshotWriter, write_surface_vtu
from ..output.timeseries import (
    COLUMNS,
    CsvAppender,
    Position,
    SeriesBuffer,
    TimeSeriesWriter,
    read_table,
)

if TYPE_CHECKING:
    from ..case import Case
    from .loop import Simulation


class _Rows:
    """Rows kept in memory and, with an output folder, appended to a CSV file."""

    file_name: str = ""  # set by each writer

    def __init__(self, columns: Iterable[str]) -> None:
        self.buffer = SeriesBuffer(columns)
        self.file: CsvAppender | None = None  # while a folder is written

    def _open_file(self, folder: Path, sim: Simulation, resume: Position | None) -> CsvAppender:
        raise NotImplementedError

    def open(self, sim: Simulation, resume: Position | None) -> None:
        folder = sim.out_dir
        if folder is None:
            return
        self.file = self._open_file(folder, sim, resume)
        if resume is not None:  # the earlier rows, for series()
            self.buffer.extend(read_table(folder / self.file_name)[0])

    def append(self, row: dict[str, float]) -> None:
        self.buffer.append(row)
        if self.file is not None:
            self.file.append(row)

    def position(self) -> Position | None:
        return self.file.position() if self.file is not None else None

    def sync(self) -> None:
        if self.file is not None:
            self.file.sync()

    def close(self) -> None:
        if self.file is not None:
            self.file.close()


class TimeSeries(_Rows):
    file_name = "timeseries.csv"

    def __init__(self) -> None:
        super().__init__(COLUMNS)

    def _open_file(self, folder: Path, sim: Simulation, resume: Position | None) -> CsvAppender:
        return TimeSeriesWriter(folder / self.file_name, resume)

    def __call__(self, sim: Simulation) -> None:
        row = sim.measure(sim.binned())
        self.append(row)
        sim.counters.iterations_since_output = 0


class Probes(_Rows):
    file_name = "probes.csv"

    def __init__(self, case: Case) -> None:
        super().__init__(probes.columns(case))
        # the pressure probes' windows: the probes, the grid and the obstacles stand still
        self._boxes: dict[str, tuple[Floats, Floats]] = {}

    def _open_file(self, folder: Path, sim: Simulation, resume: Position | None) -> CsvAppender:
        return CsvAppender(
            folder / self.file_name, probes.columns(sim.case), resume, probes.header(sim.case)
        )

    def __call__(self, sim: Simulation) -> None:
        solids = getattr(sim.scheme, "solids", None)  # the explicit scheme has none
        self.append(
            probes.measure(
                sim.case,
                sim.grid,
                sim.particles,
                sim.binned(),
                sim.time,
                solids.distance if solids is not None and solids.solids else None,
                sim.fallbacks,
                self._boxes,
                None if sim.comm.size == 1 else partial(parts.joined, sim.comm),
            )
        )


class CentreOfMass(_Rows):
    """The particles' centre of mass (m) into centre_of_mass.csv (output.centre_of_mass)."""

    file_name = "centre_of_mass.csv"

    def __init__(self, case: Case) -> None:
        super().__init__(["time"] + [f"{a}_c" for a in "xyz"[: len(case.domain.size)]])

    def _open_file(self, folder: Path, sim: Simulation, resume: Position | None) -> CsvAppender:
        columns = self.buffer.columns
        units = [f"{c} [{'s' if c == 'time' else 'm'}]" for c in columns]
        return CsvAppender(folder / self.file_name, columns, resume, units)

    def __call__(self, sim: Simulation) -> None:
        P, comm = sim.particles, sim.comm
        if sim.particle_count() == 0:  # every particle left through the outlets: no centre
            c = np.full(P.x.shape[1], np.nan)
        elif comm.size == 1:
            c = (P.mass[:, None] * P.x).sum(axis=0) / P.mass.sum()
        else:  # particles in parts: the moments of every part
            moments = np.append((P.mass[:, None] * P.x).sum(axis=0), P.mass.sum())
            whole = parts.add(comm, moments)
            c = whole[:-1] / whole[-1]
        self.append({"time": sim.time, **{f"{a}_c": float(v) for a, v in zip("xyz", c)}})


class Bodies(_Rows):
    """The moving obstacles (``obstacles.N.motion``) into bodies.csv at the output times: each
    one's pivot position (m), orientation (2D: its angle, degrees; 3D: its unit quaternion),
    velocity (m/s), turning rate (degrees/s; 3D about each axis), and the material's force
    (N; 2D N per metre of depth: a fluid's pressure, a solid's reactions at the nodes the
    body holds) and torque about the pivot (N m; 2D N m/m) in the last step
    (columns ``{name}_{quantity}``; the core's state, src/core/bodies.hpp)."""

    file_name = "bodies.csv"

    def __init__(self, movers: list[moving.Mover], dim: int) -> None:
        self.movers = movers
        self.dim = dim
        columns, self.units = ["time"], ["time [s]"]
        for m in movers:
            for q, unit in self._quantities():
                columns.append(f"{m.name}_{q}")
                self.units.append(f"{m.name}_{q} [{unit}]")
        super().__init__(columns)

    def _quantities(self) -> list[tuple[str, str]]:
        axes = "xyz"[: self.dim]
        per = "" if self.dim == 3 else "/m"
        turn = [("angle", "deg")] if self.dim == 2 else [(f"q{c}", "-") for c in "wxyz"]
        rates = [("rate", "deg/s")] if self.dim == 2 else [(f"w{a}", "deg/s") for a in axes]
        torques = [("torque", "N m/m")] if self.dim == 2 else [(f"torque_{a}", "N m") for a in axes]
        return [
            *((a, "m") for a in axes),
            *turn,
            *((f"v{a}", "m/s") for a in axes),
            *rates,
            *((f"F{a}", "N" + per) for a in axes),
            *torques,
        ]

    def _open_file(self, folder: Path, sim: Simulation, resume: Position | None) -> CsvAppender:
        return CsvAppender(folder / self.file_name, self.buffer.columns, resume, self.units)

    def __call__(self, sim: Simulation) -> None:
        # only the projection moves them: each body's force, torque and state (the domain's frame)
        force, torque, state = sim.scheme.body_values()  # type: ignore[attr-defined]
        D = self.dim
        row = {"time": sim.time}
        names = [q for q, _ in self._quantities()]
        for b, m in enumerate(self.movers):
            c, v, w, quat = state[b, :D], state[b, 3 : 3 + D], state[b, 6:9], state[b, 9:13]
            if D == 2:
                turn = [np.degrees(2.0 * np.arctan2(quat[3], quat[0]))]
                rates = [np.degrees(w[2])]
                torques = [torque[b, 2]]
            else:
                turn, rates, torques = list(quat), list(np.degrees(w)), list(torque[b])
            values = [*c, *turn, *v, *rates, *force[b], *torques]
            row.update({f"{m.name}_{q}": float(x) for q, x in zip(names, values)})
        self.append(row)


class Snapshots:
    """Snapshots when the case asks for them (``output.snapshots``) and there is a folder;
    otherwise the schedule still runs (its phase is in the checkpoints). With moving
    obstacles (``movers``), their surfaces (``Shape.boundary``) where the core puts them, in
    a file of their own beside each particles' (``Surfaces``)."""

    def __init__(self, movers: list[moving.Mover] | None = None) -> None:
        self.file: SnapshotWriter | None = None
        self.movers = movers or []
        self.surfaces: Surfaces | None = None

    def open(self, sim: Simulation, resume: int | None) -> None:
        if sim.out_dir is not None and sim.case.output.snapshots:
            self.file = SnapshotWriter(sim.out_dir, resume=resume)
            if self.movers:
                self.surfaces = Surfaces(self.movers, SnapshotWriter(sim.out_dir, "bodies", resume))

    def __call__(self, sim: Simulation) -> None:
        sim.forget_bins()  # the cells' bins are no longer needed: freed before the copies
        if self.file is not None:
            # a solid's stress history (empty for a fluid)
            history = getattr(sim.scheme, "history", {})
            # a saturated soil's stress is the effective stress, its pressure the pore pressure
            saturated = sim.case.material.model in materials.SATURATED
            name = "effective_stress" if saturated else "deviatoric_stress"
            # and the pore water's flux relative to the skeleton (Darcy): the scheme's
            flux = getattr(sim.scheme, "darcy_flux", None) if saturated else None
            extra = {"darcy_flux": flux()} if flux is not None else None
            self.file.write(sim.time, sim.particles, history, name, extra)
        if self.surfaces is not None:
            self.surfaces.write(sim)

    def position(self) -> int | None:
        return len(self.file.entries) if self.file is not None else None

    def sync(self) -> None:
        if self.file is not None:
            self.file.sync()
        if self.surfaces is not None:
            self.surfaces.file.sync()


class Surfaces:
    """The moving obstacles' surfaces for ParaView: at each snapshot one bodies_NNNNNN.vtu
    (indexed by bodies.pvd) holding every moving obstacle's surface (``Shape.boundary``: 2D
    line segments, 3D triangles) at its pose in the core's state, with each point's velocity
    (m/s, the body's v + omega x r) and, per cell, its body's number in bodies.csv's order
    (``body``), the material's force (N; 2D N/m) and torque about the pivot (N m; 2D N m/m)
    of the last step."""

    def __init__(self, movers: list[moving.Mover], file: SnapshotWriter) -> None:
        self.file = file
        self.frames = []  # each body's surface in its own frame: about its pivot at t = 0
        for m in movers:
            points, cells = m.shape.boundary()
            self.frames.append((points - m.pivot, cells))

    def write(self, sim: Simulation) -> None:
        force, torque, state = sim.scheme.body_values()  # type: ignore[attr-defined]
        D = sim.grid.dim
        points, cells, velocity, body = [], [], [], []
        count = 0
        for b, (y, c) in enumerate(self.frames):
            centre, v, w, q = state[b, :D], state[b, 3 : 3 + D], state[b, 6:9], state[b, 9:13]
            r = quaternion_matrix(*q)[:D, :D] @ y.T  # the surface's arms about the pivot, (D, n)
            points.append(centre + r.T)
            arm = np.zeros((3, r.shape[1]))
            arm[:D] = r
            velocity.append(v + np.cross(w, arm.T)[:, :D])
            cells.append(c + count)
            body.append(np.full(len(c), b, dtype=np.int64))
            count += len(y)
        index = np.concatenate(body)
        name = f"bodies_{len(self.file.entries):06d}.vtu"
        write_surface_vtu(
            self.file.folder / name,
            np.concatenate(points),
            np.concatenate(cells),
            {"velocity": np.concatenate(velocity)},
            {
                "body": index,
                "force": force[index],
                "torque": (torque[:, 2:] if D == 2 else torque)[index],
            },
        )
        self.file.add(sim.time, name)


Builtin = TimeSeries | Probes | CentreOfMass | Bodies | Snapshots  # the built-in writers
