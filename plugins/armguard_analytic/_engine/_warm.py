"""The analytic backend's first-run warm-up: what ``AnalyticBackend.warm_up`` and
``warm_up_leaves`` give the framework's :mod:`armguard.cli._compile`.

The fused kernel is a chain of compiled calls (``detect_entry => detect_rows -> pair_step ->
narrow_other -> pair_distance =>`` the pair kernels; ``=>`` a call at an address, :mod:`._calls`,
``->`` a linked call): on a cold cache numba compiles it in one thread, over a minute on a 2-core
machine, more than half of it in a few leaf kernels that share nothing.  Compiled first with the
signatures the chain calls them with (some in a second process, the others in the first), they are
in numba's on-disk cache when the chain reaches them, and it only loads them.  A signature that no
longer matches the chain's call costs time, never an answer: the chain then compiles that kernel
itself (tests/test_detect_cold.py checks they all match).  The kernels called at an address
(:mod:`._calls`) link none of the others' trees, so the chain's kernels are leaves too (the pair
step inlines ``evaluate_pair`` and links ``narrow_flat``, ``detect_rows`` links the pair step); the Checker's
entry points (:data:`LEAVES_AFTER`) compile in the second process once the first has its leaves,
while the first compiles the geometry kernels and then the Detector's entry points.
Codes: F1/F2 float64 C arrays (1-D/2-D), I1/I2 int64 ones, f float64, i int64, b boolean.
"""

from __future__ import annotations

import numpy as np

from ._calls import NATIVE


def _native(module: str, name: str) -> tuple:
    """A plan entry for a kernel called at its address, its signature codes from :data:`._calls.NATIVE`
    (the one overload the address table looks up: the plan compiles exactly that one)."""
    return next((m, f, codes) for m, f, codes, _ in NATIVE if (m, f) == (module, name))

__all__ = ["LEAVES_AFTER", "LEAVES_MAIN", "LEAVES_SIDE", "warm_up"]

LEAVES_SIDE = (
    # the scanned GJK of the W-frame SAT path (convex_convex_fast's, in the first process, reaches
    # it later), then the link-frame narrow phase: cylinders (GJK and EPA on support functions),
    # SAT on hulls and boxes, EPA (narrow_rel calls them at their addresses, ._calls)
    ("armguard.geometry._pair_gjk", "gjk_dir", "F2 F2 f f f f f f f f i"),
    _native("armguard.geometry._pair_cylinder", "support_pair_graph"),
    _native("armguard_analytic._engine._narrow", "narrow_rel"),
    # the scalar pairs' narrow phase (capsules, boxes, spheres), the pair step (it links narrow_flat and
    # inlines evaluate_pair) and the fused rows (they link the pair step)
    ("armguard_analytic._engine._narrow", "narrow_flat", "i i I1 F1 I1 F1 F1 f f f"),
    _native("armguard_analytic._engine._step", "pair_step"),
    _native("armguard_analytic._engine._kernel", "detect_rows"),
    # the static pairs' branch and bound (it calls the pair step at its address): here, while the
    # first process compiles the geometry kernels
    _native("armguard_analytic._engine._static_gjk", "static_gjk_pairs"),
)
"""Leaf kernels compiled in the second process: (module, function, signature codes)."""
LEAVES_MAIN = (
    # the link-frame GJK, then narrow_rel's SAT and EPA (narrow_rel, in the second process, calls them
    # at their addresses)
    _native("armguard.geometry._pair_gjk", "gjk_dir_rel"),
    _native("armguard_analytic._engine._narrow", "_sat_rel"),
    _native("armguard.geometry._pair_epa", "epa_depth"),
    # the other pairs' narrow phase (pair_distance; the capsule-polytope kernel linked), which the pair
    # step in the second process links: compiled early, before that process reaches the pair step
    ("armguard_analytic._engine._narrow", "_capsule_polytope", "F2 f i F2 F2 I2 F2 F2 I1 I1 I1 f F1 f f f i f"),
    _native("armguard_analytic._engine._narrow", "narrow_other"),
    # the W-frame convex kernel (pair_distance calls it at its address) and the culling tests
    _native("armguard.geometry._pair_epa", "convex_convex_fast"),
    ("armguard_analytic._engine._cull", "obb_apart_moving", "F1 i i i i F1 f f"),
    ("armguard_analytic._engine._cull", "obb_apart_static", "F1 i i F1 i f f"),
)
"""Leaf kernels compiled in the first process while the second compiles :data:`LEAVES_SIDE`."""
LEAVES_AFTER = (
    # the Checker's entry points, in the second process while the first compiles the geometry kernels
    ("armguard_analytic._engine._pair_rows", "pair_rows", "I1 F1 i i I1 I1 F1 I1 F1 I1 F1 I1 F2 F1 F2 F2"),
    ("armguard_analytic._engine._pair_rows", "pair_rows_held", "I1 F1 i i I1 I1 F1 I1 F1 I1 F1 I1 F2 F1 F2 F2"),
)
"""Kernels the second process compiles after the first process's :data:`LEAVES_MAIN` (no kernel
of either list waits for them); :func:`warm_up` waits for them by name."""


def warm_up(scene, wait=None) -> None:
    """Compile (or load) the fused Detector's entry points and the Checker's ``pair_rows`` on
    ``scene``, both GIL policies, with the argument types their callers pass.

    ``wait(name)`` (the framework's, while a second process compiles :data:`LEAVES_AFTER`) blocks
    until that process has compiled kernel ``name``: the Checker's entry points (``pair_rows``) are
    loaded once there.  (The framework runs this once the second process's leaves are compiled:
    every kernel whose address the Detector takes is in numba's cache by then.)"""
    wait = wait or (lambda name: None)
    from . import _kernel as kn
    from ._detector import FusedDetector
    from ._pair_rows import pair_rows, pair_rows_held
    from ._scratch import _entry_point, _Scratch

    det = FusedDetector(scene, threshold=0.05)
    q = scene.flat_q(scene.default_q())
    det.check(q)
    det.check_many(np.tile(q, (4, 1)))
    # the entry point that holds the GIL (calls too short for handing it over to pay, ._scratch)
    b = det._b
    s = _Scratch(b)
    _entry_point(*s.entry_args, release_gil=False)
    # the Checker's pair_distances(_many): pair_rows, with the argument types it is given
    n, nq = det.n_pairs, len(q)
    gmap = np.concatenate([[nq, nq, 0, n], np.arange(nq), np.arange(n), np.zeros(n)]).astype(np.int64)
    call = (b.fn, np.ascontiguousarray(q, dtype=np.float64), 0, 1, gmap, b.H, b.MF, b.MI, s.SF, s.SI, b.prm,
            b.iprm_by_mode[kn.MODE_ALL], s.q1, np.empty(n), np.empty((n, 3)), np.empty((n, 3)))
    wait("pair_rows")
    pair_rows(*call)
    wait("pair_rows_held")
    pair_rows_held(*call)
