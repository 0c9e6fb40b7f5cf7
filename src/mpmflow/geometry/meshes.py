"""Closed triangle meshes (3D): the ``Mesh`` shape and the reading of STL and OBJ files
(trimesh), with the user's message for every way a file can be damaged."""

import functools
import io
from pathlib import Path
from typing import Any, NoReturn, cast

import igl
import numpy as np

from .shapes import ON_SURFACE, Shape, as_points


class Mesh(Shape):
    """A closed triangle mesh (3D): ``vertices`` (m), ``faces`` (triangles of vertex indices,
    counter-clockwise seen from outside).

    Inside where the generalised winding number exceeds 1/2 (the sum of the triangles'
    signed solid angles over 4 pi), which tolerates small defects: a missing or doubled
    triangle only changes the classification near itself. Both sums over the triangles come
    from libigl (``import igl``), for the points inside the bounding box only:

    * the distance: its exact point-to-mesh distance over an AABB tree
      (``igl.point_mesh_squared_distance``), which also finds the points on the surface
      (within ON_SURFACE, where the winding number is undetermined);
    * the winding number: its fast winding number (``igl.fast_winding_number``, Barill et al.
      2018: exact over nearby triangles, a far-field expansion of distant groups), except
      within ``BAND`` of the surface, where its exact sum (``igl.winding_number``) is taken:
      the fast one works in single precision and is wrong up to about 1e-7 times the
      coordinates' size from the surface (at a vertex 7e-10 m from a grid node it gave 0.42
      instead of 1).

    Measured against the hand-written kernels they replace (kernels/triangles.py), on the
    shipped blob.stl and the tests' meshes (5e5 lattice and random points each, the grid
    nodes and seeded particles of examples/stl_drop_3d.toml): the same inside/outside
    classification everywhere except 3 points within 0.08 m of the hole of a holed unit
    icosphere, where the winding number is 1/2 +- 0.01 and libigl's agrees with the exact
    sum; distances equal to 4e-16 m.
    """

    dim = 3

    BAND = 1e-5  # relative to the coordinates' size: the exact winding number this near

    def __init__(self, vertices: Any, faces: Any) -> None:
        self.vertices = np.ascontiguousarray(vertices, dtype=float)
        self.faces = np.ascontiguousarray(np.asarray(faces, dtype=np.int64).reshape(-1, 3))
        v, f = self.vertices, self.faces
        self.v0, self.v1, self.v2 = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
        self._lo, self._hi = v.min(axis=0), v.max(axis=0)
        self.notes: list[str] = []  # what reading its file had to decide (load_mesh)
        self._band = self.BAND * float(max(np.abs(v).max(), (self._hi - self._lo).max()))

    def _winding(self, x: np.ndarray, d: np.ndarray) -> np.ndarray:
        """The winding number at points x (m) with distances d (m) to the surface."""
        w = igl.fast_winding_number(self.vertices, self.faces, x)
        close = np.flatnonzero(d <= self._band)
        if close.size:
            w[close] = igl.winding_number(self.vertices, self.faces, np.ascontiguousarray(x[close]))
        return w

    def winding_number(self, points: Any) -> tuple[np.ndarray, np.ndarray]:
        """(n,) generalised winding number at the points, and (n,) bool: on the surface."""
        x = np.ascontiguousarray(as_points(points, 3))
        if not (len(x) and len(self.faces)):
            return np.zeros(len(x)), np.zeros(len(x), dtype=bool)
        d = self.unsigned_distance(x)
        return self._winding(x, d), d <= ON_SURFACE

    def _near_box(self, x: np.ndarray) -> np.ndarray:
        return np.all((x >= self._lo - ON_SURFACE) & (x <= self._hi + ON_SURFACE), axis=1)

    def _inside(self, x: np.ndarray, d: np.ndarray) -> np.ndarray:
        """Inside or on the surface, for points x with distances d to the surface."""
        out = np.zeros(len(x), dtype=bool)
        near = np.flatnonzero(self._near_box(x))
        if near.size and len(self.faces):
            w = self._winding(np.ascontiguousarray(x[near]), d[near])
            out[near] = (w > 0.5) | (d[near] <= ON_SURFACE)
        return out

    def contains(self, points: Any) -> np.ndarray:
        x = as_points(points, 3)
        near = self._near_box(x)
        d = np.full(len(x), np.inf)
        d[near] = self.unsigned_distance(x[near])
        return self._inside(x, d)

    def unsigned_distance(self, points: Any) -> np.ndarray:
        """(n,) distance (m) to the nearest triangle."""
        x = np.ascontiguousarray(as_points(points, 3))
        if not (len(x) and len(self.faces)):
            return np.full(len(x), np.inf)
        d2, _, _ = igl.point_mesh_squared_distance(x, self.vertices, self.faces)
        return np.sqrt(d2)

    def signed_distance(self, points: Any) -> np.ndarray:
        x = as_points(points, 3)
        d = self.unsigned_distance(x)
        return np.where(self._inside(x, d) & (d > 0), -d, d)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        return self._lo.copy(), self._hi.copy()

    def volume(self) -> float:
        """Enclosed volume (m^3) by the divergence theorem over the triangles."""
        return float(abs(np.einsum("ij,ij->i", self.v0, np.cross(self.v1, self.v2)).sum()) / 6.0)

    def support(self, direction: Any) -> float:
        return float(np.max(self.vertices @ np.asarray(direction, dtype=float)))

    def boundary(self) -> tuple[np.ndarray, np.ndarray]:
        return self.vertices.copy(), self.faces.copy()


