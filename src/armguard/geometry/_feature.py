"""Which feature of a shape a surface point lies on: the detector's "face / edge / vertex id".

Indices, per shape:

* ``Sphere``: ``SURFACE 0`` (radius 0: ``VERTEX 0``).
* ``Capsule``: ``SURFACE 0`` the cylindrical side, ``SURFACE 1`` / ``2`` the caps at ``p0`` /
  ``p1`` (a zero-length capsule: ``SURFACE 0``).  Radius 0 (a segment): ``VERTEX 0`` / ``1`` at
  ``p0`` / ``p1``, otherwise ``EDGE 0``.
* ``Box``: vertices index ``Box.vertices``; face ``2 i`` is the ``-axis_i`` face and ``2 i + 1``
  the ``+axis_i`` face; edges index :data:`BOX_EDGES` (pairs of vertex indices).
* ``Prism``: vertices index ``core_points`` (bottom ring ``0..n-1``, top ring ``n..2n-1``);
  face ``k < n`` is the side whose outward normal is at angle ``2 pi k / n`` about the axis,
  ``n`` the bottom and ``n + 1`` the top; edge ``k`` is bottom ``(k, k+1)``, ``n + k`` top
  ``(n+k, n+(k+1) % n)``, ``2n + k`` the vertical ``(k, n + k)``.
* ``ConvexPolyhedron``: its own ``vertices``, ``edges`` and ``faces``.
* ``Polygon``: vertex ``i``; edge ``i`` from vertex ``i`` to ``i + 1``; ``FACE 0`` the interior.
* ``Cylinder``: ``SURFACE 0`` the curved side; ``FACE 0`` / ``1`` the caps at ``p0`` / ``p1``
  (``-`` / ``+half_length`` along the axis); ``EDGE 0`` / ``1`` their rims (circles).

A vertex wins over an edge, an edge over a face, when the point is within
``tol.feature_distance`` of several.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np

from .._errors import GeometryError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from ._check import check_point
from ._cylinder import Cylinder
from ._shapes import _BOX_SIGNS, Box, Capsule, ConvexPolyhedron, Polygon, Prism, Shape, Sphere

__all__ = ["FeatureKind", "Feature", "feature_at", "BOX_EDGES"]


class FeatureKind(enum.Enum):
    """Kind of surface feature."""

    VERTEX = "vertex"
    EDGE = "edge"
    FACE = "face"
    SURFACE = "surface"  # a curved surface: a sphere, a capsule's side or cap


@dataclass(frozen=True)
class Feature:
    """A feature of a shape: ``kind`` and ``index`` into the shape's vertices / edges / faces."""

    kind: FeatureKind
    index: int

    def __str__(self) -> str:
        """``"face 6"``, ``"edge 3"``, ``"vertex 0"``, or ``"surface"`` for curved surfaces."""
        if self.kind is FeatureKind.SURFACE:
            return "surface"
        return f"{self.kind.value} {self.index}"

    def to_dict(self) -> dict:
        """``{"kind": "face" | "edge" | "vertex" | "surface", "index": int}``: the feature as data."""
        return {"kind": self.kind.value, "index": int(self.index)}


BOX_EDGES = np.array(
    [(i, j) for i in range(8) for j in range(i + 1, 8) if np.sum(_BOX_SIGNS[i] != _BOX_SIGNS[j]) == 1],
    dtype=np.int64,
)
"""``(12, 2) int64``: the box's edges as pairs of indices into ``Box.vertices``."""
BOX_EDGES.flags.writeable = False


def _point_segment(p, a, b) -> tuple[float, float]:
    d = b - a
    dd = float(d @ d)
    t = 0.0 if dd == 0.0 else float(np.clip((p - a) @ d / dd, 0.0, 1.0))
    return float(np.linalg.norm(p - (a + t * d))), t


