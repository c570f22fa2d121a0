"""The Detector over any backend: Ranger's report from a Checker's ``pair_distances``.

``Detector(scene, ..., backend="coal")`` (or ``$ARMGUARD_BACKEND`` / ``armguard.toml``) builds a
:class:`CheckerDetector`: the same API and the same :class:`DetectionReport` /
:class:`BatchReport` / :class:`PairDistances` types as the analytic detector, computed from the
framework defaults of the backend interface — every pair's signed distance at each check, the
nearest pair per category, the status against the threshold and the stopping distance.  It has
no obstacle lists and no anytime mode: ``budget_us`` and ``lazy`` evaluate every pair (the
report is never INCOMPLETE: every pair was evaluated), and ``elapsed_us`` says what it cost.
"""

from __future__ import annotations

import math
import time

import numpy as np

from .._errors import DetectionError
from ._detector import _check_length
from ._extras import attach_extra
from ._report import CATEGORIES, BatchReport, DetectionReport, PairDistances, PairResult, Status

__all__ = ["CheckerDetector", "other_backend"]


def other_backend(backend, backend_options) -> bool:
    """Whether the precedence picks a backend other than the analytic one in its exact mode."""
    from ..backends import resolve

    name, opts = resolve(backend, backend_options)
    return name != "analytic" or str(opts.get("fidelity", "exact")) != "exact"

_CATEGORY = {  # Model pair category -> detector category
    "arm-arm": "arm", "arm-vehicle": "environment", "arm-environment": "environment", "arm-payload": "payload",
    "payload-vehicle": "payload", "payload-environment": "payload", "payload-payload": "payload",
    "workspace": "workspace",
}


class _Raw:
    """What a DetectionReport reads, from one evaluation of every pair."""

    def __init__(self, det: "CheckerDetector", d: np.ndarray, p_WA: np.ndarray, p_WB: np.ndarray) -> None:
        self.det, self.d, self.p_WA, self.p_WB = det, d, p_WA, p_WB
        self.n_evaluated = len(d)

    def _result(self, k: int) -> PairResult:
        det = self.det
        pA, pB = self.p_WA[k].copy(), self.p_WB[k].copy()
        pA.flags.writeable = pB.flags.writeable = False
        return PairResult(float(self.d[k]), pA, pB, det._a[k], det._b[k], det._cat[k], det._a[k], det._b[k], None, int(k))

    def by_category(self) -> dict:
        out = {}
        for c in CATEGORIES:
            idx = np.flatnonzero(self.det._cat_arr == c)
            if idx.size:
                out[c] = self._result(int(idx[np.argmin(self.d[idx])]))
        return out

    def within(self, threshold: float) -> tuple:
        idx = np.flatnonzero(self.d <= threshold)
        return tuple(self._result(int(k)) for k in idx[np.argsort(self.d[idx], kind="stable")])

    def not_evaluated(self) -> tuple:
        return ()


