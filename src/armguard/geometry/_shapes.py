"""Shapes in the world frame W, in metres.

Every shape is a *core* plus a *radius* (a sphere-swept convex set):

=================  ===========================  ======
shape              core                          radius
=================  ===========================  ======
Sphere             a point                       r
Capsule            a segment p0-p1 (Ranger link) r
Box (OBB)          the box itself                0
Prism (OBP)        its 2n vertices' hull         0
ConvexPolyhedron   the hull of its vertices      0
Polygon            the planar convex polygon     0
Cylinder           the solid cylinder (curved)   0
=================  ===========================  ======

so one signed-distance engine (closed forms where they exist, GJK otherwise, SAT for
penetration) serves every pair.  ``core_points`` lists the core's vertices, whose hull is
the core (a Cylinder, whose core is curved, lists a circumscribed prism's and is reached through
its exact support function: ``_cylinder``, ``_pair_cylinder``).  Shapes are immutable; their arrays are read-only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from .._errors import GeometryError
from .._tolerance import DEFAULT_TOLERANCES
from ._pack import attach_packed, face_edges, unique_pairs
from ._hull_faces import merge_hull_faces
from ._check import check_nonnegative, check_point, check_points, check_pose, check_rotation

_EPS = float(np.finfo(np.float64).eps)

__all__ = ["Shape", "Sphere", "Capsule", "Box", "Prism", "ConvexPolyhedron", "Polygon", "CoreKind"]


class CoreKind:
    """Integer codes for a shape's core, as the kernels see it."""

    POINT = 0
    SEGMENT = 1
    BOX = 2
    POLYTOPE = 3
    CYLINDER = 4


def _readonly(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a, dtype=np.float64)
    a.flags.writeable = False
    return a


class Shape:
    """Base class of the armguard shapes (not instantiated directly)."""

    core_kind: ClassVar[int]

    @property
    def core_points(self) -> np.ndarray:  # pragma: no cover - overridden
        """``(n, 3) float64, m``: vertices of the core, whose convex hull is the core."""
        raise NotImplementedError

    @property
    def core_radius(self) -> float:
        """Radius swept around the core (m); 0 for polytopes."""
        return 0.0

    def support(self, direction) -> np.ndarray:
        """``(3,) float64, m``: a point of the shape farthest along ``direction`` (W).

        Slow, obviously-correct reference used by tests: max over core vertices plus radius.
        """
        d = np.asarray(direction, dtype=np.float64)
        pts = self.core_points
        p = pts[int(np.argmax(pts @ d))]
        n = np.linalg.norm(d)
        if self.core_radius > 0.0 and n > 0.0:
            p = p + self.core_radius * d / n
        return p

    def aabb(self) -> tuple[np.ndarray, np.ndarray]:
        """Axis-aligned bounding box in W: ``(lo, hi)``, each ``(3,) float64, m``."""
        pts = self.core_points
        r = self.core_radius
        return pts.min(axis=0) - r, pts.max(axis=0) + r

    def circumscribed_sphere(self) -> "Sphere":
        """A sphere containing the shape: centred on the core's vertex centroid (not minimal)."""
        pts = self.core_points
        c = 0.5 * (pts.min(axis=0) + pts.max(axis=0))
        rad = float(np.max(np.linalg.norm(pts - c, axis=1))) + self.core_radius
        return Sphere(c, rad)

    def inscribed_sphere(self) -> "Sphere":  # pragma: no cover - overridden
        """A sphere contained in the shape (the largest for boxes, prisms and polyhedra)."""
        raise NotImplementedError

    def transformed(self, X_AW) -> "Shape":  # pragma: no cover - overridden
        """The same shape moved by the rigid transform ``X_AW`` (4x4): points p_W become X_AW @ p_W."""
        raise NotImplementedError


def _apply(X: np.ndarray, p: np.ndarray) -> np.ndarray:
    return p @ X[:3, :3].T + X[:3, 3]


