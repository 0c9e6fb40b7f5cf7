"""Fixed rigid obstacles on the grid: what the step needs to know about them, built once.

An obstacle enters the step through the signed distance phi (m, negative inside a solid) at
the grid nodes, the minimum over the case's obstacles, interpolated multilinearly inside each
cell: the solid is where that interpolant is negative, so faces lie at their true position,
not on grid lines (corners and edges are rounded within a cell). From phi:

* cells wholly inside a solid are left out of everything, like cells beyond the domain;
* cells the surface cuts get their own element integrals over the fluid part, the obstacle's
  face term, and the fluid part of their faces on the domain's walls
  (``state.cut_cell_tensors``, src/core/cut_cells.hpp): the "static" slots 1, 2, ... of the step's element integrals,
  slot 0 being the whole cell;
* ``open``: the fluid fraction of each cell, by which a cut cell's particle volume is
  divided to give its volume fraction theta (a cut cell full of water has theta = 1);
* where an obstacle touches a domain wall, its distance at the wall's nodes is taken one cell
  in, and inside it extrapolated from the two nodes behind where that is lower
  (``node_distance``), so that it meets the wall without a gap and a slanted face meets it
  at its own slope;
* the obstacle nodes: the nodes of cut cells, each with the unit normal int N_i n ds /
  |int N_i n ds| of the obstacle's face around it (pointing into the solid). They are
  contact conditions like the domain walls (src/core/walls): a node holds the material
  where it presses into the solid and lets go where holding it would need suction.

Particles that end a step inside a solid are moved out along grad phi
(``state.push_out``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from .. import state
from ..arrays import Bools, Floats, Ints
from ..geometry.shapes import Shape
from ..grid import Grid

if TYPE_CHECKING:  # the case builds its obstacles' shapes with geometry/, not with this module
    from ..case import Case

SUBCELLS = 8  # sub-cells per axis of a cut cell: the face is placed to within h / 8


@dataclass
class Tables:
    """The obstacles' fixed tables on the grid (empty arrays where there are none)."""

    phi: Floats  # (nnodes,) signed distance at the nodes (m); empty: no obstacle
    open: Floats  # (ncells,) fluid fraction of each cell
    static_slot: Ints  # (ncells,) 0 whole cell, s >= 1 cut cell's slot, -1 solid
    K: Floats  # (1 + ncut, 2^D, 2^D) element integrals by static slot
    C: Floats  # (1 + ncut, 2^D, 2^D, D)
    V: Floats  # (1 + ncut, 2^D)
    F: Floats  # (1 + ncut, 2^D, 2^D, D) obstacle face term (slot 0: zero)
    Wf: Floats  # (1 + ncut, 2D, 2^D, 2^D) fluid part of the cell faces (wall terms)
    node: Ints  # (m,) obstacle nodes
    normal: Floats  # (m, D) their unit normals, into the solid
    no_slip: Bools  # (m,) whether the node's obstacle is no-slip
    solids: list[Shape] = field(default_factory=list)  # the obstacles' shapes
    # (nnodes,) whether each node's nearest obstacle is no-slip (empty: no obstacle); moving
    # obstacles (boundaries/moving.py) read it where their cells meet a fixed one's
    node_no_slip: Bools = field(default_factory=lambda: np.zeros(0, dtype=np.bool_))

    def distance(self, points: Floats) -> Floats:
        """The signed distance (m) of points to the nearest obstacle, negative inside."""
        nearest: Floats = np.min([s.signed_distance(points) for s in self.solids], axis=0)
        return nearest

    @property
    def present(self) -> bool:
        return bool(self.phi.shape[0] > 0)


