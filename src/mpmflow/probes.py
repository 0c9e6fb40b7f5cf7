"""Probes: pressure sensors and water-level gauges sampled at every output time (probes.csv).

The case's ``[[probes]]`` (``case.Probe``) say what each measures; the definitions are in
the schema's descriptions (docs/reference.md):

- ``pressure``: the mean particle pressure (Pa) in a square window one cell wide centred on
  the probe, moved inside the domain where it would cross a wall; 0 when it holds no
  particle.
- ``level``: the height (m) where the cell volume fraction, interpolated in x between the
  cell columns around the gauge's line, first drops below 1/2 going up from the gauge's
  foot; the foot's height when the foot is dry, the grid's top when it never drops.
"""

import numpy as np

from .diagnostics import volume_fraction_field

UNITS = {"pressure": "Pa", "level": "m"}


def columns(case):
    """The columns of probes.csv: time, then one per probe."""
    return ["time"] + [p.name for p in case.probes]


def pressure_at(grid, particles, point):
    """Mean particle pressure (Pa) in the one-cell window around ``point`` (0 if dry)."""
    h = grid.spacing
    sel = np.ones(particles.count, dtype=bool)
    for axis, (c, length) in enumerate(zip(point, grid.size)):
        lo = min(max(c - 0.5 * h, 0.0), length - h)
        x = particles.x[:, axis]
        sel &= (x >= lo) & (x <= lo + h)
    return float(particles.pressure[sel].mean()) if sel.any() else 0.0


def level_at(grid, theta, foot):
    """Water level (m) on the line x = foot[0] above foot[1] (see the module docstring)."""
    f = volume_fraction_field(grid, theta)
    s = foot[0] / grid.spacing - 0.5
    i0 = int(np.clip(np.floor(s), 0, grid.cells[0] - 2))
    w = float(np.clip(s - i0, 0.0, 1.0))
    col = (1 - w) * f[i0] + w * f[i0 + 1]
    yc = grid.cell_centres(1)
    k0 = int(np.clip(np.floor(foot[1] / grid.spacing), 0, grid.cells[1] - 1))
    below = np.flatnonzero(col[k0:] < 0.5)
    if below.size == 0:
        return float(grid.size[1])
    k = k0 + below[0]
    if k == k0:
        return float(foot[1])
    y = yc[k - 1] + (yc[k] - yc[k - 1]) * (col[k - 1] - 0.5) / (col[k - 1] - col[k])
    return float(max(y, foot[1]))


def measure(case, grid, particles, theta, time):
    """One row of probes.csv: {"time": t, name: value, ...}."""
    row = {"time": time}
    for probe in case.probes:
        if probe.quantity == "pressure":
            row[probe.name] = pressure_at(grid, particles, probe.position)
        else:
            row[probe.name] = level_at(grid, theta, probe.position)
    return row
