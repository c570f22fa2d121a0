"""The python-fcl backend: a third checker in one package, on the same Model.

Each GeometryObject of the Model's collision model becomes an ``fcl.CollisionObject`` of the
same shape (capsule, sphere, box, cylinder; convex hulls as ``fcl.Convex``); Pinocchio places
them (``updateGeometryPlacements``) and ``fcl.distance`` answers each active pair with signed
distance and nearest points (``collides`` stops at the first pair within its margin).  The
workspace box is six large boxes just outside its walls (python-fcl's capsule–halfspace distance
crashes the process).  The collision objects hold the poses of one configuration: one call places
and queries them at a time (a lock), so several threads may share a checker.  ``pairs=`` is the
framework's default (the full result's rows).
"""

from __future__ import annotations

import math
import threading
from typing import Mapping

import numpy as np

from armguard._errors import BackendError
from armguard.backends import Capability, CheckerBase, check_margin, check_q, check_Q
from armguard.model import WORKSPACE

__all__ = ["FclBackend", "FclChecker"]


def _fcl_geometry(g):
    """The python-fcl geometry of a coal geometry."""
    import coal
    import fcl

    if isinstance(g, coal.Capsule):
        return fcl.Capsule(float(g.radius), 2.0 * float(g.halfLength))
    if isinstance(g, coal.Sphere):
        return fcl.Sphere(float(g.radius))
    if isinstance(g, coal.Box):
        return fcl.Box(*(2.0 * np.asarray(g.halfSide, dtype=np.float64)))
    if isinstance(g, coal.Cylinder):
        return fcl.Cylinder(float(g.radius), 2.0 * float(g.halfLength))
    if isinstance(g, coal.ConvexBase):
        from scipy.spatial import ConvexHull

        v = np.asarray(g.points(), dtype=np.float64)
        try:
            hull = ConvexHull(v)
            tris = hull.simplices
            # orient each triangle outwards
            c = v.mean(axis=0)
            tris = np.array([t if np.dot(np.cross(v[t[1]] - v[t[0]], v[t[2]] - v[t[0]]), v[t[0]] - c) >= 0
                             else t[[0, 2, 1]] for t in tris])
        except Exception:  # noqa: BLE001 - a flat hull (a polygon): a triangle fan, both sides
            n = len(v)
            tris = np.array([(0, i, i + 1) for i in range(1, n - 1)] + [(0, i + 1, i) for i in range(1, n - 1)])
        faces = np.hstack([np.full((len(tris), 1), 3), tris]).ravel().astype(np.int64)
        return fcl.Convex(np.ascontiguousarray(v), len(tris), faces)
    raise BackendError(f"fcl: no python-fcl geometry for {type(g).__name__}")


