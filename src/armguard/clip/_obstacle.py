"""Obstacles ``OB`` as the paper's primitives: line segments and planar convex polygons.

"Line segments or planar polygons are the primitive elements of each object model tested for
interference with the clipping polyhedron" (Smith, §IV).  A convex solid (Box, Prism,
ConvexPolyhedron) is its faces as polygons — its edges are the polygons' boundaries, so clipping
them as segments would add nothing — plus its planes, which let ``COLLIDE`` see a clipping volume
wholly inside the solid.  A curved obstacle (Cylinder, Sphere, Capsule) is, as §IV says, short
segments along its curves and the ruled strips between them: a *circumscribed* polytope within
the chord tolerance ``Tolerances.clip_chord`` of the shape (:mod:`._curved`).  Clipping it never
misses a contact with the shape (CLEAR is a proof about the shape); INTERSECTED proves contact
with the polytope, so about the shape it proves only that it comes within ``Obstacle.band`` of
the guard.  A curve (a wire, a path) is :meth:`Obstacle.polyline`.

Bounding volumes, all in the obstacle's frame ``F(OB)`` (m):

* ``CS(OB)``, ``RO(OB)``: the vertices' bounding-box centre and the farthest vertex from it;
* ``RI(OB)`` (solids): the largest ball about ``CS`` inside the solid (undefined, -1, when ``CS``
  is not strictly inside — never for a convex solid — and for segments and polygons);
* ``PO(OB)``: for obstacles with more than ``bounds_min_vertices`` vertices, the oriented box of
  the vertices' principal axes (it encloses every vertex, so the hull); otherwise undefined (the
  paper: "If the obstacle is not very detailed, all of its bounding volumes except the enclosing
  sphere may be left undefined");
* ``PI(OB)`` (solids with ``PO``): the hull of the vertices extreme along the 13 directions of
  the box's axes, face and body diagonals (a hull of the solid's own vertices: inside it).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .._errors import ClipError, GeometryError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from ..geometry import Box, Capsule, ConvexPolyhedron, Polygon, Prism, Sphere
from ._curved import CURVED, curved_polytopes

__all__ = ["Obstacle", "DEFAULT_BOUNDS_MIN_VERTICES"]

DEFAULT_BOUNDS_MIN_VERTICES = 24
"""An obstacle with more vertices than this gets ``PO(OB)`` / ``PI(OB)`` (a box has 8, a
16-sided prism 32): below it, clipping the obstacle itself costs about as much as its bounds."""

_EMPTY_GEOM = (
    np.zeros((0, 3)),
    np.zeros((0, 2), dtype=np.int64),
    np.zeros(1, dtype=np.int64),
    np.zeros(0, dtype=np.int64),
    np.zeros((0, 4)),
)


def _geom(verts, segs=(), polys=(), solid=None) -> tuple:
    verts = np.array(verts, dtype=np.float64).reshape(-1, 3)  # a writable copy: one kernel type
    segs = np.ascontiguousarray(np.asarray(segs, dtype=np.int64).reshape(-1, 2))
    off = np.concatenate([[0], np.cumsum([len(p) for p in polys])]).astype(np.int64)
    idx = np.concatenate([np.asarray(p, dtype=np.int64) for p in polys]) if len(polys) else np.zeros(0, dtype=np.int64)
    solid = np.zeros((0, 4)) if solid is None else np.array(solid, dtype=np.float64).reshape(-1, 4)
    return (verts, segs, off, np.ascontiguousarray(idx), solid)


def _solid_geom(poly: ConvexPolyhedron) -> tuple:
    return _geom(poly.vertices, (), [np.asarray(f) for f in poly.faces], poly.planes)


@dataclass(frozen=True, eq=False)
class Obstacle:
    """An obstacle ``OB`` in its frame ``F(OB)`` (m); pose it with ``X_W_OB`` at check time.

    ``geom``: the kernel tuple ``(verts (V, 3), segs (S, 2), poly_off (P + 1,), poly_idx,
    solid (F, 4))`` of :mod:`._kernels`; ``po`` / ``pi``: the same for ``PO(OB)`` / ``PI(OB)``
    (``V == 0``: undefined); ``cs (3,)``, ``ro``, ``ri`` (-1: undefined) the spheres; ``shape``
    the geometry shape it came from (the oracle's operand), ``name`` a label; ``band`` (m) the
    largest distance of a point of the clipped primitives from ``shape`` — 0 for exact
    primitives, at most the chord tolerance for a curved shape's circumscribed polytope (an
    INTERSECTED answer may then be a false alarm where the shape is within ``band`` of the guard).
    """

    geom: tuple
    po: tuple
    pi: tuple
    cs: np.ndarray
    ro: float
    ri: float
    shape: object = None
    name: str = ""
    band: float = 0.0
    _pack: tuple | None = field(default=None, repr=False)

    @property
    def n_vertices(self) -> int:
        return int(self.geom[0].shape[0])

    def pack(self) -> tuple:
        """The kernel tuple ``(geom, po, pi, cs, ro, ri)`` (cached)."""
        if self._pack is None:
            object.__setattr__(self, "_pack", (self.geom, self.po, self.pi, np.asarray(self.cs, float), float(self.ro), float(self.ri)))
        return self._pack

    @staticmethod
    def _spheres(verts: np.ndarray, solid: np.ndarray | None) -> tuple[np.ndarray, float, float]:
        cs = 0.5 * (verts.min(axis=0) + verts.max(axis=0))
        ro = float(np.max(np.linalg.norm(verts - cs, axis=1)))
        ri = -1.0
        if solid is not None:
            m = float(np.min(solid[:, 3] - solid[:, :3] @ cs))
            ri = m if m > 0.0 else -1.0
        return cs, ro, ri

    @classmethod
    def segment(cls, p0, p1, *, name: str = "") -> "Obstacle":
        """A line segment ``p0 -> p1`` (each ``(3,)`` m in ``F(OB)``)."""
        v = np.array([p0, p1], dtype=np.float64)
        if v.shape != (2, 3) or not np.all(np.isfinite(v)):
            raise ClipError(f"Obstacle.segment: expected two finite 3-vectors, got {v.shape}")
        cs, ro, _ = cls._spheres(v, None)
        return cls(_geom(v, [(0, 1)]), _EMPTY_GEOM, _EMPTY_GEOM, cs, ro, -1.0, None, name)

    @classmethod
    def polyline(cls, points, *, closed: bool = False, name: str = "") -> "Obstacle":
        """A curve as short segments (§IV): ``points (n, 3)`` m in ``F(OB)``, joined in order
        (and the last to the first when ``closed``).  The segments are the obstacle: sample a
        curved wire finely enough for its purpose (a chord of angle ``θ`` on radius ``r`` is off
        the arc by its sagitta ``r (1 - cos(θ/2))``)."""
        v = np.array(points, dtype=np.float64)
        if v.ndim != 2 or v.shape[1] != 3 or len(v) < 2 or not np.all(np.isfinite(v)):
            raise ClipError(f"Obstacle.polyline: expected (n >= 2, 3) finite points, got shape {v.shape}")
        n = len(v)
        segs = [(i, i + 1) for i in range(n - 1)] + ([(n - 1, 0)] if closed and n > 2 else [])
        cs, ro, _ = cls._spheres(v, None)
        return cls(_geom(v, segs), _EMPTY_GEOM, _EMPTY_GEOM, cs, ro, -1.0, None, name)

    @classmethod
    def polygon(cls, vertices, *, name: str = "") -> "Obstacle":
        """A planar convex polygon (``(n, 3)`` m in ``F(OB)``, in order; checked by
        ``armguard.geometry.Polygon``)."""
        try:
            poly = Polygon(vertices)
        except GeometryError as exc:
            raise ClipError(f"Obstacle.polygon: {exc}") from exc
        cs, ro, _ = cls._spheres(poly.vertices, None)
        return cls(_geom(poly.vertices, (), [np.arange(len(poly.vertices))]), _EMPTY_GEOM, _EMPTY_GEOM, cs, ro, -1.0, poly, name)

    @classmethod
    def from_shape(
        cls,
        shape,
        *,
        name: str = "",
        bounds_min_vertices: int = DEFAULT_BOUNDS_MIN_VERTICES,
        chord_tol: float | None = None,
        tol: Tolerances = DEFAULT_TOLERANCES,
    ) -> "Obstacle":
        """An obstacle from an ``armguard.geometry`` shape in ``F(OB)``: Polygon (one polygon);
        Box, Prism, ConvexPolyhedron (a solid: its faces and planes, with ``PO`` / ``PI`` when it
        has more than ``bounds_min_vertices`` vertices); Cylinder, Sphere, Capsule (the
        circumscribed polytope within ``chord_tol`` m of the shape, default
        ``tol.clip_chord``, as a solid; ``band`` says how far it reaches; a radius-0 capsule
        is its segment).  Raises ClipError for anything else."""
        band = 0.0
        if isinstance(shape, Polygon):
            return cls.polygon(shape.vertices, name=name)
        if isinstance(shape, Capsule) and shape.radius == 0.0:
            ob = cls.segment(shape.p0, shape.p1, name=name)
            return cls(ob.geom, ob.po, ob.pi, ob.cs, ob.ro, ob.ri, shape, name)
        if isinstance(shape, Sphere) and shape.radius == 0.0:
            ob = cls.segment(shape.center, shape.center, name=name)
            return cls(ob.geom, ob.po, ob.pi, ob.cs, ob.ro, ob.ri, shape, name)
        if isinstance(shape, (Box, Prism)):
            poly = shape.as_polyhedron()
        elif isinstance(shape, ConvexPolyhedron):
            poly = shape
        elif isinstance(shape, CURVED):
            poly, _, band = curved_polytopes(shape, tol.clip_chord if chord_tol is None else chord_tol,
                                             max_sides=tol.max_prism_sides)
        else:
            raise ClipError(
                f"Obstacle.from_shape: clipping tests segments and polygons; a {type(shape).__name__} is not one "
                "(give a Box, Prism, ConvexPolyhedron, Polygon, Cylinder, Sphere or Capsule)"
            )
        cs, ro, ri = cls._spheres(poly.vertices, poly.planes)
        po = pi = _EMPTY_GEOM
        if len(poly.vertices) > bounds_min_vertices:
            po, pi = _bounds(poly)
        return cls(_solid_geom(poly), po, pi, cs, ro, ri, shape, name, float(band))

    @classmethod
    def polyhedron(cls, vertices, *, name: str = "", bounds_min_vertices: int = DEFAULT_BOUNDS_MIN_VERTICES) -> "Obstacle":
        """The convex hull of ``vertices (n, 3)`` m in ``F(OB)`` as a solid obstacle."""
        try:
            poly = ConvexPolyhedron(vertices)
        except GeometryError as exc:
            raise ClipError(f"Obstacle.polyhedron: {exc}") from exc
        return cls.from_shape(poly, name=name, bounds_min_vertices=bounds_min_vertices)


def _bounds(poly: ConvexPolyhedron) -> tuple[tuple, tuple]:
    """``PO(OB)`` (principal-axes box) and ``PI(OB)`` (hull of 13-direction extreme vertices)."""
    v = poly.vertices
    mean = v.mean(axis=0)
    _, _, vt = np.linalg.svd(v - mean, full_matrices=False)
    R = vt.T
    if np.linalg.det(R) < 0.0:
        R[:, 2] = -R[:, 2]
    loc = (v - mean) @ R
    lo, hi = loc.min(axis=0), loc.max(axis=0)
    half = np.maximum(0.5 * (hi - lo), DEFAULT_TOLERANCES.length * max(1.0, float(np.max(np.abs(v)))))
    box = Box(mean + R @ (0.5 * (lo + hi)), half, R)
    dirs = []
    for a in (-1, 0, 1):
        for b in (-1, 0, 1):
            for c in (-1, 0, 1):
                if (a, b, c) > (0, 0, 0):
                    dirs.append(R @ np.array([a, b, c], dtype=float))
    dirs = np.array(dirs)
    proj = v @ dirs.T
    pick = np.unique(np.concatenate([np.argmax(proj, axis=0), np.argmin(proj, axis=0)]))
    try:
        pi = _solid_geom(ConvexPolyhedron(v[pick]))
    except GeometryError:  # extreme vertices coplanar (a flat solid): leave PI(OB) undefined
        pi = _EMPTY_GEOM
    return _solid_geom(box.as_polyhedron()), pi
