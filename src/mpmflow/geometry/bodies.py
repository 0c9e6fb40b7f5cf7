"""Geometry of the bodies of a case, before any particle exists: particle counts, overlaps,
and whether the material would fill the whole grid.

Each body is filled with particles on the global lattice (k + 1/2) * s, s = grid.spacing /
particles_per_cell (``lattice.lattice_in_box``): a particle stands for the square of side
s around it. A box keeps the lattice points in [min, max) along each axis; any other shape
the points of its bounding box that it ``contains`` (``geometry.shapes``); either way the
points inside an obstacle are left out (``seeded``). Bodies must not overlap (they may
touch): overlapping bodies would place their particles on top of each other and create
mass. The counts here are exact. For a box clear of obstacles they cost one pass over the
lattice columns of a body, not over its particles, so that a case can be sized
(``mpmflow.memory``) in microseconds whatever its size; for other shapes, and for a box
near an obstacle, one containment pass over the lattice points of the bounding box (of
the box's part near the obstacles).
"""

import itertools
import math
from collections.abc import Callable, Iterable, Sequence
from typing import Any

import numpy as np

from .lattice import lattice_chunks, lattice_count, lattice_indices
from .shapes import Shape

TOUCH = 1e-9  # overlaps thinner than this fraction of a grid cell are touching faces


def cosine_top(body: Any, x: Any) -> np.ndarray:
    """The top of a body at x (m): max[1] + A cos(pi (x - min[0]) / width); max[1] if flat."""
    if body.surface_amplitude == 0.0:
        return np.full(np.shape(x), body.max[1], dtype=float)
    width = body.max[0] - body.min[0]
    return body.max[1] + body.surface_amplitude * np.cos(
        np.pi * (np.asarray(x) - body.min[0]) / width
    )


# a containment pass over more lattice points than this is not made to count a body: such a
# body is far beyond any machine's memory, and its count is estimated from its volume
MAX_PASS = 2 * 10**8


def is_box(body: Any) -> bool:
    return getattr(body, "type", "box") == "box"


