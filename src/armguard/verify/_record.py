"""The record of one verification run: every evaluated configuration and its clearances.

The certified loop of :mod:`._verify` evaluates the clearances a hundred times or more per
trajectory; this record keeps them in preallocated arrays (no per-evaluation objects) and, on the
detector's fast path, asks ``Detector.pair_distances(q, robot=)`` for the moving robot's pairs
only and takes the others from :meth:`ClearanceModel.fixed_clearances`.  A backend whose detector
declares a lean evaluator (the analytic one's ``row_evaluator``: its kernel's rows for the moving
robot's shape pairs, no result object) is called that way instead, also where a link has several
shapes (each pair of parts the nearest of its shape pairs, :func:`._advance.owner_rows`); on ur5,
panda, z1 and so101 edges (``Verifier.check_edges``) 1.2x, 2.0x, 1.6x and 1.4x faster than the
``pair_distances`` path, with the same bits (``tests/test_verify_advance.py``).
"""

from __future__ import annotations

import math

import numpy as np

from ._advance import owner_rows
from ._oracle import ClearanceModel

__all__ = ["_Run"]


class _Run:
    """Book-keeping of one verification: every evaluated configuration and its clearances, in
    preallocated arrays that grow by doubling (row ``i`` is the ``i``-th evaluation, ``n`` rows used).

    D : (capacity, P) float64, m — clearances (+inf for a pair without a side on the moving robot:
    it cannot change, and is not checked);  Q : (capacity, k1 - k0) — the moving robot's joints;
    seg : (capacity,) int64;  s : (capacity,) float64, 1;  t : (capacity,) float64, s (NaN: unknown).
    Only the last evaluation's witness points are kept (the collision is the last evaluation).
    """

    def __init__(self, model: ClearanceModel, base: np.ndarray, k0: int, k1: int, robot: str | None = None,
                 capacity: int = 64) -> None:
        self.model = model
        self.robot = robot  # the moving robot: only its pairs change between evaluations
        self.base = base
        self.k0, self.k1 = k0, k1
        P = len(model.owner_a)
        cap = max(2, int(capacity))
        self.n = 0
        self.reused = 0  # rows :meth:`put` took from an earlier evaluation (not evaluations of this record)
        self.pieces = 1  # segments per segment of the trajectory as given (a Subdivided's n): seg // pieces is its index
        self.D = np.empty((cap, P))
        self.Q = np.empty((cap, k1 - k0))
        self.seg = np.empty(cap, dtype=np.int64)
        self.s = np.empty(cap)
        self.t = np.empty(cap)
        self._q = base.copy()  # the flat configuration handed to the distance source
        # the pairs without a side on the moving robot cannot change along its motion: they are
        # recorded as +inf (apart), so that neither the verdict nor the clearances report them
        self.moving = np.ones(P, dtype=bool) if robot is None else model.moving_pairs(robot)
        self._fast = model.moving_fast_path(robot)
        if self._fast:
            fixed = model.fixed_clearances(self._q, robot)
            row = np.where(self.moving, fixed[0], np.inf)
            self._fixed = (row, fixed[1], fixed[2])
            self._det = model._det
            self._det_map = model._det_map
        self._rows = self._lean_rows(model, robot, P)  # None: pair_distances each evaluation
        self._pidx = self._idx = None  # see _index_of
        self._last = None  # the last evaluation's witnesses: a detector result, or (p_WA, p_WB)

    def full_dq(self, dq_robot: np.ndarray) -> np.ndarray:
        """``(n_q,)``: the moving robot's joint step ``dq_robot`` in the flat joint vector (others 0)."""
        out = np.zeros(self.model.n_q)
        out[self.k0 : self.k1] = dq_robot
        return out

    def _grow(self) -> None:
        cap = 2 * self.D.shape[0]
        for name in ("D", "Q", "seg", "s", "t"):
            old = getattr(self, name)
            new = np.empty((cap,) + old.shape[1:], dtype=old.dtype)
            new[: self.n] = old[: self.n]
            setattr(self, name, new)

    def eval(self, si: int, s: float, q_robot: np.ndarray, t: float | None = None) -> int:
        """Evaluate the clearances with the moving robot at ``q_robot`` ``(k1 - k0,)``; returns the row
        (``n``, the rows so far, is this verification's count of evaluations).  A scene edited since the
        model was built: :class:`armguard.StaleModelError` (the Verifier starts again on the new scene)."""
        i = self.n
        if i == self.D.shape[0]:
            self._grow()
        q = self._q
        q[self.k0 : self.k1] = q_robot
        row = self.D[i]
        ev = self._lean(q) if self._rows is not None else None
        if ev is not None:
            row[:] = math.inf
            owner_rows(ev, self._rows_owner, row, self._wit)  # each moving pair: the nearest of its shape pairs
            self._last = ev.copy()  # the witnesses (the rows are the thread's scratch)
            self.model.evaluations += 1
        elif self._fast:
            res = self.model._checked(self._fast_row, q, row)  # never another scene's rows
            self._last = res
            self.model.evaluations += 1
        else:
            d, pA, pB = self.model.distances(q.copy(), self.robot)
            row[:] = np.where(self.moving, d, np.inf)
            self._last = (pA, pB)
        self.Q[i] = q_robot
        self.seg[i] = si
        self.s[i] = s
        self.t[i] = math.nan if t is None else t
        self.n = i + 1
        return i

    def put(self, si: int, s: float, q_robot: np.ndarray, d: np.ndarray) -> int:
        """A row for the configuration ``q_robot`` whose clearances ``d`` ``(P,)`` an earlier evaluation of the
        same model and configuration gave (no distance call; counted in ``reused``); returns the row."""
        i = self.n
        if i == self.D.shape[0]:
            self._grow()
        self.D[i] = d
        self.Q[i] = q_robot
        self.seg[i] = si
        self.s[i] = s
        self.t[i] = math.nan
        self.n = i + 1
        self.reused += 1
        return i

    def _lean_rows(self, model: ClearanceModel, robot: str | None, P: int):
        """The detector's lean evaluator of the moving robot's shape pairs (a backend's declared fast path:
        the analytic one's ``row_evaluator``), or None.  Its rows are the shape pairs of exactly the
        moving pairs (a link with several shapes: several rows, :func:`._advance.owner_rows` keeps the
        nearest); the other pairs' witnesses come from the full evaluation at the others' joints."""
        lean = getattr(model._det, "row_evaluator", None) if model.source == "detector" else None
        if lean is None:
            return None
        sel, rows = lean(robot)
        owner = np.ascontiguousarray(model._det_map[sel])
        if not np.array_equal(np.unique(owner), np.flatnonzero(self.moving)):
            return None  # not the moving pairs (no verdict from rows that may miss one)
        self._rows_owner, self._wit = owner, np.zeros((P, 6))
        self._fixed_wit = (np.zeros((P, 3)), np.zeros((P, 3))) if robot is None else \
            model.fixed_clearances(self._q, robot)[1:]
        return rows

    def _lean(self, q: np.ndarray):
        """The moving robot's rows ``(n, 7)`` at ``q`` by the detector's lean evaluator, or None when the
        scene changed since it was made (then the general path below raises StaleModelError)."""
        model = self.model
        try:
            ev = self._rows(q)
        except Exception:
            model._refuse_if_stale()
            raise
        if ev is not None:
            model._refuse_if_stale()  # edited during the call: the rows are of the model's revision, the verdict is not
        return ev

    def _fast_row(self, q: np.ndarray, row: np.ndarray):
        res = self._det.pair_distances(q, robot=self.robot)
        row[:] = self._fixed[0]
        row[self._index_of(res)] = res.distance
        return res

    def _index_of(self, res) -> np.ndarray:
        """Rows of the detector result ``res`` in the model's pair order (cached while the detector
        hands back the same ``pair_index`` array, i.e. the same pair selection)."""
        pidx = res.pair_index
        if pidx is not self._pidx:
            self._pidx = pidx
            self._idx = self._det_map[pidx]
        return self._idx

    def full_q(self, i: int) -> np.ndarray:
        """``(n_q,)``: the flat configuration of evaluation ``i``."""
        q = self.base.copy()
        q[self.k0 : self.k1] = self.Q[i]
        return q

    def last_witnesses(self) -> tuple[np.ndarray, np.ndarray]:
        """``(p_WA (P, 3) m, p_WB (P, 3) m)`` of the last evaluation, in the model's pair order."""
        res = self._last
        if isinstance(res, np.ndarray):  # the lean evaluator's rows [d, p_WA, p_WB]
            P = len(self.moving)
            d, wit = np.full(P, math.inf), np.zeros((P, 6))
            owner_rows(res, self._rows_owner, d, wit)
            pA, pB = self._fixed_wit[0].copy(), self._fixed_wit[1].copy()
            pA[self.moving], pB[self.moving] = wit[self.moving, :3], wit[self.moving, 3:]
            return pA, pB
        if not self._fast:
            return res
        pA = self._fixed[1].copy()
        pB = self._fixed[2].copy()
        idx = self._index_of(res)
        pA[idx] = res.p_WA
        pB[idx] = res.p_WB
        return pA, pB
