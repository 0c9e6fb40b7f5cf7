"""The 3D picture of a snapshot: the water's surface and the obstacles, drawn with matplotlib.

The field is the particles' volume fraction on the run's own grid: the particle volume
(mass / density) summed in each cell over the cell's volume, clipped to [0, 1]: the cells
of ``mpmflow.cells`` and the field that front, height and the level gauges read
(``diagnostics.volume_fraction_field``), so the picture shows the water the solver's
diagnostics see. A finer field was not taken: with 2 particles per cell and direction a
cell of half the spacing holds about one particle, and its fraction jumps between 0, 1
and 2 from one cell to the next (a surface full of holes and blobs); the grid's cells hold
8 or more and read smoothly. The cells of obstacles are counted whole (not their open part
only), so that next to an obstacle the surface lies near the obstacle's face rather than
inside it.

The surface is the field's iso-surface at 1/2 by marching cubes (scikit-image's
``skimage.measure.marching_cubes``, Lewiner et al. 2003), with the field padded by one
empty cell on every side: water against a wall is closed by a face on the wall (the 1/2
crossing between a full last cell and the empty pad lies on the wall itself), so a column
at rest is drawn as the closed box it is. Vertices are in m, cell centres at
(i + 1/2) spacing.

Drawn with mplot3d: one Poly3DCollection holding the water's triangles (blue) and the
obstacles' surfaces (grey, half transparent), each triangle shaded by a fixed light
(``LIGHT``, from above and in front of the viewer) with two-sided Lambert shading; one
collection, so that matplotlib sorts the water's and the obstacles' triangles together by
depth. Equal aspect (the box aspect is the domain's), axes in m, seen from the front, above
and the side (``VIEW``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from types import ModuleType
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

if TYPE_CHECKING:  # matplotlib is an optional extra (its mplot3d has no type information)
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection
    from mpl_toolkits.mplot3d.axes3d import Axes3D

VIEW = {"elev": 28.0, "azim": -60.0}  # degrees: in front (y < 0), above and to the side
LIGHT = np.array([0.3, -0.6, 1.0])  # towards the light: from above, behind the viewer
WATER = (0.16, 0.45, 0.80)
OBSTACLE = (0.55, 0.55, 0.55, 0.55)  # grey, half transparent
LEVEL = 0.5


def need_skimage(needs: str = "mpmflow plot") -> ModuleType:
    """skimage.measure, or CaseError saying how to install scikit-image."""
    from ..errors import CaseError

    try:
        from skimage import measure
    except ImportError:
        raise CaseError(
            f"{needs} needs scikit-image for the 3D water surface: pip install "
            "'mpmflow[plot]' (or pip install scikit-image)."
        ) from None
    return measure


def volume_fraction(
    x: NDArray[np.float64], volume: ArrayLike, spacing: float, cells: Sequence[int]
) -> NDArray[np.float64]:
    """The cells' volume fraction [cx, cy, cz] of particles at ``x`` (n, 3) m holding
    ``volume`` (n,) m^3: their volume per cell over the cell's volume, clipped to [0, 1].
    The cells are the solver's (``state.cell_index``: particles on or past the domain's
    faces count in the cells at the faces)."""
    from .. import state
    from ..diagnostics.measures import volume_fraction_field
    from ..grid import Grid

    grid = Grid(float(spacing), tuple(int(c) for c in cells))
    index = np.empty(len(x), dtype=np.int64)
    state.cell_index(np.ascontiguousarray(x, dtype=float), grid.spacing, grid.cells, index)
    theta = (
        np.bincount(index, weights=np.broadcast_to(volume, (len(x),)), minlength=grid.ncells)
        / grid.cell_volume
    )
    return volume_fraction_field(grid, theta)


def water_surface(
    f: NDArray[np.float64], spacing: float
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """The iso-surface f = 1/2 of a cell field f [cx, cy, cz] on cells of side ``spacing``
    (m), closed at the domain's faces: (vertices (m, 3) m, triangles (k, 3)); empty arrays
    when no cell reaches 1/2."""
    if f.size == 0 or float(f.max()) < LEVEL:
        return np.empty((0, 3)), np.empty((0, 3), dtype=np.int64)
    padded = np.pad(np.asarray(f, dtype=float), 1)
    verts, faces, _, _ = need_skimage().marching_cubes(
        padded, LEVEL, spacing=(spacing,) * 3, allow_degenerate=False
    )
    # the padded field's index i is the cell centred at (i - 1/2) h
    return verts.astype(float) - 0.5 * spacing, faces


def surface_area(verts: NDArray[np.float64], faces: NDArray[np.int64]) -> float:
    """The area (m^2) of a triangle surface."""
    if len(faces) == 0:
        return 0.0
    v = verts[faces]
    return float(0.5 * np.linalg.norm(np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1).sum())


def _box_triangles(lo: NDArray[np.float64], hi: NDArray[np.float64]) -> NDArray[np.float64]:
    """The 12 triangles of an axis-aligned box's faces, (12, 3, 3) m."""
    c = np.array(
        [
            [
                lo[0] if i & 1 == 0 else hi[0],
                lo[1] if i & 2 == 0 else hi[1],
                lo[2] if i & 4 == 0 else hi[2],
            ]
            for i in range(8)
        ]
    )
    quads = [(0, 1, 3, 2), (4, 5, 7, 6), (0, 1, 5, 4), (2, 3, 7, 6), (0, 2, 6, 4), (1, 3, 7, 5)]
    return np.array([c[[a, b, d]] for a, b, _, d in quads] + [c[[b, e, d]] for _, b, e, d in quads])


