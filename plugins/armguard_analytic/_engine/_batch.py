"""The fused Detector's batches: the rows of ``Q`` through the kernel, on the calling thread or
split over threads, each thread on a scratch of its own.

Used by :meth:`FusedDetector.check_many` / ``collides_many`` (``_many``, after its argument
checks) and by the Checker's ``collides`` (:func:`yesno_rows`, on rows it checked itself).
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from typing import TYPE_CHECKING

import numpy as np

from . import _kernel as kn
from ._scratch import CPUS, MIN_ROWS_PER_THREAD, row_threads

if TYPE_CHECKING:
    from ._built import Built
    from ._detector import FusedDetector

__all__ = ["rows", "rows_here", "yesno_rows"]


def rows(det: "FusedDetector", b: "Built", Q: np.ndarray, mode: int, prm: np.ndarray) -> tuple:
    """``(min_d (M, 4), status (M,), err)``: the kernel of revision ``b`` (:mod:`._built`, one for the
    whole batch) over the rows of ``Q`` (a C-contiguous float64 ``(M, n_q)`` array in the scene's joint
    order; callers check that) in ``mode``, split over threads for a large ``M``; ``err`` the first
    failing row's error code (0: none; the kernel refuses a non-finite row itself).  ``prm``: the
    threshold array the caller read from ``b`` once (``FusedDetector._set_limits``), every thread's."""
    M = Q.shape[0]
    n_threads = row_threads(M)
    if n_threads == 1:
        return rows_here(det, b, Q, mode, prm)
    min_d = np.empty((M, 4))  # the kernel writes every row (read only when err == 0)
    status = np.empty(M, dtype=np.int64)
    SF2, SI2 = np.tile(b.SF0, (n_threads, 1)), np.tile(b.SI0, (n_threads, 1))
    iprm = b.iprm.copy()
    iprm[kn.I_MODE], iprm[kn.I_STATE] = mode, 0
    bounds = [(M * k) // n_threads for k in range(n_threads + 1)]
    # each thread gets its own copy of the (small) model buffers: shared arrays would make the
    # threads contend on their cache lines (the copies cost little against a batch this long)
    per = [(b.H.copy(), b.MF.copy(), b.MI.copy(), prm.copy(), iprm.copy(), b.all_p.copy())
           for _ in range(n_threads)]

    def work(k: int) -> int:  # the kernel releases the GIL: threads run in parallel
        H, MF, MI, prm, ip, sel = per[k]
        return int(kn.detect_rows(Q, bounds[k], bounds[k + 1], H, MF, MI, SF2[k], SI2[k], prm, ip, sel, min_d, status,
                                  b.fn))

    with ThreadPoolExecutor(n_threads) as ex:
        errs = list(ex.map(work, range(n_threads)))
    return min_d, status, next((e for e in errs if e != 0), 0)


def rows_here(det: "FusedDetector", b: "Built", Q: np.ndarray, mode: int, prm: np.ndarray) -> tuple:
    """:func:`rows` on the calling thread alone: its batch scratch
    (:meth:`._scratch._Scratch.batch_buffers`), the model buffers shared (the kernel only reads
    them), nothing copied."""
    M = Q.shape[0]
    SF, SI, iprm = det._scratch(b).batch_buffers(mode)
    min_d = np.empty((M, 4))  # the kernel writes every row (read only when err == 0)
    status = np.empty(M, dtype=np.int64)
    err = kn.detect_rows(Q, 0, M, b.H, b.MF, b.MI, SF, SI, prm, iprm, b.all_p, min_d, status, b.fn)
    return min_d, status, int(err)


def yesno_rows(det: "FusedDetector", Q: np.ndarray, margin: float = 0.0) -> tuple:
    """``collides_many`` on rows the caller checked (see :func:`rows`): ``(hit (M,) bool, err)``, a hit
    where a pair is within ``margin`` (the kernel's stopping distance, ``prm[1]``: in a copy of the
    published parameters, which are never written). A few rows go straight to :func:`rows_here`: the
    Checker's ``collides`` on one row is this call, and each Python step it skips is a measurable share
    of it (``python -m bench backends``)."""
    b = det._fresh()
    prm = b.prm
    if margin != prm[1]:
        prm = prm.copy()
        prm[1] = margin
    if Q.shape[0] == 1:  # the Checker's collides on one row: this thread's buffers, no array made but the verdict
        s = det._scratch(b)
        SF, SI, iprm = s.batch_buffers(kn.MODE_YESNO)
        min_d, status = s.one_row_outputs()
        err = kn.detect_rows(Q, 0, 1, b.H, b.MF, b.MI, SF, SI, prm, iprm, b.all_p, min_d, status, b.fn)
        return np.array((status[0] == kn.ST_COLLISION,)), int(err)
    if Q.shape[0] <= MIN_ROWS_PER_THREAD or CPUS == 1:  # row_threads would say 1
        _, status, err = rows_here(det, b, Q, kn.MODE_YESNO, prm)
    else:
        _, status, err = rows(det, b, Q, kn.MODE_YESNO, prm)
    return status == kn.ST_COLLISION, err
