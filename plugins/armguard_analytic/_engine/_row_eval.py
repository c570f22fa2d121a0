"""A lean ``pair_distances(q, robot=)`` for callers that evaluate one robot's pairs at many
configurations of one scene revision: the certified verifier, the on-line Guard and the edge checker
(:class:`armguard.verify._record._Run`) evaluate a hundred configurations or more per call.

``FusedDetector.pair_distances`` re-reads the revision, the selection, the thread's scratch and the
argument on every call and copies its rows into a new ``PairDistances``: on ur5's 17 moving pairs
3.8 us of Python around a 5.4 us kernel call.  The evaluator binds the revision's compiled parts once
and hands back the thread's rows of the kernel (the same kernel, the same arguments: the same bits).
"""

from __future__ import annotations

import numpy as np

from . import _kernel as kn
from ._scratch import _entry_point, _Scratch

__all__ = ["row_evaluator"]


def row_evaluator(det, robot: str | None) -> tuple:
    """``(pair_index, rows)`` for ``det`` (a FusedDetector) and ``robot`` (None: every pair).

    ``pair_index`` ``(n,)``: the Detector pair number of each row, as ``PairDistances.pair_index``.
    ``rows(q)``: ``q`` a flat ``(n_q,)`` float64 configuration (scene joint order; the kernel refuses
    a non-finite value or one outside the joint limits, as ``pair_distances``); returns this thread's
    ``(n, 7)`` rows ``[d, p_WA, p_WB]``, valid until the thread's next query on ``det`` (copy what is
    kept), or None when the scene changed since the evaluator was made (its rows would be another
    revision's pairs: the caller asks ``pair_distances`` and sees the change)."""
    b = det._fresh()
    sel = b.selection(robot)[0]
    n = len(sel)
    scene, rev, tls = det.scene, b.revision, b.tls
    H, MF, MI, fn = b.H, b.MF, b.MI, b.fn
    # the kernel's compiled entry for these argument types, past numba's dispatcher, releasing the GIL
    # (pair_distances did; b.entry holds it for a short check: several threads' edges would queue)
    entry = b.pd_cache.get(("row_entry", robot))  # found once a revision (a verification makes an evaluator)
    if entry is None:
        s0 = _Scratch(b)  # its own buffers for the one typing call (a thread's scratch may hold a live report)
        entry = _entry_point(fn, s0.q1, H, MF, MI, s0.SF, s0.SI, b.lim[0], s0.iprm_by_mode[kn.MODE_ALL], sel)
        b.pd_cache[("row_entry", robot)] = entry

    def rows(q: np.ndarray):
        if getattr(scene, "revision", None) != rev:
            return None
        try:
            s = tls.s
        except AttributeError:
            s = det._scratch(b)
        det._release_last(s)  # a report of this thread's that still reads the scratch copies its rows out
        q1 = s.q1
        q1[0] = q
        err = entry(fn, q1, H, MF, MI, s.SF, s.SI, b.lim[0], s.iprm_by_mode[kn.MODE_ALL], sel)[2]
        if err:
            det._raise_kernel_error(err, q1, "Detector.pair_distances: q", b=b)
        return s.ev[:n]

    return sel, rows