def build(
    grid: Grid, phi: Floats | None = None, no_slip_of: Callable[[Ints], Bools] | None = None
) -> Tables:
    """The tables for signed distances ``phi`` at the nodes (None: no obstacle).
    ``no_slip_of(node_indices) -> bool array`` says which obstacle nodes are no-slip."""
    D, nc = grid.dim, grid.ncells
    NC = 2**D
    cells = tuple(int(c) for c in grid.cells)
    K0, C0, V0 = np.zeros((NC, NC)), np.zeros((NC, NC, D)), np.zeros(NC)
    state.gauss_cell_tensors(grid.spacing, K0, C0, V0)
    W0 = np.zeros((2 * D, NC, NC))
    state.face_mass(grid.spacing, D, W0)
    open_ = np.ones(nc)
    static_slot = np.zeros(nc, dtype=np.int64)
    if phi is None:
        return Tables(
            np.zeros(0),
            open_,
            static_slot,
            K0[None],
            C0[None],
            V0[None],
            np.zeros((1, NC, NC, D)),
            W0[None],
            np.zeros(0, dtype=np.int64),
            np.zeros((0, D)),
            np.zeros(0, dtype=np.bool_),
        )
    phi = np.ascontiguousarray(phi, dtype=float)
    corners = _cell_corner_phi(grid, phi)  # (ncells, 2^D)
    lo, hi = corners.min(axis=1), corners.max(axis=1)
    solid = hi <= 0.0
    touching = (lo <= 0.0) & ~solid
    # candidates: cells touching a solid and their face neighbours (a face of a fluid cell
    # may be the obstacle's face while none of its nodes is inside)
    cand = touching.reshape(cells[::-1]).copy()
    grown = cand.copy()
    for axis in range(D):
        grown |= np.roll(cand, 1, axis=axis) & _not_first(cand.shape, axis)
        grown |= np.roll(cand, -1, axis=axis) & _not_last(cand.shape, axis)
    candidates = np.flatnonzero(grown.ravel() & ~solid)
    m = candidates.size
    K = np.zeros((m, NC, NC))
    C = np.zeros((m, NC, NC, D))
    V = np.zeros((m, NC))
    F = np.zeros((m, NC, NC, D))
    Wf = np.zeros((m, 2 * D, NC, NC))
    parts = np.zeros(m, dtype=np.int64)
    state.cut_cell_tensors(
        phi, float(grid.spacing), cells, candidates, SUBCELLS, K, C, V, F, Wf, parts
    )
    # a candidate without a fluid sub-cell is solid on the staircase (a sliver of positive
    # phi at a corner, narrower than a sub-cell): left out like the cells inside
    empty = V.sum(axis=1) <= 0.0
    solid[candidates[empty]] = True
    cut = (parts > 0) & ~empty
    cut_cells = candidates[cut]
    static_slot[solid] = -1
    static_slot[cut_cells] = 1 + np.arange(cut_cells.size)
    open_[solid] = 0.0
    open_[cut_cells] = V[cut].sum(axis=1) / grid.cell_volume
    # obstacle nodes and their normals: int N_b n ds summed over the cut cells
    ns = _node_strides(cells)
    nvec = np.zeros((grid.nnodes, D))
    Fn = F[cut].sum(axis=1)  # (ncut, 2^D, D): int N_b n ds in each cut cell
    first = _first_nodes(cut_cells, cells, ns)
    for a, offset in enumerate(_corner_offsets(ns)):
        np.add.at(nvec, first + offset, Fn[:, a])
    size = np.linalg.norm(nvec, axis=1)
    node = np.flatnonzero(size > 1e-9 * grid.spacing ** (D - 1))
    normal = nvec[node] / size[node, None]
    no_slip = no_slip_of(node) if no_slip_of is not None else np.zeros(node.size, dtype=np.bool_)
    return Tables(
        phi,
        open_,
        static_slot,
        np.concatenate([K0[None], K[cut]]),
        np.concatenate([C0[None], C[cut]]),
        np.concatenate([V0[None], V[cut]]),
        np.concatenate([np.zeros((1, NC, NC, D)), F[cut]]),
        np.concatenate([W0[None], Wf[cut]]),
        node.astype(np.int64),
        normal,
        np.asarray(no_slip, dtype=np.bool_),
    )


