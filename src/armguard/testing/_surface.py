"""How far a point is from a Model shape's surface, for the witness-point checks.

``surface_residuals(model, q, names, p_W)`` poses every GeometryObject with Pinocchio
(``updateGeometryPlacements``) and returns, per point, a residual that is 0 exactly on the named
shape's surface, > 0 outside and < 0 inside: the signed distance for a sphere, capsule, box and
cylinder (coal's conventions: a capsule's and cylinder's axis is local z, ``halfLength`` half its
length; a box's ``halfSide``), the largest face-plane distance for a convex hull (exact on the
surface, a lower bound of the distance outside), and the nearest wall-plane distance for
``"workspace"`` (the box's walls, solid outside: the distance to the nearest wall, > 0 inside the
box).  Shapes it does not know (a flat hull, a height field, a mesh) give NaN: not checkable.
"""

from __future__ import annotations

import weakref

import numpy as np

from .._tolerance import DEFAULT_TOLERANCES as TOL

__all__ = ["surface_residuals"]

_HULLS: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()  # Model -> {geometry index: planes}


def _hull_planes(model, i: int, geometry):
    """``(F, 4)`` outward face planes ``n . p + c`` of a coal convex (its vertices' hull), or None."""
    cache = _HULLS.setdefault(model, {})
    if i not in cache:
        from scipy.spatial import ConvexHull, QhullError

        try:
            cache[i] = ConvexHull(np.asarray(geometry.points(), dtype=np.float64)).equations
        except (QhullError, ValueError):  # flat or degenerate: not checkable here
            cache[i] = None
    return cache[i]


def _local_residual(geometry, p: np.ndarray, planes=None) -> float:
    """Signed residual of ``p`` (3,) in the shape's own frame."""
    kind = type(geometry).__name__
    if kind == "Sphere":
        return float(np.linalg.norm(p) - geometry.radius)
    if kind == "Capsule":
        h = float(geometry.halfLength)
        axis_p = np.array([0.0, 0.0, np.clip(p[2], -h, h)])
        return float(np.linalg.norm(p - axis_p) - geometry.radius)
    if kind == "Box":
        qd = np.abs(p) - np.asarray(geometry.halfSide, dtype=np.float64)
        return float(np.linalg.norm(np.maximum(qd, 0.0)) + min(float(np.max(qd)), 0.0))
    if kind == "Cylinder":
        qd = np.array([np.hypot(p[0], p[1]) - geometry.radius, abs(p[2]) - geometry.halfLength])
        return float(np.linalg.norm(np.maximum(qd, 0.0)) + min(float(np.max(qd)), 0.0))
    if "Convex" in kind:
        if planes is None:
            return np.nan
        return float(np.max(planes[:, :3] @ p + planes[:, 3]))
    return np.nan


def surface_residuals(model, q, names, p_W) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(residual (n,), tolerance (n,), exact (n,) bool)`` of points ``p_W (n, 3)`` (W, m) against
    the shapes ``names (n,)`` at ``q`` (Pinocchio's order); NaN residual where the shape is not
    checkable.  The tolerance is ``Tolerances.differential_distance``, ``differential_hull`` on a
    convex hull; ``exact``: the residual is the signed distance itself (not a hull's bound)."""
    import pinocchio as pin

    gm = model.collision_model
    data = model.pin_model.createData()
    gdata = pin.GeometryData(gm)
    pin.updateGeometryPlacements(model.pin_model, data, gm, gdata, np.asarray(q, dtype=np.float64))
    res = np.full(len(names), np.nan)
    tol = np.full(len(names), TOL.differential_distance)
    exact = np.ones(len(names), dtype=bool)
    ws = model.scene.workspace
    for k, (name, p) in enumerate(zip(names, np.asarray(p_W, dtype=np.float64))):
        if name == "workspace":
            if ws is not None:
                lo, hi = np.asarray(ws.lo, dtype=np.float64), np.asarray(ws.hi, dtype=np.float64)
                res[k] = float(np.min(np.concatenate([p - lo, hi - p])))
            continue
        i = model.geometry_index(name)
        g = gm.geometryObjects[i].geometry
        M = gdata.oMg[i]
        hull = "Convex" in type(g).__name__
        planes = _hull_planes(model, i, g) if hull else None
        res[k] = _local_residual(g, np.asarray(M.rotation).T @ (p - np.asarray(M.translation)), planes)
        if hull:
            tol[k], exact[k] = TOL.differential_hull, False
    return res, tol, exact


def round_cores_meet(model, q, names_a, names_b) -> np.ndarray:
    """``(n,) bool``: the pairs of two spheres or capsules (coal's axis local z) whose cores, a centre
    or an axis segment, meet at ``q`` (within ``Tolerances.length``).  There the penetration has no
    one deepest direction: any pair of surface points along a line through the meeting point is as
    deep, and a backend's witness points may lie anywhere on that line (coal's do, inside the shapes)."""
    import pinocchio as pin

    from ..geometry import Capsule, Sphere, distance

    gm = model.collision_model
    data = model.pin_model.createData()
    gdata = pin.GeometryData(gm)
    pin.updateGeometryPlacements(model.pin_model, data, gm, gdata, np.asarray(q, dtype=np.float64))

    def core(name):
        if name == "workspace":
            return None
        i = model.geometry_index(name)
        g = gm.geometryObjects[i].geometry
        M = gdata.oMg[i]
        kind = type(g).__name__
        if kind == "Sphere":
            return Sphere(np.asarray(M.translation), float(g.radius)), float(g.radius)
        if kind == "Capsule":
            h = np.asarray(M.rotation)[:, 2] * float(g.halfLength)
            t = np.asarray(M.translation)
            return Capsule(t - h, t + h, float(g.radius)), float(g.radius)
        return None

    out = np.zeros(len(names_a), dtype=bool)
    for k, (a, b) in enumerate(zip(names_a, names_b)):
        ca, cb = core(a), core(b)
        if ca is not None and cb is not None:
            out[k] = distance(ca[0], cb[0]).distance + ca[1] + cb[1] <= TOL.length
    return out
