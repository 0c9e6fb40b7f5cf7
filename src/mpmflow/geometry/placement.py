"""Where the bodies, obstacles and probes of a case sit: the geometric checks of a case.

Each check raises ValueError with one paragraph naming the key and the fix (the case's
validation turns it into the user's message). Lengths in metres. The checks of boxes
against boxes (overlap, inside the domain) stay in ``case`` and ``bodies``; here are those
that involve the other shapes and the obstacles:

* a body outside the domain (by its bounding box), an obstacle reaching more than one grid
  cell beyond it or lying wholly outside (a mistake in position or in a mesh's scale);
* an obstacle thinner than two grid cells along an axis: the grid could not resolve it
  (refused, not warned: a wall of less than two cells holds at most one row of grid nodes,
  and the water would leak through it or round it);
* two bodies of which one is not a box that overlap: some lattice point seeded by both;
* a body that seeds no particle (smaller or thinner than a particle spacing);
* a body overlapping an obstacle, unless it says ``around_obstacles = true`` (then the
  lattice points inside obstacles are left out when seeding, so water can fill a tank
  round a pier); a body lying wholly inside obstacles in any case;
* a probe inside an obstacle (on its surface is fine: a sensor on a structure's face);
* two obstacles with the same name.
"""

from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

from . import bodies
from .lattice import lattice_chunks
from .shapes import Shape

THIN = 2  # grid cells: the thinnest obstacle the grid resolves


def _v(values: Iterable[float]) -> str:
    return "[" + ", ".join(f"{v:.6g}" for v in values) + "]"


def _what(kind: str, k: int, spec: Any) -> str:
    return f"{kind}.{k} (a {getattr(spec, 'type', 'box')})"


def _box_text(size: Iterable[float]) -> str:
    return " x ".join(f"[0, {s:g}]" for s in size)


def _move_keys(kind: str, k: int, spec: Any) -> str:
    keys = {
        "box": "min/max",
        "cylinder": "centre",
        "sphere": "centre",
        "disc": "centre",
        "polygon": "vertices",
        "mesh": "translate or scale",
    }[getattr(spec, "type", "box")]
    return f"{kind}.{k}.{keys}"


# spec: a case's obstacle table (mpmflow.case.shapes.Obstacle), read by its ``type`` string
# as geometry.specs does: Any because mypy cannot narrow the union by that string
def thickness(spec: Any, shape: Shape) -> tuple[float, str]:
    """The obstacle's smallest width (m) and where it is measured: exact for boxes, discs,
    spheres and cylinders; the bounding box's for polygons and meshes (a thin slanted plate
    is not detected)."""
    kind = getattr(spec, "type", "box")
    if kind in ("disc", "sphere"):
        return 2 * spec.radius, "its diameter"
    if kind == "cylinder":
        if 2 * spec.radius <= spec.length:
            return 2 * spec.radius, "its diameter"
        return spec.length, "its length"
    lo, hi = shape.bounds()
    axis = int(np.argmin(hi - lo))
    return float(hi[axis] - lo[axis]), f"its extent along {'xyz'[axis]}"


