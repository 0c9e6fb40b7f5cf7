"""Solid shapes in 2D and 3D for bodies and obstacles: containment, signed distance, bounds.

Every shape answers, for points given as an (n, D) array in metres:

* ``contains(points)``: (n,) bool, inside or on the boundary (within ``ON_SURFACE`` m);
* ``signed_distance(points)``: (n,) float (m), negative inside, positive outside: the exact
  Euclidean distance to the surface for the primitives; for a mesh the unsigned distance to
  the nearest triangle with the sign of the containment test;
* ``bounds()``: the corners (lo, hi) of its axis-aligned bounding box (m);
* ``volume()``: m^3 in 3D, the area (m^2) in 2D;
* ``support(direction)``: the largest x . direction over the shape (m for a unit direction),
  e.g. the height of its highest point against gravity.

Shapes: ``Box`` (2D, 3D), ``Disc`` and ``Polygon`` (2D), ``Sphere``, ``Cylinder`` and
``Mesh`` (3D, ``geometry.meshes``, which also reads STL and OBJ files). ``geometry.specs``
builds one from a case's ``[[bodies]]`` or ``[[obstacles]]`` table. Everything is
vectorised NumPy except the mesh's sums over triangles, which come from libigl (``igl``:
fast winding number, point-to-mesh distance).
"""

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

ON_SURFACE = 1e-12  # m: a point this close to the surface counts as inside
# a polygon whose area is below this share of its extent squared has none: its corners lie
# on one line but for the rounding of their coordinates
FLAT = 1e-9

DIM_OF = {
    "box": (2, 3),
    "disc": (2,),
    "polygon": (2,),
    "sphere": (3,),
    "cylinder": (3,),
    "mesh": (3,),
}


def as_points(points: Any, dim: int) -> np.ndarray:
    x = np.asarray(points, dtype=float)
    if x.ndim == 1 and x.shape[0] == dim:
        x = x[None, :]
    if x.ndim != 2 or x.shape[1] != dim:
        raise ValueError(
            f"points must be an (n, {dim}) array of coordinates (m), got shape {x.shape}"
        )
    return x


class Shape:
    """A closed solid region; subclasses define ``dim`` and the methods below."""

    dim: int

    def contains(self, points: Any) -> np.ndarray:
        """(n,) bool: inside or on the boundary within ON_SURFACE (m)."""
        return self.signed_distance(points) <= ON_SURFACE

    def signed_distance(self, points: Any) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - abstract
        raise NotImplementedError

    def volume(self) -> float:  # pragma: no cover - abstract
        raise NotImplementedError

    def support(self, direction: Any) -> float:  # pragma: no cover - abstract
        raise NotImplementedError

    def boundary(self) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - abstract
        """The surface as a mesh for drawing: vertices (n, D) m and cells (m, D) vertex
        indices, line segments in 2D and triangles in 3D, outward by the right-hand rule
        (2D: counter-clockwise)."""
        raise NotImplementedError


# segments of a circle and sections of a cylinder's drawn surface, subdivisions of a sphere's
# icosahedron (642 vertices): within 0.12% of the radius
ROUND = 64
SPHERE_SUBDIVISIONS = 3


def _ring(n: int) -> np.ndarray:
    """Segments (n, 2) joining n points in a closed ring."""
    i = np.arange(n, dtype=np.int64)
    return np.stack([i, (i + 1) % n], axis=1)


class Box(Shape):
    """Axis-aligned box [lo, hi] (m), 2D or 3D."""

    def __init__(self, lo: ArrayLike, hi: ArrayLike) -> None:
        self.lo = np.asarray(lo, dtype=float)
        self.hi = np.asarray(hi, dtype=float)
        self.dim = len(self.lo)

    def contains(self, points: Any) -> np.ndarray:
        x = as_points(points, self.dim)
        return np.all((x >= self.lo - ON_SURFACE) & (x <= self.hi + ON_SURFACE), axis=1)

    def signed_distance(self, points: Any) -> np.ndarray:
        x = as_points(points, self.dim)
        q = np.abs(x - 0.5 * (self.lo + self.hi)) - 0.5 * (self.hi - self.lo)
        outside = np.linalg.norm(np.maximum(q, 0.0), axis=1)
        return outside + np.minimum(q.max(axis=1), 0.0)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        return self.lo.copy(), self.hi.copy()

    def volume(self) -> float:
        return float(np.prod(self.hi - self.lo))

    def support(self, direction: Any) -> float:
        d = np.asarray(direction, dtype=float)
        return float(np.sum(np.where(d > 0, self.hi, self.lo) * d))

    def boundary(self) -> tuple[np.ndarray, np.ndarray]:
        lo, hi = self.lo, self.hi
        if self.dim == 2:
            corners = np.array([[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]])
            return corners, _ring(4)
        # corner i lies at hi along axis k where bit k of i is set
        corners = np.array([[(lo, hi)[(i >> k) & 1][k] for k in range(3)] for i in range(8)])
        quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
        faces = [(a, b, c) for a, b, c, _ in quads] + [(a, c, d) for a, _, c, d in quads]
        return corners, np.array(faces, dtype=np.int64)


