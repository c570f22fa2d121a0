"""A mesh's vertices -> its convex hull, in O(N log N) time and O(N) memory.

A robot's collision meshes come with 10^3 to 10^6 vertices (example-robot-data's so101 has
meshes of 160 000); armguard uses their convex hulls.  :func:`mesh_hull` takes the (N, 3)
vertices and returns the hull, never allocating more than a few (N, 3) arrays:

1. every vertex must be finite (a NaN or an infinity is an error naming the vertex);
2. exact duplicates are dropped (a mesh file repeats each vertex for every triangle that uses
   it; Qhull is several times slower on the repeats): rows are ordered by a hash of their bits
   and a row equal to the one before it is dropped, so no distinct point is ever lost;
3. the best-fit plane comes from the SVD of the 3x3 triangular factor R of the centred points
   (``np.linalg.qr(..., mode="r")``: the same singular values and right singular vectors as the
   points themselves, without their N x N left factor);
4. points within ``Tolerances.planarity`` (scaled by the extent when it exceeds 1 m) of that
   plane are flat: their 2-D hull (Qhull) is a :class:`~armguard.geometry.Polygon`, unless they
   also lie on a line or a point (an error: no area, no volume);
5. otherwise the 3-D hull (Qhull, Barber, Dobkin & Huhdanpaa 1996, "The Quickhull algorithm
   for convex hulls", ACM TOMS 22(4)) of the points gives vertices and triangles.

:func:`mesh_polytope` goes one step further for a URDF's meshes: the 3-D hull's triangles are
merged into planar faces (as :class:`~armguard.geometry.ConvexPolyhedron` merges them), so the
one Qhull run gives both coal's ``Convex`` and armguard's polyhedron, the same vertices for both.

Qhull's own failures come back as :class:`~armguard.GeometryError`, never as ``QhullError``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._errors import GeometryError
from .._tolerance import DEFAULT_TOLERANCES

__all__ = ["MeshHull", "MeshPolytope", "mesh_hull", "mesh_polytope", "unique_rows"]


@dataclass(frozen=True)
class MeshHull:
    """The convex hull of a point set.

    ``vertices (V, 3) float64, m``: the hull's vertices (a subset of the input points);
    ``triangles (T, 3) int64``: Qhull's triangulation of the hull's surface (not consistently
    oriented), indices into ``vertices``; empty when ``flat``;
    ``flat``: the points are coplanar: ``vertices`` go counter-clockwise around the polygon.
    """

    vertices: np.ndarray
    triangles: np.ndarray
    flat: bool


_MIX = np.array([0x9E3779B97F4A7C15, 0xC2B2AE3D27D4EB4F, 0x165667B19E3779F9], dtype=np.uint64)


def unique_rows(p: np.ndarray) -> np.ndarray:
    """The distinct rows of ``p (N, 3) float64`` (first occurrences, in an arbitrary order).

    O(N log N) time, O(N) memory: rows are sorted by a 64-bit hash of their bits (a 1-D sort,
    unlike ``np.unique(axis=0)``'s lexicographic one) and a row equal to its predecessor is
    dropped.  Two distinct rows with the same hash may both stay (a duplicate left in is harmless
    to a hull); a distinct row is never dropped."""
    p = np.ascontiguousarray(p, dtype=np.float64)
    if len(p) < 2:
        return p
    bits = p.view(np.uint64)
    with np.errstate(over="ignore"):
        key = (bits[:, 0] * _MIX[0]) ^ (bits[:, 1] * _MIX[1]) ^ (bits[:, 2] * _MIX[2])
    s = p[np.argsort(key, kind="stable")]
    keep = np.empty(len(s), dtype=bool)
    keep[0] = True
    np.any(s[1:] != s[:-1], axis=1, out=keep[1:])
    return s[keep]


def _qhull(points: np.ndarray, what: str):
    from scipy.spatial import ConvexHull, QhullError

    try:
        return ConvexHull(points)
    except (QhullError, ValueError) as exc:
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise GeometryError(f"Qhull could not build the {what} hull of the vertices ({first})") from None


def mesh_hull(points, *, solid: bool = True) -> MeshHull:
    """The convex hull of ``points (N, 3)`` m (see the module docstring); raises GeometryError
    for non-finite points, fewer than three distinct points, or points on a line.

    ``solid=False``: points that are not flat come back as they are (the distinct ones, no
    triangles), for a caller that builds the 3-D hull itself (``ConvexPolyhedron``)."""
    hull, _ = _mesh_qhull(points, solid)
    return hull


@dataclass(frozen=True)
class MeshPolytope:
    """A mesh's hull as the shape armguard and coal both use, in the mesh's frame G.

    ``vertices (V, 3) float64, m``; ``flat``: a polygon (``vertices`` counter-clockwise around
    it, no faces); else a polyhedron with ``faces`` (tuple of ``int64`` loops into ``vertices``,
    counter-clockwise seen from outside), ``planes (F, 4)`` (``[n, d]``, inside ``n . x <= d``)
    and ``triangles (T, 3) int64`` (Qhull's triangulation, counter-clockwise about the outward
    normals), as :class:`~armguard.geometry.ConvexPolyhedron` keeps them."""

    vertices: np.ndarray
    faces: tuple
    planes: np.ndarray
    triangles: np.ndarray
    flat: bool


def mesh_polytope(points) -> MeshPolytope:
    """The hull of ``points (N, 3)`` m with its faces merged, from one Qhull run on the points:
    :func:`mesh_hull`'s hull, merged into planar faces as ``ConvexPolyhedron`` merges them
    (:func:`armguard.geometry._hull_faces.hull_faces`); the same errors as :func:`mesh_hull`, and
    a solid with no volume is an error as for ``ConvexPolyhedron``."""
    from ..geometry._hull_faces import hull_faces

    hull, qh = _mesh_qhull(points, True)
    if hull.flat:
        return _readonly_polytope(hull.vertices, (), np.zeros((0, 4)), np.zeros((0, 3), dtype=np.int64), True)
    h, p, A, c = qh
    scale = max(1.0, float(np.max(np.abs(A))))
    if h.volume <= DEFAULT_TOLERANCES.coplanar_volume * scale**3:
        raise GeometryError("the vertices are coplanar (hull volume 0)")
    used, faces, planes, tri = hull_faces(A, c, h.simplices, h.equations, h.neighbors, h.vertices,
                                          DEFAULT_TOLERANCES.planarity)
    return _readonly_polytope(p[used], tuple(faces), planes, tri, False)


def _readonly_polytope(vertices, faces, planes, tri, flat: bool) -> MeshPolytope:
    faces = tuple(f if isinstance(f, np.ndarray) and f.dtype == np.int64 else np.asarray(f, dtype=np.int64) for f in faces)
    arrays = [np.ascontiguousarray(vertices, dtype=np.float64), np.ascontiguousarray(planes, dtype=np.float64),
              np.ascontiguousarray(tri, dtype=np.int64), *faces]
    for a in arrays:
        a.flags.writeable = False
    return MeshPolytope(arrays[0], faces, arrays[1], arrays[2], flat)


def _mesh_qhull(points, solid: bool):
    """``(MeshHull, (qhull, p, A, c) or None)``: :func:`mesh_hull`, and when it built a 3-D hull,
    Qhull's hull of the distinct points ``p``, given to it as ``A = p - c``."""
    tol = DEFAULT_TOLERANCES
    p = np.asarray(points, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3:
        raise GeometryError(f"expected (N, 3) vertices, got an array of shape {p.shape}")
    finite = np.isfinite(p).all(axis=1)
    if not finite.all():
        bad = np.flatnonzero(~finite)
        raise GeometryError(f"{len(bad)} {'vertex' if len(bad) == 1 else 'vertices'} not finite (NaN or inf), the first is "
                            f"vertex {int(bad[0])} = {p[bad[0]].tolist()}")
    if len(p) == 0:
        raise GeometryError("the mesh has no vertices")
    big = np.abs(p).max(axis=1) > tol.max_magnitude  # as every length of a file: beyond it, the hull's arithmetic
    if big.any():                                     # overflows (1e300 read as "the vertices lie on a line")
        k = int(np.flatnonzero(big)[0])
        raise GeometryError(f"vertex {k} = {p[k].tolist()} is beyond {tol.max_magnitude:g} m (Tolerances.max_magnitude; "
                            "as scaled: a unit or scale error?)")
    p = unique_rows(p)
    ext = float(np.ptp(p, axis=0).max())
    if len(p) < 3 or ext <= tol.length:
        raise GeometryError(f"the vertices span {ext:.3g} m ({len(p)} distinct): no area and no volume "
                            "(a zero scale?)")
    c = p.mean(axis=0)
    A = p - c
    _, _s, vt = np.linalg.svd(np.linalg.qr(A, mode="r"))
    flat_tol = tol.planarity * max(1.0, ext)
    if float(np.max(np.abs(A @ vt[2]))) > flat_tol:
        if not solid:
            return MeshHull(p, np.zeros((0, 3), dtype=np.int64), False), None
        h = _qhull(A, "3-D")
        idx = np.asarray(h.vertices, dtype=np.int64)
        remap = np.full(len(p), -1, dtype=np.int64)
        remap[idx] = np.arange(len(idx))
        return MeshHull(p[idx], remap[np.asarray(h.simplices, dtype=np.int64)], False), (h, p, A, c)
    along = A @ vt[0]
    if float(np.max(np.linalg.norm(A - along[:, None] * vt[0], axis=1))) <= flat_tol:
        raise GeometryError(f"the vertices lie on a line ({ext:.3g} m long): no area and no volume")
    h = _qhull(A @ vt[:2].T, "2-D")
    return MeshHull(p[np.asarray(h.vertices, dtype=np.int64)], np.zeros((0, 3), dtype=np.int64), True), None
