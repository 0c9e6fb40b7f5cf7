"""Obstacles that move along a prescribed path (``obstacles.N.motion``): what the compiled
step needs to move them (src/core/bodies.hpp), built once.

A moving obstacle is its shape, rigid, in a frame of its own whose origin is its pivot
(``motion.pivot``; by default the centre of its bounding box) and whose axes are the grid's at
t = 0, where the case file gives the shape. The core reads:

* the shape's signed distance on a lattice in that frame (``LATTICE_POINTS`` points per cell,
  reaching ``LATTICE_MARGIN`` cells beyond the shape, so that every cell the surface cuts and
  its neighbours read it), sampled once from the exact distance of ``geometry.shapes``;
* its path: the pivot's position and velocity and the angle and turning rate at increasing
  times, which the core interpolates by cubic Hermite segments. An analytic motion
  ("velocity", "oscillation") is sampled with its exact rates, finely enough (``SAMPLES``
  per period or ramp) that the interpolation's error is below 1e-6 of its amplitude; a
  table's rates are its second-order differences.

bodies.csv writes the core's own state (``State.body_state``); ``Trajectory.at`` evaluates
the core's interpolation here, for a reader of a path (the tests check it against the
motions).
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..arrays import Floats
from ..errors import CaseError
from ..geometry.rotation import quaternion_matrix
from ..geometry.shapes import Shape
from ..grid import Grid

if TYPE_CHECKING:
    from ..case import Case
    from ..case.motion import Motion

LATTICE_POINTS = 2  # lattice points per cell along each axis (spacing h / 2)
LATTICE_MARGIN = 4  # cells the lattice reaches beyond the shape
SAMPLES = 128  # path samples per period of an oscillation or per ramp


@dataclass
class Trajectory:
    """A body's path: the pivot's position (m) and velocity (m/s), (n, D); the angle (rad)
    and turning rate (rad/s) about the body's axis, (n,); at the times (s), (n,)."""

    time: Floats
    centre: Floats
    velocity: Floats
    angle: Floats
    rate: Floats

    def at(self, t: float) -> tuple[Floats, Floats, float, float]:
        """(centre, velocity, angle, rate) at time t: the core's interpolation
        (src/core/bodies.cpp, Body::pose), held at the table's ends beyond them."""
        T = self.time
        if t <= T[0] or T.size == 1:
            j = 0
            return self.centre[j], self.velocity[j], float(self.angle[j]), float(self.rate[j])
        if t >= T[-1]:
            return self.centre[-1], self.velocity[-1], float(self.angle[-1]), float(self.rate[-1])
        j = int(np.searchsorted(T, t, side="right")) - 1
        w = T[j + 1] - T[j]
        s = (t - T[j]) / w
        h = np.array(
            [2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2, s**3 - s**2]
        )
        d = np.array([6 * s**2 - 6 * s, 3 * s**2 - 4 * s + 1, -6 * s**2 + 6 * s, 3 * s**2 - 2 * s])

        def value(p: Any, m: Any) -> Any:
            return h[0] * p[j] + h[1] * w * m[j] + h[2] * p[j + 1] + h[3] * w * m[j + 1]

        def rate(p: Any, m: Any) -> Any:
            return (d[0] * p[j] + d[1] * w * m[j] + d[2] * p[j + 1] + d[3] * w * m[j + 1]) / w

        return (
            value(self.centre, self.velocity),
            rate(self.centre, self.velocity),
            float(value(self.angle, self.rate)),
            float(rate(self.angle, self.rate)),
        )


@dataclass
class Freedom:
    """A free body's mass (kg; 2D kg/m), inertia about its pivot (3 x 3, kg m^2; 2D the
    zz entry, kg m), held degrees of freedom (6 flags: translations, then rotations; 2D:
    x, y, rotation about z), starting velocity (m/s) and turning rate (rad/s), its
    centroid from its pivot (m; 0 but for a hinge) and its contacts' Coulomb friction
    coefficient."""

    mass: float
    inertia: Floats
    locked: list[bool]
    velocity: Floats
    rate: float
    offset: Floats
    friction: float = 0.0