class CheckerDetector:
    """A Detector whose distances come from a backend Checker (see the module docstring)."""

    def __init__(self, scene, threshold: float = 0.05, *, stopping_distance: float = 0.0, active: str | None = None,
                 backend: str | None = None, backend_options=None, model=None, tol=None, reach_margin=None,
                 terrain=None) -> None:
        from ..backends import checker
        from ..model import model_of

        self.scene = scene
        self._threshold = _check_length(threshold, "threshold")
        self._stopping = _check_length(stopping_distance, "stopping_distance")
        self.model = model if model is not None else model_of(scene)
        self.checker = checker(self.model, backend, backend_options)
        self.backend = self.checker.name
        from ..backends import Capability

        self._distances = Capability.DISTANCES in self.checker.capabilities
        self._active = None
        self.terrain = None
        self.set_active(active)
        if terrain is not None:  # the terrain category, composed outside the backend
            attach_extra(self, "terrain", terrain)

    def _require_distances(self, what: str) -> None:
        if not self._distances:
            from .._errors import BackendError

            raise BackendError(f"backend {self.backend!r} answers verdicts only (no distances), so it has no {what}; "
                               "use collides_many(Q) with it, or a backend that answers distances")

    # ------------------------------------------------------------------ settings
    threshold = property(lambda self: self._threshold, doc="Detection threshold (m).")
    stopping_distance = property(lambda self: self._stopping, doc="Stopping distance (m); 0 when unset.")
    active = property(lambda self: self._active, doc="The active robot's name, or None for all arms.")

    @property
    def n_pairs(self) -> int:
        return len(self._sel)

    @property
    def link_names(self) -> tuple:
        return tuple(f"{r}/{ln}" for r, robot in self.scene.robots.items() for ln in robot.link_names)

    def set_threshold(self, threshold: float) -> None:
        self._threshold = _check_length(threshold, "threshold")

    def set_stopping_distance(self, stopping_distance: float) -> None:
        self._stopping = _check_length(stopping_distance, "stopping_distance")

    def set_active(self, name: str | None) -> None:
        if name is not None and name not in self.scene.robots:
            raise DetectionError(f"active: unknown robot {name!r}; robots are {list(self.scene.robots)}")
        self._active = name
        self.prepare()

    def prepare(self) -> "CheckerDetector":
        """The pairs checked (all, or those with a side on the active arm), moving side on A."""
        pairs = self.model.pairs
        bodies = set(self.scene.bodies)
        sel, a, b, swap = [], [], [], []
        for k, (oa, ob) in enumerate(zip(pairs.owner_a, pairs.owner_b)):
            if self._active is not None and not (oa.startswith(self._active + "/") or ob.startswith(self._active + "/")
                                                 or self._payload_of(oa) == self._active or self._payload_of(ob) == self._active):
                continue
            s = oa in bodies
            sel.append(k), swap.append(s)
            a.append(ob if s else oa), b.append(oa if s else ob)
        self._sel = np.asarray(sel, dtype=np.int64)
        self._swap = np.asarray(swap, dtype=bool)
        self._a, self._b = tuple(a), tuple(b)
        self._cat = tuple(_CATEGORY[pairs.category[k]] for k in sel)
        self._cat_arr = np.asarray(self._cat, dtype=object)
        self._cat_code = np.array([CATEGORIES.index(c) for c in self._cat], dtype=np.int64)
        self._revision = getattr(self.scene, "revision", None)
        return self

    def _payload_of(self, owner: str):
        p = self.scene.payloads.get(owner)
        return None if p is None else p.robot

    # ------------------------------------------------------------------ checks
    def _eval(self, q_flat: np.ndarray):
        self._require_distances("per-pair distances (check, pair_distances, check_many)")
        if getattr(self.scene, "revision", None) != self._revision:
            raise DetectionError("the scene changed after this detector was built; build a new one")
        self.model.check_limits(q_flat, "Detector.check")
        r = self.checker.pair_distances(self.model.pin_q(q_flat))
        d = r.distance[self._sel]
        p_WA = np.where(self._swap[:, None], r.p_WB[self._sel], r.p_WA[self._sel])
        p_WB = np.where(self._swap[:, None], r.p_WA[self._sel], r.p_WB[self._sel])
        return d, p_WA, p_WB

    def _flat(self, q) -> np.ndarray:
        try:
            q = self.scene.flat_q(q)
        except Exception as exc:  # noqa: BLE001 - one error type at the boundary
            raise DetectionError(f"q: {exc}") from None
        q = np.asarray(q, dtype=np.float64)
        if not np.all(np.isfinite(q)):
            raise DetectionError(f"q: contains NaN or infinite values: {q.tolist()}")
        return q

    def _status(self, dmin: float) -> Status:
        if dmin <= max(self.model.tol.length, self._stopping):
            return Status.COLLISION
        if dmin <= max(self._threshold, self._stopping):
            return Status.WARNING
        return Status.CLEAR

    def check(self, q, *, budget_us: float | None = None, lazy: bool = False) -> DetectionReport:
        """Every pair's distance at ``q`` (mapping robot -> joints, or flat); see the module docstring."""
        t0 = time.perf_counter()
        d, pA, pB = self._eval(self._flat(q))
        status = self._status(float(d.min(initial=math.inf)))
        return DetectionReport._from_check(status, self._threshold, self._stopping, (time.perf_counter() - t0) * 1e6,
                                           _Raw(self, d, pA, pB))

    def pair_distances(self, q, *, robot: str | None = None) -> PairDistances:
        """Every checked pair's signed distance (rows: one per shape pair), as the analytic detector's."""
        d, pA, pB = self._eval(self._flat(q))
        names = self.link_names
        li = {n: i for i, n in enumerate(names)}
        rid = {r: i for i, r in enumerate(self.scene.robots)}
        link_a = np.array([li.get(a, li.get(self._carrier(a), -1)) for a in self._a], dtype=np.int64)
        robot_a = np.array([rid.get(a.split("/", 1)[0], rid.get(self._payload_of(a), -1)) for a in self._a], dtype=np.int64)
        link_b = np.array([li.get(b, li.get(self._carrier(b), -1)) for b in self._b], dtype=np.int64)
        idx = np.arange(len(d), dtype=np.int64)
        if robot is not None:
            if robot not in rid:
                raise DetectionError(f"robot: unknown robot {robot!r}; robots are {list(rid)}")
            on = robot_a == rid[robot]
            on |= np.array([rid.get(b.split("/", 1)[0], rid.get(self._payload_of(b), -2)) == rid[robot] for b in self._b])
            idx = np.flatnonzero(on)
        ro = lambda x: np.ascontiguousarray(x)  # noqa: E731
        return PairDistances(d[idx].copy(), pA[idx].copy(), pB[idx].copy(), ro(link_a[idx]), ro(robot_a[idx]),
                             ro(link_b[idx]), ro(self._cat_code[idx]), tuple(self._a[i] for i in idx),
                             tuple(self._b[i] for i in idx), names, ro(idx))

    def _carrier(self, owner: str):
        p = self.scene.payloads.get(owner)
        return None if p is None else f"{p.robot}/{p.link}"

    def _rows(self, Q) -> np.ndarray:
        try:
            Q = np.asarray(Q, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise DetectionError(f"Q: expected an (M, {len(self.scene.joint_names)}) array of numbers") from exc
        n = len(self.scene.joint_names)
        if Q.ndim != 2 or Q.shape[1] != n:
            raise DetectionError(f"Q: expected shape (M, {n}), got {Q.shape}")
        if not np.all(np.isfinite(Q)):
            raise DetectionError("Q contains NaN or infinite values")
        return Q

    def check_many(self, Q) -> BatchReport:
        """Per-category nearest distances and status for each row of ``Q`` ``(M, n_q)``."""
        Q = self._rows(Q)
        min_d = np.full((len(Q), 4), np.inf)
        status = np.zeros(len(Q), dtype=np.int8)
        for i, q in enumerate(Q):
            d, _, _ = self._eval(q)
            for c in range(4):
                sel = self._cat_code == c
                if sel.any():
                    min_d[i, c] = d[sel].min()
            status[i] = {Status.CLEAR: 0, Status.WARNING: 1, Status.COLLISION: 2}[self._status(float(d.min(initial=math.inf)))]
        return BatchReport(min_d, status == 2, status, self._threshold, self._stopping)

    check_many_bruteforce = check_many

    def collides_many(self, Q) -> np.ndarray:
        """``(M,) bool``: collision (distance <= 0, or <= the stopping distance) per row (the backend's batch)."""
        Q = self._rows(Q)
        for i, q in enumerate(Q):
            self.model.check_limits(q, f"Detector.collides_many: Q[{i}]")
        if self._active is None and len(self._sel) == len(self.model.pairs):
            return self.checker.collides(self.model.pin_q(Q), margin=self._stopping)
        self._require_distances("active-arm batches (collides_many with active= checks the whole Model)")
        return self.check_many(Q).collision

    def __repr__(self) -> str:
        return (f"Detector({self.scene.name!r}, backend={self.backend!r}, threshold={self._threshold}, "
                f"stopping_distance={self._stopping}, active={self._active!r}, {len(self._sel)} pairs)")
