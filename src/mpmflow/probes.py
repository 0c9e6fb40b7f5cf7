"""Probes: pressure sensors and water-level gauges sampled at every output time (probes.csv).

The case's ``[[probes]]`` (``case.Probe``) say what each measures; the definitions are in
the schema's descriptions (docs/reference.md). In 2D and 3D alike (the vertical is the last
axis):

- ``pressure`` (Pa): the water's pressure at the probe's point, from the particles in a
  window (a square, in 3D a cube, of side ``probes.N.window``, one grid cell by default)
  around it. The window is centred on the point, except that along an axis where the point
  lies on a wall it lies on the water's side of the wall (from the wall one window inward),
  and it is cut at any other wall it would cross. ``estimate = "fit"`` (the default) fits
  p = a + b.(x - point) to the window's particles by least squares and reads a, the
  pressure AT the point; ``"mean"`` is the window's mean particle pressure, the pressure
  near the window's centre of particles (half a cell from a wall sensor's point: on the
  hydrostatic column that reads rho g h/2 low). A window without particles reads 0 (a dry
  sensor reads the atmosphere's gauge pressure); a fit with too few particles, or particles
  in one layer, falls back to the mean; a fit below 0 in a window of pressures that are
  not negative reads 0 (the point lies above the water).
- ``level`` (m): the water level above the gauge's foot on the vertical line through
  ``position`` (x in 2D; x and y in 3D). The cell volume fraction f is interpolated
  linearly in x (bilinearly in x and y in 3D) between the cell columns around the line; the
  level is where that profile first drops below 1/2 going up from the foot (linear between
  cell centres), minus the foot's height: the top of the water layer above the foot, 0 when
  the foot is dry, the grid's top minus the foot when it never drops. Splashes above the
  layer are not counted.

Cost: the particles are binned by cell once per output anyway (``cells.bin_particles``);
a pressure probe reads only the particles of the cells its window overlaps, so the probes
cost no pass over all particles (``tests/test_probes.py`` measures 20 probes on 0.7 million
particles in 3D).

Obstacles (the hook): ``measure(..., solid_distance=f)`` takes the signed distance to the
solid obstacles, ``f(points) -> distances`` for an (n, D) array of points (m; negative
inside a solid, as ``shapes.Shape.signed_distance``). A pressure probe closer to a solid than
half its window, e.g. a sensor on an obstacle's face, has its window's centre moved along
the solid's outward normal (the gradient of f, by central differences) until the window no
longer reaches into it, as a wall moves it; the fit still reads the pressure at the point.
Without it (the default, and all cases so far) only the domain's walls move windows.
"""

import itertools

import numpy as np

from .diagnostics import volume_fraction_field

UNITS = {"pressure": "Pa", "level": "m"}
ON_WALL = 1e-6  # a point within this share of the window from a wall lies on the wall
FLAT = 0.05     # a fit needs the particles spread over at least this share of the window


def columns(case):
    """The keys of a probes.csv row: time, then one per probe (the probes' names)."""
    return ["time"] + [p.name for p in case.probes]


def header(case):
    """The header of probes.csv: each column's name with its unit, ``time [s]``,
    ``wall_p [Pa]``, ``gauge_1 [m]`` (``output.timeseries.read_table`` strips the units)."""
    return ["time [s]"] + [f"{p.name} [{UNITS[p.quantity]}]" for p in case.probes]


def window(probe, grid):
    """The side (m) of a pressure probe's window: probes.N.window, else one grid cell."""
    return float(probe.window) if probe.window is not None else grid.spacing


def window_box(point, side, size, solid_distance=None):
    """The (lo, hi) corners (m) of the window of side ``side`` around ``point`` in the
    domain [0, size] (see the module docstring: on a wall the window lies on the water's
    side; elsewhere it is centred and cut at the walls; ``solid_distance`` moves it off a
    solid obstacle)."""
    point = np.asarray(point, dtype=float)
    size = np.asarray(size, dtype=float)
    centre = point.copy()
    if solid_distance is not None:
        centre = _off_solid(centre, side, solid_distance)
    lo, hi = centre - 0.5 * side, centre + 0.5 * side
    tol = ON_WALL * side
    for k in range(point.size):
        if point[k] <= tol:
            lo[k], hi[k] = 0.0, side
        elif point[k] >= size[k] - tol:
            lo[k], hi[k] = size[k] - side, size[k]
    return np.maximum(lo, 0.0), np.minimum(hi, size)


