"""The fused Detector's compiled entry points: one check per call, the GIL released or held.

Both call the fused kernel :func:`._kernel.detect_rows` at its address (:mod:`._native`), not
through a link, so each compiles its own few lines (~0.3 s) instead of generating the whole
kernel's machine code again (~5 s each on a cold cache).  The fused kernel calls the pair step and
the static pairs' branch and bound the same way, so none of the three compiles another's tree, and
a first run compiles them in parallel, in either process, in any order.  Callers pass the
addresses, :func:`addresses` in their own process (``fns``, indexed by ``FN_*``), as the first
argument of an entry point; the kernels pass them on.
"""

from __future__ import annotations

import numpy as np

from numba import carray, njit, types

from ._layout import K, SUM_NEVAL, SUM_STATUS, at, seg1
from ._native import native_address, native_caller

__all__ = ["FN_ROWS", "FN_STATIC", "FN_STEP", "ROWS_ARGTYPES", "addresses", "call_rows", "detect_entry",
           "detect_entry_held"]

_F1, _F2, _I1 = types.float64[::1], types.float64[:, ::1], types.int64[::1]
ROWS_ARGTYPES = (_F2, types.int64, types.int64, _I1, _F1, _I1, _F1, _I1, _F1, _I1, _I1, _F2, _I1, _I1)
""":func:`._kernel.detect_rows`'s argument types ``(Q, lo, hi, H, MF, MI, SF, SI, prm, iprm, sel,
min_d, status_out, fns)``: the one overload its native callers call."""
FN_ROWS, FN_STEP, FN_STATIC = 0, 1, 2
"""Where :func:`addresses` holds the fused kernel's, the pair step's and the static pairs' address."""
call_rows = native_caller(types.int64, ROWS_ARGTYPES)
"""``call_rows(fn, (Q, lo, hi, ...))``: :func:`._kernel.detect_rows` at address ``fn``."""

_K_best = K["best"]
_K_summary = K["summary"]


_fns: list = []


def addresses() -> np.ndarray:
    """``fns`` ``(3,) int64``: the addresses, in this process, of :func:`._kernel.detect_rows`,
    :func:`._step.pair_step` and :func:`._static_gjk.static_gjk_pairs` (each compiled, or loaded
    from numba's cache, on the first call).  The same array every call: the kernels only read it."""
    if not _fns:
        from ._kernel import detect_rows
        from ._static_gjk import STATIC_ARGTYPES, STATIC_RETURN, static_gjk_pairs
        from ._step import STEP_ARGTYPES, STEP_RETURN, pair_step

        fns = np.array([native_address(detect_rows, types.int64, ROWS_ARGTYPES),
                        native_address(pair_step, STEP_RETURN, STEP_ARGTYPES),
                        native_address(static_gjk_pairs, STATIC_RETURN, STATIC_ARGTYPES)], dtype=np.int64)
        if not _fns:  # another thread may have been first: the addresses are the same
            _fns.append(fns)
    return _fns[0]


@njit(cache=True, nogil=True)
def detect_entry(fns, q, H, MF, MI, SF, SI, prm, iprm, sel):  # pragma: no cover - compiled
    """One check at ``q`` ``(1, n_q)``, returning ``(status, n_evaluated, error)`` (saves reads from
    Python); ``fns``: :func:`addresses`."""
    summary = seg1(SI, H, _K_summary)
    best = carray(at(SF, H[2 * _K_best]), (1, 4))
    st = summary[SUM_STATUS:SUM_STATUS + 1]
    err = call_rows(fns[FN_ROWS], (q, np.int64(0), np.int64(1), H, MF, MI, SF, SI, prm, iprm, sel, best, st, fns))
    return summary[SUM_STATUS], summary[SUM_NEVAL], err


@njit(cache=True)
def detect_entry_held(fns, q, H, MF, MI, SF, SI, prm, iprm, sel):  # pragma: no cover - compiled
    """:func:`detect_entry` holding the GIL (a check too short for a hand-over to pay, ``_scratch``)."""
    return detect_entry(fns, q, H, MF, MI, SF, SI, prm, iprm, sel)
