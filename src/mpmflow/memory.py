"""How much memory a run needs, estimated from the case before anything is allocated, and
how much this machine can give it.

The estimate is the peak resident memory of the run's process: the program (Python, NumPy,
SciPy and the compiled core), the particles, the grid's arrays, the pressure solver (its
matrix and multigrid hierarchy, by pressure unknowns), the time series kept in memory, and
the largest passing need: writing a particle snapshot (meshio builds copies of the arrays),
or measuring an output row (binning the particles again). The bytes per particle, node and
unknown were measured on the dam break at six meshes (benchmarks/investigations/memory.py,
which also checks the estimate against the measured peak; the numbers are in
docs/notes/benchmarks-diary.md); the pressure solver's bytes per unknown in 3D on the 3D
dam break (benchmarks/investigations/mpi/memory_ranks.py --ranks 1).

A case whose estimate is above what the machine can give is refused before the run
(CaseError, exit code 2) with the estimate and the settings that size it; the size limits
of a case are this check, not fixed numbers. What the machine can give is the memory the
kernel reports available (MemAvailable, and the cgroup's limit when the run is in a
container or a batch job) plus what the process already holds, or MPMFLOW_MEMORY_LIMIT when
set (bytes, or with a unit: 512M, 8G, 1.5GB).
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .errors import CaseError
from .geometry import bodies
from .geometry.lattice import lattice_axes, lattice_count
from .grid import Grid
from .materials import is_solid

if TYPE_CHECKING:
    from .case import Case

MB = 2**20
# measured (benchmarks/investigations/memory.py): see the module docstring
PROGRAM = 70 * MB  # Python, NumPy, SciPy and the compiled core
PER_PARTICLE = 84  # B: x, v (2 each), pressure, mass, volume, the cell index and order
AFFINE = 8  # B per entry of a particle's D x D affine matrix (solver.transfer = "apic")
# a solid's history (material.model = "elastic", ...): its D x D deviatoric stress, its
# plastic strain and yielding flag, 8 B each per particle; the step's D force values a node
# and its pressure's per node and per cell (counted, not measured: arrays of that size)
HISTORY = 8
PER_NODE = 195  # B: nodal arrays of the scheme, the free surface, quadrature, corrections
PER_UNKNOWN = 590  # B: matrix (9 entries), multigrid levels, CG vectors (2D)
# 3D: rows of 27 entries, and multigrid's Galerkin levels as wide; measured on the 3D dam
# break at 130k, 312k and 1.04M particles (benchmarks/investigations/mpi/memory_ranks.py
# --ranks 1), where 590 B left the estimate 17-23% under the peak
PER_UNKNOWN_3D = 1840
SPREAD = 1.25  # unknowns over the run / unknowns at the start (the material spreads)
PER_ROW = 8  # B per value of a row kept in memory (time series and probes)
SNAPSHOT = 185  # B per particle while a snapshot is written (meshio's copies)
MEASURE = (56, 16)  # B per particle and per node while an output row is measured


@dataclass
class Estimate:
    """The parts of the estimated peak (bytes) and the counts they come from."""

    # counts: exact ints while they fit, floats (inf included) beyond
    particles: float
    nodes: float
    unknowns: float
    rows: float
    program: float
    particle_bytes: float
    grid_bytes: float
    solver_bytes: float
    rows_bytes: float
    passing_bytes: float  # the largest passing need: a snapshot or a row's measures
    passing_what: str
    disk_bytes: float  # the outputs on disk at the end (timeseries, snapshots, checkpoints)
    # a run over MPI ranks: each rank's estimate (parallel.memory.RanksEstimate), else None
    per_rank: Any = None

    @property
    def total(self) -> float:
        return (
            self.program
            + self.particle_bytes
            + self.grid_bytes
            + self.solver_bytes
            + self.rows_bytes
            + self.passing_bytes
        )

    def text(self) -> str:
        """One line: the total and its parts."""
        return (
            f"about {size(self.total)} (particles {size(self.particle_bytes)}, grid "
            f"{size(self.grid_bytes)}, pressure solver {size(self.solver_bytes)}, "
            f"{self.passing_what} {size(self.passing_bytes)}, time series "
            f"{size(self.rows_bytes)}, program {size(self.program)})"
        )

    def as_dict(self) -> dict[str, object]:
        return {
            "total": self.total,
            "program": self.program,
            "particles": self.particle_bytes,
            "grid": self.grid_bytes,
            "pressure_solver": self.solver_bytes,
            "time_series": self.rows_bytes,
            "passing": self.passing_bytes,
            "passing_what": self.passing_what,
            "counts": {
                "particles": self.particles,
                "nodes": self.nodes,
                "unknowns": self.unknowns,
                "rows": self.rows,
            },
            "disk": self.disk_bytes,
            **({"per_rank": self.per_rank.as_dict()} if self.per_rank is not None else {}),
        }


def size(nbytes: float) -> str:
    """Bytes for people: 512 MB, 3.4 GB, 2.1e+05 TB."""
    if not math.isfinite(nbytes):
        return "more than can be counted"
    for unit, scale in (("TB", 2**40), ("GB", 2**30), ("MB", MB)):
        if nbytes >= scale:
            value = nbytes / scale
            return f"{value:.3g} {unit}" if value < 1e4 else f"{value:.2g} {unit}"
    return f"{nbytes / 2**10:.0f} kB"


def _as_float(n: float) -> float:
    try:
        return float(n)
    except OverflowError:
        return math.inf


def inflow_count(case: Case) -> int:
    """The particles the case's inlets bring over the whole run (whole layers, one more
    each): an upper bound on what the run gains, since outlets may let water leave."""
    total = 0
    size = case.domain.size
    D = len(size)
    for inlet in case.inlets:
        s = inlet.spacing(case.grid.spacing)
        across = 1  # the lattice's rows across the side's horizontal axes
        for k in range(D - 1):
            if k != inlet.axis:
                across *= lattice_count([0.0], [size[k]], s)
        heights = lattice_axes([0.0], [inlet.top(case.grid.spacing)], s)[0]
        per_row = np.floor(inlet.speed_at(heights) * case.time.end / s) + 1
        total += across * int(per_row.sum())
    return total


def estimate(case: Case) -> Estimate:
    """The Estimate of a validated case (no allocation: counts from the geometry)."""
    grid = Grid.covering(case.domain.size, case.grid.spacing)
    h = case.grid.spacing
    count = sum(case.particle_counts()) + inflow_count(case)  # exact (obstacles left out), or inf
    particles = _as_float(count)  # a count of 1e400 (grid.spacing = 1e-300) is inf here
    nodes = math.prod(float(n) for n in grid.nodes)
    # pressure unknowns: the nodes of the cells the material covers, with room to spread
    unknowns = 0.0
    for k, body in enumerate(case.bodies):
        lo, hi = bodies.seed_region(body, case.body_shape(k), h)  # a cosine top included
        unknowns += math.prod((float(b) - float(a)) / h + 1 for a, b in zip(lo, hi))
    unknowns = min(nodes, SPREAD * unknowns)
    rows = case.time.end / case.output.interval + 2
    values = len(case.probes) + 1 + 14  # probes.csv and timeseries.csv
    if case.output.snapshots:
        passing, what = SNAPSHOT * particles, "writing a snapshot"
    else:
        passing, what = MEASURE[0] * particles + MEASURE[1] * nodes, "measuring a row"
    program = PROGRAM
    snaps = (
        case.time.end / (case.output.snapshot_interval or case.output.interval) + 2
        if case.output.snapshots
        else 0
    )
    # APIC's affine matrices, a solid's history: in memory and in each checkpoint; a
    # solid's force, D values a node
    D = len(case.domain.size)
    solid = is_solid(case.material)
    carried = (AFFINE * D**2 if case.solver.transfer == "apic" else 0) + (
        HISTORY * (D * D + 2) if solid else 0
    )
    force = HISTORY * D if solid else 0
    # a solid's pressure per cell (src/core/cell_pressure.hpp, counted, not measured): a
    # node's held projector (D x D), volume and mean; a cell's corner gradients (2^D x D),
    # centroid and gradient (D each), value, and its row's two indices
    if solid:
        force += 8 * (D * D + 2)
    per_cell = 8 * (2**D * D + 2 * D + 1) + 16 if solid else 0
    disk = (
        rows * (170 + 12 * len(case.probes))
        + snaps * (120 * particles + 200)
        + 2 * ((56 + carried) * particles + 16 * nodes)
    )
    return Estimate(
        particles=count if count < 10**15 else particles,
        nodes=int(nodes) if math.isfinite(nodes) else nodes,
        unknowns=unknowns,
        rows=rows,
        program=program,
        particle_bytes=(PER_PARTICLE + carried) * particles,
        grid_bytes=(PER_NODE + force) * nodes,
        solver_bytes=((PER_UNKNOWN_3D if D == 3 else PER_UNKNOWN) + per_cell) * unknowns,
        rows_bytes=PER_ROW * values * rows,
        passing_bytes=passing,
        passing_what=what,
        disk_bytes=disk,
    )


_UNITS = {
    "": 1,
    "B": 1,
    "K": 2**10,
    "KB": 2**10,
    "KIB": 2**10,
    "M": MB,
    "MB": MB,
    "MIB": MB,
    "G": 2**30,
    "GB": 2**30,
    "GIB": 2**30,
    "T": 2**40,
    "TB": 2**40,
    "TIB": 2**40,
}


def parse_size(text: str, name: str) -> float:
    m = re.fullmatch(r"\s*([0-9.eE+]+)\s*([A-Za-z]*)\s*", text)
    unit = m.group(2).upper() if m else None
    try:
        value = float(m.group(1)) * _UNITS[unit] if m and unit in _UNITS else None
    except ValueError:
        value = None
    if value is None or not value > 0 or not math.isfinite(value):
        raise CaseError(
            f"{name} = {text!r} is not a memory size; give bytes or a number with "
            "a unit, e.g. 8G or 512M, or unset it to use the memory available."
        )
    return value


def _read_int(path: str | Path) -> int | None:
    try:
        text = Path(path).read_text().strip()
    except OSError:
        return None
    return int(text) if text.isdigit() else None


def resident_bytes() -> int:
    """This process's resident memory now (bytes; 0 where it cannot be read)."""
    try:
        pages = int(Path("/proc/self/statm").read_text().split()[1])
        return pages * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        return 0