@dataclass
class Mover:
    """One moving obstacle: obstacles.index of the case, its name, shape (at t = 0), pivot
    (m, at t = 0; a free body's centroid), rotation axis (unit, 3 entries), no-slip flag,
    path (a free body's: where it starts) and, for a free body, its mass properties."""

    index: int
    name: str
    shape: Shape
    pivot: Floats
    axis: Floats
    no_slip: bool
    path: Trajectory
    free: Freedom | None = None

    def reach(self) -> float:
        """The farthest point of the shape's bounding box from the pivot (m)."""
        lo, hi = self.shape.bounds()
        corners = np.array(np.meshgrid(*zip(lo, hi), indexing="ij")).reshape(len(lo), -1).T
        return float(np.max(np.linalg.norm(corners - self.pivot, axis=1)))

    def max_speed(self) -> float:
        """The largest speed of a point of the body along its path (m/s)."""
        v = np.linalg.norm(self.path.velocity, axis=1)
        return float(np.max(v + np.abs(self.path.rate) * self.reach()))

    def core(self, grid: Grid) -> dict[str, Any]:
        """The body as src/core/bodies.hpp reads it (``State.set_bodies``)."""
        D = grid.dim
        h = grid.spacing
        lo, hi = (np.asarray(b, dtype=float) for b in self.shape.bounds())
        spacing = h / LATTICE_POINTS
        margin = LATTICE_MARGIN * h
        start = lo - margin - self.pivot  # in the body's frame
        counts = np.ceil((hi - lo + 2 * margin) / spacing).astype(np.int64) + 1
        axes = [start[k] + spacing * np.arange(counts[k]) for k in range(D)]
        # (axis 0 fastest: Fortran order of the (counts) array)
        y = np.stack([g.ravel(order="F") for g in np.meshgrid(*axes, indexing="ij")], axis=1)
        phi = np.ascontiguousarray(self.shape.signed_distance(y + self.pivot), dtype=float)
        surface = _surface(phi, counts, spacing, y) if self.free is not None else None
        p = self.path
        return {
            "phi": phi,
            "counts": [int(c) for c in counts],
            "origin": [float(s) for s in start],
            "spacing": float(spacing),
            "lo": [float(v) for v in lo - self.pivot],
            "hi": [float(v) for v in hi - self.pivot],
            "axis": [float(a) for a in self.axis],
            "time": np.ascontiguousarray(p.time, dtype=float),
            "centre": np.ascontiguousarray(p.centre, dtype=float),
            "velocity": np.ascontiguousarray(p.velocity, dtype=float),
            "angle": np.ascontiguousarray(p.angle, dtype=float),
            "rate": np.ascontiguousarray(p.rate, dtype=float),
            "no_slip": bool(self.no_slip),
            **(self._freedom() if self.free is not None else {}),
            **({"surface": surface} if surface is not None else {}),
        }

    def _freedom(self) -> dict[str, Any]:
        f = self.free
        assert f is not None
        D = self.pivot.size
        velocity = [float(v) for v in f.velocity]
        return {
            "free": True,
            "mass": float(f.mass),
            "inertia": [[float(v) for v in row] for row in f.inertia],
            "locked": [bool(b) for b in f.locked],
            "centre_now": [float(c) for c in self.pivot],
            "velocity_now": velocity[:D],
            "omega_now": [0.0, 0.0, float(f.rate)] if D == 2 else [0.0, 0.0, 0.0],
            "quat": [1.0, 0.0, 0.0, 0.0],
            "offset": [float(o) for o in f.offset],
            "friction": float(f.friction),
        }


def _surface(phi: Floats, counts: Any, spacing: float, y: Floats) -> Floats:
    """Points on a body's surface in its frame (m x D): the lattice points within a
    spacing inside it, moved onto the surface along the distance's gradient (the contact of
    a free body checks them, src/core/bodies.hpp)."""
    D = y.shape[1]
    grid = phi.reshape(tuple(int(c) for c in counts[::-1]))  # axis 0 fastest: [.., i1, i0]
    grads = np.gradient(grid, spacing)  # along the reversed axes
    grad = np.stack([grads[D - 1 - k].ravel() for k in range(D)], axis=1)
    size = np.linalg.norm(grad, axis=1)
    band = (phi <= 0.0) & (phi > -spacing) & (size > 0.5)
    moved = y[band] - (phi[band] / size[band] ** 2)[:, None] * grad[band]
    return np.ascontiguousarray(moved, dtype=float)


