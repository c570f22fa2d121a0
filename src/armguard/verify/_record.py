"""The record of one verification run: every evaluated configuration and its clearances.

The certified loop of :mod:`._verify` evaluates the clearances a hundred times or more per
trajectory; this record keeps them in preallocated arrays (no per-evaluation objects) and, on the
detector's fast path, asks ``Detector.pair_distances(q, robot=)`` for the moving robot's pairs
only and takes the others from :meth:`ClearanceModel.fixed_clearances`.
"""

from __future__ import annotations

import math

import numpy as np

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
        if self._fast:
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
        if not self._fast:
            return self._last
        res = self._last
        idx = self._index_of(res)
        pA = self._fixed[1].copy()
        pB = self._fixed[2].copy()
        pA[idx] = res.p_WA
        pB[idx] = res.p_WB
        return pA, pB
