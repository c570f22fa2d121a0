"""Slow, obviously-correct references for the fast kernels (plain NumPy, no numba, no GJK).

* Core distance by exact feature enumeration: every vertex against every vertex, edge and face
  of the other core, every edge against every edge and face (a segment crossing a face gives 0),
  plus vertex containment -- the minimum over all of them is the distance between two convex
  polytopes.  Segment-segment follows Hermes (seed ``001``): the interior stationary point when
  both parameters are inside, otherwise the minimum over the end-point cases; point-face follows
  Ranger §4 (project, test inside with the edge cross products, else the nearest edge).
* Penetration depth by exhaustive SAT over every face normal and every edge-edge cross product
  (no deduplication), plus the radii.
* ``sdf(p, shape)``: signed distance from a point to a shape's surface.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._shapes import Box, Capsule, ConvexPolyhedron, Polygon, Prism, Shape, Sphere

__all__ = ["Core", "core_of", "reference_distance", "sdf", "point_segment", "segment_segment"]


@dataclass(frozen=True)
class Core:
    """A polytopal core: vertices (n, 3), edges as index pairs, faces as (vertex indices, unit normal)."""

    vertices: np.ndarray
    edges: list
    faces: list
    radius: float
    solid: bool  # has volume (a point can be strictly inside)


def core_of(shape: Shape) -> Core:
    if isinstance(shape, Sphere):
        return Core(shape.center.reshape(1, 3), [], [], shape.radius, False)
    if isinstance(shape, Capsule):
        if np.array_equal(shape.p0, shape.p1):
            return Core(shape.p0.reshape(1, 3), [], [], shape.radius, False)
        return Core(np.stack([shape.p0, shape.p1]), [(0, 1)], [], shape.radius, False)
    if isinstance(shape, Polygon):
        n = len(shape.vertices)
        idx = np.arange(n)
        return Core(shape.vertices, [(i, (i + 1) % n) for i in range(n)], [(idx, shape.normal)], 0.0, False)
    if isinstance(shape, (Box, Prism)):
        shape = shape.as_polyhedron()
    if isinstance(shape, ConvexPolyhedron):
        faces = [(np.asarray(f), shape.planes[k, :3]) for k, f in enumerate(shape.faces)]
        return Core(shape.vertices, [tuple(e) for e in shape.edges], faces, 0.0, True)
    raise TypeError(type(shape).__name__)


def point_segment(p, a, b):
    """(distance, closest point) from ``p`` to segment ``a-b``."""
    d = b - a
    dd = d @ d
    t = 0.0 if dd == 0.0 else min(1.0, max(0.0, float((p - a) @ d / dd)))
    q = a + t * d
    return float(np.linalg.norm(p - q)), q


def segment_segment(a0, a1, b0, b1):
    """(distance, point on a, point on b): Hermes's interior solution or the end-point cases."""
    d1 = a1 - a0
    d2 = b1 - b0
    r = b0 - a0
    # normal equations of min |a0 + s d1 - b0 - t d2|^2 (Cramer's rule on the 2x2 system)
    m00, m01, m11 = float(d1 @ d1), -float(d1 @ d2), float(d2 @ d2)
    r0, r1 = float(r @ d1), -float(r @ d2)
    det = m00 * m11 - m01 * m01
    best = None
    if abs(det) > 1e-14 * max(1.0, m00 * m11):
        s = (r0 * m11 - m01 * r1) / det
        t = (m00 * r1 - m01 * r0) / det
        if 0.0 <= s <= 1.0 and 0.0 <= t <= 1.0:
            pa, pb = a0 + s * d1, b0 + t * d2
            best = (float(np.linalg.norm(pa - pb)), pa, pb)
    cands = []
    for p in (a0, a1):
        dist, q = point_segment(p, b0, b1)
        cands.append((dist, p, q))
    for p in (b0, b1):
        dist, q = point_segment(p, a0, a1)
        cands.append((dist, q, p))
    if best is not None:
        cands.append(best)
    return min(cands, key=lambda c: c[0])


def _point_polygon(p, V, n):
    """Ranger §4: (distance, closest point) from p to the convex polygon V (CCW about n)."""
    d_f = float((p - V.mean(axis=0)) @ n)
    q = p - d_f * n
    k = len(V)
    if all(np.cross(V[(i + 1) % k] - V[i], q - V[i]) @ n >= 0.0 for i in range(k)):
        return abs(d_f), q
    return min((point_segment(p, V[i], V[(i + 1) % k]) for i in range(k)), key=lambda c: c[0])