def _ramp(t: Floats, width: float) -> tuple[Floats, Floats, Floats]:
    """The smooth ramp r(t) = 0.5 (1 - cos(pi t / width)) for 0 <= t <= width (0 before, 1
    after), its rate and its integral from 0 (width 0: a step)."""
    if width <= 0.0:
        on = (t >= 0.0).astype(float)
        return on, np.zeros_like(t), np.maximum(t, 0.0)
    s = np.clip(t / width, 0.0, 1.0)
    r = 0.5 * (1.0 - np.cos(math.pi * s))
    dr = np.where((t > 0) & (t < width), 0.5 * math.pi / width * np.sin(math.pi * s), 0.0)
    tau = np.clip(t, 0.0, width)
    integral = 0.5 * (tau - width / math.pi * np.sin(math.pi * tau / width)) + np.maximum(
        t - width, 0.0
    )
    return r, dr, integral


def path_of(motion: Motion, pivot: Floats, end: float, base_dir: Path, where: str) -> Trajectory:
    """The sampled path of ``motion`` from t = 0 to ``end`` (s) for a body whose pivot is at
    ``pivot`` (m) at t = 0; ``where`` names the motion in messages."""
    D = pivot.size
    if motion.type == "table":
        return _table(motion, pivot, end, base_dir, where)
    if motion.type == "oscillation":
        period = float(motion.period or 0.0)
        step = min(period, motion.ramp or period) / SAMPLES
        t = np.linspace(0.0, end, max(2, int(math.ceil(end / step)) + 1))
        t = np.union1d(t, [motion.ramp] if 0 < motion.ramp < end else [])
        r, dr, _ = _ramp(t, motion.ramp)
        w = 2 * math.pi / period
        a = np.asarray(motion.amplitude or [0.0] * D, dtype=float)
        sin, cos = np.sin(w * t), np.cos(w * t)
        centre = pivot + (r * sin)[:, None] * a
        velocity = (dr * sin + r * w * cos)[:, None] * a
        theta = math.radians(motion.angle_amplitude)
        return Trajectory(t, centre, velocity, theta * r * sin, theta * (dr * sin + r * w * cos))
    # "velocity": from start (ramped over motion.ramp) to stop
    v = np.asarray(motion.velocity or [0.0] * D, dtype=float)
    rate = math.radians(motion.rate)
    start, stop = motion.start, motion.stop if motion.stop is not None else math.inf
    knots = [0.0, end]
    eps = 1e-9 * max(end, 1.0)  # a jump in velocity: two samples this close
    for k in (start, stop):
        if 0.0 < k < end:
            knots += [k - eps, k]
    if motion.ramp > 0:
        n = SAMPLES
        knots += list(start + motion.ramp * np.arange(1, n + 1) / n)
    t = np.unique(np.clip(np.array(knots), 0.0, end))
    moving_for = np.minimum(t, stop) - start
    r, dr, integral = _ramp(moving_for, motion.ramp)
    running = (t >= start) & (t < stop)
    factor = np.where(running, r, 0.0)
    return Trajectory(
        t, pivot + integral[:, None] * v, factor[:, None] * v, rate * integral, rate * factor
    )


