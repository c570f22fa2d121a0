"""An example armguard backend: every active pair of a Model by ``armguard.geometry.distance``.

A third-party backend in one package (``docs/backends.md``).  It reads only what the plugin
contract promises: the Model's Pinocchio side (``pin_model``, ``collision_model``), its active
``pairs`` and its workspace box, and answers with :mod:`armguard.geometry` — exact, one pair at a
time, in plain Python (slow next to ``analytic``, simple to read).

* Each GeometryObject's coal shape becomes an :mod:`armguard.geometry` shape in its own frame,
  once; each configuration poses it with Pinocchio (``updateGeometryPlacements``).
* A pair's answer is ``armguard.geometry.distance(A, B)``: signed distance, witness points.
* A workspace pair (side B ``"workspace"``: the box's walls, solid outside) is the least over the
  six walls of ``wall - support(A, outward normal)``, the witness on A its support point and the
  one on the wall that point moved onto the wall.

It takes no options.  Calls from several threads at once are safe: every call poses its own
shapes (nothing is shared between calls).
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from armguard import BackendError, GeometryError
from armguard.backends import Capability, CheckerBase, check_margin, check_q, check_Q

__all__ = ["PairwiseBackend", "PairwiseChecker"]

def local_shape(geometry):
    """The :mod:`armguard.geometry` shape of a coal geometry, in the geometry's own frame."""
    import coal
    from armguard import geometry as ag

    if isinstance(geometry, coal.Sphere):
        return ag.Sphere(np.zeros(3), float(geometry.radius))
    if isinstance(geometry, coal.Capsule):
        h = float(geometry.halfLength)
        return ag.Capsule([0.0, 0.0, -h], [0.0, 0.0, h], float(geometry.radius))
    if isinstance(geometry, coal.Box):
        return ag.Box(np.zeros(3), np.asarray(geometry.halfSide, dtype=np.float64))
    if isinstance(geometry, coal.Cylinder):
        return ag.Cylinder(np.zeros(3), np.eye(3), float(geometry.radius), float(geometry.halfLength))
    if isinstance(geometry, coal.ConvexBase):
        v = np.asarray(geometry.points(), dtype=np.float64)
        try:
            return ag.ConvexPolyhedron(v)
        except GeometryError:  # a flat hull (Ranger's polygon obstacles): its vertices in order around it
            c = v.mean(axis=0)
            _, _, axes = np.linalg.svd(v - c)
            angle = np.arctan2((v - c) @ axes[1], (v - c) @ axes[0])
            return ag.Polygon(v[np.argsort(angle)])
    raise BackendError(f"pairwise: no armguard.geometry shape for {type(geometry).__name__}")


class PairwiseChecker(CheckerBase):
    """A Checker over :func:`armguard.geometry.distance` (see the module docstring)."""

    name = "pairwise"
    capabilities = frozenset({Capability.DISTANCES, Capability.VERDICTS})

    def __init__(self, model, options: Mapping | None = None) -> None:
        import pinocchio as pin

        super().__init__(model)
        if options:
            raise BackendError(f"pairwise: unknown options {sorted(options)}; this backend takes none")
        gm = model.collision_model
        self._local = [local_shape(go.geometry) for go in gm.geometryObjects]
        pairs = model.pairs
        self._ia = [model.geometry_index(a) for a in pairs.a]
        self._ib = [None if b == "workspace" else model.geometry_index(b) for b in pairs.b]
        ws = model.workspace  # the Model's own box (model.scene may have been edited since)
        self._walls = None if ws is None else (np.asarray(ws.lo, dtype=np.float64), np.asarray(ws.hi, dtype=np.float64))
        self._pin = pin

    def _posed(self, q):
        """Every shape in W at ``q`` (a new list per call: nothing shared between calls)."""
        pin = self._pin
        data = self.model.pin_model.createData()
        gdata = pin.GeometryData(self.model.collision_model)
        pin.updateGeometryPlacements(self.model.pin_model, data, self.model.collision_model, gdata, q)
        return [s.transformed(M.homogeneous) for s, M in zip(self._local, gdata.oMg)]

    def _workspace(self, shape):
        """``(d, p_WA, p_WB)`` of ``shape`` against the workspace walls (positive inside the box)."""
        lo, hi = self._walls
        best = None
        for axis in range(3):
            for sign, bound in ((1.0, hi[axis]), (-1.0, lo[axis])):
                n = np.zeros(3)
                n[axis] = sign  # the wall's outward normal (towards its solid)
                p_WA = shape.support(n)
                d = sign * (bound - p_WA[axis])
                if best is None or d < best[0]:
                    p_WB = p_WA.copy()
                    p_WB[axis] = bound
                    best = (d, p_WA, p_WB)
        return best

    def pair_distances(self, q):
        from armguard.geometry import distance

        q = check_q(self.model, q)
        shapes = self._posed(q)
        n = len(self._ia)
        d, p_WA, p_WB = np.empty(n), np.empty((n, 3)), np.empty((n, 3))
        for k, (ia, ib) in enumerate(zip(self._ia, self._ib)):
            if ib is None:
                d[k], p_WA[k], p_WB[k] = self._workspace(shapes[ia])
            else:
                r = distance(shapes[ia], shapes[ib])
                d[k], p_WA[k], p_WB[k] = r.distance, r.p_WA, r.p_WB
        if not np.all(np.isfinite(d)):
            raise BackendError("pairwise: a distance came back NaN or infinite; no verdict")
        return self.result(d, p_WA, p_WB)

    def collides(self, Q, *, margin: float = 0.0) -> np.ndarray:
        Q = check_Q(self.model, Q)
        margin = check_margin(margin)
        return np.array([bool(np.min(self.pair_distances(q).distance, initial=np.inf) <= margin) for q in Q],
                        dtype=bool)


class PairwiseBackend:
    """Entry point ``pairwise`` of the group ``armguard.backends``."""

    name = "pairwise"

    def build(self, model, options: Mapping | None = None) -> PairwiseChecker:
        return PairwiseChecker(model, options)