def _point_segments(p, a, b) -> np.ndarray:
    """Distances ``(k,)`` from point ``p`` to the segments ``a[i]-b[i]`` (vectorised `_point_segment`)."""
    d = b - a
    dd = np.einsum("ij,ij->i", d, d)
    t = np.einsum("ij,ij->i", p - a, d)
    t = np.clip(np.divide(t, dd, out=np.zeros_like(t), where=dd > 0.0), 0.0, 1.0)
    r = p - (a + t[:, None] * d)
    return np.sqrt(np.einsum("ij,ij->i", r, r))


def _polytope_parts(shape):
    """(vertices (V, 3), edges (E, 2), planes (F, 4) [n, d] with n . x <= d inside)."""
    if isinstance(shape, Box):
        R, c, h = shape.rotation, shape.center, shape.half_extents
        planes = []
        for i in range(3):
            for s in (-1.0, 1.0):
                n = s * R[:, i]
                planes.append([*n, n @ c + h[i]])
        return shape.vertices, BOX_EDGES, np.array(planes)
    if isinstance(shape, Prism):
        n = shape.n_sides
        R, c = shape.rotation, shape.center
        ang = np.arange(n) * (2.0 * np.pi / n)
        normals = np.stack([np.cos(ang), np.sin(ang), np.zeros(n)], axis=1) @ R.T
        planes = [[*m, m @ c + shape.apothem] for m in normals]
        planes.append([*(-R[:, 2]), -R[:, 2] @ c + shape.half_length])
        planes.append([*R[:, 2], R[:, 2] @ c + shape.half_length])
        k = np.arange(n)
        edges = np.concatenate(
            [np.stack([k, (k + 1) % n], 1), np.stack([n + k, n + (k + 1) % n], 1), np.stack([k, n + k], 1)]
        )
        return shape.core_points, edges, np.array(planes)
    if isinstance(shape, ConvexPolyhedron):
        return shape.vertices, shape.edges, shape.planes
    raise TypeError  # pragma: no cover


_BOX_EDGE_INDEX = {(int(i), int(j)): k for k, (i, j) in enumerate(BOX_EDGES)}


def _box_feature(box: Box, p: np.ndarray, eps: float) -> Feature:
    """Closed form in the box frame; same numbering as :func:`_polytope_parts` (faces ``2 i + (s > 0)``,
    vertices as ``Box.vertices``, edges as ``BOX_EDGES``)."""
    local = box.rotation.T @ (p - box.center)
    excess = np.abs(local) - box.half_extents
    off = float(excess.max())
    if abs(off) > eps:
        raise GeometryError(f"p_W: {off:.3g} m off the Box's surface")
    on = np.abs(excess) <= eps  # axes on which the point is on a face plane
    sign = local > 0.0
    n_on = int(on.sum())
    if n_on == 1:
        i = int(np.argmax(on))
        return Feature(FeatureKind.FACE, 2 * i + int(sign[i]))
    bits = (4, 2, 1)  # Box.vertices order: x sign slowest, z fastest
    if n_on == 3:
        return Feature(FeatureKind.VERTEX, sum(b for b, sgn in zip(bits, sign) if sgn))
    free = int(np.argmin(on))  # the edge runs along the one axis not on a face plane
    base = sum(b for k, (b, sgn) in enumerate(zip(bits, sign)) if sgn and k != free)
    return Feature(FeatureKind.EDGE, _BOX_EDGE_INDEX[(base, base + bits[free])])


