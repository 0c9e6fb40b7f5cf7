"""Probes: pressure sensors and water-level gauges sampled at every output time (probes.csv).

The case's ``[[probes]]`` (``case.sections.Probe``) say what each measures; the definitions are in
the schema's descriptions (docs/reference.md). In 2D and 3D alike (the vertical is the last
axis):

- ``pressure`` (Pa): the water's pressure at the probe's point, from the particles in a
  window (a square, in 3D a cube, of side ``probes.N.window``; by default the fewest whole
  grid cells that hold 2 (D + 1) particles at the bodies' seeding density: one cell at
  ``particles_per_cell`` >= 3 in 2D and >= 2 in 3D, two at the default 2 in 2D) around it. The window is centred on the point, except that along an axis where the point
  lies on a wall it lies on the water's side of the wall (from the wall one window inward),
  and it is cut at any other wall it would cross. ``estimate = "fit"`` (the default) fits
  p = a + b.(x - point) to the window's particles by least squares and reads a, the
  pressure AT the point; ``"mean"`` is the window's mean particle pressure, the pressure
  near the window's centre of particles (half a cell from a wall sensor's point: on the
  hydrostatic column that reads rho g h/2 low). A window without particles reads 0 (a dry
  sensor reads the atmosphere's gauge pressure). A fit needs 2 (D + 1) particles spread
  over the window: with fewer, or particles in one layer (a wave front's first particles
  against a face), the probe reads their mean; a fit below 0 in a window of pressures
  that are not negative reads 0 (the point lies above the water). Each such mean and 0 is
  counted in the run's summary (``mpmflow.fallbacks``). The window is not widened
  instead: a wider window reads particles farther from the point (on SPHERIC Test 2 it
  moved the first impact at P1 by 0.025 s at 0.05 m).
- ``level`` (m): the water level above the gauge's foot on the vertical line through
  ``position`` (x in 2D; x and y in 3D). The cell volume fraction f is interpolated
  linearly in x (bilinearly in x and y in 3D) between the cell columns around the line.
  ``probes.N.gauge = "integral"`` (the default) reads the integral of f along the line from
  the foot up, f constant in each cell: the water's depth if it were gathered into one
  layer, as a resistance or capacitance wave probe reads its wetted wire and CFD codes
  compare (OpenFOAM's interfaceHeight); a splash above the layer and the spray in it
  count by their volume, an air pocket under the surface counts out by its volume, a
  single aerated cell at the foot lowers the reading by its air only. f is the particles'
  volume in the cell over the cell's, not clipped at 1: it steps by a row of particles, so
  a strained lattice puts 0.75 and 1.25 in neighbouring cells, and a clip at 1 dropped the
  excess (on SPHERIC Test 2 at 0.04 m the gauges read 7-17% low over 1-2 s; in a steady
  channel 0.115 m where the particles held 0.13 m).
  ``"first_drop"`` reads where the profile first drops below 1/2 going up from the foot
  (linear between cell centres), minus the foot's height: the top of the first layer above
  the foot, 0 when the foot's cell is less than half full (so one aerated cell under a
  deep bore reads a dry gauge), the grid's top minus the foot when it never drops (counted
  in the summary: the water may reach higher); splashes above the layer are not counted.

Cost: the particles are binned by cell once per output anyway (``cells.bin_particles``);
a pressure probe reads only the particles of the cells its window overlaps, so the probes
cost no pass over all particles (``tests/diagnostics/test_probes.py`` measures 20 probes on 0.7 million
particles in 3D).

Obstacles (the hook): ``measure(..., solid_distance=f)`` takes the signed distance to the
solid obstacles, ``f(points) -> distances`` for an (n, D) array of points (m; negative
inside a solid, as ``shapes.Shape.signed_distance``). A pressure probe closer to a solid than
half its window, e.g. a sensor on an obstacle's face, has its window's centre moved along
the solid's outward normal (the gradient of f, by central differences) until the window no
longer reaches into it, as a wall moves it; the fit still reads the pressure at the point.
Without it (the default, and all cases so far) only the domain's walls move windows.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ..arrays import Floats, Ints
from ..cells import CellBins
from ..fallbacks import Fallbacks
from ..grid import Grid
from ..particles import Particles
from .measures import volume_fraction_field

if TYPE_CHECKING:
    from ..case import Case
    from ..case.sections import Probe

# the obstacles' signed distance f(points) -> distances for an (n, D) array of points
Distance = Callable[[Floats], ArrayLike]
# told of each fallback that acted (a key of fallbacks.WHAT)
Note = Callable[[str], None]
# the window's positions and pressures joined over the parts of particles held in parts
Join = Callable[[Floats, Floats], tuple[Floats, Floats]]

UNITS = {"pressure": "Pa", "level": "m"}
ON_WALL = 1e-6  # a point within this share of the window from a wall lies on the wall
FLAT = 0.05  # a fit needs the particles spread over at least this share of the window


def columns(case: Case) -> list[str]:
    """The keys of a probes.csv row: time, then one per probe (the probes' names)."""
    return ["time"] + [p.name for p in case.probes]


def header(case: Case) -> list[str]:
    """The header of probes.csv: each column's name with its unit, ``time [s]``,
    ``wall_p [Pa]``, ``gauge_1 [m]`` (``output.timeseries.read_table`` strips the units)."""
    return ["time [s]"] + [f"{p.name} [{UNITS[p.quantity]}]" for p in case.probes]


def window(probe: Probe, grid: Grid, case: Case) -> float:
    """The side (m) of a pressure probe's window: probes.N.window, else the fewest whole
    grid cells that hold the 2 (D + 1) particles of a fit at the sparsest body's seeding
    density (particles_per_cell along each axis)."""
    if probe.window is not None:
        return float(probe.window)
    per_axis = min((b.particles_per_cell for b in case.bodies), default=1)
    need = fit_minimum(grid.dim) ** (1.0 / grid.dim) / per_axis
    return grid.spacing * max(1, int(np.ceil(need - 1e-9)))


def fit_minimum(dim: int) -> int:
    """The particles a fit of p = a + b.(x - point) needs in its window: 2 (D + 1)."""
    return 2 * (dim + 1)


def window_box(
    point: ArrayLike,
    side: float,
    size: ArrayLike,
    solid_distance: Distance | None = None,
    periodic: Sequence[bool] = (),
) -> tuple[Floats, Floats]:
    """The (lo, hi) corners (m) of the window of side ``side`` around ``point`` in the
    domain [0, size] (see the module docstring: on a wall the window lies on the water's
    side; elsewhere it is centred and cut at the walls; ``solid_distance`` moves it off a
    solid obstacle). Along a periodic axis (``periodic[k]``) there is no wall: the window
    stays centred and may reach beyond the ends (``window_particles`` wraps it round)."""
    point = np.asarray(point, dtype=float)
    size = np.asarray(size, dtype=float)
    centre: Floats = point.copy()
    if solid_distance is not None:
        centre = _off_solid(centre, side, solid_distance)
    lo, hi = centre - 0.5 * side, centre + 0.5 * side
    tol = ON_WALL * side
    wraps = np.zeros(point.size, dtype=bool)
    wraps[: len(periodic)] = periodic
    for k in range(point.size):
        if wraps[k]:
            continue
        if point[k] <= tol:
            lo[k], hi[k] = 0.0, side
        elif point[k] >= size[k] - tol:
            lo[k], hi[k] = size[k] - side, size[k]
    return np.where(wraps, lo, np.maximum(lo, 0.0)), np.where(wraps, hi, np.minimum(hi, size))


def _off_solid(centre: Floats, side: float, solid_distance: Distance) -> Floats:
    """The window's centre moved along the solid's outward normal until a window of side
    ``side`` no longer reaches into it (unchanged when it does not)."""
    d = float(np.asarray(solid_distance(centre[None, :])).ravel()[0])
    if d >= 0.5 * side:
        return centre
    eps = 1e-3 * side
    steps = np.eye(centre.size) * eps
    grad = (
        np.asarray(solid_distance(centre + steps)).ravel()
        - np.asarray(solid_distance(centre - steps)).ravel()
    ) / (2 * eps)
    norm = float(np.linalg.norm(grad))
    if norm == 0.0:
        return centre
    moved: Floats = centre + grad / norm * (0.5 * side - d)
    return moved


def window_particles(
    grid: Grid, particles: Particles, bins: CellBins, lo: Floats, hi: Floats
) -> tuple[Ints, Floats]:
    """Indices of the particles in the box [lo, hi] (both ends included), read from the
    cells the box overlaps (``bins``: ``cells.bin_particles``), not from all particles,
    and their positions seen from the box: along a periodic axis a box reaching beyond an
    end takes the particles of the other end too, moved by one period."""
    size = grid.size
    shifts = [np.zeros(grid.dim)]
    for k, flag in enumerate(grid.periodic):
        if flag and (lo[k] < 0.0 or hi[k] > size[k]):
            step = np.zeros(grid.dim)
            step[k] = -size[k] if lo[k] < 0.0 else size[k]
            shifts += [s + step for s in shifts]
    found, where = [], []
    for shift in shifts:  # particles at x lie in the box moved by -shift at x + shift
        a, b = np.maximum(lo - shift, 0.0), np.minimum(hi - shift, size)
        if np.any(a > b):
            continue
        idx = _box_particles(grid, particles, bins, a, b)
        found.append(idx)
        where.append(particles.x[idx] + shift)
    if len(found) == 1:
        return found[0], where[0]
    return np.concatenate(found), np.concatenate(where)


def _box_particles(
    grid: Grid, particles: Particles, bins: CellBins, lo: Floats, hi: Floats
) -> Ints:
    """Indices of the particles in the box [lo, hi] inside the domain."""
    h, cells = grid.spacing, grid.cells
    first = [int(np.clip(np.floor(a / h), 0, n - 1)) for a, n in zip(lo, cells)]
    last = [int(np.clip(np.floor(b / h), 0, n - 1)) for b, n in zip(hi, cells)]
    strides = np.cumprod((1,) + tuple(cells[:-1]))
    runs = []
    # along x (stride 1) the cells of the box are consecutive in the flat cell order
    for rest in itertools.product(*[range(a, b + 1) for a, b in zip(first[1:], last[1:])]):
        base = int(np.dot(rest, strides[1:])) if rest else 0
        runs.append(bins.order[bins.start[base + first[0]] : bins.start[base + last[0] + 1]])
    idx = np.concatenate(runs) if runs else np.empty(0, dtype=np.int64)
    x = particles.x[idx]
    inside = np.all((x >= lo) & (x <= hi), axis=1)
    return idx[inside]


def pressure_at(
    grid: Grid,
    particles: Particles,
    bins: CellBins,
    probe: Probe,
    case: Case,
    solid_distance: Distance | None = None,
    note: Note | None = None,
    boxes: dict[str, tuple[Floats, Floats]] | None = None,
    join: Join | None = None,
) -> float:
    """The pressure (Pa) a pressure probe reads (see the module docstring). ``note(what)``
    is told of each fallback that acted (a key of ``fallbacks.WHAT``). ``boxes``: the
    windows found so far, by probe name, kept by the caller for a run whose probes,
    grid and obstacles stand still (the window's move off a solid evaluates the obstacles'
    distance: a fifth of the probes' time on SPHERIC Test 2). ``join``: for particles held
    in parts (one per MPI rank), the window's positions and pressures joined over the parts
    (``diagnostics.parts.joined``)."""
    note = note or (lambda what: None)
    side = window(probe, grid, case)
    if boxes is not None and probe.name in boxes:
        lo, hi = boxes[probe.name]
    else:
        lo, hi = window_box(probe.position, side, grid.size, solid_distance, grid.periodic)
        if boxes is not None:
            boxes[probe.name] = (lo, hi)
    idx, x = window_particles(grid, particles, bins, lo, hi)
    p = particles.pressure[idx]
    if join is not None:  # particles in parts: the window's from every part
        x, p = join(x, p)
    if p.size == 0:
        return 0.0  # a dry sensor
    if probe.estimate == "mean":
        return float(p.mean())
    value = _fit(x, p, probe.position, side, grid.dim)
    if value is None:
        note("probe fit fell back to the window mean")
        return float(p.mean())
    if value < 0.0 <= float(p.min()):
        note("probe fit below 0 read as 0")
        return 0.0
    return value


def _fit(x: Floats, p: Floats, point: ArrayLike, side: float, dim: int) -> float | None:
    """a of the plane p = a + b.(x - point) fitted to the particles (x, p) by least squares;
    None when they are too few or lie in one layer (the gradient along its normal is then
    undetermined)."""
    if p.size < fit_minimum(dim):
        return None
    X = np.empty((p.size, dim + 1))
    X[:, 0] = 1.0
    X[:, 1:] = (x - np.asarray(point)) / side
    centred = X[:, 1:] - X[:, 1:].mean(axis=0)
    spread = np.linalg.svd(centred, compute_uv=False)
    if spread[-1] < FLAT * np.sqrt(p.size):
        return None
    return float(np.linalg.lstsq(X, p, rcond=None)[0][0])


def level_at(
    grid: Grid, f: Floats, foot: Sequence[float], note: Note | None = None, gauge: str = "integral"
) -> float:
    """Water level (m) above ``foot`` on the vertical line through it, as ``gauge`` reads it
    (see the module docstring); ``f``: the cell volume fractions
    (``diagnostics.volume_fraction_field``); ``note(what)`` is told when a "first_drop"
    level is cut at the grid's top."""
    col = _column(grid, f, foot)
    if gauge == "integral":
        return _integral(grid, col, float(foot[-1]))
    return _first_drop(grid, col, float(foot[-1]), note)


def _integral(grid: Grid, col: Floats, z0: float) -> float:
    """The integral (m) of the column's fractions ``col`` (constant in each cell) from
    height z0 (m) to the grid's top."""
    h = grid.spacing
    k0 = int(np.clip(np.floor(z0 / h), 0, grid.cells[-1] - 1))
    part = (k0 + 1) * h - z0  # the foot's cell above the foot
    return float(max(col[k0] * part + h * np.sum(col[k0 + 1 :]), 0.0))


def _column(grid: Grid, f: Floats, foot: Sequence[float]) -> Floats:
    """The column of f on the vertical line through ``foot`` (one value per cell along the
    last axis)."""
    h, dim = grid.spacing, grid.dim
    col = 0.0
    # the column of f on the line: linear in each horizontal axis between the two cell
    # columns around it (bilinear in 3D)
    lows, weights = [], []
    for axis in range(dim - 1):
        s = foot[axis] / h - 0.5
        i0 = int(np.clip(np.floor(s), 0, grid.cells[axis] - 2))
        lows.append(i0)
        weights.append(float(np.clip(s - i0, 0.0, 1.0)))
    for corner in itertools.product((0, 1), repeat=dim - 1):
        w = 1.0
        for c, wk in zip(corner, weights):
            w *= wk if c else 1.0 - wk
        if w:
            col = col + w * f[tuple(i + c for i, c in zip(lows, corner))]
    return np.broadcast_to(col, (grid.cells[-1],))


def _first_drop(grid: Grid, col: Floats, z0: float, note: Note | None) -> float:
    """Where the column ``col`` first drops below 1/2 above z0, minus z0 (m)."""
    h = grid.spacing
    zc = grid.cell_centres(grid.dim - 1)
    k0 = int(np.clip(np.floor(z0 / h), 0, grid.cells[-1] - 1))
    below = np.flatnonzero(col[k0:] < 0.5)
    if below.size == 0:
        if note is not None:
            note("level gauge reached the grid's top")
        return float(grid.size[-1]) - z0
    k = k0 + below[0]
    if k == k0:
        return 0.0
    z = zc[k - 1] + (zc[k] - zc[k - 1]) * (col[k - 1] - 0.5) / (col[k - 1] - col[k])
    return float(max(z - z0, 0.0))


def measure(
    case: Case,
    grid: Grid,
    particles: Particles,
    bins: CellBins,
    time: float,
    solid_distance: Distance | None = None,
    fallbacks: Fallbacks | None = None,
    boxes: dict[str, tuple[Floats, Floats]] | None = None,
    join: Join | None = None,
) -> dict[str, float]:
    """One row of probes.csv: {"time": t, name: value, ...}. ``bins``: the particles binned
    by cell (``cells.bin_particles``) at this state; ``solid_distance``: the obstacles' hook
    (module docstring); ``fallbacks``: a ``fallbacks.Fallbacks`` that counts the fallbacks
    that acted; ``boxes``: the pressure probes' windows kept between calls (``pressure_at``);
    ``join``: as ``pressure_at`` takes it, for particles in parts (``bins`` then holds theta
    summed over the parts)."""
    row = {"time": time}
    fields: dict[bool, Floats] = {}  # the volume fraction, clipped at 1 (first_drop) or not
    for probe in case.probes:

        def note(what: str, name: str = probe.name) -> None:
            if fallbacks is not None:
                fallbacks.count(what, f"probe {name}", time=time)

        if probe.quantity == "pressure":
            row[probe.name] = pressure_at(
                grid, particles, bins, probe, case, solid_distance, note, boxes, join
            )
        else:
            clip = probe.gauge == "first_drop"
            if clip not in fields:
                fields[clip] = volume_fraction_field(grid, bins.theta, clip=clip)
            row[probe.name] = level_at(grid, fields[clip], probe.position, note, probe.gauge)
    return row
