"""Reading a run's results: ``mpmflow.open_run(DIR)``.

    run = mpmflow.open_run("runs/db")
    run.status                      # "completed", "failed", "interrupted", "stopped", ... or "running"
    run.timeseries["front"]         # numpy arrays by column (COLUMNS; "time" in s)
    run.probes["sensor_1"]          # probes.csv columns ("time" too); {} without probes
    snap = run.snapshots[-1]        # Snapshot(time, path)
    data = snap.read()              # {"x": (n, 2), "velocity": (n, 2), "pressure", "mass"}
    run.summary["wall_seconds"]     # summary.json as a dict ({} while the run goes)
    run.case                        # the resolved case (dict) the run was made with
    run.units                       # the unit of every column and summary value

A run that is still going, or was killed, can be read too: a last row cut short by a
crash is left out (``run.notes`` says so), and ``summary`` is empty until the run ends.
Nothing here writes into the folder or needs its lock.
"""

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .errors import CaseError
from .output.snapshots import read_index, read_pvtu
from .output.timeseries import COLUMNS, Table, header_units, read_table


@dataclass(frozen=True)
class Snapshot:
    """One particle snapshot: its simulated time (s) and VTU file."""

    time: float
    path: Path
    dim: int = 2  # the run's dimension (VTU points always have 3 coordinates)

    def read(self) -> dict[str, NDArray[np.float64]]:
        """The particle data: x (n, dim) m, velocity (n, dim) m/s, pressure (n,) Pa, mass
        (n,) kg/m in 2D, kg in 3D. CaseError when the file is missing or damaged. A run
        over ranks writes a .pvtu naming one piece a rank: its pieces are read and put
        back in the particles' order (their ids), as one process writes them."""
        if self.path.suffix == ".pvtu":
            return self._pieces()
        return self._vtu(self.path)

    def _pieces(self) -> dict[str, NDArray[np.float64]]:
        if not self.path.is_file():
            raise CaseError(
                f"snapshot {self.path} (t = {self.time:g} s) is missing: the "
                "index particles.pvd lists it, but the file was deleted or "
                "moved."
            )
        parts = [self._vtu(self.path.parent / name, ids=True) for name in read_pvtu(self.path)]
        joined = {k: np.concatenate([p[k] for p in parts]) for k in parts[0]} if parts else {}
        order = np.argsort(joined.pop("id", np.zeros(0)), kind="stable")
        return {k: a[order] for k, a in joined.items()}

    def _vtu(self, path: Path, ids: bool = False) -> dict[str, NDArray[np.float64]]:
        from meshio import vtu

        if not path.is_file():
            raise CaseError(
                f"snapshot {path} (t = {self.time:g} s) is missing: the "
                "index particles.pvd lists it, but the file was deleted or "
                "moved."
            )
        if _no_points(path):  # every particle had left through the outlets: meshio
            # writes such a file but cannot read it back ("Inconsistent data!")
            empty = np.zeros((0, self.dim))
            return {
                "x": empty,
                "velocity": empty.copy(),
                "pressure": np.zeros(0),
                "mass": np.zeros(0),
                **({"id": np.zeros(0)} if ids else {}),
            }
        try:
            # the VTU reader itself: meshio.read prints a damaged file's error and calls
            # sys.exit(1) (mpmflow plot exited 1 on a truncated snapshot)
            mesh = vtu.read(path)
            data = {
                "x": np.asarray(mesh.points[:, : self.dim]),
                "velocity": np.asarray(mesh.point_data["velocity"][:, : self.dim]),
                "pressure": np.asarray(mesh.point_data["pressure"]),
                "mass": np.asarray(mesh.point_data["mass"]),
            }
            if ids:
                data["id"] = np.asarray(mesh.point_data["id"])
        except FileNotFoundError:
            raise CaseError(
                f"snapshot {path} (t = {self.time:g} s) is missing: the "
                "index particles.pvd lists it, but the file was deleted or "
                "moved."
            ) from None
        except Exception as err:  # meshio raises many types for a damaged file
            raise CaseError(
                f"snapshot {path} (t = {self.time:g} s) cannot be read "
                f"({type(err).__name__}: {err}); it is damaged, e.g. cut short."
            ) from None
        if data["pressure"].shape[0] != data["x"].shape[0]:
            raise CaseError(
                f"snapshot {path} (t = {self.time:g} s) is damaged: its "
                "arrays have different lengths."
            )
        return data


def _no_points(path: Path) -> bool:
    """Whether the VTU file ``path`` (as mpmflow writes it) holds no particle: its header
    says NumberOfPoints="0" (False when it cannot be read: ``read`` says why)."""
    try:
        with open(path, "rb") as f:
            head = f.read(512)
    except OSError:
        return False
    return b'<Piece NumberOfPoints="0"' in head


class RunResults:
    """The results in a run's folder (see the module docstring)."""

    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder)
        if not self.folder.is_dir():
            raise CaseError(f"{self.folder} is not a folder; give the --out folder of a run.")
        csv = self.folder / "timeseries.csv"
        if not csv.is_file():
            raise CaseError(
                f"{self.folder} holds no timeseries.csv; give the --out folder of a "
                "run (mpmflow run CASE --out DIR)."
            )
        self.notes: list[str] = []
        self.timeseries, notes = read_table(csv, required=tuple(COLUMNS)[:3])
        self.notes += notes
        probes = self.folder / "probes.csv"
        self.probes: Table = {}
        if probes.is_file():
            self.probes, notes = read_table(probes)
            self.notes += notes
        self.summary = self._summary()
        self.snapshots: list[Snapshot] = []
        pvd = self.folder / "particles.pvd"
        if pvd.is_file():
            entries, complete = read_index(pvd)
            dim = len(self.summary.get("grid", {}).get("cells", [0, 0]))
            self.snapshots = [Snapshot(t, self.folder / f, dim) for t, f in entries]
            if not complete and entries:
                self.notes.append("particles.pvd is cut short after its last whole entry")

    def _summary(self) -> dict[str, Any]:  # JSON: summary.json as the run wrote it
        path = self.folder / "summary.json"
        if not path.is_file():
            return {}
        try:
            summary = json.loads(path.read_text())
        except (OSError, ValueError, UnicodeDecodeError) as err:
            self.notes.append(f"summary.json cannot be read ({type(err).__name__}); it is left out")
            return {}
        if not isinstance(summary, dict):
            self.notes.append("summary.json is not a JSON object; it is left out")
            return {}
        return summary

    @property
    def status(self) -> str:
        """The run's status from summary.json; "running" (or killed) while it has none."""
        status: str = self.summary.get("status", "running")
        return status

    @property
    def case(self) -> dict[str, Any]:
        """The resolved case (JSON) the run was made with; {} while the run goes."""
        case: dict[str, Any] = self.summary.get("case", {})
        return case

    @property
    def units(self) -> dict[str, str]:
        units = dict(COLUMNS)
        units.update(self.summary.get("units", {}))
        units.update(header_units(self.folder / "probes.csv"))
        for name, probe in self.summary.get("probes", {}).items():
            units[name] = probe.get("unit")
        return units

    def __repr__(self) -> str:
        n = len(self.timeseries.get("time", []))
        return (
            f"<mpmflow run {self.folder}: {self.status}, {n} rows, "
            f"{len(self.snapshots)} snapshots, {max(len(self.probes) - 1, 0)} probes>"
        )


def open_run(folder: str | Path) -> RunResults:
    """The results of the run in ``folder`` (RunResults); CaseError when it holds none."""
    return RunResults(folder)
