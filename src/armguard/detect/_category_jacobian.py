"""The nearest pair's distance Jacobian per category: ``Detector.check(q, jacobian=True)``.

For each category of a :class:`~armguard.detect.DetectionReport`, the row ``d(distance)/dq``
``(nv,)`` of its nearest pair (``nv = pin_model.nv``, Pinocchio's velocity order; equation (1) of
:mod:`armguard.backends._jacobian`) and whether the distance is differentiable there.  It is
asked of the Model's Checker (``distance_jacobian`` of the one Model pair row): only when asked,
so ``check(q)`` costs nothing more.

The analytic Detector numbers its pairs by compiled element pairs, not Model rows; the row of
its nearest pair is found by owners: among the Model rows between the same two owners, the
nearest at ``q``.  Where two of those rows are equally near (within ``Tolerances.length``) the
category minimum is a minimum of two distances and ``smooth`` is False (the row is then one of its
one-sided derivatives).  :class:`~armguard.detect.RangerDetector` pairs are Model rows already.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass

import numpy as np

from .._errors import DetectionError

__all__ = ["CategoryJacobian", "CategoryJacobians"]


@dataclass(frozen=True)
class CategoryJacobian:
    """The nearest pair of one category, differentiated.

    ``jacobian`` ``(nv,) float64, m/rad or m/m``: ``d(distance)/dq`` in ``pin_model``'s velocity
    order (read-only); ``smooth``: False where the category minimum is not differentiable (non-unique
    witnesses, touching, or a tie between two pairs), the row then being a one-sided derivative;
    ``row``: the Model pair row differentiated; ``distance`` (m): the Checker's distance of that row.
    """

    jacobian: np.ndarray
    smooth: bool
    row: int
    distance: float


class CategoryJacobians:
    """Per-Detector state: the Model, its Checker and the rows between each pair of owners (built once)."""

    def __init__(self, model, backend: str | None = None, backend_options=None, checker=None) -> None:
        self._model = model
        self._backend, self._options = backend, backend_options
        self._checker = checker
        self._lock = threading.Lock()
        self._by_owners = None

    def _ready(self):
        with self._lock:
            if self._checker is None:
                from ..backends import checker

                self._checker = checker(self._model, self._backend, self._options)
            if self._by_owners is None:
                pairs = self._model.pairs
                by: dict = {}
                for k, (oa, ob) in enumerate(zip(pairs.owner_a, pairs.owner_b)):
                    by.setdefault(frozenset((oa, ob)), []).append(k)
                self._by_owners = {key: np.array(v, dtype=np.int64) for key, v in by.items()}
        return self._checker, self._by_owners

    def of(self, q_scene: np.ndarray, nearest: dict, rows: dict | None = None) -> dict:
        """``{category: CategoryJacobian}`` for the report's ``nearest`` ``{category: PairResult}`` at
        the scene configuration ``q_scene`` ``(n,)``; ``rows`` ``{category: Model row}`` where known."""
        checker, by_owners = self._ready()
        m = self._model
        q = m.pin_q(np.asarray(q_scene, dtype=np.float64))
        tie = m.tol.length
        cats, cands = [], []
        for cat, res in nearest.items():
            if cat not in ("arm", "environment", "workspace", "payload"):  # an attached extra (terrain)
                continue
            known = None if rows is None else rows.get(cat)
            cand = (np.array([known], dtype=np.int64) if known is not None
                    else by_owners.get(frozenset((res.a, res.b))))
            if cand is None or not len(cand):
                raise DetectionError(f"jacobian: no Model pair between {res.a!r} and {res.b!r} (category {cat})")
            cats.append(cat)
            cands.append(cand)
        if not cats:
            return {}
        # one distance call for every Model row (a fixed query the Checker plans once; a subset that
        # changes from call to call would be planned anew each time), one Jacobian call for the chosen rows
        r = checker.pair_distances(q)
        d_all = np.asarray(r.distance, dtype=np.float64)
        picks, tied = [], []
        for cand in cands:
            d = d_all[cand]
            if not np.all(np.isfinite(d)):
                raise DetectionError(f"jacobian: backend {checker.name!r} answered a non-finite distance; no Jacobian")
            k = int(np.argmin(d))
            picks.append(int(cand[k]))
            tied.append(int(np.sum(d <= d[k] + tie)) > 1)
        chosen = np.array(picks, dtype=np.int64)
        J, smooth = checker.distance_jacobian(q, r.take(chosen), chosen)
        out = {}
        for i, cat in enumerate(cats):
            row = np.array(J[i], dtype=np.float64)
            row.flags.writeable = False
            out[cat] = CategoryJacobian(row, bool(smooth[i]) and not tied[i], int(chosen[i]), float(d_all[chosen[i]]))
        return out