# summary: summary.json as read (mpmflow.results): parsed JSON, hence Any for its values
def obstacle_triangles(
    summary: Mapping[str, Any], notes: list[str], samples: int = 32
) -> NDArray[np.float64]:
    """The surfaces of the case's obstacles as triangles (k, 3, 3) m: a box's six faces, a
    mesh's own triangles, any other shape (ball, cylinder) the zero level set of its signed
    distance by marching cubes on ``samples`` points along its bounding box's longest
    side. Rebuilt from the case in summary.json; what cannot be rebuilt is left out with a
    note (as for the slice's obstacles)."""
    from ..case import validate_case
    from ..errors import CaseError
    from ..geometry.meshes import Mesh
    from ..geometry.shapes import Box

    spec = summary.get("case", {})
    if not spec.get("obstacles"):
        return np.empty((0, 3, 3))
    try:
        case = validate_case(spec)
        solids = [case.obstacle_shape(k) for k in range(len(case.obstacles))]
    except CaseError as err:
        notes.append(f"the obstacles cannot be drawn in 3D: {err}")
        return np.empty((0, 3, 3))
    parts = []
    for s in solids:
        if isinstance(s, Box):
            parts.append(_box_triangles(s.lo, s.hi))
        elif isinstance(s, Mesh):
            parts.append(s.vertices[s.faces])
        else:
            lo, hi = s.bounds()
            step = float(np.max(hi - lo)) / samples
            lo, hi = lo - 2 * step, hi + 2 * step
            axes = [np.arange(a, b + 0.5 * step, step) for a, b in zip(lo, hi)]
            pts = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
            phi = s.signed_distance(pts).reshape([len(a) for a in axes])
            v, tri, _, _ = need_skimage().marching_cubes(phi, 0.0, spacing=(step,) * 3)
            parts.append((v + lo)[tri])
    return np.concatenate(parts) if parts else np.empty((0, 3, 3))


def _shaded(
    triangles: NDArray[np.float64], rgb: Sequence[float], alpha: float
) -> NDArray[np.float64]:
    """RGBA per triangle: ``rgb`` times 0.25 + 0.75 |n . l| (two-sided Lambert shading by
    LIGHT)."""
    n = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    light = LIGHT / np.linalg.norm(LIGHT)
    k = 0.25 + 0.75 * np.abs(n @ light)
    out = np.empty((len(triangles), 4))
    out[:, :3] = np.clip(np.outer(k, rgb), 0.0, 1.0)
    out[:, 3] = alpha
    return out


def draw_surface(
    ax: Axes3D,
    verts: NDArray[np.float64],
    faces: NDArray[np.int64],
    obstacles: NDArray[np.float64],
    size: Sequence[float] | NDArray[np.float64],
    title: str | None = None,
    labels: bool = True,
) -> Poly3DCollection:
    """Draw the water's surface (``verts``, ``faces``) and the obstacles' triangles on a 3D
    axes ``ax`` over the domain [0, size] (m); returns the collection. A long domain is
    zoomed in (its box leaves the axes' corners empty), up to 1.25 for 3 to 1 and longer."""
    from matplotlib.ticker import MaxNLocator
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    water = verts[faces] if len(faces) else np.empty((0, 3, 3))
    tris = np.concatenate([water, obstacles])
    colours = np.concatenate(
        [_shaded(water, WATER, 1.0), _shaded(obstacles, OBSTACLE[:3], OBSTACLE[3])]
    )
    art = Poly3DCollection(
        tris, facecolors=colours, edgecolors="none", linewidths=0, antialiased=False
    )
    ax.add_collection3d(art)
    ax.set_xlim(0, size[0])
    ax.set_ylim(0, size[1])
    ax.set_zlim(0, size[2])
    ratio = float(max(size)) / float(sorted(size)[1])  # the longest side over the middle
    ax.set_box_aspect(size, zoom=float(np.clip(0.95 + 0.15 * (ratio - 1.0), 0.95, 1.25)))
    ax.view_init(**VIEW)
    longest = float(max(size))
    for axis, name, side in zip((ax.xaxis, ax.yaxis, ax.zaxis), "xyz", size):
        # ticks by the side's length, so that a narrow side's labels do not overlap
        axis.set_major_locator(MaxNLocator(nbins=max(1, round(5 * side / longest))))
        if labels:
            axis.set_label_text(f"{name} [m]", fontsize=7)
            axis.labelpad = -3
    ax.tick_params(labelsize=6, pad=-2)
    if title is not None:
        ax.set_title(title, fontsize=9)
    return art