class Ball(Shape):
    """Points within ``radius`` (m) of ``centre``: a disc in 2D, a sphere in 3D."""

    def __init__(self, centre: ArrayLike, radius: float) -> None:
        self.centre = np.asarray(centre, dtype=float)
        self.radius = float(radius)
        self.dim = len(self.centre)

    def signed_distance(self, points: Any) -> np.ndarray:
        x = as_points(points, self.dim)
        return np.linalg.norm(x - self.centre, axis=1) - self.radius

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        return self.centre - self.radius, self.centre + self.radius

    def volume(self) -> float:
        r = self.radius
        return math.pi * r * r if self.dim == 2 else 4.0 / 3.0 * math.pi * r**3

    def support(self, direction: Any) -> float:
        d = np.asarray(direction, dtype=float)
        return float(self.centre @ d + self.radius * np.linalg.norm(d))

    def boundary(self) -> tuple[np.ndarray, np.ndarray]:
        if self.dim == 2:
            a = np.linspace(0.0, 2.0 * math.pi, ROUND, endpoint=False)
            ring = np.stack([np.cos(a), np.sin(a)], axis=1)
            return self.centre + self.radius * ring, _ring(ROUND)
        import trimesh

        sphere = trimesh.creation.icosphere(subdivisions=SPHERE_SUBDIVISIONS, radius=self.radius)
        return self.centre + np.asarray(sphere.vertices), np.asarray(sphere.faces, np.int64)


Disc = Sphere = Ball


class Cylinder(Shape):
    """A solid circular cylinder (3D) with flat ends: the base's centre ``base`` (m), the
    ``axis`` direction (any length), ``radius`` and ``length`` (m) along the axis."""

    dim = 3

    def __init__(self, base: ArrayLike, axis: ArrayLike, radius: float, length: float) -> None:
        self.base = np.asarray(base, dtype=float)
        axis = np.asarray(axis, dtype=float)
        norm = np.linalg.norm(axis)
        if not norm > 0:
            raise ValueError("the cylinder's axis must not be the zero vector")
        self.axis = axis / norm
        self.radius = float(radius)
        self.length = float(length)

    def signed_distance(self, points: Any) -> np.ndarray:
        x = as_points(points, 3) - self.base
        t = x @ self.axis
        rho = np.linalg.norm(x - t[:, None] * self.axis, axis=1)
        dr = rho - self.radius
        da = np.abs(t - 0.5 * self.length) - 0.5 * self.length
        return np.minimum(np.maximum(dr, da), 0.0) + np.hypot(
            np.maximum(dr, 0.0), np.maximum(da, 0.0)
        )

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        top = self.base + self.length * self.axis
        reach = self.radius * np.sqrt(np.clip(1.0 - self.axis**2, 0.0, 1.0))
        return np.minimum(self.base, top) - reach, np.maximum(self.base, top) + reach

    def volume(self) -> float:
        return math.pi * self.radius**2 * self.length

    def support(self, direction: Any) -> float:
        d = np.asarray(direction, dtype=float)
        along = self.axis @ d
        across = math.sqrt(max(float(d @ d) - along * along, 0.0))
        return float(self.base @ d + max(0.0, self.length * along) + self.radius * across)

    def boundary(self) -> tuple[np.ndarray, np.ndarray]:
        import trimesh

        # trimesh's cylinder stands on the z axis, centred on the origin
        c = trimesh.creation.cylinder(radius=self.radius, height=self.length, sections=ROUND)
        turn = trimesh.geometry.align_vectors([0.0, 0.0, 1.0], self.axis)[:3, :3]
        centre = self.base + 0.5 * self.length * self.axis
        return centre + np.asarray(c.vertices) @ turn.T, np.asarray(c.faces, np.int64)


