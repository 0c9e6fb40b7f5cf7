"""Points against a triangle mesh (3D): generalised winding number and nearest distance.

Brute force over the triangles for each point, parallel over points in ``CHUNKS`` fixed
chunks (``parallel``), so results do not depend on the thread count. Lengths in metres.
``mpmflow.shapes.Mesh`` calls these on the points inside the mesh's bounding box only.
"""

import math

import numpy as np
from numba import njit, prange

from .parallel import CHUNKS


@njit(cache=True, inline="always")
def _solid_angle(ax, ay, az, bx, by, bz, cx, cy, cz):
    """Signed solid angle (sr) of the triangle (a, b, c), vertices relative to the point:
    Van Oosterom & Strackee (1983), tan(Omega / 2) = a.(b x c) / (|a||b||c| + (a.b)|c| +
    (a.c)|b| + (b.c)|a|)."""
    la = math.sqrt(ax * ax + ay * ay + az * az)
    lb = math.sqrt(bx * bx + by * by + bz * bz)
    lc = math.sqrt(cx * cx + cy * cy + cz * cz)
    det = ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx)
    den = (la * lb * lc + (ax * bx + ay * by + az * bz) * lc
           + (ax * cx + ay * cy + az * cz) * lb + (bx * cx + by * cy + bz * cz) * la)
    return 2.0 * math.atan2(det, den)


@njit(cache=True)
def _triangle_distance2(px, py, pz, v0, v1, v2):
    """Squared distance from p to the triangle (v0, v1, v2): the closest point by the
    Voronoi regions of its vertices, edges and face (Ericson, Real-Time Collision
    Detection, 5.1.5)."""
    abx, aby, abz = v1[0] - v0[0], v1[1] - v0[1], v1[2] - v0[2]
    acx, acy, acz = v2[0] - v0[0], v2[1] - v0[1], v2[2] - v0[2]
    apx, apy, apz = px - v0[0], py - v0[1], pz - v0[2]
    d1 = abx * apx + aby * apy + abz * apz
    d2 = acx * apx + acy * apy + acz * apz
    if d1 <= 0.0 and d2 <= 0.0:  # vertex v0
        return apx * apx + apy * apy + apz * apz
    bpx, bpy, bpz = px - v1[0], py - v1[1], pz - v1[2]
    d3 = abx * bpx + aby * bpy + abz * bpz
    d4 = acx * bpx + acy * bpy + acz * bpz
    if d3 >= 0.0 and d4 <= d3:  # vertex v1
        return bpx * bpx + bpy * bpy + bpz * bpz
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:  # edge v0 v1
        t = d1 / (d1 - d3)
        qx, qy, qz = apx - t * abx, apy - t * aby, apz - t * abz
        return qx * qx + qy * qy + qz * qz
    cpx, cpy, cpz = px - v2[0], py - v2[1], pz - v2[2]
    d5 = abx * cpx + aby * cpy + abz * cpz
    d6 = acx * cpx + acy * cpy + acz * cpz
    if d6 >= 0.0 and d5 <= d6:  # vertex v2
        return cpx * cpx + cpy * cpy + cpz * cpz
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:  # edge v0 v2
        t = d2 / (d2 - d6)
        qx, qy, qz = apx - t * acx, apy - t * acy, apz - t * acz
        return qx * qx + qy * qy + qz * qz
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:  # edge v1 v2
        t = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        ex, ey, ez = v2[0] - v1[0], v2[1] - v1[1], v2[2] - v1[2]
        qx, qy, qz = bpx - t * ex, bpy - t * ey, bpz - t * ez
        return qx * qx + qy * qy + qz * qz
    denom = 1.0 / (va + vb + vc)  # inside the face
    v = vb * denom
    w = vc * denom
    qx = apx - abx * v - acx * w
    qy = apy - aby * v - acy * w
    qz = apz - abz * v - acz * w
    return qx * qx + qy * qy + qz * qz