def feature_at(shape: Shape, p_W, tol: Tolerances = DEFAULT_TOLERANCES) -> Feature:
    """The feature of ``shape`` on which the surface point ``p_W`` ``(3,) float64, m`` lies.

    Raises GeometryError if ``p_W`` is farther than ``tol.feature_distance`` from the surface.
    """
    p = check_point(p_W, "p_W")
    eps = tol.feature_distance
    if isinstance(shape, Sphere):
        dist = float(np.linalg.norm(p - shape.center))
        if abs(dist - shape.radius) > eps:
            raise GeometryError(f"p_W: {dist - shape.radius:.3g} m off the sphere's surface")
        return Feature(FeatureKind.VERTEX if shape.radius == 0.0 else FeatureKind.SURFACE, 0)
    if isinstance(shape, Capsule):
        dist, t = _point_segment(p, shape.p0, shape.p1)
        if abs(dist - shape.radius) > eps:
            raise GeometryError(f"p_W: {dist - shape.radius:.3g} m off the capsule's surface")
        length = shape.length
        if shape.radius == 0.0:
            if np.linalg.norm(p - shape.p0) <= eps:
                return Feature(FeatureKind.VERTEX, 0)
            if np.linalg.norm(p - shape.p1) <= eps:
                return Feature(FeatureKind.VERTEX, 1)
            return Feature(FeatureKind.EDGE, 0)
        if length <= tol.length:
            return Feature(FeatureKind.SURFACE, 0)
        u = (shape.p1 - shape.p0) / length
        s = float((p - shape.p0) @ u)
        if s < -eps:
            return Feature(FeatureKind.SURFACE, 1)
        if s > length + eps:
            return Feature(FeatureKind.SURFACE, 2)
        return Feature(FeatureKind.SURFACE, 0)
    if isinstance(shape, Polygon):
        v = shape.vertices
        plane = abs(float(p @ shape.normal) - shape.offset)
        dv = np.linalg.norm(v - p, axis=1)
        if dv.min() <= eps:
            return Feature(FeatureKind.VERTEX, int(np.argmin(dv)))
        de = _point_segments(p, v, np.roll(v, -1, axis=0))
        if de.min() <= eps:
            return Feature(FeatureKind.EDGE, int(np.argmin(de)))
        q = p - (p @ shape.normal - shape.offset) * shape.normal
        inside = all(
            np.cross(v[(i + 1) % len(v)] - v[i], q - v[i]) @ shape.normal >= 0.0 for i in range(len(v))
        )
        if plane <= eps and inside:
            return Feature(FeatureKind.FACE, 0)
        raise GeometryError("p_W: not on the polygon")
    if isinstance(shape, Box):
        return _box_feature(shape, p, eps)
    if isinstance(shape, Cylinder):
        loc = shape.rotation.T @ (p - shape.center)
        rho = float(np.hypot(loc[0], loc[1]))
        dr = rho - shape.radius
        dz = abs(float(loc[2])) - shape.half_length
        off = float(np.hypot(max(dr, 0.0), max(dz, 0.0))) + min(max(dr, dz), 0.0)
        if abs(off) > eps:
            raise GeometryError(f"p_W: {off:.3g} m off the Cylinder's surface")
        end = int(loc[2] > 0.0)
        if abs(dr) <= eps and abs(dz) <= eps:
            return Feature(FeatureKind.EDGE, end)
        if abs(dz) <= eps:
            return Feature(FeatureKind.FACE, end)
        return Feature(FeatureKind.SURFACE, 0)
    if isinstance(shape, (Prism, ConvexPolyhedron)):
        v, edges, planes = _polytope_parts(shape)
        dv = np.linalg.norm(v - p, axis=1)
        if dv.min() <= eps:
            return Feature(FeatureKind.VERTEX, int(np.argmin(dv)))
        de = _point_segments(p, v[edges[:, 0]], v[edges[:, 1]])
        if de.min() <= eps:
            return Feature(FeatureKind.EDGE, int(np.argmin(de)))
        s = planes[:, :3] @ p - planes[:, 3]
        if abs(float(s.max())) <= eps:
            return Feature(FeatureKind.FACE, int(np.argmax(s)))
        raise GeometryError(f"p_W: {float(s.max()):.3g} m off the {type(shape).__name__}'s surface")
    raise GeometryError(f"shape: expected an armguard shape, got {type(shape).__name__}")