def check(case: Any, body_shapes: Sequence[Shape], obstacle_shapes: Sequence[Shape]) -> None:
    """Raise ValueError for the first geometric problem of the case (see the module)."""
    size = np.asarray(case.domain.size, dtype=float)
    h = case.grid.spacing
    tol = 1e-12 * max(1.0, float(size.max()))
    for k, (body, shape) in enumerate(zip(case.bodies, body_shapes)):
        if bodies.is_box(body):
            continue  # case: the box's own message
        lo, hi = shape.bounds()
        if np.any(lo < -tol) or np.any(hi > size + tol):
            raise ValueError(
                f"{_what('bodies', k, body)} spans {_v(lo)} to {_v(hi)} m, outside the domain "
                f"{_box_text(size)} m; move it inside ({_move_keys('bodies', k, body)}) or "
                "enlarge domain.size"
            )
    names: dict[str, int] = {}
    for k, (obstacle, shape) in enumerate(zip(case.obstacles, obstacle_shapes)):
        lo, hi = shape.bounds()
        if (
            np.any(lo < -h - tol)
            or np.any(hi > size + h + tol)
            or np.any(hi < 0)
            or np.any(lo > size)
        ):
            raise ValueError(
                f"{_what('obstacles', k, obstacle)} spans {_v(lo)} to {_v(hi)} m, more than "
                f"one grid cell (grid.spacing = {h:g} m) beyond the domain {_box_text(size)} m "
                "(the part outside would be wall anyway, so this is a mistake of position"
                + (
                    " or of units: scale converts the file's units to metres"
                    if getattr(obstacle, "type", "") == "mesh"
                    else ""
                )
                + f"); move it inside ({_move_keys('obstacles', k, obstacle)}) or enlarge "
                "domain.size"
            )
        width, measure = thickness(obstacle, shape)
        if width < THIN * h * (1 - 1e-9):
            raise ValueError(
                f"{_what('obstacles', k, obstacle)} is {width:.4g} m thin ({measure}), less "
                f"than {THIN} grid cells (grid.spacing = {h:g} m): the grid holds at most one "
                "row of nodes inside it, so water would leak through or round it; make it at "
                f"least {THIN * h:.4g} m thick, or refine grid.spacing to at most "
                f"{width / THIN:.4g} m"
                + (
                    f" (or, if the file is not in metres, check obstacles.{k}.scale = "
                    f"{obstacle.scale:g}, the factor from its units to metres)"
                    if getattr(obstacle, "type", "") == "mesh"
                    else ""
                )
            )
        if obstacle.name is not None:
            if obstacle.name in names:
                raise ValueError(
                    f"obstacles.{k}.name = {obstacle.name!r} is the name of obstacles."
                    f"{names[obstacle.name]}; give each obstacle its own name"
                )
            names[obstacle.name] = k
    _bodies_apart(case, body_shapes)
    _bodies_seeded(case, body_shapes)
    for k, probe in enumerate(case.probes):
        for j, (obstacle, shape) in enumerate(zip(case.obstacles, obstacle_shapes)):
            depth = -float(shape.signed_distance(np.asarray([probe.position], dtype=float))[0])
            if depth > tol:
                raise ValueError(
                    f"probes.{k}.position = {probe.position} m lies {depth:.4g} m inside "
                    f"{_what('obstacles', j, obstacle)}, where there is never water; move "
                    "it out, e.g. onto the obstacle's surface facing the flow (a sensor on a "
                    "structure's face)"
                )


def _bodies_apart(case: Any, body_shapes: Sequence[Shape]) -> None:
    """Bodies of which one is not a box must not share a seeded lattice point."""
    h = case.grid.spacing
    listed = case.bodies
    for i in range(len(listed)):
        for j in range(i + 1, len(listed)):
            a, b = listed[i], listed[j]
            if bodies.is_box(a) and bodies.is_box(b):
                continue  # bodies.overlap_message
            for (p, P), (q, Q) in (((i, a), (j, b)), ((j, b), (i, a))):
                n, lo, hi = _shared(P, body_shapes[p], Q, body_shapes[q], h / P.particles_per_cell)
                if n and lo is not None and hi is not None:  # n > 0: lo, hi are set
                    raise ValueError(
                        f"{_what('bodies', i, a)} and {_what('bodies', j, b)} overlap: {n} "
                        f"lattice points of bodies.{p} (spacing {h / P.particles_per_cell:.4g}"
                        f" m) lie in both, from {_v(lo)} to {_v(hi)} m. Bodies are filled "
                        "with particles one by one, so an overlap would be filled twice, "
                        "adding mass that is not there. Bodies may touch but not overlap: "
                        f"move or shrink one of them ({_move_keys('bodies', i, a)} or "
                        f"{_move_keys('bodies', j, b)})"
                    )


def _bodies_seeded(case: Any, body_shapes: Sequence[Shape]) -> None:
    """Every body seeds at least one particle: one that seeds none (smaller or thinner
    than a particle spacing, often a mesh whose scale is off by a thousand) would be left
    out of the run without a word. (A body that obstacles take whole: empty_body_message.)"""
    h = case.grid.spacing
    for k, (body, shape) in enumerate(zip(case.bodies, body_shapes)):
        if not bodies.seeds_any(body, h, shape):
            raise ValueError(_too_small_message(case, k, body, shape))


_SIZE_KEYS = {
    "box": "min/max",
    "cylinder": "radius/length",
    "sphere": "radius",
    "disc": "radius",
    "polygon": "vertices",
    "mesh": "scale",
}