def _segment_polygon(a, b, V, n):
    """(distance, point on segment, point on polygon)."""
    c = V.mean(axis=0)
    sa = (a - c) @ n
    sb = (b - c) @ n
    if sa * sb <= 0.0 and sa != sb:
        x = a + (sa / (sa - sb)) * (b - a)
        k = len(V)
        if all(np.cross(V[(i + 1) % k] - V[i], x - V[i]) @ n >= 0.0 for i in range(k)):
            return 0.0, x, x
    cands = []
    for p in (a, b):
        dist, q = _point_polygon(p, V, n)
        cands.append((dist, p, q))
    k = len(V)
    for i in range(k):
        cands.append(segment_segment(a, b, V[i], V[(i + 1) % k]))
    return min(cands, key=lambda c: c[0])


def _inside(p, core: Core) -> bool:
    return core.solid and all((p - core.vertices[f[0]]) @ n <= 0.0 for f, n in core.faces)


def core_distance(A: Core, B: Core):
    """(distance, point on A's core, point on B's core) by feature enumeration."""
    cands = []
    for X, Y, swap in ((A, B, False), (B, A, True)):
        for p in X.vertices:
            if _inside(p, Y):
                cands.append((0.0, p, p, swap))
            for q in Y.vertices:
                cands.append((float(np.linalg.norm(p - q)), p, q, swap))
            for i, j in Y.edges:
                dist, q = point_segment(p, Y.vertices[i], Y.vertices[j])
                cands.append((dist, p, q, swap))
            for f, n in Y.faces:
                dist, q = _point_polygon(p, Y.vertices[f], n)
                cands.append((dist, p, q, swap))
        for i, j in X.edges:
            for f, n in Y.faces:
                dist, p, q = _segment_polygon(X.vertices[i], X.vertices[j], Y.vertices[f], n)
                cands.append((dist, p, q, swap))
    for i, j in A.edges:
        for k, m in B.edges:
            dist, p, q = segment_segment(A.vertices[i], A.vertices[j], B.vertices[k], B.vertices[m])
            cands.append((dist, p, q, False))
    dist, p, q, swap = min(cands, key=lambda c: c[0])
    return (dist, q, p) if swap else (dist, p, q)


def _sat_axes(A: Core, B: Core):
    axes = [n for _, n in A.faces] + [n for _, n in B.faces]
    for i, j in A.edges:
        for k, m in B.edges:
            u = np.cross(A.vertices[j] - A.vertices[i], B.vertices[m] - B.vertices[k])
            nu = np.linalg.norm(u)
            if nu > 1e-12 * np.linalg.norm(A.vertices[j] - A.vertices[i]) * np.linalg.norm(B.vertices[m] - B.vertices[k]):
                axes.append(u / nu)
    return axes


def reference_distance(a: Shape, b: Shape):
    """``(signed distance, p_WA, p_WB)`` by enumeration (separated) or exhaustive SAT (depth).

    For penetration only the depth is a reference value; the returned points are ``None``.
    """
    A, B = core_of(a), core_of(b)
    d, pa, pb = core_distance(A, B)
    if d > 0.0:
        n = (pb - pa) / d
        return d - A.radius - B.radius, pa + A.radius * n, pb - B.radius * n
    axes = _sat_axes(A, B)
    if not axes:
        return -(A.radius + B.radius), None, None
    depth = np.inf
    for u in axes:
        sa = A.vertices @ u
        sb = B.vertices @ u
        depth = min(depth, sa.max() - sb.min(), sb.max() - sa.min())
    return -(max(depth, 0.0) + A.radius + B.radius), None, None


def sdf(p, shape: Shape) -> float:
    """Signed distance (m) from point ``p (3,)`` to the surface of ``shape`` (< 0 inside)."""
    p = np.asarray(p, dtype=np.float64)
    C = core_of(shape)
    d, _, _ = core_distance(Core(p.reshape(1, 3), [], [], 0.0, False), C)
    if d == 0.0 and C.solid:
        return -min(float((C.vertices[f[0]] - p) @ n) for f, n in C.faces) - C.radius
    return d - C.radius