def available() -> tuple[float, str]:
    """(bytes this run may use at its peak, where that number comes from)."""
    limit = os.environ.get("MPMFLOW_MEMORY_LIMIT")
    if limit:
        return parse_size(limit, "MPMFLOW_MEMORY_LIMIT"), "MPMFLOW_MEMORY_LIMIT"
    free, source = None, ""
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                free, source = int(line.split()[1]) * 1024, "MemAvailable"
    except (OSError, ValueError):
        pass
    # a container's or batch job's limit (cgroup v2, then v1)
    for limit_path, usage_path in (
        ("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current"),
        (
            "/sys/fs/cgroup/memory/memory.limit_in_bytes",
            "/sys/fs/cgroup/memory/memory.usage_in_bytes",
        ),
    ):
        cap, used = _read_int(limit_path), _read_int(usage_path)
        if cap is not None and used is not None and cap < 2**60:
            left = max(cap - used, 0)
            if free is None or left < free:
                free, source = left, "left under the cgroup's memory limit"
            break
    if free is None:
        try:
            free = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_AVPHYS_PAGES")
            source = "free physical memory"
        except (ValueError, OSError, AttributeError):
            return math.inf, "unknown on this system (no check)"
    return free + resident_bytes(), source


def check(case: Case, est: Estimate | None = None) -> Estimate:
    """CaseError when the case's estimated peak is above what the machine can give."""
    est = est or estimate(case)
    budget, source = available()
    if est.total <= budget:
        return est
    # the particles and the nodes go as (1 / grid.spacing)^D: the square in 2D, the cube in 3D
    power = {2: "square", 3: "cube"}[len(case.domain.size)]
    settings = f"grid.spacing (memory grows as its inverse {power}), bodies.N.particles_per_cell"
    if case.output.snapshots and math.isfinite(est.passing_bytes):
        settings += (
            ", output.snapshots = false (a snapshot needs "
            f"{size(est.passing_bytes)} while it is written)"
        )
    count = f"{est.particles:.3g}" if isinstance(est.particles, float) else f"{est.particles:,}"
    raise CaseError(
        (
            f"This case needs {est.text()} of memory: {count} particles, {est.nodes:.3g} grid "
            "nodes."
            if math.isfinite(est.total)
            else "This case needs more memory than any machine has: its particles and grid nodes "
            "are too many to count."
        )
        + f" This machine can give the run {size(budget)} ({source}), so it would be "
        f"killed by the system when it runs out. Make the case smaller: {settings}; or run "
        "it on a machine with more memory. (MPMFLOW_MEMORY_LIMIT sets the memory a run may "
        "use, if the available memory is measured wrong here.)"
    )