def _too_small_message(case: Any, k: int, body: Any, shape: Shape) -> str:
    h, ppc = case.grid.spacing, body.particles_per_cell
    kind = getattr(body, "type", "box")
    lo, hi = (body.min, body.max) if kind == "box" else shape.bounds()
    size = " x ".join(f"{b - a:.4g}" for a, b in zip(lo, hi))
    head = (
        f"{_what('bodies', k, body)} seeds no particle: it spans {size} m (from {_v(lo)} "
        f"to {_v(hi)} m), and no point of its particle lattice, spaced grid.spacing / "
        f"bodies.{k}.particles_per_cell = {h:g} / {ppc} = {h / ppc:.4g} m, lies inside "
        "it, so the run would leave it out. "
    )
    resize = (
        f"make it larger than one particle spacing (bodies.{k}.{_SIZE_KEYS[kind]}), "
        f"raise bodies.{k}.particles_per_cell (at most 16) or refine grid.spacing, or "
        f"remove bodies.{k}"
    )
    if kind == "mesh":
        return head + (
            f"Check bodies.{k}.scale = {body.scale:g}: it converts the file's "
            "units to metres (1 for a file in metres, 0.001 for millimetres). "
            f"If it is right, {resize}."
        )
    return head + resize[0].upper() + resize[1:] + "."


def _shared(
    P: Any, shape_p: Shape, Q: Any, shape_q: Shape, s: float
) -> tuple[int, np.ndarray | None, np.ndarray | None]:
    """Lattice points (spacing s) that both bodies keep: count and their bounding box."""
    lo_p, hi_p = bodies.seed_region(P, shape_p, s)
    lo_q, hi_q = bodies.seed_region(Q, shape_q, s)
    lo, hi = np.maximum(lo_p, lo_q), np.minimum(hi_p, hi_q)
    if np.any(hi <= lo):
        return 0, None, None
    n, first, last = 0, None, None
    for points in lattice_chunks(lo, hi, s):
        both = bodies.in_body(P, shape_p, points, s)
        both[both] = bodies.in_body(Q, shape_q, points[both], s)
        if both.any():
            x = points[both]
            n += len(x)
            first = x.min(axis=0) if first is None else np.minimum(first, x.min(axis=0))
            last = x.max(axis=0) if last is None else np.maximum(last, x.max(axis=0))
    return n, first, last


def empty_body_message(
    case: Any, k: int, body_shape: Shape, obstacle_shapes: Sequence[Shape]
) -> str | None:
    """The message for bodies.k when obstacles take every one of its lattice points, or
    None (a count pass without obstacles; called only when its count is 0)."""
    body = case.bodies[k]
    alone = bodies.particle_count(body, case.grid.spacing, body_shape)
    if not alone:
        return None
    return (
        f"{_what('bodies', k, body)} lies wholly inside obstacles: all {alone} of its "
        "lattice points are inside an obstacle, where the material cannot start, so it "
        f"would hold no particles; remove bodies.{k} or move it out of the obstacles "
        f"({_move_keys('bodies', k, body)})"
    )


def overlap_message(
    case: Any, k: int, count: float, body_shape: Shape, obstacle_shapes: Sequence[Shape]
) -> str | None:
    """The message for bodies.k overlapping an obstacle (``count``: its particles with the
    obstacles left out), or None when no obstacle takes any of its lattice points."""
    body = case.bodies[k]
    h = case.grid.spacing
    alone = bodies.particle_count(body, h, body_shape)
    if alone == count:
        return None
    for j, shape in enumerate(obstacle_shapes):
        taken = alone - bodies.particle_count(body, h, body_shape, [shape])
        if taken:
            obstacle = case.obstacles[j]
            return (
                f"{_what('bodies', k, body)} overlaps {_what('obstacles', j, obstacle)}: "
                f"{taken} of its {alone} lattice points lie inside the obstacle, where "
                "the material cannot start. Move them apart "
                f"({_move_keys('bodies', k, body)} or {_move_keys('obstacles', j, obstacle)})"
                f", or, to fill the body's shape round the obstacle (water in a tank round "
                f"a pier), set bodies.{k}.around_obstacles = true"
            )
    return None
