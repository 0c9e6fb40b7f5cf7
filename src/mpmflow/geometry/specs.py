"""The shape of a case's ``[[bodies]]`` or ``[[obstacles]]`` table."""

from pathlib import Path
from typing import Any

from .meshes import load_mesh
from .shapes import DIM_OF, Ball, Box, Cylinder, Polygon, Shape


def from_spec(spec: Any, dim: int, base_dir: str | Path, key: str | None = None) -> Shape:
    """The Shape of a case's ``[[bodies]]`` or ``[[obstacles]]`` table ``spec`` (its ``type``
    and shape fields) in a ``dim``-dimensional case. ``base_dir``: the folder relative mesh
    paths start from (the case file's). ``key``: the table's name for messages, e.g.
    "obstacles.1". ValueError for a shape the dimension does not offer or a bad mesh."""
    kind = getattr(spec, "type", "box")
    key = key or kind
    if dim not in DIM_OF[kind]:
        others = ", ".join(k for k, d in DIM_OF.items() if dim in d)
        raise ValueError(
            f"{key}.type = {kind!r} is a {DIM_OF[kind][0]}D shape but the case "
            f"is {dim}D; use one of {others} (or give domain.size "
            f"{DIM_OF[kind][0]} entries)"
        )
    if kind == "box":
        return Box(spec.min, spec.max)
    if kind in ("disc", "sphere"):
        return Ball(spec.centre, spec.radius)
    if kind == "cylinder":
        return Cylinder(spec.centre, spec.axis, spec.radius, spec.length)
    if kind == "polygon":
        return Polygon(spec.vertices)
    path = Path(spec.path).expanduser()
    if not path.is_absolute():
        path = Path(base_dir) / path
    return load_mesh(path, spec.scale, spec.translate, key=key, shown=spec.path)