@dataclass(frozen=True, eq=False)
class Sphere(Shape):
    """A ball: ``center`` ``(3,)`` m, ``radius`` >= 0 m (radius 0 is a point)."""

    center: np.ndarray
    radius: float
    core_kind: ClassVar[int] = CoreKind.POINT

    def __post_init__(self) -> None:
        object.__setattr__(self, "center", check_point(self.center, "Sphere.center"))
        object.__setattr__(self, "radius", check_nonnegative(self.radius, "Sphere.radius"))
        attach_packed(self)

    @property
    def core_points(self) -> np.ndarray:
        return self.center.reshape(1, 3)

    @property
    def core_radius(self) -> float:
        return self.radius

    def circumscribed_sphere(self) -> "Sphere":
        return self

    def inscribed_sphere(self) -> "Sphere":
        return self

    def transformed(self, X_AW) -> "Sphere":
        X = check_pose(X_AW, "X_AW")
        return Sphere(_apply(X, self.center), self.radius)


@dataclass(frozen=True, eq=False)
class Capsule(Shape):
    """Ranger's link: the points within ``radius`` of the segment ``p0``-``p1`` (W, m).

    Radius 0 is a segment (an edge); ``p0 == p1`` is a sphere.
    """

    p0: np.ndarray
    p1: np.ndarray
    radius: float
    core_kind: ClassVar[int] = CoreKind.SEGMENT

    def __post_init__(self) -> None:
        object.__setattr__(self, "p0", check_point(self.p0, "Capsule.p0"))
        object.__setattr__(self, "p1", check_point(self.p1, "Capsule.p1"))
        object.__setattr__(self, "radius", check_nonnegative(self.radius, "Capsule.radius"))
        attach_packed(self)

    @property
    def core_points(self) -> np.ndarray:
        return _readonly(np.stack([self.p0, self.p1]))

    @property
    def core_radius(self) -> float:
        return self.radius

    @property
    def length(self) -> float:
        """Length of the axis segment (m)."""
        return float(np.linalg.norm(self.p1 - self.p0))

    def circumscribed_sphere(self) -> "Sphere":
        return Sphere(0.5 * (self.p0 + self.p1), 0.5 * self.length + self.radius)

    def inscribed_sphere(self) -> "Sphere":
        return Sphere(0.5 * (self.p0 + self.p1), self.radius)

    def transformed(self, X_AW) -> "Capsule":
        X = check_pose(X_AW, "X_AW")
        return Capsule(_apply(X, self.p0), _apply(X, self.p1), self.radius)


_BOX_SIGNS = np.array(
    [[sx, sy, sz] for sx in (-1.0, 1.0) for sy in (-1.0, 1.0) for sz in (-1.0, 1.0)], dtype=np.float64
)


@dataclass(frozen=True, eq=False)
class Box(Shape):
    """An oriented bounding box (OBB).

    ``center`` (3,) m in W; ``half_extents`` (3,) m, each > 0; ``rotation`` R_WB (3, 3) whose
    columns are the box axes in W (identity: axis-aligned).
    """

    center: np.ndarray
    half_extents: np.ndarray
    rotation: np.ndarray = field(default_factory=lambda: np.eye(3))
    core_kind: ClassVar[int] = CoreKind.BOX

    def __post_init__(self) -> None:
        object.__setattr__(self, "center", check_point(self.center, "Box.center"))
        h = check_point(self.half_extents, "Box.half_extents")
        if np.any(h <= 0.0):
            raise GeometryError(f"Box.half_extents: each must be > 0 (a box with volume), got {h.tolist()}")
        object.__setattr__(self, "half_extents", h)
        object.__setattr__(self, "rotation", check_rotation(self.rotation, "Box.rotation"))
        attach_packed(self)

    @property
    def core_points(self) -> np.ndarray:
        return _readonly(self.center + (_BOX_SIGNS * self.half_extents) @ self.rotation.T)

    @property
    def vertices(self) -> np.ndarray:
        """``(8, 3) float64, m``: the corners in W."""
        return self.core_points

    def circumscribed_sphere(self) -> "Sphere":
        return Sphere(self.center, float(np.linalg.norm(self.half_extents)))

    def inscribed_sphere(self) -> "Sphere":
        return Sphere(self.center, float(np.min(self.half_extents)))

    def transformed(self, X_AW) -> "Box":
        X = check_pose(X_AW, "X_AW")
        return Box(_apply(X, self.center), self.half_extents, X[:3, :3] @ self.rotation)

    def as_polyhedron(self) -> "ConvexPolyhedron":
        """The same box as a ConvexPolyhedron (6 faces, 12 edges, 8 vertices)."""
        return ConvexPolyhedron(self.vertices)