@njit(cache=True, parallel=True)
def winding_numbers(points, v0, v1, v2, normals, tol, tree, centre, radius, dipole, far,
                    winding, on_surface):
    """Generalised winding number of the mesh (triangles v0[t], v1[t], v2[t], unit normals)
    at every point: the sum of the triangles' signed solid angles over 4 pi, 1 inside a
    closed outward-oriented mesh, 0 outside, and close to those near small defects (a
    missing triangle changes it only near the hole). ``on_surface[p]``: the point lies
    within ``tol`` (m) of a triangle, where the sum itself is undetermined.

    The fast winding number of Barill et al. (2018), to first order: a binary tree over the
    spatially sorted triangles, node k = (first triangle, end, left child, right child) in
    ``tree[k]`` (children -1 at a leaf), each with a bounding sphere (centre, radius) and its
    area-weighted normal sum ``dipole``. A node farther than ``far`` times its radius from
    the point adds its far field dipole . (centre - p) / |centre - p|^3 (the solid angle of
    a small patch) instead of its triangles' exact sum; the error is of order (radius /
    distance)^2 of that node's part, far below the 1/2 threshold."""
    n = points.shape[0]
    nchunks = min(CHUNKS, max(n, 1))
    inv = 1.0 / (4.0 * math.pi)
    for c in prange(nchunks):
        stack = np.empty(256, dtype=np.int64)
        for p in range(c * n // nchunks, (c + 1) * n // nchunks):
            px, py, pz = points[p, 0], points[p, 1], points[p, 2]
            total = 0.0
            near = False
            stack[0] = 0
            top = 1
            while top > 0:
                top -= 1
                k = stack[top]
                dx, dy, dz = centre[k, 0] - px, centre[k, 1] - py, centre[k, 2] - pz
                d2 = dx * dx + dy * dy + dz * dz
                reach = far * radius[k]
                if d2 > reach * reach:
                    total += (dipole[k, 0] * dx + dipole[k, 1] * dy
                              + dipole[k, 2] * dz) / (d2 * math.sqrt(d2))
                    continue
                if tree[k, 2] >= 0:
                    stack[top] = tree[k, 2]
                    stack[top + 1] = tree[k, 3]
                    top += 2
                    continue
                for t in range(tree[k, 0], tree[k, 1]):
                    ax, ay, az = v0[t, 0] - px, v0[t, 1] - py, v0[t, 2] - pz
                    total += _solid_angle(ax, ay, az, v1[t, 0] - px, v1[t, 1] - py,
                                          v1[t, 2] - pz, v2[t, 0] - px, v2[t, 1] - py,
                                          v2[t, 2] - pz)
                    plane = ax * normals[t, 0] + ay * normals[t, 1] + az * normals[t, 2]
                    if abs(plane) <= tol and not near:
                        near = _triangle_distance2(px, py, pz, v0[t], v1[t],
                                                   v2[t]) <= tol * tol
            winding[p] = total * inv
            on_surface[p] = near


@njit(cache=True, parallel=True)
def nearest_distances(points, v0, v1, v2, centres, radii, out):
    """Distance (m) from every point to the nearest triangle. A triangle whose bounding
    sphere (centre, radius) lies farther than the nearest found so far is skipped."""
    n = points.shape[0]
    m = v0.shape[0]
    nchunks = min(CHUNKS, max(n, 1))
    for c in prange(nchunks):
        for p in range(c * n // nchunks, (c + 1) * n // nchunks):
            px, py, pz = points[p, 0], points[p, 1], points[p, 2]
            best = math.inf
            for t in range(m):
                dx, dy, dz = centres[t, 0] - px, centres[t, 1] - py, centres[t, 2] - pz
                reach = math.sqrt(dx * dx + dy * dy + dz * dz) - radii[t]
                if reach > 0.0 and reach * reach >= best:
                    continue
                d2 = _triangle_distance2(px, py, pz, v0[t], v1[t], v2[t])
                if d2 < best:
                    best = d2
            out[p] = math.sqrt(best)