def _table(motion: Motion, pivot: Floats, end: float, base_dir: Path, where: str) -> Trajectory:
    D = pivot.size
    path = (base_dir / str(motion.file)).resolve()
    try:
        with path.open(newline="") as f:
            rows = [r for r in csv.reader(f) if r and any(c.strip() for c in r)]
        data = np.array([[float(c) for c in r] for r in rows[1:]], dtype=float)
    except OSError as err:
        raise CaseError(f"{where}.file: cannot read {path}: {err.strerror or err}") from err
    except ValueError as err:
        raise CaseError(
            f"{where}.file: {path} must hold a header line, then rows of numbers "
            f"(t, the displacement along each of the {D} axes, optionally the angle in "
            f"degrees): {err}"
        ) from err
    if data.ndim != 2 or data.shape[0] < 2 or data.shape[1] not in (1 + D, 2 + D):
        raise CaseError(
            f"{where}.file: {path} needs at least two rows of {1 + D} or {2 + D} columns (t, "
            f"the displacement along each axis, optionally the angle in degrees)"
        )
    t = data[:, 0]
    if not np.all(np.diff(t) > 0) or t[0] != 0.0 or t[-1] < end:
        raise CaseError(
            f"{where}.file: the times of {path} must increase from 0 to at least time.end = "
            f"{end:g} s (they run from {t[0]:g} to {t[-1]:g} s)"
        )
    d = data[:, 1 : 1 + D]
    angle = np.radians(data[:, 1 + D]) if data.shape[1] == 2 + D else np.zeros(t.size)
    if np.any(d[0] != 0.0) or angle[0] != 0.0:
        raise CaseError(
            f"{where}.file: the first row of {path} must be t = 0 with displacement 0 and angle "
            "0: the obstacle's shape is given where it is at t = 0"
        )
    velocity: Floats = np.gradient(d, t, axis=0, edge_order=2 if t.size > 2 else 1)
    rate: Floats = np.gradient(angle, t, edge_order=2 if t.size > 2 else 1)
    return Trajectory(t, pivot + d, velocity, angle, rate)


def mass_properties(
    shape: Shape, h: float, density: float | None, mass: float | None
) -> tuple[float, Floats, Floats]:
    """(mass, centroid, inertia about it) of a solid shape: the midpoint rule on a lattice of
    spacing h / 4 over its bounding box (exact for a box on the lattice). 2D: per metre of
    depth, the inertia's zz entry (the others 0). density (kg/m^3), or the mass (kg) that
    sets it."""
    lo, hi = (np.asarray(b, dtype=float) for b in shape.bounds())
    D = lo.size
    step = h / 4
    counts = np.maximum(np.ceil((hi - lo) / step).astype(int), 1)
    spacing = (hi - lo) / counts
    axes = [lo[k] + spacing[k] * (np.arange(counts[k]) + 0.5) for k in range(D)]
    x = np.stack([g.ravel() for g in np.meshgrid(*axes, indexing="ij")], axis=1)
    x = x[shape.signed_distance(x) < 0.0]
    dv = float(np.prod(spacing))
    volume = x.shape[0] * dv
    rho = float(density) if density is not None else float(mass or 0.0) / volume
    centroid = x.mean(axis=0)
    r = x - centroid
    inertia = np.zeros((3, 3))
    if D == 2:
        inertia[2, 2] = rho * dv * float(np.sum(r * r))
    else:
        inertia = rho * dv * (np.sum(r * r) * np.eye(3) - r.T @ r)
    return rho * volume, centroid, inertia


def _freedom(case: Case, k: int, shape: Shape, where: str) -> tuple[Freedom, Floats]:
    """A free body's mass properties and its pivot: its centroid, or a hinge (motion.pivot,
    every translation held; the inertia then about it, by the parallel-axis theorem)."""
    from ..case.motion import DOF_NAMES

    motion = case.obstacles[k].motion
    assert motion is not None
    D = len(case.domain.size)
    names = DOF_NAMES[D]
    wrong = [n for n in motion.locked if n not in names]
    if wrong:
        raise CaseError(
            f"{where}.locked = {motion.locked}: {', '.join(wrong)} is not a degree of freedom "
            f"of a {D}D body; give some of {', '.join(repr(n) for n in names)}"
        )
    mass, centroid, inertia = mass_properties(
        shape, float(case.grid.spacing), motion.density, motion.mass
    )
    flags = [n in motion.locked for n in names]
    pivot = centroid
    if motion.pivot is not None:
        free = [n for n, held in zip(names[:D], flags[:D]) if not held]
        if free:
            raise CaseError(
                f"{where}.pivot = {motion.pivot}: a free body turns about its centroid; a pivot "
                f"elsewhere is a hinge, which holds it there: add {free} to locked, or remove "
                "the pivot"
            )
        pivot = np.asarray(motion.pivot, dtype=float)
        d = centroid - pivot
        d3 = np.zeros(3)
        d3[:D] = d
        shift = mass * (float(d3 @ d3) * np.eye(3) - np.outer(d3, d3))
        inertia = inertia + (shift if D == 3 else np.diag([0.0, 0.0, shift[2, 2]]))
    # the core's order: translations, then rotations (2D: x, y, rotation; the rest unused)
    locked = (flags + [True] * 3) if D == 2 else flags
    velocity = np.asarray(motion.velocity or [0.0] * D, dtype=float)
    rate = math.radians(motion.rate)
    freedom = Freedom(
        mass, inertia, locked, velocity, rate, centroid - pivot, float(motion.friction)
    )
    return freedom, pivot