# --------------------------------------------------------------------------- mesh files


def _refuse(key: str, text: str) -> NoReturn:
    raise ValueError(f"{key}.path = {text}")


STL_HEADER = 84  # bytes: an 80-byte free header, then the triangle count (uint32)
STL_TRIANGLE = 50  # bytes: normal, three vertices (float32 each), a 2-byte attribute


class MeshFileError(ValueError):
    """A mesh file whose bytes say it is damaged (the message says how)."""


def _stl_bytes(raw: bytes) -> tuple[bytes, str | None]:
    """(the STL bytes for trimesh, a note or None): a binary STL whose header count
    disagrees with the file's size, with its count set to the triangles the file holds.

    trimesh reads a binary STL only when 84 + 50 x its header's count is the file's size,
    and otherwise takes it for ASCII text, which it is not: it then fails with a decoding
    error, or reads no triangles. Writers that stream (and cannot go back to fill in the
    count) leave the count 0 or wrong, while the triangles are all there. When the bytes
    after the header are a whole number of 50-byte triangles, which triangles the file
    holds is unambiguous: they are read, and the note tells the user that the count was
    not used (a truncated file then shows as an open surface, refused with that note).
    When they are not, the file is cut inside a triangle or has bytes appended, and which
    triangles are meant is a guess: MeshFileError."""
    if _is_ascii_stl(raw):
        return raw, None
    if b"\0" not in raw:  # text (no binary STL is without a NUL byte) that is not an STL
        raise MeshFileError(
            'is text, but not an ASCII STL (which starts with "solid"); '
            "export the surface again as STL (binary or ASCII) or OBJ."
        )
    if len(raw) < STL_HEADER:
        raise MeshFileError(
            f"has {len(raw)} bytes, fewer than the {STL_HEADER}-byte header of "
            "a binary STL, and is not an ASCII STL; export it again."
        )
    count = int.from_bytes(raw[80:84], "little")
    body = len(raw) - STL_HEADER
    if count * STL_TRIANGLE == body:
        return raw, None
    held, rest = divmod(body, STL_TRIANGLE)
    if rest:
        raise MeshFileError(
            f"is a binary STL whose header counts {count:,} triangles "
            f"({STL_HEADER + STL_TRIANGLE * count:,} bytes), but the file has {len(raw):,} "
            f"bytes: {held:,} whole triangles and {rest} bytes more, so it is cut short "
            "inside a triangle or has bytes appended, and which triangles it holds is "
            "unclear; export it again from your CAD tool."
        )
    note = (
        f"the binary STL's header counts {count:,} triangles but its {len(raw):,} bytes "
        f"hold {held:,}; the {held:,} triangles of the file were read"
    )
    return raw[:80] + held.to_bytes(4, "little") + raw[STL_HEADER:], note


def _is_ascii_stl(raw: bytes) -> bool:
    """An ASCII STL: it starts with ``solid`` and holds no NUL byte (binary triangles hold
    many: the attribute bytes, coordinates 0.0; a binary header may start with "solid")."""
    return raw.lstrip()[:5].lower() == b"solid" and b"\0" not in raw


BOMS = ((b"\xef\xbb\xbf", "utf-8-sig"), (b"\xff\xfe", "utf-16"), (b"\xfe\xff", "utf-16"))


def _has_bom(raw: bytes) -> bool:
    """Text that starts with a byte-order mark (no binary STL header does, in practice)."""
    return any(raw.startswith(bom) for bom, _ in BOMS)


