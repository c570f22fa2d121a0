"""The guarded test object ``VOL``: outer and inner convex polyhedra, outer and inner spheres.

Smith, Appendix A: ``RO`` / ``RI`` the radii of a circumscribed / inscribed sphere, ``CS`` the
origin of both, ``PO`` an outer object-enclosing and ``PI`` an inner object-enclosed convex
polyhedron, all in the object's own frame ``F(VOL)``.  A :class:`Guard` holds them for one
convex shape given in ``F(VOL)`` (a link shape in its link frame L):

================  ==========================================  ===================================
shape             ``PO(VOL)`` (encloses the shape)             ``PI(VOL)`` (enclosed by it)
================  ==========================================  ===================================
Box, Prism,       the shape's own hull (exact)                 ``PO`` shrunk about ``CS`` by
ConvexPolyhedron                                               ``inner_scale`` (convexity: every
                                                               ``CS + s (v - CS)`` is in the hull)
Sphere, Capsule   ``PI`` scaled about ``CS`` by ``1 / s``, with the hull of points *on* the shape's
                  ``s`` the largest factor whose every face     surface (latitude rings on each
                  plane still supports the shape (checked      cap; convexity puts their hull
                  face by face against the shape's support)    inside the shape)
Cylinder          the circumscribed ``n``-gon prism (apothem   ``PO`` shrunk about the centre by
                  ``r``; ``n`` from ``Tolerances.clip_chord``,  ``cos(π/n)``: the inscribed
                  :func:`._curved.chord_sides`)                 ``n``-gon, ``h cos(π/n)`` long
================  ==========================================  ===================================

``PI`` is always ``PO`` shrunk about ``CS`` (homothetic), so the shell between them splits into
one frustum per outer face (:mod:`._cells`).  ``CS`` is the shape's centre (the Chebyshev centre
of a polyhedron); ``RI`` is the largest ball about ``CS`` inside the shape; ``RO`` the smallest
ball about ``CS`` containing it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .._errors import ClipError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from ..geometry import Box, Capsule, ConvexPolyhedron, Cylinder, Prism, Sphere
from ._cells import CellKind, CellTree, build_cells

__all__ = ["Guard", "DEFAULT_INNER_SCALE", "DEFAULT_MAX_DEPTH", "DEFAULT_RINGS"]

DEFAULT_INNER_SCALE = 0.5
"""``PI`` of a polyhedral guard: its hull shrunk to this fraction about ``CS``.  The paper
leaves the inner polyhedron's choice to the modeller; at one half every one of the 8 steps is
exercised and the second level settles what step 8 leaves (the shell of a polyhedral guard is
inside the shape).  ``inner_scale=1.0`` makes ``PI = PO`` and step 7 decides every contact."""

DEFAULT_MAX_DEPTH = 2
"""Splits of a MIXED shell cell (only curved shapes have them) below the level-1 frustums."""

DEFAULT_RINGS = (8, 2)
"""Curved guards' inner polytope: ``(points per ring, rings per quarter meridian)``."""