def _node_strides(cells: Sequence[int]) -> Ints:
    """Flat node strides ns_k (axis 0 fastest): 1, cells[0] + 1, (cells[0] + 1)(cells[1] + 1)."""
    return np.cumprod([1] + [int(c) + 1 for c in cells[:-1]]).astype(np.int64)


def _corner_offsets(ns: Ints) -> Ints:
    """Flat offset of each of the 2^D corners of a cell from its first node (corner a is
    offset (a >> k) & 1 along axis k)."""
    return np.array(
        [sum(int(s) for k, s in enumerate(ns) if (a >> k) & 1) for a in range(1 << len(ns))],
        dtype=np.int64,
    )


def _first_nodes(cells_flat: Ints, cells: Sequence[int], ns: Ints) -> Ints:
    """The first node of each cell (flat indices, axis 0 fastest)."""
    first = np.zeros(cells_flat.size, dtype=np.int64)
    r = cells_flat.copy()
    for k, n in enumerate(cells):
        first += (r % n) * ns[k]
        r //= n
    return first


def _cell_corner_phi(grid: Grid, phi: Floats) -> Floats:
    """phi at the 2^D corners of every cell, (ncells, 2^D)."""
    cells = tuple(int(c) for c in grid.cells)
    ns = _node_strides(cells)
    first = _first_nodes(np.arange(grid.ncells), cells, ns)
    out = np.empty((grid.ncells, 2 ** len(cells)))
    for a, offset in enumerate(_corner_offsets(ns)):
        out[:, a] = phi[first + offset]
    return out


def _not_first(shape: tuple[int, ...], axis: int) -> Bools:
    """Mask, False at index 0 along ``axis`` (arrays indexed last axis first)."""
    m = np.ones(shape, dtype=bool)
    idx: list[slice | int] = [slice(None)] * len(shape)
    idx[axis] = 0
    m[tuple(idx)] = False
    return m


def _not_last(shape: tuple[int, ...], axis: int) -> Bools:
    m = np.ones(shape, dtype=bool)
    idx: list[slice | int] = [slice(None)] * len(shape)
    idx[axis] = -1
    m[tuple(idx)] = False
    return m


def in_solid_cells(tables: Tables, grid: Grid, x: Floats) -> Bools:
    """Which of the points ``x`` (n, D) lie in the solid the grid sees: in cells it takes as
    wholly solid (fluid fraction 0), or where phi interpolated from the nodes is negative.
    The bodies are seeded round the obstacles' own shapes, and the grid's solid differs from
    them within a cell: where an obstacle touches two or three walls, the wall shift
    (``node_distance``) closes the corner between it and the walls within the first cell (no
    flow reaches a point there, phi is flat, no direction to push it out along, and held by
    nothing it fell freely in place); under a disc or a sphere tangent to the floor, or an
    overhang meeting it, the shift fills the thin wedge of water below within the first cell.
    A point seeded there would be pushed out at the first step onto the face, several onto
    one point (a disc on the floor at 0.01 m: three pairs of particles, pushed again at every
    step of a column at rest)."""
    if not tables.present:
        return np.zeros(x.shape[0], dtype=bool)
    cells = np.array([int(c) for c in grid.cells])
    ci = np.clip(np.floor(x / grid.spacing).astype(np.int64), 0, cells - 1)
    strides = np.cumprod(np.concatenate([[1], cells[:-1]]))
    solid: Bools = (tables.open[ci @ strides] <= 0.0) | (grid_distance(tables, grid, x) < 0.0)
    return solid


def grid_distance(tables: Tables, grid: Grid, x: Floats) -> Floats:
    """phi (m) at the points ``x`` (n, D), interpolated multilinearly from the nodes in the
    cell holding each: the solid the step sees (its edges and corners rounded within a cell,
    its faces on the walls as ``node_distance`` takes them) is where this is negative."""
    return grid.interpolate(tables.phi, x)