def _text_bytes(raw: bytes) -> bytes:
    """Text (an ASCII STL, an OBJ) as UTF-8 for trimesh. trimesh decodes other text with
    charset_normalizer's guess, a module it does not install (a Latin-1 solid name, "solid
    W\xfcrfel", failed with "No module named 'charset_normalizer'"); the keywords and numbers
    of both formats are ASCII, so reading the bytes as Latin-1 (every byte a character)
    changes only names, never the geometry. A byte-order mark names its encoding."""
    for bom, encoding in BOMS:
        if raw.startswith(bom):
            try:
                return raw.decode(encoding).encode("utf-8")
            except UnicodeDecodeError:
                raise MeshFileError(
                    f"starts with a {encoding.upper()} byte-order mark but "
                    f"is not {encoding.upper()} text; save it as plain "
                    "(ASCII) text, or export it again."
                ) from None
    try:
        raw.decode("utf-8")
        return raw
    except UnicodeDecodeError:
        return raw.decode("latin-1").encode("utf-8")


def _signed_volume(vertices: np.ndarray, faces: np.ndarray) -> float:
    """The volume (m^3, in file units cubed) a closed, outward-oriented surface encloses, by
    the divergence theorem (trimesh's ``volume`` also divides by it, with a warning when
    it is 0)."""
    v0, v1, v2 = (vertices[faces[:, k]] for k in range(3))
    return float(np.einsum("ij,ij->i", v0, np.cross(v1, v2)).sum()) / 6.0


# (vertices, faces, boundary edge count, unmatched, note) of a mesh file (_read_mesh)
MeshData = tuple[np.ndarray, np.ndarray, int, int, str | None]


@functools.lru_cache(maxsize=16)
def _read_mesh(path: str, stamp: tuple[int, int]) -> MeshData:
    """(vertices, faces, boundary edge count, unmatched, note) of a mesh file; ``stamp``
    (size, mtime) invalidates the cache when the file changes. ``note``: what the reading
    had to decide (a binary STL's wrong count), or None."""
    import trimesh

    raw = Path(path).read_bytes()
    kind = Path(path).suffix.lower()[1:]
    note = None
    if not raw.strip():
        raise MeshFileError(
            "holds no triangles: the file is empty; export the closed "
            "surface of the solid as STL or OBJ."
        )
    if kind == "obj" or _has_bom(raw):
        raw = _text_bytes(raw)
    if kind == "stl":
        raw, note = _stl_bytes(raw)
        if _is_ascii_stl(raw):
            raw = _text_bytes(raw)
    # unprocessed first, and quietly: trimesh's constructor checks the stored normals
    # against the corners, arithmetic that warns on inf or nan coordinates; such a file is
    # refused right below, before its vertices are merged
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
        # force="mesh" gives a Trimesh (or raises); trimesh's annotation says Geometry
        loaded = trimesh.load(io.BytesIO(raw), file_type=kind, force="mesh", process=False)
        mesh = cast("trimesh.Trimesh", loaded)
    if not np.isfinite(np.asarray(mesh.vertices, dtype=float)).all():
        return np.asarray(mesh.vertices, dtype=float), np.zeros((1, 3), np.int64), 0, 0, note
    # a binary STL's triangles share no vertex until equal corners are merged: exactly
    # equal ones (writers repeat a corner's coordinates bit for bit), not trimesh's
    # merge_vertices, which rounds the coordinates to integers of 1e-8 units and so breaks
    # (int64 overflow) beyond about 1e10 file units
    vertices, shared = np.unique(
        np.asarray(mesh.vertices, dtype=float), axis=0, return_inverse=True
    )
    faces = shared.reshape(-1)[np.asarray(mesh.faces, dtype=np.int64).reshape(-1, 3)]
    # a triangle with a repeated corner (after merging equal vertices) has no area and
    # no solid angle: it is no part of the surface, and its edge from a corner to itself
    # would count as an open edge
    faces = faces[
        (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])
    ]
    if len(faces) == 0:
        return vertices, faces, 0, 0, note
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    boundary = len(trimesh.grouping.group_rows(mesh.edges_sorted, require_count=1))
    oriented = boundary == 0 and mesh.is_winding_consistent
    if oriented and _signed_volume(vertices, faces) < 0:
        faces = faces[:, ::-1]  # inside out: turn the triangles to face outwards
    unmatched = 0 if oriented or boundary else 1
    return vertices, faces, boundary, unmatched, note


def _read(path: Path, key: str, shown: str) -> MeshData:
    """_read_mesh, with what the file system and trimesh raise as the user's message."""
    if path.is_dir():
        _refuse(
            key,
            f"{shown} is a folder, not a file; give the path of an STL or OBJ file "
            "(relative paths are taken from the case file's folder).",
        )
    if not path.exists():
        _refuse(
            key,
            f"{shown} does not exist (relative paths are taken from the case file's "
            "folder); give the path of an STL or OBJ file.",
        )
    if path.suffix.lower() not in (".stl", ".obj"):
        _refuse(
            key,
            f"{shown} is not an STL or OBJ file (its name ends in "
            f"{path.suffix or 'nothing'!r}); export the surface as .stl or .obj.",
        )
    try:
        stat = path.stat()
        return _read_mesh(str(path.resolve()), (stat.st_size, stat.st_mtime_ns))
    except MeshFileError as err:
        _refuse(key, f"{shown} {err}")
    except OSError as err:
        _refuse(
            key,
            f"{shown} cannot be read ({err.strerror or err}); check the file's "
            "permissions, or give another path.",
        )
    except Exception as err:  # trimesh raises many kinds on a bad file
        _refuse(
            key,
            f"{shown} cannot be read as a triangle mesh ({type(err).__name__}: "
            f"{err}); export it again from your CAD tool as STL or OBJ.",
        )


