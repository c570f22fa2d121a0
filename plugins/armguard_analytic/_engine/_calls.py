"""The kernels the analytic engine calls at an address (:mod:`._native`), and those addresses.

Each row of :data:`NATIVE` is a kernel its callers call at ``fns[FN_*]`` instead of linking it: the
fused kernel (from the entry points, :mod:`._entry`), the static pairs' branch and bound and the
pair step it calls, the link-frame narrow phase the pair step calls, and the large pair kernels the
narrow phases call (GJK, SAT and EPA in link frames, the cylinder and convex kernels).  A caller linking such a
kernel had LLVM generate its whole tree's machine code again: ``narrow_rel`` took 15 s of a cold
compile, nearly all of it the four kernels it calls, ``pair_distance``'s caller 12.6 s.  Called at
an address, each kernel's machine code is generated once, and a caller compiles without its
callees (in any order, in either process of the first run's warm-up, :mod:`._warm`).  The cost per
call is one indirect call with its arguments, against a microsecond of GJK; the hot small calls
stay linked (the fused kernel links the pair step, the pair step the scalar pairs' kernel).  The
pair step calls both narrow phases at their addresses, so that it links nothing compiled with
reference counting and may be compiled without (``._step``).

``fns`` (:func:`addresses`) is made in each process and passed down as an argument from the entry
points: an address is never stored in a buffer that could reach another process.  The signature
codes are the ones the warm-up plan compiles (:mod:`armguard.cli._compile`): F1/F2 float64 C arrays
(1-D/2-D), I1/I2 int64 ones, f float64, i int64, b boolean.
"""

from __future__ import annotations

import importlib

import numpy as np

from numba import types

from armguard._numba_cache import signature

from ._native import native_address, native_caller

__all__ = ["FN_CONVEX", "FN_EPA", "FN_GJK_REL", "FN_NARROW_OTHER", "FN_NARROW_REL", "FN_ROWS", "FN_SAT_REL",
           "FN_STATIC", "FN_STEP", "FN_SUPPORT", "NATIVE", "addresses", "argtypes", "call_convex", "call_epa",
           "call_gjk_rel", "call_narrow_other", "call_narrow_rel", "call_rows", "call_sat_rel", "call_static",
           "call_step", "call_support"]

_f, _i, _b = types.float64, types.int64, types.boolean
argtypes = signature
"""The numba types of signature codes (:func:`armguard._numba_cache.signature`, the warm-up's)."""


NATIVE = (
    ("armguard_analytic._engine._kernel", "detect_rows", "F2 i i I1 F1 I1 F1 I1 F1 I1 I1 F2 I1 I1", _i),
    ("armguard_analytic._engine._step", "pair_step", "i i i b I1 F1 I1 F1 I1 F1 f f f i f f f i i I1",
     types.Tuple((_f, _i))),
    ("armguard_analytic._engine._static_gjk", "static_gjk_pairs", "I1 F1 I1 F1 I1 F1 i f b f f f i f f f i i I1",
     types.Tuple((_i, _i, _b))),
    ("armguard.geometry._pair_gjk", "gjk_dir_rel", "F2 I1 I1 F2 I1 I1 F1 f f f f f f f f i F1 f I1",
     types.Tuple((_i,) + (_f,) * 7)),
    ("armguard_analytic._engine._narrow", "_sat_rel", "F2 F2 F2 I1 I1 f F2 F2 F2 I1 I1 f F1 f f f F1 i F1 F1 f f f i f f",
     types.Tuple((_f, _i))),
    ("armguard.geometry._pair_epa", "epa_depth", "F2 I1 F2 I1 F1 f F1 f f f I1 I1 f", types.Tuple((_b,) + (_f,) * 10)),
    ("armguard.geometry._pair_cylinder", "support_pair_graph", "F2 I1 F1 f F2 I1 F1 f F1 F1 f f i f I1 I1",
     types.Tuple((_f, _i))),
    ("armguard.geometry._pair_epa", "convex_convex_fast", "F2 F2 F2 I1 I2 f F2 F2 F2 I1 I2 f F1 F1 f f f i f f",
     types.Tuple((_f, _i))),
    ("armguard_analytic._engine._narrow", "narrow_rel", "i i I1 F1 I1 F1 F1 f f f i f f f I1 i", types.Tuple((_f, _i))),
    ("armguard_analytic._engine._narrow", "narrow_other", "i i I1 F1 I1 F1 F1 f f f i f f I1", types.Tuple((_f, _i))),
)
"""``(module, function, signature codes, return type)`` of each kernel called at an address, in
``FN_*`` order.  Append only: the ``FN_*`` indices are compiled into the callers as constants, and
numba's cache keys on a function's own file, so a caller cached before a row moved would call the
wrong kernel (a crash, not an error); a row that is no longer called stays (``tests/test_native_call.py``
pins the order).  After editing this table in a checkout: ``make clean-cache``."""
(FN_ROWS, FN_STEP, FN_STATIC, FN_GJK_REL, FN_SAT_REL, FN_EPA, FN_SUPPORT, FN_CONVEX, FN_NARROW_REL,
 FN_NARROW_OTHER) = range(len(NATIVE))
(call_rows, call_step, call_static, call_gjk_rel, call_sat_rel, call_epa, call_support, call_convex, call_narrow_rel,
 call_narrow_other) = (native_caller(ret, argtypes(codes)) for _, _, codes, ret in NATIVE)
"""``call_X(fns[FN_X], (args...))``: kernel ``FN_X`` of :data:`NATIVE` at its address."""

_fns: list = []


def addresses() -> np.ndarray:
    """``fns`` ``(len(NATIVE),) int64``: the addresses, in this process, of the :data:`NATIVE`
    kernels (each compiled, or loaded from numba's cache, on the first call).  The same array every
    call: the kernels only read it."""
    if not _fns:
        fns = np.array([native_address(getattr(importlib.import_module(m), f), ret, argtypes(codes))
                        for m, f, codes, ret in NATIVE], dtype=np.int64)
        if not _fns:  # another thread may have been first: the addresses are the same
            _fns.append(fns)
    return _fns[0]
