"""The coal reference backend: Pinocchio's GeometryModel checked by coal.

The Model's ``collision_model`` as Pinocchio built it — ``coal.Capsule`` links,
``coal.Convex`` hulls (never raw BVH meshes), boxes, spheres, cylinders — with one collision
pair per active Model pair; ``pinocchio.computeDistances`` gives signed distances and nearest
points (``getNearestPoint1/2``), ``pinocchio.computeCollisions`` the verdicts, and
``computeCollisionsInParallel`` over a ``GeometryPool`` the batches.  The workspace box is six
``coal.Halfspace`` walls (solid outside the box); a pair's workspace distance is the least over
the six.  Budgets and per-category nearest pairs come from the framework defaults.

Thread safety: each calling thread gets its own ``pinocchio.Data`` / ``GeometryData`` (their
placements and requests are per-call state), and the batch pool is used by one call at a time.
A GeometryData's distance functors keep their GJK solver's state from one call to the next (a
thread's own, never shared; the support hint survives ``DefaultGuess``), so an answer depends, in
its last bits, on the thread's earlier calls: where GJK stops at its tolerance rather than on a
vertex (a hull against a cylinder, large hulls), and where the nearest points are not unique (two
parallel faces: any pair of points of the overlap is nearest).  100 random configurations called
in order, then shuffled, on one thread (``armguard.load_model(name).random_q(100, 2)``): ur5 and
panda, 0 calls differ; z1, 1 (distances by 6.2e-10 m, witness points by 0.55 mm); kinova, 44
(distances by 2.2e-14 m, witness points by 6.4 mm on parallel faces); so101, 96 (1.1e-9 m,
5.5 mm).  A fresh GeometryData per call gives the same answers in any order, but Pinocchio exposes
no reset of that state and a fresh GeometryData costs ~26 µs a call; so the answers are identical
across threads, batches and pair subsets only to ``gjk_tolerance`` on such models (declared in
:attr:`CoalChecker.conformance_xfail`; ``tests/test_threads.py`` holds them bit-equal on its
models).

Options: ``threads`` (batches; default: the cores this process may run on, its CPU affinity), ``gjk_tolerance`` (m, default 1e-9: coal's
own default of 1e-6 stops GJK up to ~1e-5 m above the distance on curved hulls; a reference
has to be tighter than the 1e-6 m the differential tests hold the backends to).  Where coal's EPA
gives up on a penetrating pair (it returns ``-DBL_MAX`` as the distance: z1's cylinder pairs at
the 1e-9 EPA tolerance), that pair is computed again with the EPA tolerance loosened step by step
(:data:`EPA_RETRY_TOLERANCES`), and a pair no tolerance settles is an error: never a distance of
-1.8e308 m.
"""

from __future__ import annotations

import math
import os
import threading
import warnings
from typing import Mapping

import numpy as np

from armguard._errors import BackendError
from armguard.backends import (Capability, CheckerBase, PairDistances, PairDistancesMany, check_margin, check_pairs, check_q,
                               check_Q)
from armguard.model import WORKSPACE

__all__ = ["CoalBackend", "CoalChecker", "EPA_FAILED", "EPA_RETRY_TOLERANCES"]

# Pinocchio's GeometryData turns coal's cached GJK guess on, and the one switch that turns it off,
# ``enable_cached_gjk_guess``, warns that it is deprecated (coal 3).  The warning is silenced once
# here, for this module's own assignments only: a ``warnings.catch_warnings()`` around them (as
# before) changes the process's filters for the while, and from several threads at once (each
# thread's first call makes its GeometryData) they restored one another's filters -- tests/
# test_threads_edits.py saw 672 of the warnings through, and a process could be left with a filter
# it never asked for.
warnings.filterwarnings("ignore", message="enable_cached_gjk_guess has been marked as deprecated",
                        category=DeprecationWarning, module="armguard_coal")

EPA_FAILED = -1e300
"""m: a distance at or below this is coal's sign that its EPA gave up (``-DBL_MAX``, -1.8e308 m),
not a depth.  Seen on z1's cylinder pairs with the reference's EPA tolerance of 1e-9: the
polytope outgrows EPA's own limits on a curved core before the gap closes."""
EPA_RETRY_TOLERANCES = (1e-8, 1e-7, 1e-6, 1e-5)
"""m: the EPA tolerances a pair whose EPA gave up is computed again with, in order (the first
that settles a depth is kept; the differential tests hold depths to 1e-6 m only where both sides
are polytopes)."""