def load_mesh(
    path: str | Path,
    scale: float = 1.0,
    translate: Any = (0.0, 0.0, 0.0),
    key: str = "mesh",
    shown: str | None = None,
) -> Mesh:
    """A closed Mesh from an STL or OBJ file (read by trimesh): file units times ``scale``
    are metres, then moved by ``translate`` (m). ValueError, naming ``key``, for a file that
    is missing, unreadable, empty, not a closed surface or enclosing no volume. ``shown``:
    the path as the user wrote it, for messages.

    Read as the file is, not as its writer may have meant it: ASCII text of any encoding
    (names aside, STL and OBJ are ASCII), and a binary STL whose header count disagrees
    with its size by the triangles it holds, when that is unambiguous (``_stl_bytes``; the
    mesh's ``notes`` then say so, and the run prints them); refused otherwise."""
    path = Path(path)
    shown = repr(str(shown if shown is not None else path))
    vertices, faces, boundary, unmatched, note = _read(path, key, shown)
    said = f" ({note})" if note else ""
    if len(faces) == 0:
        _refuse(
            key,
            f"{shown} holds no triangles{said} (an empty or non-triangle file, or "
            "only triangles with no area); export the closed surface of the solid as "
            "STL or OBJ.",
        )
    if not np.isfinite(vertices).all():
        _refuse(
            key,
            f"{shown} holds coordinates that are not numbers (nan or inf){said}; "
            "export it again from your CAD tool.",
        )
    if boundary:
        _refuse(
            key,
            f"{shown} is not a closed surface{said}: {boundary} boundary edges "
            "(edges of only one triangle), so its inside is not defined; close the mesh "
            "in your CAD tool or with trimesh.repair.fill_holes, and check it with "
            "trimesh.load(path).is_watertight.",
        )
    if unmatched:
        _refuse(
            key,
            f"{shown} is closed but its triangles are not consistently oriented"
            f"{said} (neighbours list their shared edge in the same direction); fix the "
            "normals in your CAD tool or with trimesh.repair.fix_normals.",
        )
    with np.errstate(over="ignore", invalid="ignore"):  # checked next, named in the error
        v = vertices * float(scale) + np.asarray(translate, dtype=float)
    _check_extent(key, shown, scale, vertices, v, faces)
    mesh = Mesh(v, faces)
    mesh.notes = [f"{key}.path = {shown}: {note}"] if note else []
    return mesh


def _check_extent(
    key: str, shown: str, scale: float, vertices: np.ndarray, v: np.ndarray, faces: np.ndarray
) -> None:
    """A mesh that encloses no volume (flat, or all its corners at one point; measured in
    the file's units, a tiny scale aside), or whose coordinates times ``scale`` leave the
    floating-point range, is refused: its inside is empty, and every size measured from it
    (an obstacle's thickness) would be 0."""
    extent = vertices.max(axis=0) - vertices.min(axis=0)
    volume = abs(_signed_volume(vertices, faces))
    if not (np.all(extent > 0) and volume > 1e-12 * float(extent.max()) ** 3):
        size = " x ".join(f"{e:.4g}" for e in extent)
        _refuse(
            key,
            f"{shown} encloses no volume: its corners span {size} (file units), "
            "flat or a single point, so it has no inside; export the closed surface of "
            "the solid.",
        )
    with np.errstate(over="ignore", invalid="ignore"):
        scaled = vertices * float(scale)
    if not (np.isfinite(scaled).all() and np.all(scaled.max(axis=0) > scaled.min(axis=0))):
        raise ValueError(
            f"{key}.scale = {scale:g} takes the coordinates of {shown} (up to "
            f"{np.abs(vertices).max():.4g} file units) beyond what a floating-point number "
            "holds; give the factor from the file's units to metres (1: metres, 0.001: "
            "millimetres)."
        )
    if not (np.isfinite(v).all() and np.all(v.max(axis=0) > v.min(axis=0))):
        raise ValueError(
            f"{key}.translate moves {shown} (up to {np.abs(scaled).max():.4g} m across) so "
            "far that its coordinates lose its shape; give the shift (m) that places it in "
            "the domain."
        )