def _merge_hull_faces(points: np.ndarray, tol: float):
    """Merge a scipy hull's triangles into planar polygon faces, CCW seen from outside
    (:func:`._hull_faces.merge_hull_faces`).

    Returns ``(vertex_index_map, faces, planes, triangles)``: faces and the hull's (oriented)
    triangles index into the returned vertex set.
    """
    return merge_hull_faces(points, tol)


def _edges_of(faces) -> np.ndarray:
    a, b, _ = face_edges(faces)
    return np.ascontiguousarray(unique_pairs(np.minimum(a, b), np.maximum(a, b)), dtype=np.int64).reshape(-1, 2)


@dataclass(frozen=True, eq=False, init=False)
class ConvexPolyhedron(Shape):
    """The convex hull of ``vertices`` ``(n, 3)`` m in W (at least four non-coplanar points).

    Attributes computed at construction, as Ranger's ODDB stores them:

    * ``vertices`` ``(V, 3)``: the hull's vertices only (interior points are dropped);
    * ``faces``: tuple of ``int64`` index arrays, each a planar face's vertices counter-clockwise
      seen from outside;
    * ``planes`` ``(F, 4)``: ``[n, d]`` per face with unit outward ``n``; inside is ``n . x <= d``;
    * ``edges`` ``(E, 2)``: vertex index pairs.
    """

    vertices: np.ndarray
    faces: tuple
    planes: np.ndarray
    edges: np.ndarray
    core_kind: ClassVar[int] = CoreKind.POLYTOPE

    def __init__(self, vertices) -> None:
        pts = check_points(vertices, "ConvexPolyhedron.vertices", min_count=4)
        used, faces, planes, tri = _merge_hull_faces(pts, DEFAULT_TOLERANCES.planarity)
        self._set(pts[used], tuple(faces), planes, tri)

    def _set(self, vertices, faces, planes, tri=None) -> None:
        if tri is not None:  # the vertex graph's triangulation (_pack._build_adjacency): Qhull's
            tri = np.ascontiguousarray(tri, dtype=np.int64)
            tri.flags.writeable = False
            object.__setattr__(self, "_hull_tri", tri)
        for f in faces:
            f.flags.writeable = False
        object.__setattr__(self, "vertices", _readonly(vertices))
        object.__setattr__(self, "faces", tuple(faces))
        object.__setattr__(self, "planes", _readonly(planes))
        edges = _edges_of(faces)
        edges.flags.writeable = False
        object.__setattr__(self, "edges", edges)
        attach_packed(self)

    @classmethod
    def _from_parts(cls, vertices, faces, planes, tri=None) -> "ConvexPolyhedron":
        """A polyhedron of parts already merged (``faces``, ``planes`` and the hull's ``tri`` as
        :func:`._hull_faces.hull_faces` gives them): no hull is built again."""
        obj = cls.__new__(cls)
        obj._set(vertices, faces, planes, tri)
        return obj

    @property
    def core_points(self) -> np.ndarray:
        return self.vertices

    def face_polygon(self, i: int) -> "Polygon":
        """Face ``i`` as a Polygon (its normal is the outward face normal)."""
        return Polygon(self.vertices[self.faces[i]])

    def inscribed_sphere(self) -> "Sphere":
        """The largest inscribed sphere (Chebyshev centre, a small LP: max r with n_f . x + r <= d_f).

        Posed about the vertex centroid; HiGHS's dual simplex, then its interior-point method: the
        simplex once gave up on a regular pentagonal prism (status "Unknown", a feasible LP: x = 0,
        r = half its length), which the interior-point method solves."""
        from scipy.optimize import linprog

        c0 = self.vertices.mean(axis=0)
        A = np.hstack([self.planes[:, :3], np.ones((len(self.planes), 1))])
        b = self.planes[:, 3] - self.planes[:, :3] @ c0
        for method in ("highs-ds", "highs-ipm"):
            res = linprog(c=[0, 0, 0, -1], A_ub=A, b_ub=b, bounds=[(None, None)] * 3 + [(0, None)], method=method)
            if res.success:
                return Sphere(c0 + res.x[:3], max(0.0, float(res.x[3])))
        raise GeometryError(f"ConvexPolyhedron: inscribed sphere LP failed ({res.message})")  # pragma: no cover

    def transformed(self, X_AW) -> "ConvexPolyhedron":
        X = check_pose(X_AW, "X_AW")
        R = X[:3, :3]
        v = _apply(X, self.vertices)
        n = self.planes[:, :3] @ R.T
        d = self.planes[:, 3] + n @ X[:3, 3]
        planes = np.hstack([n, d[:, None]])
        return ConvexPolyhedron._from_parts(v, tuple(np.array(f) for f in self.faces), planes,
                                            getattr(self, "_hull_tri", None))


