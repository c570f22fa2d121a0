"""The fused Detector's compiled entry points: one check per call, the GIL released or held.

Both call the fused kernel :func:`._kernel.detect_rows` at its address (:mod:`._native`), not
through a link, so each compiles its own few lines (~0.3 s) instead of generating the whole
kernel's machine code again (~5 s each on a cold cache).  The fused kernel calls the pair step and
the static pairs' branch and bound the same way, so none of the three compiles another's tree, and
a first run compiles them in parallel, in either process, in any order.  Callers pass the
addresses, :func:`._calls.addresses` in their own process (``fns``, indexed by ``FN_*``), as the
first argument of an entry point; the kernels pass them on.

Compiled without numba's reference counting (``_nrt=False``: they allocate nothing and keep no
array): with it, numba's wrapper gave each array argument a new meminfo on entry and released it
on return (``NRT_adapt_ndarray_from_python``, ``NRT_MemInfo_new``, ``NRT_incref`` / ``NRT_decref``
calls, seen in perf samples of ur3's ``pair_distances``; :mod:`._pair_rows` alike).
"""

from __future__ import annotations

import numpy as np

from numba import njit

from ._calls import FN_ROWS, call_rows
from ._layout import K, SUM_NEVAL, SUM_STATUS, seg1, view2

__all__ = ["detect_entry", "detect_entry_held"]

_K_best = K["best"]
_K_summary = K["summary"]


@njit(cache=True, nogil=True, _nrt=False)
def detect_entry(fns, q, H, MF, MI, SF, SI, prm, iprm, sel):  # pragma: no cover - compiled
    """One check at ``q`` ``(1, n_q)``, returning ``(status, n_evaluated, error)`` (saves reads from
    Python); ``fns``: :func:`._calls.addresses`."""
    summary = seg1(SI, H, _K_summary)
    best = view2(SF, H[2 * _K_best], 1, 4)
    st = summary[SUM_STATUS:SUM_STATUS + 1]
    err = call_rows(fns[FN_ROWS], (q, np.int64(0), np.int64(1), H, MF, MI, SF, SI, prm, iprm, sel, best, st, fns))
    return summary[SUM_STATUS], summary[SUM_NEVAL], err


@njit(cache=True, _nrt=False)
def detect_entry_held(fns, q, H, MF, MI, SF, SI, prm, iprm, sel):  # pragma: no cover - compiled
    """:func:`detect_entry` holding the GIL (a check too short for a hand-over to pay, ``_scratch``)."""
    return detect_entry(fns, q, H, MF, MI, SF, SI, prm, iprm, sel)
