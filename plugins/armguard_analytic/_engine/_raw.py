"""One check's outputs held by its report, copied out of the detector's scratch only when needed."""

from __future__ import annotations

import sys
import threading
from typing import TYPE_CHECKING

import numpy as np

from armguard.detect._report import CATEGORIES, NotEvaluated, PairResult

from . import _kernel as kn
from ._layout import EV_W, SUM_BSLOT, SUM_SIZE

if TYPE_CHECKING:
    from ._built import Built


def _refcount(obj) -> int:
    return sys.getrefcount(obj)


def _unheld_count() -> int:
    """What :func:`_refcount` says of an object held only by one local name of the caller, called
    the way :meth:`FusedDetector._release_last` calls it (measured, not assumed: interpreters differ in
    whether a call's arguments hold references of their own)."""
    last = _Probe()
    return _refcount(last)


class _Probe:
    __slots__ = ()


_UNHELD = _unheld_count()
_DETACH = threading.Lock()  # one copy out of the scratch at a time: the checking thread's, or a reader's


class _Raw:
    """One check's compact kernel outputs; builds the report's views on demand, with the names of the
    revision ``b`` (:mod:`._built`) that made them.

    ``f`` ``(n, 7)``: ``[distance, p_WA, p_WB]`` of the ``n`` evaluated pairs in evaluation order;
    ``i``: the summary slots followed by the ``n`` pair numbers; ``flags`` / ``bounds`` ``(P,)``
    only for the lazy and anytime modes (their reports name every skipped pair).

    ``f`` and ``i`` are copied out of the detector's scratch buffers only when needed: on first
    access, or when the detector is about to overwrite the buffers while this object is still
    referenced (:meth:`FusedDetector._release_last`).  A report dropped before the next check (a
    control loop reading only ``status``) costs no copy."""

    __slots__ = ("b", "_f", "_i", "_SF", "_SI", "_of", "_oi", "n_evaluated", "flags", "bounds", "mode", "reach")

    def __init__(self, b: "Built", SF: np.ndarray, SI: np.ndarray, of: int, oi: int, n_evaluated: int,
                 flags, bounds, mode, reach: float = 0.0) -> None:
        self.b, self._SF, self._SI, self._of, self._oi, self.n_evaluated = b, SF, SI, of, oi, n_evaluated
        self._f = self._i = None
        self.flags, self.bounds, self.mode = flags, bounds, mode
        self.reach = reach  # the larger of the threshold and stopping distance the check used (lazy mode)

    def detach(self) -> None:
        """Copy this check's rows out of the scratch buffers (idempotent, and safe when the report is read
        on another thread: a UI thread reading the control loop's latest report copies under the same
        lock as the checking thread does before its next check overwrites the scratch, so neither sees
        the buffers gone nor a copy half overwritten)."""
        if self._f is not None:
            return
        with _DETACH:
            if self._f is None:
                n, o = self.n_evaluated, self._of
                f = self._SF[o:o + EV_W * n].reshape(n, EV_W).copy()
                self._i = self._SI[self._oi:self._oi + SUM_SIZE + n].copy()
                self._f = f  # last: a reader that sees _f set finds _i set too
                self._SF = self._SI = None

    @property
    def f(self) -> np.ndarray:
        if self._f is None:
            self.detach()
        return self._f

    @property
    def i(self) -> np.ndarray:
        if self._f is None:
            self.detach()
        return self._i

    def row(self, k: int) -> PairResult:
        r = self.f[k]
        return self.b.pair_result(int(self.i[SUM_SIZE + k]), float(r[0]), r[1:4].copy(), r[4:7].copy())

    def by_category(self) -> dict[str, PairResult]:
        out = {}
        for c in range(4):
            k = int(self.i[SUM_BSLOT + c])
            if k >= 0:
                out[CATEGORIES[c]] = self.row(k)
        return out

    def within(self, threshold: float) -> tuple[PairResult, ...]:
        d = self.f[:, 0]
        idx = np.flatnonzero(d <= threshold)
        idx = idx[np.lexsort((self.i[SUM_SIZE:][idx], d[idx]))]  # nearest first, ties by pair number
        return tuple(self.row(int(k)) for k in idx)

    def not_evaluated(self) -> tuple[NotEvaluated, ...]:
        if self.flags is None:  # exact: every skipped pair is beyond its category's cut-off
            return ()
        b, flags, plb = self.b, self.flags, self.bounds
        cat = b.model.pair_cat
        out = []
        for p in np.flatnonzero(flags == 0):
            na, nb = b.pair_names(int(p))
            out.append(NotEvaluated(na, nb, CATEGORIES[int(cat[p])], float(plb[p]), int(p)))
        if self.mode == kn.MODE_LAZY or self.mode == kn.MODE_ANYTIME:  # proved beyond the threshold (lazy)
            thr = self.reach
            for p in np.flatnonzero(flags == 2):
                na, nb = b.pair_names(int(p))
                out.append(NotEvaluated(na, nb, CATEGORIES[int(cat[p])], max(float(plb[p]), thr), int(p)))
        return tuple(out)
