"""coal geometries <-> armguard shapes, placed in a frame.

``shape_from_coal(geometry, X_FG)`` gives the armguard shape of a coal geometry whose frame G
is at ``X_FG`` in frame F, and a representation note when the two are not the same set of
points (none today: capsules, spheres, boxes, cylinders and convex meshes all map exactly; a
cylinder is an exact :class:`armguard.geometry.Cylinder`).  ``coal_from_shape`` is the inverse,
used for bodies a scene file adds (a Cylinder maps to ``coal.Cylinder``).
"""

from __future__ import annotations

import numpy as np

from .._errors import GeometryError, SceneError
from ..geometry import Box, Capsule, ConvexPolyhedron, Cylinder, Polygon, Prism, Sphere
from ._hull import MeshPolytope, mesh_hull, mesh_polytope

__all__ = ["shape_from_coal", "placed_shapes", "coal_from_shape", "convex_hull", "convex_of_polytope", "shape_of_polytope",
           "strip_triangles", "CYLINDER_PRISM_SIDES", "COAL_MAX_NEIGHBOURS"]

CYLINDER_PRISM_SIDES = 16
"""Sides of the prism that circumscribes a cylinder where a caller wants a polytope for it
(apothem = radius; :data:`armguard.geometry.CYLINDER_HULL_SIDES`): the shapes themselves are
exact cylinders."""

COAL_MAX_NEIGHBOURS = 254
"""The most edges at one vertex of a coal Convex: its ``buildConvexRepresentation`` raises "Too
many neighbors" beyond (coal 3.0.3: a cone whose apex has 254 edges builds, 255 does not)."""


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
    time, O(N) memory); a flat polygon becomes two triangle fans, both sides (strips where a fan
    would give a vertex more edges than coal holds, :data:`COAL_MAX_NEIGHBOURS`)."""
    hull = mesh_hull(pts)
    try:
        return _coal_convex(hull.vertices, hull.triangles, hull.flat)
    except _TooManyNeighbours:  # Qhull's fan over a large flat face: the same hull, its faces in strips
        return convex_of_polytope(mesh_polytope(pts))


def convex_of_polytope(mp: MeshPolytope):
    """The coal.Convex of a mesh's hull (:func:`~armguard.model._hull.mesh_polytope`), in its frame:
    the same vertices and triangles as the armguard shape of :func:`shape_of_polytope`, except
    where Qhull's triangulation fans a large flat face out from one vertex with more edges than
    coal's Convex holds (centauro's 566-gon): coal's copy then triangulates every face in a strip
    (:func:`strip_triangles`; the same surface, so the same convex set and support function).  A
    vertex with that many edges of the hull itself (a cone's apex) is a GeometryError."""
    try:
        return _coal_convex(mp.vertices, mp.triangles, mp.flat)
    except _TooManyNeighbours:
        pass
    tris = strip_triangles(np.arange(len(mp.vertices))) if mp.flat else np.concatenate(
        [strip_triangles(f) for f in mp.faces])
    try:
        return _coal_convex(mp.vertices, tris, mp.flat, stripped=True)
    except _TooManyNeighbours as exc:
        raise GeometryError(f"a vertex of the hull has {exc.args[0]} edges; coal's Convex holds at most "
                            f"{COAL_MAX_NEIGHBOURS} (a cone's apex over a fine base: coarsen the mesh's base)") from None


def strip_triangles(loop) -> np.ndarray:
    """``(k - 2, 3) int64``: convex polygon ``loop`` (k vertex indices, in order) cut into a zigzag
    strip of triangles, each in the loop's order (so the same orientation): every vertex gets at
    most two diagonals, where a fan gives its first vertex k - 3."""
    loop = np.asarray(loop, dtype=np.int64)
    lo, hi, out, turn = 0, len(loop) - 1, [], True
    while hi - lo >= 2:
        if turn:
            out.append((loop[lo], loop[lo + 1], loop[hi]))
            lo += 1
        else:
            out.append((loop[lo], loop[hi - 1], loop[hi]))
            hi -= 1
        turn = not turn
    return np.asarray(out, dtype=np.int64).reshape(-1, 3)


def _max_neighbours(tris: np.ndarray, n: int) -> int:
    """The most edges at one vertex of the triangle mesh ``tris`` over ``n`` vertices."""
    e = np.sort(np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]]), axis=1)
    return int(np.bincount(np.unique(e, axis=0).ravel(), minlength=n).max())


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


class _TooManyNeighbours(Exception):
    """coal refused a Convex: ``args[0]`` is the most edges at one vertex of the triangles given."""


def _coal_convex(v: np.ndarray, tris: np.ndarray, flat: bool, *, stripped: bool = False):
    """coal's Convex of vertices ``v`` and ``tris``; a flat polygon (``v`` in order around it)
    becomes two fans, one a side (``stripped``: ``tris`` is one side's strip, the other side its
    reverse).  Raises :class:`_TooManyNeighbours` where a vertex has more edges than coal holds."""
    import coal

    if flat:
        if stripped:
            tris = np.concatenate([tris, tris[:, ::-1]])
        else:
            k = np.arange(1, len(v) - 1, dtype=np.int64)
            zero = np.zeros_like(k)
            tris = np.concatenate([np.stack([zero, k, k + 1], axis=1), np.stack([zero, k + 1, k], axis=1)])
    m = coal.BVHModelOBBRSS()
    m.beginModel(len(tris), len(v))
    m.addVertices(np.ascontiguousarray(v, dtype=np.float64))
    m.addTriangles(np.ascontiguousarray(tris, dtype=np.int64))
    # no endModel(): it builds the model's bounding-volume tree (80% of this function's time for a
    # 5 000-vertex hull), which nothing uses; the Convex is a copy of the vertices and triangles
    try:
        m.buildConvexRepresentation(False)
    except RuntimeError:
        most = _max_neighbours(np.asarray(tris, dtype=np.int64), len(v))
        if most > COAL_MAX_NEIGHBOURS:
            raise _TooManyNeighbours(most) from None
        raise
    return m.convex


def placed_shapes(model, q, names) -> list:
    """The armguard shapes (in W) of ``model``'s geometries ``names`` at ``q`` (Pinocchio's joint
    order), read from the coal geometries Pinocchio places (``updateGeometryPlacements``): taken
    without any backend, the inputs of the slow reference
    (:func:`armguard.geometry._support_reference.reference_signed_distance`)."""
    import pinocchio as pin

    gm = model.collision_model
    data, gdata = model.pin_model.createData(), gm.createData()
    pin.updateGeometryPlacements(model.pin_model, data, gm, gdata, np.asarray(q, dtype=np.float64))
    return [shape_from_coal(gm.geometryObjects[i].geometry, gdata.oMg[i].homogeneous)[0]
            for i in (model.geometry_index(n) for n in names)]