@dataclass(frozen=True, eq=False, init=False)
class Polygon(Shape):
    """A planar convex face: ``vertices`` ``(n, 3)`` m in W, n >= 3, in order around the face.

    ``normal`` follows Ranger §4: the average of ``A_i x A_(i+1)`` over the unit edge directions
    ``A_i``, so the vertices are counter-clockwise seen from the side ``normal`` points to.
    ``offset`` is ``normal . centroid`` (Ranger eq. 7).
    """

    vertices: np.ndarray
    normal: np.ndarray
    offset: float
    core_kind: ClassVar[int] = CoreKind.POLYTOPE

    def __init__(self, vertices) -> None:
        tol = DEFAULT_TOLERANCES
        pts = check_points(vertices, "Polygon.vertices", min_count=3)
        n_v = len(pts)
        A = np.roll(pts, -1, axis=0) - pts
        lengths = np.linalg.norm(A, axis=1)
        if np.any(lengths <= tol.length):
            raise GeometryError("Polygon.vertices: two consecutive vertices coincide")
        A = A / lengths[:, None]
        crosses = np.cross(A, np.roll(A, -1, axis=0))
        n = crosses.sum(axis=0)
        nn = np.linalg.norm(n)
        if nn <= tol.parallel:
            raise GeometryError("Polygon.vertices: the polygon has no area (collinear vertices)")
        n = n / nn
        c = pts.mean(axis=0)
        off = np.abs((pts - c) @ n)
        # its own extent, and the rounding of its coordinates far from W's origin (a flat square moved to 1e7 m was
        # refused: a coordinate's rounding, 9e-10 m there, is as large as the tolerance)
        if np.max(off) > tol.planarity * max(1.0, float(np.max(np.abs(pts - c)))) + 16.0 * _EPS * float(np.max(np.abs(pts))):
            raise GeometryError(
                f"Polygon.vertices: not planar (vertex {int(np.argmax(off))} is {float(np.max(off)):.3g} m off the plane)"
            )
        turn = crosses @ n
        if np.any(turn <= tol.parallel):
            bad = int(np.argmin(turn))
            raise GeometryError(
                f"Polygon.vertices: not strictly convex at vertex {(bad + 1) % n_v} "
                "(the vertices must go around a convex face, no reflex or straight angles)"
            )
        # A convex polygon turns through exactly 2*pi; more means a self-intersecting star.
        total = float(np.sum(np.arccos(np.clip(np.sum(A * np.roll(A, -1, axis=0), axis=1), -1.0, 1.0))))
        if total > 2.0 * math.pi + 1e-6:
            raise GeometryError("Polygon.vertices: the vertices wind more than once (self-intersecting)")
        object.__setattr__(self, "vertices", _readonly(pts))
        object.__setattr__(self, "normal", _readonly(n))
        object.__setattr__(self, "offset", float(n @ c))
        attach_packed(self)

    @property
    def core_points(self) -> np.ndarray:
        return self.vertices

    def inscribed_sphere(self) -> "Sphere":
        """A polygon has no volume: a zero-radius sphere at its vertex centroid."""
        return Sphere(self.vertices.mean(axis=0), 0.0)

    def transformed(self, X_AW) -> "Polygon":
        X = check_pose(X_AW, "X_AW")
        return Polygon(_apply(X, self.vertices))