class Polygon(Shape):
    """A simple polygon (2D, convex or not) through ``vertices`` (m), closed implicitly."""

    dim = 2

    def __init__(self, vertices: ArrayLike) -> None:
        v = np.asarray(vertices, dtype=float)
        self.vertices = v
        self.a = v
        self.b = np.roll(v, -1, axis=0)

    def _edge_distance(self, x: np.ndarray) -> np.ndarray:
        best = np.full(len(x), np.inf)
        for a, b in zip(self.a, self.b):
            e = b - a
            t = np.clip(((x - a) @ e) / (e @ e), 0.0, 1.0)
            best = np.minimum(best, np.linalg.norm(x - a - t[:, None] * e, axis=1))
        return best

    def _crossings(self, x: np.ndarray) -> np.ndarray:
        """Inside by the crossing number: a ray to +x crosses an odd number of edges (the
        half-open rule counts a vertex on the ray once)."""
        inside = np.zeros(len(x), dtype=bool)
        px, py = x[:, 0], x[:, 1]
        for (ax, ay), (bx, by) in zip(self.a, self.b):
            if ay == by:
                continue  # a horizontal edge never crosses the ray by the half-open rule
            straddles = (ay > py) != (by > py)
            cross_x = ax + (py - ay) * (bx - ax) / (by - ay)
            inside ^= straddles & (px < cross_x)
        return inside

    def contains(self, points: Any) -> np.ndarray:
        x = as_points(points, 2)
        return self._crossings(x) | (self._edge_distance(x) <= ON_SURFACE)

    def signed_distance(self, points: Any) -> np.ndarray:
        x = as_points(points, 2)
        d = self._edge_distance(x)
        return np.where(self._crossings(x) | (d == 0.0), -d, d)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        return self.vertices.min(axis=0), self.vertices.max(axis=0)

    def volume(self) -> float:
        return float(0.5 * abs(np.sum(self.a[:, 0] * self.b[:, 1] - self.b[:, 0] * self.a[:, 1])))

    def support(self, direction: Any) -> float:
        return float(np.max(self.vertices @ np.asarray(direction, dtype=float)))

    def boundary(self) -> tuple[np.ndarray, np.ndarray]:
        v = self.vertices
        x, y = v[:, 0], v[:, 1]
        ccw = float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)) > 0.0
        return (v if ccw else v[::-1]).copy(), _ring(len(v))


def polygon_problem(vertices: Any) -> str | None:
    """Why these corners (m) are not a simple polygon (all on one line, edges that cross or
    touch), or None. O(n^2) in the corners: a case's polygon has tens, not thousands. The
    crossing edges are looked for before the area: a bow tie's two loops can enclose areas
    that cancel, and "no area" would hide that its edges cross."""
    v = np.asarray(vertices, dtype=float)
    d = v - v[0]
    far = d[np.argmax(np.abs(d).sum(axis=1))]
    # on one line to rounding: no corner further from the line through the first and the
    # farthest than FLAT times their distance ([0.005, 0.025], [0.015, 0.035], [0.025, 0.045]
    # has cross products of 1e-19 m^2, not 0, and seeded the lattice points on its edge)
    scale = float(far @ far)
    if not np.any(np.abs(far[0] * d[:, 1] - far[1] * d[:, 0]) > FLAT * scale):
        return (
            "vertices: the polygon's corners lie on one line, so they enclose no area; "
            "give its corners in order around its boundary"
        )
    crossing = _crossing_edges(v)
    if crossing:
        return crossing
    area = 0.5 * np.sum(v[:, 0] * np.roll(v[:, 1], -1) - np.roll(v[:, 0], -1) * v[:, 1])
    if not abs(area) > FLAT * scale:
        return (
            "vertices: the polygon's corners enclose no area; give its corners in order "
            "around its boundary"
        )
    return None


def _crossing_edges(v: np.ndarray) -> str | None:
    """The message for the first two edges of the polygon v that cross (each passes
    through the other's inside) or touch, or None."""
    n = len(v)

    def cross(o: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
        return float((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]))

    def spans_meet(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray, k: int) -> bool:
        return bool(max(min(a[k], b[k]), min(c[k], d[k])) <= min(max(a[k], b[k]), max(c[k], d[k])))

    for i in range(n):
        a, b = v[i], v[(i + 1) % n]
        for j in range(i + 2, n):
            if (j + 1) % n == i:
                continue  # the last edge and the first share a corner
            c, d = v[j], v[(j + 1) % n]
            sides = (cross(c, d, a) * cross(c, d, b), cross(a, b, c) * cross(a, b, d))
            if max(sides) <= 0 and spans_meet(a, b, c, d, 0) and spans_meet(a, b, c, d, 1):
                how = "cross" if max(sides) < 0 else "touch"
                return (
                    f"vertices: the polygon's edges {i} (corners {i} to {(i + 1) % n}) and "
                    f"{j} (corners {j} to {(j + 1) % n}) {how}, so it is not a simple "
                    "polygon; list its corners in order around the boundary"
                )
    return None