def _closest_on_segment(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    ab = b - a
    L2 = float(ab @ ab)
    if L2 == 0.0:
        return np.broadcast_to(a, p.shape).copy()
    t = np.clip((p - a) @ ab / L2, 0.0, 1.0)
    return a + t[..., None] * ab


class _Body:
    """The test object's convex shape in ``F(VOL)``: containment, support and normals."""

    def __init__(self, shape) -> None:
        self.shape = shape
        if isinstance(shape, Cylinder):
            self.kind, self.p0, self.p1, self.r = "cylinder", shape.center, shape.center, shape.radius
            self.R, self.h = shape.rotation, shape.half_length
        elif isinstance(shape, Sphere):
            self.kind, self.p0, self.p1, self.r = "round", shape.center, shape.center, shape.radius
        elif isinstance(shape, Capsule):
            self.kind, self.p0, self.p1, self.r = "round", shape.p0, shape.p1, shape.radius
        else:
            self.kind = "poly"
            self.poly = shape if isinstance(shape, ConvexPolyhedron) else shape.as_polyhedron()

    def outside(self, p: np.ndarray) -> np.ndarray:
        """``(n,)`` m: > 0 outside the shape (the signed distance for round shapes, the largest
        plane excess for polyhedra — both have the sign of the signed distance)."""
        p = np.atleast_2d(p)
        if self.kind == "round":
            return np.linalg.norm(p - _closest_on_segment(p, self.p0, self.p1), axis=-1) - self.r
        if self.kind == "cylinder":  # the larger of the radial and axial excesses
            loc = (p - self.p0) @ self.R
            return np.maximum(np.hypot(loc[:, 0], loc[:, 1]) - self.r, np.abs(loc[:, 2]) - self.h)
        P = self.poly.planes
        return np.max(p @ P[:, :3].T - P[:, 3], axis=1)

    def support(self, n: np.ndarray) -> float:
        """``max_{x in shape} n . x`` (m) for unit ``n``."""
        if self.kind == "round":
            return max(float(n @ self.p0), float(n @ self.p1)) + self.r
        if self.kind == "cylinder":
            return float(n @ self.shape.support(n))
        return float(np.max(self.poly.vertices @ n))

    def normal_toward(self, u: np.ndarray) -> np.ndarray:
        """Outward unit normal where the ray from the centre along unit ``u`` leaves the shape."""
        c = 0.5 * (self.p0 + self.p1) if self.kind != "poly" else self.poly.vertices.mean(axis=0)
        lo, hi = 0.0, 1.0
        while self.outside(c + hi * u)[0] <= 0.0:
            hi *= 2.0
        for _ in range(60):  # halvings of [lo, hi]: float64 resolution of the surface point
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if self.outside(c + mid * u)[0] <= 0.0 else (lo, mid)
        q = c + hi * u
        if self.kind == "round":
            g = q - _closest_on_segment(q[None], self.p0, self.p1)[0]
        elif self.kind == "cylinder":
            x, y, z = (q - self.p0) @ self.R
            rad = math.hypot(x, y)
            g = self.R @ ([x / rad, y / rad, 0.0] if rad - self.r >= abs(z) - self.h else [0.0, 0.0, math.copysign(1.0, z)])
        else:
            P = self.poly.planes
            g = P[int(np.argmax(q @ P[:, :3].T - P[:, 3])), :3].copy()
        return g / np.linalg.norm(g)

    def all_inside(self, verts: np.ndarray, tol: float) -> bool:
        """Is the convex hull of ``verts`` inside the shape (every vertex within ``tol``)?"""
        return bool(np.all(self.outside(verts) <= tol))

    def label(self, verts: np.ndarray, planes: np.ndarray, tol: float) -> int:
        """INSIDE / OUTSIDE / MIXED for the cell ``verts`` / ``planes`` (see :mod:`._cells`).

        OUTSIDE needs a plane with the cell on one side and the shape beyond ``tol`` on the
        other; the candidates are the cell's own planes and the direction from the shape's
        nearest core point to the cell's centroid (a certificate, not the exact distance: a
        cell it misses stays MIXED, which costs answers, never correctness)."""
        if self.all_inside(verts, tol):
            return CellKind.INSIDE
        for n, d in zip(planes[:, :3], planes[:, 3]):
            if -self.support(-n) >= d + tol:  # the shape lies beyond this face of the cell
                return CellKind.OUTSIDE
        g = verts.mean(axis=0)
        if self.kind == "round":
            q = _closest_on_segment(g[None], self.p0, self.p1)[0]
            n = g - q
            if np.linalg.norm(n) > 0.0:
                n = n / np.linalg.norm(n)
                if float(np.min(verts @ n)) >= self.support(n) + tol:
                    return CellKind.OUTSIDE
        return CellKind.MIXED


def _surface_points(p0: np.ndarray, p1: np.ndarray, r: float, n_ring: int, n_lat: int) -> np.ndarray:
    """Points on the surface of the capsule ``p0-p1`` of radius ``r`` (a sphere when they
    coincide): on each hemispherical cap ``n_lat`` latitude rings of ``n_ring`` points (the
    equator included, alternate rings offset by half a step) and the pole."""
    a = p1 - p0
    L = float(np.linalg.norm(a))
    a = a / L if L > 0.0 else np.array([0.0, 0.0, 1.0])
    e1 = np.cross(a, [1.0, 0.0, 0.0] if abs(a[0]) < 0.9 else [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(a, e1)
    pts = []
    for end, sgn in ((p1, 1.0), (p0, -1.0)):
        for j in range(n_lat):
            phi = j * (0.5 * math.pi) / n_lat
            th = (np.arange(n_ring) + 0.5 * (j % 2)) * (2.0 * math.pi / n_ring)
            ring = math.cos(phi) * (np.cos(th)[:, None] * e1 + np.sin(th)[:, None] * e2) + sgn * math.sin(phi) * a
            pts.append(end + r * ring)
        pts.append((end + sgn * r * a)[None])
    return np.vstack(pts)


@dataclass(frozen=True, eq=False)
class Guard:
    """A guarded test object ``VOL`` in its own frame ``F(VOL)`` (m).

    ``outer_planes (K, 4)`` / ``inner_planes (K', 4)``: ``PO(VOL)`` / ``PI(VOL)`` as outward
    ``[n, d]`` rows (``K' = 0``: ``PI`` undefined); ``outer`` / ``inner``: the same as
    ConvexPolyhedra when their vertices are known (``None`` for grown swept hulls); ``cs (3,)``
    ``CS(VOL)``; ``ro`` ``RO(VOL)``; ``ri`` ``RI(VOL)`` (``-1`` undefined); ``inner_scale`` the
    factor ``s`` with ``PI = CS + s (PO - CS)``; ``cells`` the second-level shell cells;
    ``shape`` the guarded convex shape (``None`` for a swept guard, whose test object is the
    swept volume).  Build with :meth:`from_shape`; :meth:`pack` gives the kernel tuple.
    """

    outer_planes: np.ndarray
    inner_planes: np.ndarray
    cs: np.ndarray
    ro: float
    ri: float
    inner_scale: float
    cells: CellTree
    outer: ConvexPolyhedron | None = None
    inner: ConvexPolyhedron | None = None
    shape: object = None
    _pack: tuple | None = field(default=None, repr=False)

    @classmethod
    def from_shape(
        cls,
        shape,
        *,
        inner_scale: float = DEFAULT_INNER_SCALE,
        max_depth: int = DEFAULT_MAX_DEPTH,
        rings: tuple[int, int] = DEFAULT_RINGS,
        tol: Tolerances = DEFAULT_TOLERANCES,
    ) -> "Guard":
        """The guard of one convex ``shape`` given in ``F(VOL)`` (see the module table).

        ``inner_scale`` in (0, 1]: ``PI`` of polyhedral shapes; ``max_depth`` >= 0: splits of
        MIXED shell cells; ``rings``: curved shapes' surface sampling.  Raises ClipError for a
        shape without volume (Polygon, zero radius)."""
        if not 0.0 < inner_scale <= 1.0:
            raise ClipError(f"Guard.from_shape: inner_scale must be in (0, 1], got {inner_scale!r}")
        if int(max_depth) != max_depth or max_depth < 0:
            raise ClipError(f"Guard.from_shape: max_depth must be an integer >= 0, got {max_depth!r}")
        if isinstance(shape, (Sphere, Capsule)):
            if shape.radius <= 0.0:
                raise ClipError(f"Guard.from_shape: a {type(shape).__name__} of radius 0 has no volume to guard")
            n_ring, n_lat = (int(x) for x in rings)
            if n_ring < 3 or n_lat < 1:
                raise ClipError(f"Guard.from_shape: rings must be (>= 3, >= 1), got {rings!r}")
            body = _Body(shape)
            cs = 0.5 * (body.p0 + body.p1)
            inner0 = ConvexPolyhedron(_surface_points(body.p0, body.p1, body.r, n_ring, n_lat))
            P = inner0.planes
            # largest s with every face of (inner0 scaled by 1/s about cs) supporting the shape
            s = min(
                (float(P[f, 3] - P[f, :3] @ cs)) / (body.support(P[f, :3]) - float(P[f, :3] @ cs)) for f in range(len(P))
            )
            outer = ConvexPolyhedron(cs + (inner0.vertices - cs) / s)
            ri = body.r
            ro = 0.5 * float(np.linalg.norm(body.p1 - body.p0)) + body.r
        elif isinstance(shape, Cylinder):
            from ._curved import chord_sides  # (_curved imports this module's surface sampling)

            body = _Body(shape)
            n = chord_sides(shape.radius, tol.clip_chord, tol.max_prism_sides)
            outer = Prism(shape.center, shape.rotation, shape.radius, shape.half_length, n).as_polyhedron()
            cs = np.asarray(shape.center, float)
            s = math.cos(math.pi / n)  # PO's vertices, at r / cos(pi/n), come in onto the circle
            ri = min(shape.radius, shape.half_length)
            ro = math.hypot(shape.radius, shape.half_length)
        elif isinstance(shape, (Box, Prism, ConvexPolyhedron)):
            body = _Body(shape)
            outer = body.poly
            cs = outer.inscribed_sphere().center
            s = float(inner_scale)
            ri = float(np.min(outer.planes[:, 3] - outer.planes[:, :3] @ cs))
            ro = float(np.max(np.linalg.norm(outer.vertices - cs, axis=1)))
        else:
            raise ClipError(
                f"Guard.from_shape: expected a Sphere, Capsule, Cylinder, Box, Prism or ConvexPolyhedron, got {type(shape).__name__}"
            )
        P = outer.planes
        inner_planes = np.hstack([P[:, :3], (P[:, :3] @ cs + s * (P[:, 3] - P[:, :3] @ cs))[:, None]])
        inner = ConvexPolyhedron(cs + s * (outer.vertices - cs))
        cells = build_cells(body, outer, cs, s, int(max_depth), tol.clip_plane)
        return cls(np.ascontiguousarray(P), inner_planes, np.asarray(cs, float), ro, ri, s, cells, outer, inner, shape)

    def pack(self) -> tuple:
        """The kernel tuple ``(outer_planes, inner_planes, cs, ro, ri, cell_planes, cell_off,
        cell_probe, cell_kind, child_off, child_idx, roots)`` (cached)."""
        if self._pack is None:
            c = self.cells
            tup = (
                np.array(self.outer_planes, dtype=np.float64),  # writable copies: one kernel type
                np.array(self.inner_planes, dtype=np.float64).reshape(-1, 4),
                np.array(self.cs, dtype=np.float64),
                float(self.ro),
                float(self.ri),
                np.array(c.planes, dtype=np.float64),
                c.off,
                np.array(c.probe, dtype=np.float64),
                c.kind,
                c.child_off,
                c.child_idx,
                c.roots,
            )
            object.__setattr__(self, "_pack", tup)
        return self._pack
