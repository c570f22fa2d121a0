"""Triangle meshes of armguard shapes for display, and the rigid motion between two poses of a shape.

The console draws each shape once as a mesh (built with trimesh at the home configuration) and
afterwards only moves it: :func:`rigid_motion` recovers the rotation and translation that carry
a shape's core points at home to its core points now (Kabsch's least-squares fit via SVD, exact
for a rigid motion), or :func:`item_frames` gives each shape's frame from forward kinematics
alone.  Display only: nothing here feeds a distance.
"""

from __future__ import annotations

import numpy as np

from ..geometry import Box, Capsule, ConvexPolyhedron, Polygon, Prism, Shape, Sphere
from ..model import kinematics_of

__all__ = ["mesh_of", "rigid_motion", "item_frames", "link_poses", "quat_wxyz_from_matrix", "SPHERE_SUBDIVISIONS", "CAPSULE_SECTIONS"]

SPHERE_SUBDIVISIONS = 2
"""Icosphere subdivisions for spheres (320 faces)."""
CAPSULE_SECTIONS = 16
"""Segments around a capsule's circumference."""


def mesh_of(shape: Shape) -> tuple[np.ndarray, np.ndarray]:
    """``(vertices (V, 3) float64 m in W, faces (F, 3) int64)`` of ``shape`` for display.

    Sphere: icosphere; Capsule: trimesh capsule along its axis; Box: its 12 triangles; Prism and
    ConvexPolyhedron: convex hull of the vertices; Polygon: a triangle fan (draw double-sided).
    """
    import trimesh

    if isinstance(shape, Sphere):
        m = trimesh.creation.icosphere(subdivisions=SPHERE_SUBDIVISIONS, radius=max(shape.radius, 1e-4))
        return np.asarray(m.vertices) + shape.center, np.asarray(m.faces)
    if isinstance(shape, Capsule):
        axis = shape.p1 - shape.p0
        length = float(np.linalg.norm(axis))
        r = max(shape.radius, 1e-3)
        m = trimesh.creation.capsule(height=length, radius=r, count=[CAPSULE_SECTIONS, CAPSULE_SECTIONS])
        R = _rotation_z_to(axis / length if length > 0.0 else np.array([0.0, 0.0, 1.0]))
        v = np.asarray(m.vertices) @ R.T + 0.5 * (shape.p0 + shape.p1)
        return v, np.asarray(m.faces)
    if isinstance(shape, Box):
        X = np.eye(4)
        X[:3, :3] = shape.rotation
        X[:3, 3] = shape.center
        m = trimesh.creation.box(extents=2.0 * shape.half_extents, transform=X)
        return np.asarray(m.vertices), np.asarray(m.faces)
    if isinstance(shape, (ConvexPolyhedron, Prism)):
        m = trimesh.convex.convex_hull(np.asarray(shape.core_points))
        return np.asarray(m.vertices), np.asarray(m.faces)
    if isinstance(shape, Polygon):
        v = np.asarray(shape.vertices)
        n = len(v)
        faces = np.array([[0, i, i + 1] for i in range(1, n - 1)], dtype=np.int64)
        return v.copy(), faces
    raise TypeError(f"no display mesh for {type(shape).__name__}")


def _rotation_z_to(d: np.ndarray) -> np.ndarray:
    """A rotation matrix taking +z to the unit vector ``d``."""
    z = np.array([0.0, 0.0, 1.0])
    c = float(z @ d)
    if c > 1.0 - 1e-12:
        return np.eye(3)
    if c < -1.0 + 1e-12:
        return np.diag([1.0, -1.0, -1.0])
    v = np.cross(z, d)
    s = np.linalg.norm(v)
    K = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return np.eye(3) + K + K @ K * ((1.0 - c) / (s * s))