def workspace_walls(lo, hi):
    """Six ``(name, coal.Halfspace)`` walls, solid outside the box ``[lo, hi]`` (W, m)."""
    import coal

    out = []
    for axis in range(3):
        for sign, bound, tag in ((1.0, hi, "hi"), (-1.0, lo, "lo")):
            n = np.zeros(3)
            n[axis] = -sign  # {x : n.x <= d} is the solid beyond the wall
            out.append((f"{WORKSPACE}_{'xyz'[axis]}{tag}", coal.Halfspace(n, -sign * float(bound[axis]))))
    return out


def _reference_requests(gdata, tolerance: float) -> None:
    """Set every request of ``gdata`` so that coal answers as a reference must.

    * GJK and EPA stop within ``tolerance`` (the option ``gjk_tolerance``), the collision requests as
      the distance ones: with coal's 1e-6 on the collision requests, ``collides`` said collision at
      +1e-6 m where the distance query, ``check`` and the analytic backend said apart;
    * GJK starts afresh: with a guess carried over from another configuration, GJK was seen to
      stop 1.4e-5 m above a Panda hull pair's distance whatever the tolerance, and a batch to miss
      a 0.16 mm penetration;
    * collisions are computed with contacts: with ``enable_contact = False`` (Pinocchio's default)
      coal's convex–box and convex–convex collision missed penetrations of 0.8 and 6 mm between the
      KUKA iiwa's hulls and a box that its own distance query reports.
    """
    import coal

    for req in [*gdata.distanceRequests, *gdata.collisionRequests]:
        req.gjk_initial_guess = coal.GJKInitialGuess.DefaultGuess
        req.enable_cached_gjk_guess = False  # its deprecation warning: silenced at import (above)
        req.gjk_tolerance = req.epa_tolerance = tolerance
        req.gjk_max_iterations = req.epa_max_iterations = 1000
    for req in gdata.collisionRequests:
        req.enable_contact = True


def _option(opts: dict, key: str, default, kind, expected: str, ok):
    """Option ``key`` of ``opts`` (popped) as ``kind``; a value that is not ``expected`` is a BackendError
    naming it (an armguard.toml's ``threads = "x"`` was an internal ValueError)."""
    raw = opts.pop(key, default)
    try:
        value = kind(raw)
        good = not isinstance(raw, bool) and (kind is not int or float(raw) == value) and ok(value)
    except (TypeError, ValueError):
        good = False
    if not good:
        raise BackendError(f"coal: option {key} = {raw!r}: expected {expected}")
    return value


_HISTORY = ("the GJK solver state coal keeps between calls (the module docstring) changes the last bits of "
            "distances and, on parallel faces, which nearest points: measured on this public robot")


