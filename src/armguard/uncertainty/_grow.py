"""Shapes grown by a distance: conservative outer approximations of the Minkowski sum with a ball.

``grow_shape(shape, g)`` returns a shape of the same placement that contains ``shape ⊕ B(g)``
(every point within ``g`` m of the shape):

==================  ===================================================================
Sphere, Capsule     radius ``+ g`` — exactly the Minkowski sum
Box                 half extents ``+ g`` — every face plane pushed out by ``g`` (contains the
                    sum; exceeds it near edges and corners by up to ``(√3 − 1) g``)
Prism               apothem and half length ``+ g`` — the same face offset
Cylinder            radius and half length ``+ g`` — contains the sum (a point within ``g``
                    of the cylinder is within ``g`` of its axis segment's slab and of its
                    radius); exceeds it at the rims by up to ``(√2 − 1) g``
ConvexPolyhedron    every face plane pushed out by ``g``, the vertices of the offset planes'
                    intersection (``scipy.spatial.HalfspaceIntersection``)
Polygon             a flat slab: its plane pushed by ``± g`` and each edge by ``g`` in the plane
==================  ===================================================================

A polytope's face offset ``{x : n_i · x ≤ d_i + g}`` contains the Minkowski sum because the sum's
support along each face normal ``n_i`` is ``d_i + g``; it is never smaller, so a verification
against grown shapes is conservative.
"""

from __future__ import annotations

import numpy as np

from .._errors import UncertaintyError
from ..geometry import Box, Capsule, ConvexPolyhedron, Cylinder, Polygon, Prism, Sphere

__all__ = ["grow_shape"]


def _offset_planes(planes: np.ndarray, interior: np.ndarray) -> ConvexPolyhedron:
    """The polyhedron ``{x : n · x <= d}`` of ``planes (F, 4)`` rows ``[n, d]`` (``interior``
    strictly inside)."""
    from scipy.spatial import HalfspaceIntersection

    hs = np.hstack([planes[:, :3], -planes[:, 3:4]])  # scipy: A x + b <= 0
    pts = HalfspaceIntersection(hs, interior).intersections
    return ConvexPolyhedron(pts)


def grow_shape(shape, g: float):
    """``shape`` grown by ``g`` m (>= 0), containing ``shape ⊕ B(g)`` (see the module table)."""
    g = float(g)
    if not (g >= 0.0 and np.isfinite(g)):
        raise UncertaintyError(f"grow_shape: expected a finite growth >= 0 m, got {g!r}")
    if g == 0.0:
        return shape
    if isinstance(shape, Sphere):
        return Sphere(shape.center, shape.radius + g)
    if isinstance(shape, Capsule):
        return Capsule(shape.p0, shape.p1, shape.radius + g)
    if isinstance(shape, Box):
        return Box(shape.center, shape.half_extents + g, shape.rotation)
    if isinstance(shape, Cylinder):
        return Cylinder(shape.center, shape.rotation, shape.radius + g, shape.half_length + g)
    if isinstance(shape, Prism):
        return Prism(shape.center, shape.rotation, shape.apothem + g, shape.half_length + g, shape.n_sides)
    if isinstance(shape, ConvexPolyhedron):
        planes = np.array(shape.planes, dtype=np.float64)
        planes[:, 3] += g
        return _offset_planes(planes, shape.inscribed_sphere().center)
    if isinstance(shape, Polygon):
        v = np.asarray(shape.vertices, dtype=np.float64)
        n = np.asarray(shape.normal, dtype=np.float64)
        c = v.mean(axis=0)
        rows = [np.r_[n, n @ c + g], np.r_[-n, -(n @ c) + g]]
        for i in range(len(v)):
            e = v[(i + 1) % len(v)] - v[i]
            out = np.cross(e, n)
            out /= np.linalg.norm(out)
            if out @ (c - v[i]) > 0.0:
                out = -out
            rows.append(np.r_[out, out @ v[i] + g])
        return _offset_planes(np.array(rows), c)
    raise UncertaintyError(f"grow_shape: cannot grow a {type(shape).__name__}")