def rigid_motion(P0: np.ndarray, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(R (3, 3), t (3,))`` with ``P ≈ P0 @ R.T + t`` for corresponding points ``P0``, ``P`` (n, 3), m.

    Kabsch: R from the SVD of the centred cross-covariance, with the reflection removed.  With one
    point R is the identity; with two the rotation about their line is the smallest one.
    """
    P0 = np.asarray(P0, dtype=np.float64)
    P = np.asarray(P, dtype=np.float64)
    c0 = P0.mean(axis=0)
    c = P.mean(axis=0)
    if len(P0) == 1:
        return np.eye(3), c - c0
    H = (P0 - c0).T @ (P - c)
    U, _, Vt = np.linalg.svd(H)
    D = np.diag([1.0, 1.0, float(np.sign(np.linalg.det(Vt.T @ U.T))) or 1.0])
    R = Vt.T @ D @ U.T
    return R, c - R @ c0


def quat_wxyz_from_matrix(R: np.ndarray) -> np.ndarray:
    """``(4,)`` unit quaternion ``(w, x, y, z)`` of the rotation matrix ``R`` (3, 3) (Shepperd's method)."""
    R = np.asarray(R, dtype=np.float64)
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    if tr > 0.0:
        s = 2.0 * np.sqrt(tr + 1.0)
        q = [0.25 * s, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s]
    elif R[0, 0] > R[1, 1] and R[0, 0] > R[2, 2]:
        s = 2.0 * np.sqrt(1.0 + R[0, 0] - R[1, 1] - R[2, 2])
        q = [(R[2, 1] - R[1, 2]) / s, 0.25 * s, (R[0, 1] + R[1, 0]) / s, (R[0, 2] + R[2, 0]) / s]
    elif R[1, 1] > R[2, 2]:
        s = 2.0 * np.sqrt(1.0 + R[1, 1] - R[0, 0] - R[2, 2])
        q = [(R[0, 2] - R[2, 0]) / s, (R[0, 1] + R[1, 0]) / s, 0.25 * s, (R[1, 2] + R[2, 1]) / s]
    else:
        s = 2.0 * np.sqrt(1.0 + R[2, 2] - R[0, 0] - R[1, 1])
        q = [(R[1, 0] - R[0, 1]) / s, (R[0, 2] + R[2, 0]) / s, (R[1, 2] + R[2, 1]) / s, 0.25 * s]
    q = np.array(q)
    q /= np.linalg.norm(q)
    return q if q[0] >= 0.0 else -q


def link_poses(scene, q) -> dict:
    """Robot name -> ``(n_links, 4, 4)`` link poses at ``q``: the scene's Model moves them
    (:meth:`armguard.model.Model.link_poses`, compiled from ``pin_model``)."""
    kin = kinematics_of(scene)
    return kin.link_poses(q) if kin is not None else {}


def item_frames(scene, q) -> list[np.ndarray]:
    """``X_W`` (4, 4) of each item of ``scene.shapes_at(q)``, in its order: the identity for a body
    (drawn where it is), the link's pose ``X_WL`` for a link's shape, ``X_WP`` for a payload's.

    Only forward kinematics, no shape transformed: the view moves each mesh by
    ``X(q) X(q_built)⁻¹`` (a ConvexPolyhedron's ``transformed`` rebuilds its packed directions,
    milliseconds a shape).
    """
    eye = np.eye(4)
    out: list[np.ndarray] = []
    for b in scene.bodies.values():
        out.extend(eye for _ in b.shapes)
    poses = link_poses(scene, q)
    for name, robot in scene.robots.items():
        X = poses[name]
        for i, ln in enumerate(robot.link_names):
            out.extend(X[i] for _ in robot.link_shapes.get(ln, ()))
    for p in scene.payloads.values():
        robot = scene.robots[p.robot]
        X_WP = poses[p.robot][robot.link_index(p.link)] @ np.asarray(p.X_LP, dtype=np.float64)
        out.extend(X_WP for _ in p.shapes)
    return out
