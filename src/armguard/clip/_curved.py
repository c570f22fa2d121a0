"""Curved obstacles as the clipping paper's primitives: short segments and ruled surfaces.

Smith, §IV: "Line segments or planar polygons are the primitive elements of each object model
tested for interference with the clipping polyhedron.  Thus, a general curve is first
approximated with a series of short line segments ...  A surface can be checked ... by ruling the
surface with a set of curves ... or by approximating the surface as a set of polygons ... the
curve spacing must be small enough that the clipping polyhedron cannot penetrate the ruled volume
to any significant extent without intersecting a curve."

The paper leaves "significant" open; here it is a stated length, the *chord tolerance* ``tol``
(m, default ``Tolerances.clip_chord``), and the approximation is **circumscribed**: it contains
the curved shape, so clipping it never misses a contact with the shape.  Its price is the
*band*: every point of the approximation lies within ``band <= tol`` of the shape, so an
INTERSECTED answer may be a false alarm only where the shape is within ``band`` of the guard.

**Cylinder** (radius ``r``, half length ``h``): each cap circle becomes ``n`` short segments
tangent to it (the circumscribed ``n``-gon, apothem ``r``); the lateral surface is ruled by the
``n`` generator lines through the rim vertices, and each strip between two neighbouring rulings
is a planar rectangle; the caps are the two ``n``-gons.  That is the right prism over the
circumscribed ``n``-gon.  A chord of angle ``θ = 2π / n`` on radius ``r`` has sagitta
``r (1 − cos(θ/2))`` — how far an *inscribed* polygon's chords dip inside the circle — and the
circumscribed polygon's vertices stand ``r (sec(θ/2) − 1)`` outside it (the larger of the two,
by a factor ``sec(θ/2)``).  :func:`chord_sides` picks the smallest ``n`` with
``r (sec(π/n) − 1) <= tol``; the band is exactly that (the farthest points are the rim vertices,
radially out).

**Sphere, Capsule**: latitude rings of points on the surface (``n`` per ring, ``⌈n/4⌉`` per
quarter meridian on each cap; a capsule's lateral surface is ruled between its two equators), the
hull's faces each pushed out along their normal until they touch the shape (the plane at the
shape's support value: contains the shape), and the polytope those planes bound.  Its band is
measured, not bounded: the largest distance of a vertex from the shape (the distance to a convex
shape is convex, so its maximum over the polytope is at a vertex); ``n`` grows until it is
``<= tol``.

Both approximations also give the **inscribed** polytope (every point inside the shape: the
cylinder's ``n``-gon prism with its vertices *on* the circles, chords dipping ``r (1 − cos(π/n))``
inside; the hull of the round shapes' surface points), for callers that bracket the shape.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import HalfspaceIntersection

from .._errors import ClipError, GeometryError
from .._tolerance import DEFAULT_TOLERANCES
from ..geometry import Capsule, ConvexPolyhedron, Cylinder, Prism, Sphere
from ._guard import _closest_on_segment, _surface_points

__all__ = ["CURVED", "chord_sides", "circumscribed_band", "curved_polytopes"]

CURVED = (Cylinder, Sphere, Capsule)
"""The curved shapes an :class:`Obstacle` approximates."""


def circumscribed_band(radius: float, n: int) -> float:
    """``r (sec(π/n) − 1)`` (m): how far the vertices of the ``n``-gon circumscribed about a
    circle of radius ``r`` stand outside it (chord angle ``θ = 2π/n``)."""
    return radius * (1.0 / math.cos(math.pi / n) - 1.0)


def chord_sides(radius: float, tol: float, max_sides: int = DEFAULT_TOLERANCES.max_prism_sides) -> int:
    """The smallest ``n >= 3`` with :func:`circumscribed_band` ``(r, n) <= tol``.

    Closed form ``n = ⌈π / acos(r / (r + tol))⌉``, then checked (and stepped) in floating point.
    Raises ClipError when it takes more than ``max_sides`` (``Tolerances.max_prism_sides``)."""
    r, tol = float(radius), float(tol)
    if not (r > 0.0 and math.isfinite(r)) or not (tol > 0.0 and math.isfinite(tol)):
        raise ClipError(f"chord_sides: radius and tolerance must be finite and > 0, got {radius!r}, {tol!r}")
    n = max(3, math.ceil(math.pi / math.acos(r / (r + tol))))
    while n > 3 and circumscribed_band(r, n - 1) <= tol:
        n -= 1
    while circumscribed_band(r, n) > tol:
        n += 1
    if n > max_sides:
        raise ClipError(
            f"chord_sides: a chord tolerance of {tol:g} m on radius {r:g} m needs {n} sides, more than "
            f"{max_sides} (Tolerances.max_prism_sides); give a coarser tolerance"
        )
    return n


def _round_polytopes(shape, tol: float, max_sides: int) -> tuple[ConvexPolyhedron, ConvexPolyhedron, float]:
    if isinstance(shape, Sphere):
        p0 = p1 = np.asarray(shape.center, float)
    else:
        p0, p1 = np.asarray(shape.p0, float), np.asarray(shape.p1, float)
    r = float(shape.radius)
    if r <= 0.0:
        raise ClipError(f"Obstacle.from_shape: a {type(shape).__name__} of radius 0 is a segment or a point: give Obstacle.segment")
    c = 0.5 * (p0 + p1)
    n = max(8, chord_sides(r, tol, max_sides))
    while True:
        inner = ConvexPolyhedron(_surface_points(p0, p1, r, n, max(1, math.ceil(n / 4))))
        P = inner.planes
        # each face pushed out to the shape's support plane along its normal: the bounded region contains the shape
        h = np.maximum(P[:, :3] @ p0, P[:, :3] @ p1) + r
        hs = np.hstack([P[:, :3], -h[:, None]])  # scipy's A x + b <= 0
        verts = HalfspaceIntersection(hs, c).intersections
        band = float(np.max(np.linalg.norm(verts - _closest_on_segment(verts, p0, p1), axis=1) - r))
        if band <= tol:
            return ConvexPolyhedron(verts), inner, max(band, 0.0)
        if n >= max_sides:
            raise ClipError(
                f"Obstacle.from_shape: a chord tolerance of {tol:g} m on a {type(shape).__name__} of radius {r:g} m "
                f"needs more than {max_sides} points per ring (Tolerances.max_prism_sides); give a coarser tolerance"
            )
        n = min(max_sides, math.ceil(1.25 * n))


def curved_polytopes(shape, tol: float | None = None, *, max_sides: int = DEFAULT_TOLERANCES.max_prism_sides):
    """``(outer, inner, band)`` for a Cylinder, Sphere or Capsule (in the shape's frame).

    ``outer`` (ConvexPolyhedron) contains the shape and lies within ``band <= tol`` m of it;
    ``inner`` (ConvexPolyhedron) lies inside the shape.  ``tol`` (m, > 0) the chord tolerance,
    default ``Tolerances.clip_chord``.  See the module docstring."""
    tol = DEFAULT_TOLERANCES.clip_chord if tol is None else float(tol)
    if not (tol > 0.0 and math.isfinite(tol)):
        raise ClipError(f"curved_polytopes: the chord tolerance must be finite and > 0 m, got {tol!r}")
    try:
        if isinstance(shape, Cylinder):
            n = chord_sides(shape.radius, tol, max_sides)
            outer = Prism(shape.center, shape.rotation, shape.radius, shape.half_length, n).as_polyhedron()
            inner = Prism(shape.center, shape.rotation, shape.radius * math.cos(math.pi / n), shape.half_length, n)
            return outer, inner.as_polyhedron(), circumscribed_band(shape.radius, n)
        if isinstance(shape, (Sphere, Capsule)):
            return _round_polytopes(shape, tol, max_sides)
    except GeometryError as exc:
        raise ClipError(f"curved_polytopes: {exc}") from exc
    raise ClipError(f"curved_polytopes: expected a Cylinder, Sphere or Capsule, got {type(shape).__name__}")