@dataclass(frozen=True, eq=False)
class Prism(Shape):
    """An oriented bounding prism (OBP): a right prism over a regular ``n_sides``-gon.

    ``center`` (3,) m; ``rotation`` R_WP (3, 3), the prism axis is its third column and the first
    face normal its first column; ``apothem`` (m, > 0) is the centre-to-side distance of the
    cross-section; ``half_length`` (m, > 0) is half the axial length.  With ``n_sides`` even the
    prism is exactly the union of ``n_sides / 2`` OBBs (the JPL brief's octagon from four OBBs):
    see :meth:`as_boxes`; it is also a convex polyhedron: see :meth:`as_polyhedron`.
    """

    center: np.ndarray
    rotation: np.ndarray
    apothem: float
    half_length: float
    n_sides: int = 8
    core_kind: ClassVar[int] = CoreKind.POLYTOPE

    def __post_init__(self) -> None:
        object.__setattr__(self, "center", check_point(self.center, "Prism.center"))
        object.__setattr__(self, "rotation", check_rotation(self.rotation, "Prism.rotation"))
        a = check_nonnegative(self.apothem, "Prism.apothem")
        h = check_nonnegative(self.half_length, "Prism.half_length")
        if a <= 0.0 or h <= 0.0:
            raise GeometryError("Prism: apothem and half_length must be > 0 (a prism with volume)")
        if isinstance(self.n_sides, bool) or int(self.n_sides) != self.n_sides or self.n_sides < 3:
            raise GeometryError(f"Prism.n_sides: expected an integer >= 3, got {self.n_sides!r}")
        if self.n_sides > DEFAULT_TOLERANCES.max_prism_sides:
            raise GeometryError(f"Prism.n_sides: at most {DEFAULT_TOLERANCES.max_prism_sides} "
                                f"(Tolerances.max_prism_sides), got {self.n_sides}")
        object.__setattr__(self, "apothem", a)
        object.__setattr__(self, "half_length", h)
        object.__setattr__(self, "n_sides", int(self.n_sides))
        attach_packed(self)

    @property
    def core_points(self) -> np.ndarray:
        n = self.n_sides
        r = self.apothem / math.cos(math.pi / n)  # circumradius of the cross-section
        ang = (np.arange(n) + 0.5) * (2.0 * math.pi / n)
        ring = np.stack([r * np.cos(ang), r * np.sin(ang), np.zeros(n)], axis=1)
        local = np.vstack([ring + [0, 0, -self.half_length], ring + [0, 0, self.half_length]])
        return _readonly(self.center + local @ self.rotation.T)

    def as_polyhedron(self) -> ConvexPolyhedron:
        """The prism as a ConvexPolyhedron (n + 2 faces, 2n vertices)."""
        return ConvexPolyhedron(self.core_points)

    def as_boxes(self) -> tuple[Box, ...]:
        """The prism as the union of ``n_sides / 2`` OBBs (requires an even ``n_sides``).

        Box ``j`` spans two opposite sides: its first axis is rotated by ``j * 2 pi / n`` about
        the prism axis, half extents ``(apothem, apothem * tan(pi / n), half_length)``.
        """
        n = self.n_sides
        if n % 2:
            raise GeometryError(f"Prism.as_boxes: needs an even number of sides, got {n}")
        k = n // 2
        half_side = self.apothem * math.tan(math.pi / n)
        boxes = []
        for j in range(k):
            t = j * 2.0 * math.pi / n
            Rz = np.array([[math.cos(t), -math.sin(t), 0.0], [math.sin(t), math.cos(t), 0.0], [0.0, 0.0, 1.0]])
            boxes.append(Box(self.center, [self.apothem, half_side, self.half_length], self.rotation @ Rz))
        return tuple(boxes)

    def circumscribed_sphere(self) -> "Sphere":
        r = self.apothem / math.cos(math.pi / self.n_sides)
        return Sphere(self.center, math.hypot(r, self.half_length))

    def inscribed_sphere(self) -> "Sphere":
        return Sphere(self.center, min(self.apothem, self.half_length))

    def transformed(self, X_AW) -> "Prism":
        X = check_pose(X_AW, "X_AW")
        return Prism(_apply(X, self.center), X[:3, :3] @ self.rotation, self.apothem, self.half_length, self.n_sides)