class CoalChecker(CheckerBase):
    """A Checker over Pinocchio + coal (see the module docstring)."""

    name = "coal"
    capabilities = frozenset({Capability.DISTANCES, Capability.VERDICTS})
    conformance_xfail = {  # armguard.testing: public robots where the bit-equality checks fail (2026-12-05)
        **{f"deterministic[{m}]": _HISTORY for m in ("kinova", "so101", "z1")},
        **{f"thread_safety[{m}]": _HISTORY for m in ("kinova", "so101", "z1")},
        **{f"pair_distances_many[{m}]": _HISTORY for m in ("so101", "z1")},
        **{f"pair_subset[{m}]": _HISTORY for m in ("kinova", "so101", "z1")},
    }

    def __init__(self, model, options: Mapping | None = None) -> None:
        import pinocchio as pin

        super().__init__(model)
        opts = dict(options or {})
        cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
        self.threads = _option(opts, "threads", cpus, int, "an integer >= 1", lambda v: v >= 1)
        self.gjk_tolerance = _option(opts, "gjk_tolerance", 1e-9, float, "a finite length > 0 (m)",
                                     lambda v: math.isfinite(v) and v > 0.0)
        if opts:
            raise BackendError(f"coal: unknown options {sorted(opts)}; options are ['gjk_tolerance', 'threads']")
        self.representation = {}
        geom = model.collision_model.copy()
        ws = model.workspace  # the Model's own box (model.scene may have been edited since)
        walls = []
        if ws is not None:
            for name, hs in workspace_walls(ws.lo, ws.hi):
                walls.append(geom.addGeometryObject(pin.GeometryObject(name, 0, 0, pin.SE3.Identity(), hs)))
        index = {go.name: i for i, go in enumerate(geom.geometryObjects)}
        rows, swapped = [], []  # per collision pair: the Model pair row, whether first/second are B/A
        pairs = model.pairs
        for k, (a, b) in enumerate(zip(pairs.a, pairs.b)):
            for jb in (walls if b == WORKSPACE else [index[b]]):
                ia = index[a]
                geom.addCollisionPair(pin.CollisionPair(ia, jb))
                cp = geom.collisionPairs[len(geom.collisionPairs) - 1]
                rows.append(k)
                swapped.append(cp.first != ia)
        self._rows = np.asarray(rows, dtype=np.int64)
        self._swapped = np.asarray(swapped, dtype=bool)
        # per Model row, its collision pairs (a workspace row has six)
        self._row_pairs = [[] for _ in range(len(pairs))]
        for i, k in enumerate(rows):
            self._row_pairs[k].append(i)
        self.geometry_model = geom
        self._tls = threading.local()
        self._pool = None
        self._pool_lock = threading.Lock()

    def _thread_data(self):
        """The calling thread's ``(pinocchio.Data, GeometryData)`` (made on its first call)."""
        try:
            return self._tls.dg
        except AttributeError:
            import pinocchio as pin

            gdata = pin.GeometryData(self.geometry_model)
            _reference_requests(gdata, self.gjk_tolerance)
            dg = self._tls.dg = (self.model.pin_model.createData(), gdata)
            return dg

    def _distances_into(self, q, d, p_WA, p_WB, idx) -> None:
        """Rows ``idx`` (None: every Model row) at ``q`` (checked) into ``d`` / ``p_WA`` / ``p_WB``."""
        import pinocchio as pin

        data, gdata = self._thread_data()
        if idx is None:
            pin.computeDistances(self.model.pin_model, data, self.geometry_model, gdata, q)
            self._read(list(gdata.distanceResults), np.arange(len(self._rows)), self._rows, gdata, q, d, p_WA, p_WB)
            return
        # only the collision pairs of the rows asked for
        pin.updateGeometryPlacements(self.model.pin_model, data, self.geometry_model, gdata, q)
        cps = [i for k in idx for i in self._row_pairs[k]]
        rows = [j for j, k in enumerate(idx) for _ in self._row_pairs[k]]
        results = [pin.computeDistance(self.geometry_model, gdata, i) for i in cps]
        self._read(results, np.asarray(cps, dtype=np.int64), np.asarray(rows, dtype=np.int64), gdata, q, d, p_WA, p_WB)

    def _read(self, results: list, cps, rows, gdata, q, d, p_WA, p_WB) -> None:
        """coal's ``results`` of collision pairs ``cps`` into output rows ``rows``: read as whole arrays (list
        comprehensions; a per-pair loop was most of coal's time from Python), a row's least distance over its
        collision pairs (a workspace row has six), a tie to the last of them."""
        dist = np.fromiter((r.min_distance for r in results), dtype=np.float64, count=len(results))
        p1 = np.array([r.getNearestPoint1() for r in results], dtype=np.float64).reshape(len(results), 3)
        p2 = np.array([r.getNearestPoint2() for r in results], dtype=np.float64).reshape(len(results), 3)
        # coal's EPA gave up (-DBL_MAX), or left NaN witness points (tiago's 1 mm sphere 1 mm into a box): again, looser
        for i in np.flatnonzero((dist <= EPA_FAILED) | ~np.isfinite(p1).all(axis=1) | ~np.isfinite(p2).all(axis=1)):
            results[i] = r = self._depth_retry(gdata, int(cps[i]), q)
            dist[i], p1[i], p2[i] = r.min_distance, r.getNearestPoint1(), r.getNearestPoint2()
        sw = self._swapped[cps]
        p1[sw], p2[sw] = p2[sw], p1[sw].copy()
        if len(rows) == len(d):  # one collision pair per row: each row once
            pick = np.arange(len(rows))
        else:  # per row its least distance, the last of equal ones
            order = np.lexsort((-np.arange(len(rows)), dist, rows))
            first = np.ones(len(order), dtype=bool)
            first[1:] = rows[order[1:]] != rows[order[:-1]]
            pick = order[first]
        d[rows[pick]] = dist[pick]
        p_WA[rows[pick]] = p1[pick]
        p_WB[rows[pick]] = p2[pick]
        if not np.all(np.isfinite(d)):
            raise BackendError("coal: a distance came back NaN or infinite; no verdict")

    def _depth_retry(self, gdata, i: int, q):
        """Collision pair ``i`` again (placements at ``q`` already in ``gdata``) after coal's EPA gave up
        (``-DBL_MAX``) or left NaN witness points, with its EPA tolerance loosened step by step (:data:`EPA_RETRY_TOLERANCES`);
        the request is restored after.  No tolerance settling it: ``BackendError`` naming the pair."""
        import pinocchio as pin

        req = gdata.distanceRequests[i]
        keep = req.epa_tolerance
        try:
            for tol in EPA_RETRY_TOLERANCES:
                req.epa_tolerance = tol
                r = pin.computeDistance(self.geometry_model, gdata, i)
                if r.min_distance > EPA_FAILED and np.isfinite(r.getNearestPoint1()).all() \
                        and np.isfinite(r.getNearestPoint2()).all():
                    return r
        finally:
            req.epa_tolerance = keep
        cp = self.geometry_model.collisionPairs[i]
        names = [self.geometry_model.geometryObjects[k].name for k in (cp.first, cp.second)]
        raise BackendError(f"coal: no penetration depth for {names[0]} / {names[1]} at q = {np.asarray(q).tolist()} "
                           f"(its EPA gave up, or left no finite witness points, at every tolerance up to "
                           f"{EPA_RETRY_TOLERANCES[-1]:g} m); no verdict")

    distance_jacobian = CheckerBase.witness_jacobian  # Pinocchio's frame Jacobians at coal's witness points

    def pair_distances(self, q, *, pairs=None, jacobian: bool = False):
        q = check_q(self.model, q)
        idx = None if pairs is None else check_pairs(self.model, pairs)
        n = len(self._category) if idx is None else len(idx)
        d, p_WA, p_WB = np.empty(n), np.zeros((n, 3)), np.zeros((n, 3))
        self._distances_into(q, d, p_WA, p_WB, idx)
        names, cat = self._subset(idx)
        r = PairDistances(names, d, p_WA, p_WB, cat)
        return r.with_jacobian(*self.distance_jacobian(q, r, idx)) if jacobian else r

    def pair_distances_many(self, Q, *, pairs=None) -> PairDistancesMany:
        Q = check_Q(self.model, Q)
        idx = None if pairs is None else check_pairs(self.model, pairs)
        n = len(self._category) if idx is None else len(idx)
        M = len(Q)
        d, p_WA, p_WB = np.empty((M, n)), np.zeros((M, n, 3)), np.zeros((M, n, 3))
        for m in range(M):
            self._distances_into(Q[m], d[m], p_WA[m], p_WB[m], idx)
        names, cat = self._subset(idx)
        return PairDistancesMany(names, d, p_WA, p_WB, cat)

    def collides(self, Q, *, margin: float = 0.0) -> np.ndarray:
        import pinocchio as pin

        Q = check_Q(self.model, Q)
        margin = check_margin(margin)
        if self.threads > 1 and len(Q) >= 64:
            with self._pool_lock:  # one batch at a time on the pool (its datas hold the margin)
                if self._pool is None:
                    self._pool = pin.GeometryPool(self.model.pin_model, self.geometry_model, self.threads)
                    for gd in self._pool.getGeometryDatas():
                        _reference_requests(gd, self.gjk_tolerance)
                for gd in self._pool.getGeometryDatas():
                    for req in gd.collisionRequests:
                        req.security_margin = margin
                out = pin.computeCollisionsInParallel(self.threads, self._pool, np.asfortranarray(Q.T), True)
            return np.asarray(out, dtype=bool)
        d, gd = self._thread_data()
        for req in gd.collisionRequests:
            req.security_margin = margin
        m, g = self.model.pin_model, self.geometry_model
        return np.array([bool(pin.computeCollisions(m, d, g, gd, q, True)) for q in Q], dtype=bool)


class CoalBackend:
    """Entry point ``coal`` of the group ``armguard.backends``."""

    name = "coal"

    def build(self, model, options: Mapping | None = None) -> CoalChecker:
        return CoalChecker(model, options)