class FclChecker(CheckerBase):
    """A Checker over python-fcl (see the module docstring)."""

    name = "fcl"
    capabilities = frozenset({Capability.DISTANCES, Capability.VERDICTS})
    distances_may_run_long = True  # the budgeted / lazy Detector then proves nothing from its memory
    conformance_xfail = {  # armguard.testing: where python-fcl is known not to meet the suite, and why (measured at
        # the bundled run's seed 0 and at seeds 1, 2 and 5; on the other models it meets every check)
        **{f"coal_distances[{m}]": "python-fcl's GJK stops early: separated distances run long (up to 0.39 m on Hermes in "
                                   "10^4 configurations, docs/backends.md), never short of the exact distance "
                                   "(tests/test_backends.py holds it to that bound)"
           for m in ("ranger", "hermes", "puma560", "gmf_s480", "kinova", "panda+edits")},
        **{f"witness_on_surfaces[{m}]": "python-fcl's GJK stops early: its witness points lie off the surfaces (up to "
                                        "14 mm on ranger's workspace pairs, 0.2 mm on Hermes's hulls), and away from "
                                        "the nearest points where its distance runs long"
           for m in ("ranger", "hermes", "puma560", "gmf_s480", "kinova", "panda+edits")},
        "distance_jacobian[ranger]": "python-fcl's GJK stops early: its distances carry an error of their own that the "
                                     "framework's central differences (step 1e-6) magnify (-1.3e-3 m/rad where "
                                     "differences at 1e-4 give 1.3e-5)",
    }

    def __init__(self, model, options: Mapping | None = None) -> None:
        import fcl
        import pinocchio as pin

        super().__init__(model)
        if options:
            raise BackendError(f"fcl: unknown options {sorted(options)}; this backend takes none")
        self.representation = {}
        gm = model.collision_model
        self._objs = [fcl.CollisionObject(_fcl_geometry(go.geometry), fcl.Transform()) for go in gm.geometryObjects]
        walls = []
        ws = model.workspace  # the Model's own box (model.scene may have been edited since)
        if ws is not None:
            # each wall is a large box just outside it (python-fcl's capsule-halfspace distance crashes)
            lo, hi = np.asarray(ws.lo, dtype=np.float64), np.asarray(ws.hi, dtype=np.float64)
            big = 4.0 * float(np.max(hi - lo)) + 10.0
            mid = 0.5 * (lo + hi)
            for axis in range(3):
                for sign, bound in ((1.0, hi), (-1.0, lo)):
                    c = mid.copy()
                    c[axis] = bound[axis] + sign * 0.5 * big
                    walls.append(fcl.CollisionObject(fcl.Box(big, big, big), fcl.Transform(np.eye(3), c)))
        self._walls = walls
        pairs = model.pairs
        self._ia = np.array([model.geometry_index(a) for a in pairs.a], dtype=np.int64)
        self._ib = np.array([-1 if b == WORKSPACE else model.geometry_index(b) for b in pairs.b], dtype=np.int64)
        self._data = model.pin_model.createData()
        self._gdata = pin.GeometryData(gm)
        self._lock = threading.Lock()  # the objects' poses and the GeometryData are one call's state

    def _place(self, q) -> None:
        import fcl
        import pinocchio as pin

        pin.updateGeometryPlacements(self.model.pin_model, self._data, self.model.collision_model, self._gdata, q)
        for o, M in zip(self._objs, self._gdata.oMg):
            o.setTransform(fcl.Transform(np.asarray(M.rotation), np.asarray(M.translation)))

    def pair_distances(self, q):
        q = check_q(self.model, q)
        with self._lock:
            return self._distances(q)

    def _distances(self, q):
        import fcl

        self._place(q)
        n = len(self._ia)
        d = np.empty(n)
        p_WA = np.empty((n, 3))
        p_WB = np.empty((n, 3))
        req = fcl.DistanceRequest(enable_nearest_points=True, enable_signed_distance=True)
        for k in range(n):
            others = self._walls if self._ib[k] < 0 else [self._objs[self._ib[k]]]
            best = None
            for ob in others:
                res = fcl.DistanceResult()
                dist = fcl.distance(self._objs[self._ia[k]], ob, req, res)
                if best is None or dist < best[0]:
                    best = (dist, np.asarray(res.nearest_points[0]), np.asarray(res.nearest_points[1]))
            d[k], p_WA[k], p_WB[k] = best
        if not np.all(np.isfinite(d)):
            raise BackendError("fcl: a distance came back NaN or infinite; no verdict")
        return self._result(d, p_WA, p_WB)

    def collides(self, Q, *, margin: float = 0.0) -> np.ndarray:
        """Per row of ``Q``: some pair's distance ``<= margin``.  The pairs in order, stopping at the
        first within ``margin`` (python-fcl answers one pair at a time, so the rest are never computed),
        each with ``pair_distances``' request: the same distances, so the same verdicts."""
        Q = check_Q(self.model, Q)
        margin = check_margin(margin)
        out = np.zeros(len(Q), dtype=bool)
        with self._lock:
            for m, q in enumerate(Q):
                out[m] = self._any_within(q, margin)
        return out

    def _any_within(self, q, margin: float) -> bool:
        import fcl

        self._place(q)
        req = fcl.DistanceRequest(enable_nearest_points=True, enable_signed_distance=True)
        for k in range(len(self._ia)):
            for ob in self._walls if self._ib[k] < 0 else (self._objs[self._ib[k]],):
                dist = fcl.distance(self._objs[self._ia[k]], ob, req, fcl.DistanceResult())
                if not math.isfinite(dist):  # never a verdict from it, nor past it
                    raise BackendError("fcl: a distance came back NaN or infinite; no verdict")
                if dist <= margin:
                    return True
        return False


class FclBackend:
    """Entry point ``fcl`` of the group ``armguard.backends``."""

    name = "fcl"
    requires = ("fcl",)  # python-fcl, imported on build: without it armguard.testing calls every check not applicable

    def build(self, model, options: Mapping | None = None) -> FclChecker:
        return FclChecker(model, options)
