"""coal geometries <-> armguard shapes, placed in a frame.

``shape_from_coal(geometry, X_FG)`` gives the armguard shape of a coal geometry whose frame G
is at ``X_FG`` in frame F, and a representation note when the two are not the same set of
points (none today: capsules, spheres, boxes, cylinders and convex meshes all map exactly; a
cylinder is an exact :class:`armguard.geometry.Cylinder`).  ``coal_from_shape`` is the inverse,
used for bodies a scene file adds (a Cylinder maps to ``coal.Cylinder``).
"""

from __future__ import annotations

import numpy as np

from .._errors import SceneError
from ..geometry import Box, Capsule, ConvexPolyhedron, Cylinder, Polygon, Prism, Sphere
from ._hull import MeshPolytope, mesh_hull

__all__ = ["shape_from_coal", "coal_from_shape", "convex_hull", "convex_of_polytope", "shape_of_polytope",
           "CYLINDER_PRISM_SIDES"]

CYLINDER_PRISM_SIDES = 16
"""Sides of the prism that circumscribes a cylinder where a caller wants a polytope for it
(apothem = radius; :data:`armguard.geometry.CYLINDER_HULL_SIDES`): the shapes themselves are
exact cylinders."""


def shape_from_coal(g, X_FG: np.ndarray):
    """``(shape in F, note)`` for the coal geometry ``g`` at ``X_FG`` (4, 4); note "" if exact."""
    import coal

    R, t = X_FG[:3, :3], X_FG[:3, 3]
    if isinstance(g, coal.Capsule):
        h = float(g.halfLength)
        return Capsule(t - h * R[:, 2], t + h * R[:, 2], float(g.radius)), ""
    if isinstance(g, coal.Sphere):
        return Sphere(t, float(g.radius)), ""
    if isinstance(g, coal.Box):
        return Box(t, np.asarray(g.halfSide, dtype=np.float64), R), ""
    if isinstance(g, coal.Cylinder):
        return Cylinder(t, R, float(g.radius), float(g.halfLength)), ""
    if isinstance(g, coal.ConvexBase):
        v = np.asarray(g.points(), dtype=np.float64).reshape(-1, 3) if callable(g.points) else np.asarray(g.points)
        hull = mesh_hull(v @ R.T + t, solid=False)  # ConvexPolyhedron builds the 3-D hull
        return (Polygon(hull.vertices) if hull.flat else ConvexPolyhedron(hull.vertices)), ""
    raise SceneError(f"coal geometry {type(g).__name__} has no armguard shape (expected capsule, sphere, box, "
                     "cylinder or convex mesh)")


def coal_from_shape(shape):
    """``(coal geometry, X_SG (4, 4))``: the coal geometry of an armguard shape given in frame S."""
    import coal

    X = np.eye(4)
    if isinstance(shape, Sphere):
        X[:3, 3] = shape.center
        return coal.Sphere(float(shape.radius)), X
    if isinstance(shape, Capsule):
        axis = shape.p1 - shape.p0
        L = float(np.linalg.norm(axis))
        X[:3, 3] = 0.5 * (shape.p0 + shape.p1)
        if L > 0:
            z = axis / L
            a = np.array([1.0, 0, 0]) if abs(z[0]) < 0.9 else np.array([0, 1.0, 0])
            x = np.cross(a, z)
            x /= np.linalg.norm(x)
            X[:3, :3] = np.column_stack([x, np.cross(z, x), z])
        return coal.Capsule(float(shape.radius), L), X
    if isinstance(shape, Box):
        X[:3, :3] = shape.rotation
        X[:3, 3] = shape.center
        return coal.Box(*(2.0 * np.asarray(shape.half_extents))), X
    if isinstance(shape, Cylinder):
        X[:3, :3] = shape.rotation
        X[:3, 3] = shape.center
        return coal.Cylinder(float(shape.radius), 2.0 * float(shape.half_length)), X
    if isinstance(shape, (ConvexPolyhedron, Prism, Polygon)):
        pts = np.asarray(shape.as_polyhedron().vertices if isinstance(shape, Prism) else shape.vertices, dtype=np.float64)
        return convex_hull(pts), X
    raise SceneError(f"shape {type(shape).__name__} has no coal geometry")


def convex_hull(pts: np.ndarray):
    """A coal.Convex of the points' hull (:func:`~armguard.model._hull.mesh_hull`: O(N log N)
    time, O(N) memory); a flat polygon becomes two triangle fans, both sides."""
    hull = mesh_hull(pts)
    return _coal_convex(hull.vertices, hull.triangles, hull.flat)


def convex_of_polytope(mp: MeshPolytope):
    """The coal.Convex of a mesh's hull (:func:`~armguard.model._hull.mesh_polytope`), in its frame:
    the same vertices and triangles as the armguard shape of :func:`shape_of_polytope`."""
    return _coal_convex(mp.vertices, mp.triangles, mp.flat)


def shape_of_polytope(mp: MeshPolytope, X_FG: np.ndarray):
    """The armguard shape (in F) of a mesh's hull given in its frame G at ``X_FG (4, 4)``: a
    Polygon, or a ConvexPolyhedron of the hull's merged faces moved, not built again."""
    R, t = X_FG[:3, :3], X_FG[:3, 3]
    v = mp.vertices @ R.T + t
    if mp.flat:
        return Polygon(v)
    n = mp.planes[:, :3] @ R.T
    d = mp.planes[:, 3] + n @ t
    return ConvexPolyhedron._from_parts(v, mp.faces, np.hstack([n, d[:, None]]), mp.triangles)


def _coal_convex(v: np.ndarray, tris: np.ndarray, flat: bool):
    import coal

    if flat:
        k = np.arange(1, len(v) - 1, dtype=np.int64)
        zero = np.zeros_like(k)
        tris = np.concatenate([np.stack([zero, k, k + 1], axis=1), np.stack([zero, k + 1, k], axis=1)])
    m = coal.BVHModelOBBRSS()
    m.beginModel(len(tris), len(v))
    m.addVertices(np.ascontiguousarray(v, dtype=np.float64))
    m.addTriangles(np.ascontiguousarray(tris, dtype=np.int64))
    # no endModel(): it builds the model's bounding-volume tree (80% of this function's time for a
    # 5 000-vertex hull), which nothing uses; the Convex is a copy of the vertices and triangles
    m.buildConvexRepresentation(False)
    return m.convex