def seed_region(body: Any, shape: Shape | None, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi): the part of the lattice of ``spacing`` that holds the body's particles,
    for ``lattice.lattice_in_box`` (half open, [lo, hi)): a box's [min, max) (up to the
    crest of a cosine top); for other shapes the bounding box, widened a little so that
    lattice points on its upper faces are kept where the shape contains them."""
    if is_box(body):
        top = list(body.max)
        top[1] += abs(body.surface_amplitude)
        return np.asarray(body.min, dtype=float), np.asarray(top, dtype=float)
    assert shape is not None  # every shape but a box has one
    lo, hi = shape.bounds()
    return lo, hi + 2e-9 * spacing


def in_body(body: Any, shape: Shape | None, points: np.ndarray, spacing: float) -> np.ndarray:
    """Which of the points the body keeps (before obstacles): a box's half-open [min, max)
    on its own lattice (``lattice_indices``: max - 1e-9 spacing excluded) and below a
    cosine top; any other shape, ``shape.contains``."""
    if not is_box(body):
        assert shape is not None  # every shape but a box has one
        return shape.contains(points)
    lo = np.asarray(body.min) - 1e-9 * spacing
    hi = np.asarray(body.max) - 1e-9 * spacing
    if body.surface_amplitude:
        hi[1] += abs(body.surface_amplitude)
    keep = np.all((points >= lo) & (points <= hi), axis=1)
    if body.surface_amplitude:
        keep &= points[:, 1] < cosine_top(body, points[:, 0])
    return keep


def in_obstacles(obstacles: Sequence[Shape], points: np.ndarray) -> np.ndarray:
    """Which of the points lie inside (or on) any of the obstacle shapes."""
    inside = np.zeros(len(points), dtype=bool)
    for shape in obstacles:
        lo, hi = shape.bounds()
        near = np.flatnonzero(np.all((points >= lo - 1e-12) & (points <= hi + 1e-12), axis=1))
        if len(near):
            inside[near[shape.contains(points[near])]] = True
    return inside


def seeded(
    body: Any,
    shape: Shape | None,
    points: np.ndarray,
    spacing: float,
    obstacles: Sequence[Shape] = (),
) -> np.ndarray:
    """The body's particles among these lattice points: kept by the body, outside every
    obstacle (the material cannot start inside a structure)."""
    keep = in_body(body, shape, points, spacing)
    if obstacles and keep.any():
        keep[keep] = ~in_obstacles(obstacles, points[keep])
    return keep


def _clip(
    lo: np.ndarray, hi: np.ndarray, shapes: Sequence[Shape]
) -> tuple[np.ndarray, np.ndarray] | None:
    """The part of [lo, hi) inside the union of the shapes' bounding boxes, as one box
    (their hull), or None when none reaches it."""
    parts = []
    for shape in shapes:
        a, b = shape.bounds()
        a, b = np.maximum(lo, a - 1e-9), np.minimum(hi, b + 1e-9)
        if np.all(b >= a):
            parts.append((a, b))
    if not parts:
        return None
    return np.min([p[0] for p in parts], axis=0), np.max([p[1] for p in parts], axis=0)


def particle_count(
    body: Any, grid_spacing: float, shape: Shape | None = None, obstacles: Sequence[Shape] = ()
) -> float:
    """The number of particles the body is seeded with (exact; ``setup_case`` seeds them);
    inf when the count overflows a float. ``shape``: the body's ``mpmflow.shapes`` shape
    (needed unless the body is a box); ``obstacles``: the obstacles' shapes, whose points
    are left out."""
    try:
        s = grid_spacing / body.particles_per_cell
        if is_box(body):
            n = _count(body, grid_spacing)
            lo, hi = seed_region(body, shape, s)
            near = _clip(lo, hi, obstacles) if obstacles else None
            if near is None or not n:
                return n
            return n - _pass(body, shape, near, s, obstacles, carved=True)
        lo, hi = seed_region(body, shape, s)
        return _pass(body, shape, (lo, hi), s, obstacles)
    except OverflowError:
        return math.inf


def seeds_any(body: Any, grid_spacing: float, shape: Shape | None = None) -> bool:
    """Whether the body keeps at least one lattice point, obstacles aside: exact for a box
    (its count, O(1)); for another shape a pass over the lattice points of its bounding box
    that stops at the first chunk holding one. A body whose box holds more than MAX_PASS
    points (or too many to count) is taken to seed some: the memory check refuses it."""
    try:
        if is_box(body):
            return _count(body, grid_spacing) > 0
        s = grid_spacing / body.particles_per_cell
        lo, hi = seed_region(body, shape, s)
        if lattice_count(lo, hi, s) > MAX_PASS:
            return True
        return any(in_body(body, shape, points, s).any() for points in lattice_chunks(lo, hi, s))
    except OverflowError:
        return True


def _pass(
    body: Any,
    shape: Shape | None,
    region: tuple[np.ndarray, np.ndarray],
    s: float,
    obstacles: Sequence[Shape],
    carved: bool = False,
) -> int:
    """Lattice points in region the body keeps (carved: that the obstacles remove)."""
    lo, hi = region
    total = lattice_count(lo, hi, s)
    if total > MAX_PASS:  # beyond any machine: the volume's worth of lattice points
        volume = shape.volume() if shape is not None else float(np.prod(np.subtract(hi, lo)))
        return 0 if carved else int(round(volume / s ** len(lo)))
    n = 0
    for points in lattice_chunks(lo, hi, s):
        keep = in_body(body, shape, points, s)
        if carved:
            n += int(np.count_nonzero(in_obstacles(obstacles, points[keep])))
        else:
            n += int(np.count_nonzero(seeded(body, shape, points, s, obstacles)))
    return n


def _count(body: Any, grid_spacing: float) -> int:
    s = grid_spacing / body.particles_per_cell
    k0, k1 = lattice_indices(body.min[0], body.max[0], s)
    nx = max(0, k1 - k0 + 1)
    if body.surface_amplitude == 0.0:
        n = nx
        for a, b in zip(body.min[1:], body.max[1:]):
            j0, j1 = lattice_indices(a, b, s)
            n *= max(0, j1 - j0 + 1)
        return n
    # cosine top: per lattice column, the rows below the surface (as seeding.body_pieces keeps)
    j0, j1 = lattice_indices(body.min[1], body.max[1] + abs(body.surface_amplitude), s)
    if nx == 0 or j1 < j0:
        return 0
    if nx > 10**8:  # an absurd column count: bound it by the box instead
        return nx * (j1 - j0 + 1)
    x = (np.arange(k0, k1 + 1) + 0.5) * s
    top = cosine_top(body, x)
    y = (np.arange(j0, j1 + 1) + 0.5) * s
    return int(np.searchsorted(y, top, side="left").sum())


def region(body: Any) -> tuple[float, float, float, Callable[[Any], np.ndarray]]:
    """The body's region as (x0, x1, y0, top(x)) with top a function of x."""
    return body.min[0], body.max[0], body.min[1], lambda x: cosine_top(body, x)


def overlap(a: Any, b: Any, tol: float) -> tuple[list[float], list[float]] | None:
    """The intersection of two bodies' regions if its extent is positive (more than ``tol``
    across every axis), as (lo, hi) corner lists; None when they are apart or only touch.
    Bodies with a cosine top (2D) are sampled along x."""
    lo = [max(p, q) for p, q in zip(a.min, b.min)]
    hi = [min(p, q) for p, q in zip(a.max, b.max)]
    if not a.surface_amplitude and not b.surface_amplitude:
        return None if any(h - l <= tol for l, h in zip(lo, hi)) else (lo, hi)
    x0, x1 = lo[0], hi[0]
    if x1 - x0 <= tol:
        return None
    y0 = lo[1]
    xs = np.linspace(x0, x1, 257)[1:-1]  # the tops are monotone in x: samples suffice
    top = np.minimum(cosine_top(a, xs), cosine_top(b, xs))
    inside = top - y0 > tol
    if not inside.any():
        return None
    return ([float(xs[inside].min()), y0], [float(xs[inside].max()), float(top[inside].max())])