def of_case(case: Case, grid: Grid) -> Tables:
    """The tables of the case's fixed ``[[obstacles]]`` (none: empty tables); those with a
    ``motion`` are the moving obstacles' (boundaries/moving.py)."""
    fixed = [
        (k, o)
        for k, o in enumerate(getattr(case, "obstacles", None) or [])
        if getattr(o, "motion", None) is None
    ]
    if not fixed:
        return build(grid)
    specs = [o for _, o in fixed]
    solids = [case.obstacle_shape(k) for k, _ in fixed]
    x = grid.node_coordinates()
    dist = np.array([node_distance(grid, s, x) for s in solids])  # (nobstacles, nnodes)
    phi = dist.min(axis=0)
    nearest = dist.argmin(axis=0)
    walls = [
        case.domain.uniform_walls() if getattr(o, "walls", "domain") == "domain" else o.walls
        for o in specs
    ]
    # an obstacle under bonded domain walls holds as a no-slip one (obstacles are never bonded)
    no_slip = np.array([w in ("no_slip", "bonded") for w in walls], dtype=bool)
    tables = build(grid, phi, lambda nodes: no_slip[nearest[nodes]])
    tables.solids = solids
    tables.node_no_slip = no_slip[nearest]
    return tables


def node_distance(grid: Grid, shape: Shape, x: Floats) -> Floats:
    """The shape's signed distance at the grid's nodes ``x`` (``grid.node_coordinates()``),
    taken one cell in from a domain wall the shape touches or crosses: there the shape's own
    face on the wall would put phi = 0 at every wall node under it, and the interpolated
    surface would open a wedge of fluid under the obstacle's edge. One cell in, a face
    meeting the wall would be taken as perpendicular to it within the first cell (exact for
    boxes and upright cylinders); a slanted face (a triangle's or a ramp's slope, a mesh's
    facet) would leave a wedge of fluid in the first cell that the particles, seeded round
    the shape itself, do not fill, or cover one they fill. So a wall node inside the shape
    (or on its face) also takes the distance extrapolated linearly along the wall's normal
    from the two nodes behind it, 2 phi_1 - phi_2, where that is lower: the slanted face
    then meets the wall at its own slope, and under a face parallel to the wall (phi falling
    inwards, 2 phi_1 - phi_2 >= phi_1) nothing changes."""
    h = grid.spacing
    lo, hi = shape.bounds()
    size = grid.size
    tol = 1e-9 * h
    moved = x.copy()
    touched = []  # (axis, (the wall's layer of nodes, the next two in))
    for k in range(grid.dim):
        if lo[k] <= tol:
            moved[x[:, k] <= tol, k] += h
            touched.append((k, (0, 1, 2)))
        if hi[k] >= size[k] - tol:
            moved[x[:, k] >= size[k] - tol, k] -= h
            touched.append((k, (-1, -2, -3)))
    shifted = shape.signed_distance(moved)
    nodes = [int(n) for n in grid.nodes]
    if not touched or min(nodes) < 3:
        return shifted
    # the nodes as arrays indexed [i_0, i_1, ...] (flat order: axis 0 fastest)
    phi = shifted.reshape(nodes[::-1]).transpose()
    inside = shape.signed_distance(x).reshape(nodes[::-1]).transpose() <= tol
    out = phi.copy()
    for k, layers in touched:
        wall, first, second = (_layer(grid.dim, k, i) for i in layers)
        line = 2.0 * phi[first] - phi[second]
        out[wall] = np.where(inside[wall], np.minimum(out[wall], line), out[wall])
    result: Floats = out.transpose().reshape(-1)
    return result


def _layer(dim: int, axis: int, index: int) -> tuple[slice | int, ...]:
    """The index of the layer of nodes ``index`` along ``axis`` (arrays indexed [i_0, i_1,
    ...])."""
    at: list[slice | int] = [slice(None)] * dim
    at[axis] = index
    return tuple(at)