def free_energy(movers: list[Mover], state: Floats, gravity: Any) -> float:
    """The free bodies' kinetic and potential energy (J; 2D J/m) at ``state``
    (``State.body_state``: each body's pivot, velocity, angular velocity and orientation
    quaternion): 1/2 m |v|^2 + 1/2 omega . I omega (I about the pivot, turned to the grid's
    axes: the pivot is the centroid, or a hinge that does not move) and -m g . x of the
    centroid, from the origin as the particles' ``potential_energy``. 0 without free bodies.
    The prescribed bodies' energy is not counted: their paths do work on the water."""
    g = np.zeros(3)
    g[: len(gravity)] = np.asarray(gravity, dtype=float)
    total = 0.0
    for k, mover in enumerate(movers):
        f = mover.free
        if f is None:
            continue
        row = np.asarray(state[k], dtype=float)
        R = quaternion_matrix(*row[9:13])
        offset = np.zeros(3)
        offset[: len(f.offset)] = f.offset
        centroid = row[:3] + R @ offset
        v, w = row[3:6], row[6:9]
        inertia = R @ np.asarray(f.inertia, dtype=float) @ R.T
        total += 0.5 * f.mass * float(v @ v) + 0.5 * float(w @ inertia @ w)
        total -= f.mass * float(g @ centroid)
    return total


def free_mass(movers: list[Mover]) -> float:
    """The free bodies' mass (kg; 2D kg/m)."""
    return sum(m.free.mass for m in movers if m.free is not None)


def motions(case: Case) -> list[Motion | None]:
    """Each obstacle's ``motion``, in the order of [[obstacles]] (None: it stands still)."""
    return [getattr(spec, "motion", None) for spec in case.obstacles]


def of_case(case: Case) -> list[Mover]:
    """The case's moving obstacles (those with a ``motion``), in the order of [[obstacles]]."""
    D = len(case.domain.size)
    movers = []
    for k, (spec, motion) in enumerate(zip(case.obstacles, motions(case))):
        if motion is None:
            continue
        shape = case.obstacle_shape(k)
        where = f"obstacles.{k}.motion"
        if motion.type == "free":
            free, pivot = _freedom(case, k, shape, where)
            axis = np.array([0.0, 0.0, 1.0])
            walls = case.domain.uniform_walls() if spec.walls == "domain" else spec.walls
            start = Trajectory(
                np.zeros(1),
                pivot[None, :],
                free.velocity[None, :],
                np.zeros(1),
                np.array([free.rate]),
            )
            name = spec.name or f"obstacle{k}"
            no_slip = walls in ("no_slip", "bonded")
            movers.append(Mover(k, name, shape, pivot, axis, no_slip, start, free))
            continue
        lo, hi = shape.bounds()
        pivot = (
            np.asarray(motion.pivot, dtype=float)
            if motion.pivot is not None
            else 0.5 * (np.asarray(lo, dtype=float) + np.asarray(hi, dtype=float))
        )
        axis = np.array([0.0, 0.0, 1.0]) if D == 2 else np.asarray(motion.axis, dtype=float)
        axis = axis / np.linalg.norm(axis)
        walls = case.domain.uniform_walls() if spec.walls == "domain" else spec.walls
        path = path_of(motion, pivot, float(case.time.end), case.base_dir, where)
        name = spec.name or f"obstacle{k}"
        movers.append(Mover(k, name, shape, pivot, axis, walls in ("no_slip", "bonded"), path))
    return movers
