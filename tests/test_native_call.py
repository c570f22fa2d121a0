"""Calls between compiled kernels at an address (armguard_analytic._engine._native).

The fused kernel's entry points call it, it calls the pair step and the static pairs' branch
and bound, and the narrow phase its large pair kernels, at addresses looked up in the calling
process: the answers must be those of a linked call, an exception in the callee must reach the
caller, and a call with other argument types than the callee's must not compile.
"""

from __future__ import annotations

import threading

import numpy as np
import pytest
from numba import njit, types
from numba.core.errors import TypingError

from armguard_analytic._engine import _calls
from armguard_analytic._engine._native import native_address, native_caller

_ARGS = (types.float64[::1], types.int64)


@njit(cache=False)
def _weighted_sum(x, k):
    if k < 0:
        raise ValueError("k must be >= 0")
    s = 0.0
    for i in range(x.shape[0]):
        s += x[i] * (k + i)
    return s


_call = native_caller(types.float64, _ARGS)


@njit(cache=False)
def _through_address(fn, x, k):
    return _call(fn, (x, k))


@njit(cache=False)
def _linked(x, k):
    return _weighted_sum(x, k)


def test_a_call_at_the_address_returns_what_a_linked_call_returns():
    fn = native_address(_weighted_sum, types.float64, _ARGS)
    rng = np.random.default_rng(3)
    for n in (0, 1, 7, 100):
        x = rng.normal(size=n)
        for k in (0, 2, 11):
            assert _through_address(fn, x, k) == _linked(x, k) == _weighted_sum.py_func(x, k)


def test_an_exception_in_the_callee_reaches_the_caller():
    fn = native_address(_weighted_sum, types.float64, _ARGS)
    with pytest.raises(ValueError, match="k must be >= 0"):
        _through_address(fn, np.ones(3), -1)


def test_arguments_of_other_types_do_not_compile():
    fn = native_address(_weighted_sum, types.float64, _ARGS)

    @njit(cache=False)
    def strided(fn, x, k):
        return _call(fn, (x[::2], k))  # a strided view: not the callee's C-contiguous layout

    with pytest.raises(TypingError, match="do not match"):
        strided(fn, np.ones(6), 1)


def test_a_callee_returning_another_type_is_refused():
    with pytest.raises(TypeError, match="returns float64"):
        native_address(_weighted_sum, types.int64, _ARGS)


def test_the_kernels_addresses_are_one_array_per_process_whichever_thread_asks():
    got = []
    threads = [threading.Thread(target=lambda: got.append(_calls.addresses())) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(got) == 4 and all(a is got[0] for a in got)
    fns = got[0]
    assert fns.dtype == np.int64 and fns.shape == (len(_calls.NATIVE),) and np.all(fns != 0)
    assert len(set(fns.tolist())) == len(_calls.NATIVE)  # one kernel, one address


def test_the_address_table_only_grows():
    """The ``FN_*`` indices are compiled into the callers, and numba's cache keys on a caller's own
    file: a row moved or removed in ``_calls.NATIVE`` would make a caller cached before the edit
    call another kernel.  New rows go at the end; this list grows with them."""
    pinned = ["detect_rows", "pair_step", "static_gjk_pairs", "gjk_dir_rel", "_sat_rel", "epa_depth",
              "support_pair_graph", "convex_convex_fast", "narrow_rel", "narrow_other"]
    assert [row[1] for row in _calls.NATIVE][:len(pinned)] == pinned
    for k, name in enumerate(pinned):
        assert getattr(_calls, "FN_" + {"detect_rows": "ROWS", "pair_step": "STEP", "static_gjk_pairs": "STATIC",
                                        "gjk_dir_rel": "GJK_REL", "_sat_rel": "SAT_REL", "epa_depth": "EPA",
                                        "support_pair_graph": "SUPPORT", "convex_convex_fast": "CONVEX",
                                        "narrow_rel": "NARROW_REL", "narrow_other": "NARROW_OTHER"}[name]) == k