def _off_solid(centre, side, solid_distance):
    """The window's centre moved along the solid's outward normal until a window of side
    ``side`` no longer reaches into it (unchanged when it does not)."""
    d = float(np.asarray(solid_distance(centre[None, :])).ravel()[0])
    if d >= 0.5 * side:
        return centre
    eps = 1e-3 * side
    steps = np.eye(centre.size) * eps
    grad = (np.asarray(solid_distance(centre + steps)).ravel()
            - np.asarray(solid_distance(centre - steps)).ravel()) / (2 * eps)
    norm = float(np.linalg.norm(grad))
    if norm == 0.0:
        return centre
    return centre + grad / norm * (0.5 * side - d)


def window_particles(grid, particles, bins, lo, hi):
    """Indices of the particles in the box [lo, hi] (both ends included), read from the
    cells the box overlaps (``bins``: ``cells.bin_particles``), not from all particles."""
    h, cells = grid.spacing, grid.cells
    first = [int(np.clip(np.floor(a / h), 0, n - 1)) for a, n in zip(lo, cells)]
    last = [int(np.clip(np.floor(b / h), 0, n - 1)) for b, n in zip(hi, cells)]
    strides = np.cumprod((1,) + tuple(cells[:-1]))
    runs = []
    # along x (stride 1) the cells of the box are consecutive in the flat cell order
    for rest in itertools.product(*[range(a, b + 1) for a, b in zip(first[1:], last[1:])]):
        base = int(np.dot(rest, strides[1:])) if rest else 0
        runs.append(bins.order[bins.start[base + first[0]]:bins.start[base + last[0] + 1]])
    idx = np.concatenate(runs) if runs else np.empty(0, dtype=np.int64)
    x = particles.x[idx]
    inside = np.all((x >= lo) & (x <= hi), axis=1)
    return idx[inside]


def pressure_at(grid, particles, bins, probe, solid_distance=None):
    """The pressure (Pa) a pressure probe reads (see the module docstring)."""
    side = window(probe, grid)
    lo, hi = window_box(probe.position, side, grid.size, solid_distance)
    idx = window_particles(grid, particles, bins, lo, hi)
    if idx.size == 0:
        return 0.0
    p = particles.pressure[idx]
    mean = float(p.mean())
    if probe.estimate == "mean":
        return mean
    dim = grid.dim
    if idx.size < 2 * (dim + 1):
        return mean
    X = np.empty((idx.size, dim + 1))
    X[:, 0] = 1.0
    X[:, 1:] = (particles.x[idx] - np.asarray(probe.position)) / side
    # particles in one layer (a thin wet film, a row at the surface) leave the gradient
    # along the layer's normal undetermined: then the mean
    centred = X[:, 1:] - X[:, 1:].mean(axis=0)
    spread = np.linalg.svd(centred, compute_uv=False)
    if spread[-1] < FLAT * np.sqrt(idx.size):
        return mean
    coef = np.linalg.lstsq(X, p, rcond=None)[0]
    value = float(coef[0])
    if value < 0.0 <= float(p.min()):
        return 0.0
    return value


def level_at(grid, f, foot):
    """Water level (m) above ``foot`` on the vertical line through it (see the module
    docstring); ``f``: the cell volume fractions (``diagnostics.volume_fraction_field``)."""
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
    col = np.broadcast_to(col, (grid.cells[-1],))
    z0 = float(foot[-1])
    zc = grid.cell_centres(dim - 1)
    k0 = int(np.clip(np.floor(z0 / h), 0, grid.cells[-1] - 1))
    below = np.flatnonzero(col[k0:] < 0.5)
    if below.size == 0:
        return float(grid.size[-1]) - z0
    k = k0 + below[0]
    if k == k0:
        return 0.0
    z = zc[k - 1] + (zc[k] - zc[k - 1]) * (col[k - 1] - 0.5) / (col[k - 1] - col[k])
    return float(max(z - z0, 0.0))


def measure(case, grid, particles, bins, time, solid_distance=None):
    """One row of probes.csv: {"time": t, name: value, ...}. ``bins``: the particles binned
    by cell (``cells.bin_particles``) at this state; ``solid_distance``: the obstacles' hook
    (module docstring)."""
    row = {"time": time}
    f = None
    for probe in case.probes:
        if probe.quantity == "pressure":
            row[probe.name] = pressure_at(grid, particles, bins, probe, solid_distance)
        else:
            if f is None:
                f = volume_fraction_field(grid, bins.theta)
            row[probe.name] = level_at(grid, f, probe.position)
    return row
