"""What a held object rested on, checked during the motion that lifts it off.

At a grasp the bodies the object rests on (within :data:`CONTACT_TOLERANCE`) are its
supports: the next motion starts in contact with them, so their pairs with it cannot be checked as
they stand.  Left unchecked, a depart that lowers the object pushed it through the table without a
word.  So the next motion is also verified, certified, on a copy of the cell that holds only those
pairs, the object *eroded* by :data:`SINK` (every point of the eroded object has a ball of radius
``SINK`` about it inside the object, so the eroded object meets a support only where the object has
sunk at least ``SINK`` into it, more than it already had at the grasp): lifting it off passes,
pushing it in further than ``SINK`` is a collision.  Erosion is exact for the shapes here (box, cylinder, sphere, capsule, prism: their sizes
less ``SINK``; a convex polyhedron: its face planes moved in); an object of another shape, or too
thin to erode, keeps the earlier rule (its supports unchecked during that motion) and says so.
"""

from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["CONTACT_TOLERANCE", "SINK", "support_scene", "eroded"]

CONTACT_TOLERANCE = 1e-3
"""m: at a grasp, the bodies the object is closer to than this are its supports (it rests on them).
During the next motion their pairs with the held object are checked on their own, with the object
eroded (:data:`SINK` more than it sat in them): lifting it off passes, pushing it in is refused."""

SINK = 2.0 * CONTACT_TOLERANCE
"""m: how far a held object may sink into what it rested on during the motion that lifts it off (twice
the contact tolerance of a support: an object resting up to 1 mm into its support still lifts off)."""


def eroded(shape, by: float):
    """``shape`` less a ball of radius ``by`` (its Minkowski erosion), or None where that is empty or not
    made here (a polygon, a shape too thin)."""
    from ..geometry import Box, Capsule, ConvexPolyhedron, Cylinder, Prism, Sphere

    if isinstance(shape, Sphere):
        return dataclasses.replace(shape, radius=shape.radius - by) if shape.radius > by else None
    if isinstance(shape, Capsule):
        return dataclasses.replace(shape, radius=shape.radius - by) if shape.radius > by else None
    if isinstance(shape, Box):
        h = np.asarray(shape.half_extents, dtype=np.float64) - by
        return dataclasses.replace(shape, half_extents=h) if np.all(h > 0.0) else None
    if isinstance(shape, Cylinder):
        ok = shape.radius > by and shape.half_length > by
        return dataclasses.replace(shape, radius=shape.radius - by, half_length=shape.half_length - by) if ok else None
    if isinstance(shape, Prism):
        ok = shape.apothem > by and shape.half_length > by
        return dataclasses.replace(shape, apothem=shape.apothem - by, half_length=shape.half_length - by) if ok else None
    if isinstance(shape, ConvexPolyhedron):
        return _eroded_polyhedron(shape, by)
    return None


def _eroded_polyhedron(shape, by: float):
    from scipy.spatial import HalfspaceIntersection, QhullError

    from ..geometry import ConvexPolyhedron

    P = np.asarray(shape.planes, dtype=np.float64)  # rows (n, d): n . x <= d, |n| = 1
    inside = np.asarray(shape.vertices, dtype=np.float64).mean(axis=0)
    if not np.all(P[:, :3] @ inside - P[:, 3] < -by):
        return None  # the centroid is not deeper than ``by``: too thin to erode this simply
    halfspaces = np.hstack([P[:, :3], -(P[:, 3:4] - by)])  # scipy's A x + b <= 0
    try:
        return ConvexPolyhedron(HalfspaceIntersection(halfspaces, inside).intersections)
    except (QhullError, ValueError):
        return None


def support_scene(scene, obj: str, supports, robot: str, link: str, q):
    """A copy of ``scene`` (``obj`` still a body there) in which ``obj``, eroded by :data:`SINK` more than it
    already sinks into a support (a found object may sit a little into the table), is held by ``robot``'s
    ``link`` at ``q`` and only its pairs with ``supports`` are checked; None where ``obj`` cannot be eroded."""
    from ..geometry import distance

    body = scene.bodies[obj]
    d0 = min((float(distance(a, b).distance) for s in supports if s in scene.bodies
              for a in body.shapes for b in scene.bodies[s].shapes), default=0.0)
    shapes = [eroded(s, SINK + max(0.0, -d0)) for s in body.shapes]
    if any(s is None for s in shapes):
        return None
    sub = scene.copy()
    sub.remove_body(obj)
    sub.add_body(obj, shapes, category=body.category)
    sub.grasp(obj, robot, link, q)
    keep = {frozenset((obj, b)) for b in supports}
    for b in supports:
        if frozenset((obj, b)) in sub.disabled_pairs:
            sub.enable_pair(obj, b)
    for cp in sub.allowed_pairs():
        if frozenset((cp.a, cp.b)) not in keep:
            sub.disable_pair(cp.a, cp.b)
    if sub.workspace is not None:
        sub.clear_workspace()
    return sub