def _fmt(values: Iterable[float]) -> str:
    return "[" + ", ".join(f"{v:.6g}" for v in values) + "]"


def _trims(j: int, body: Any, other: Any, tol: float) -> list[str]:
    """Changes of ``body`` (bodies.j) that remove its overlap with ``other`` and keep the
    union of the two: a face of body moved to other's face, where the overlap spans body
    across the other axis. Flat boxes only."""
    out: list[str] = []
    if body.surface_amplitude or other.surface_amplitude:
        return out
    D = len(body.min)
    for axis in range(D):
        spans = all(
            other.min[k] <= body.min[k] + tol and other.max[k] >= body.max[k] - tol
            for k in range(D)
            if k != axis
        )
        if not spans:
            continue
        if other.min[axis] <= body.min[axis] + tol and other.max[axis] < body.max[axis] - tol:
            lo = list(body.min)
            lo[axis] = other.max[axis]
            out.append(f"bodies.{j}.min = {_fmt(lo)}")
        if other.max[axis] >= body.max[axis] - tol and other.min[axis] > body.min[axis] + tol:
            hi = list(body.max)
            hi[axis] = other.min[axis]
            out.append(f"bodies.{j}.max = {_fmt(hi)}")
    return out


def _inside(a: Any, b: Any, tol: float) -> bool:
    """Body a lies inside body b (flat boxes)."""
    return (
        not a.surface_amplitude
        and not b.surface_amplitude
        and all(
            bl <= al + tol and ah <= bh + tol for al, ah, bl, bh in zip(a.min, a.max, b.min, b.max)
        )
    )


def overlap_message(bodies: Sequence[Any], spacing: float) -> str | None:
    """One paragraph naming the first pair of overlapping bodies and the fix; None if no two
    bodies overlap."""
    tol = TOUCH * spacing
    for i in range(len(bodies)):
        for j in range(i + 1, len(bodies)):
            a, b = bodies[i], bodies[j]
            if not is_box(a) or not is_box(b):
                continue  # shapes: mpmflow.placement.body_overlap
            box = overlap(a, b, tol)
            if box is None:
                continue
            where = "they share the region " + ", ".join(
                f"{name} = {lo:.6g} to {hi:.6g} m" for name, lo, hi in zip("xyz", *box)
            )
            head = (
                f"bodies.{i} (min {_fmt(a.min)}, max {_fmt(a.max)} m) and bodies.{j} (min "
                f"{_fmt(b.min)}, max {_fmt(b.max)} m) overlap: {where}. Bodies are "
                "filled with particles one by one, so an overlap would be filled twice, "
                "adding mass that is not there and packing the particles twice as close. "
                "Bodies may touch but not overlap. "
            )
            if _inside(b, a, tol) and _inside(a, b, tol):
                return head + f"The two are the same box: remove bodies.{j}."
            if _inside(b, a, tol):
                return head + f"bodies.{j} lies inside bodies.{i}: remove it."
            if _inside(a, b, tol):
                return head + f"bodies.{i} lies inside bodies.{j}: remove it."
            trims = _trims(i, a, b, tol) + _trims(j, b, a, tol)
            if trims:
                return head + (
                    "To keep the same material, set "
                    + trims[0]
                    + "".join(f" (or {t})" for t in trims[1:])
                    + "."
                )
            return head + (f"Split bodies.{i} or bodies.{j} into boxes that only touch the other.")
    return None


def fills_grid(
    bodies: Sequence[Any], spacing: float, grid_size: Sequence[float] | np.ndarray
) -> bool:
    """True when the particles of the bodies (each the square of its lattice cell) cover the
    whole grid, leaving no empty space (flat boxes; a cosine top always leaves some, other
    shapes are taken to: the start's free-surface check catches what remains)."""
    if any(not is_box(b) or b.surface_amplitude for b in bodies):
        return False
    rects = []
    for body in bodies:
        s = spacing / body.particles_per_cell
        r = []
        for a, b in zip(body.min, body.max):
            k0, k1 = lattice_indices(a, b, s)
            if k1 < k0:
                break
            r.append((k0 * s, (k1 + 1) * s))
        else:
            rects.append(r)
    if not rects:
        return False
    # the union's measure on the compressed coordinates of the boxes' edges: every cell of
    # that irregular grid (inside the domain) must lie in some box
    D = len(grid_size)
    tol = TOUCH * spacing
    cuts = []
    for k in range(D):
        edges = sorted({0.0, float(grid_size[k])} | {v for r in rects for v in r[k]})
        cuts.append(
            [
                0.5 * (p + q)
                for p, q in zip(edges, edges[1:])
                if q - p > tol and p < grid_size[k] - tol
            ]
        )
    for mid in itertools.product(*cuts):
        if not any(all(r[k][0] <= mid[k] <= r[k][1] for k in range(D)) for r in rects):
            return False
    return True
