"""The analytic Checker's entry point: every pair of a selection, in the Model's joint and pair order.

``AnalyticChecker.pair_distances(_many)`` (:mod:`armguard_analytic`) is one call of
:func:`pair_rows`: it reorders Pinocchio's joints into the scene's, runs the fused kernel's
all-pairs mode (:func:`._kernel.detect_rows`, ``MODE_ALL``) and writes each selected pair's row
straight into the caller's arrays, sides exchanged where the Model holds the pair the other way
round.  Split from :mod:`._kernel` (it calls that kernel and reads the same packed buffers); it
calls the kernel at its address (:func:`._calls.addresses`, the first argument), so it compiles
its own lines only (:mod:`._native`).  Compiled without numba's reference counting, as the
Detector's entry points (:mod:`._entry`): the fixed cost per call of ``python -m bench pair_profile``.
"""

from __future__ import annotations

import math

import numpy as np

from numba import njit

from armguard.backends._interface import UNIT_CIRCLE  # compiled in as a constant (numba's cache keys on this file)

# The segment numbers K come from ._layout and are compiled in as constants; numba's cache keys on
# this file only, so a change of the segment tuples in ._layout must come with an edit here.
from ._layout import EV_W, K, SUM_STATUS, seg1, seg2, view2
from ._calls import FN_ROWS, call_rows

__all__ = ["pair_rows", "pair_rows_held", "scene_rows"]

_K_best = K["best"]
_K_ev = K["ev"]
_K_summary = K["summary"]


@njit(cache=True, inline="always")
def _scene_row(Q, b, qidx, circ, out) -> bool:  # pragma: no cover - compiled
    """One row of Pinocchio's joint values (``Q[b:b + nq]``) in the scene's joint order, into ``out``:
    the scene's joint ``k`` is ``Q[b + qidx[k]]``, a continuous joint ``k`` in ``circ`` the angle of
    Pinocchio's ``(cos, sin)`` there.  False (``out`` partly written) where such a pair is off the unit
    circle (``UNIT_CIRCLE``).  :func:`pair_rows`' joint map and :func:`scene_rows`'."""
    for k in range(qidx.shape[0]):
        out[k] = Q[b + qidx[k]]
    for c in range(circ.shape[0]):
        k = circ[c]
        i = b + qidx[k]
        x = Q[i]
        y = Q[i + 1]
        if abs(x * x + y * y - 1.0) > UNIT_CIRCLE:
            return False
        out[k] = math.atan2(y, x)
    return True


@njit(cache=True, nogil=True, _nrt=False)
def pair_rows(fns, Q, lo, hi, gmap, H, MF, MI, SF, SI, prm, iprm, q1, d_out, pA_out, pB_out):  # pragma: no cover - compiled
    """Every pair of a selection at rows ``lo:hi`` of ``Q`` (Pinocchio's joint order, flattened:
    row ``m`` is ``Q[m * nq:(m + 1) * nq]``), written straight into the caller's order.

    ``gmap`` (int64): ``[nq, n_q, n_circ, n_sel, qidx (n_q), circ (n_circ), sel (n_sel), swap (n_sel)]``
    -- the scene's joint ``k`` is ``Q[qidx[k]]`` (a continuous joint ``k`` in ``circ``: the angle of
    Pinocchio's ``(cos, sin)`` at ``qidx[k]``), output row ``j`` is the detector's pair ``sel[j]``,
    with sides A and B exchanged where ``swap[j]``.  Row ``m``'s pairs go to rows ``m * n_sel + j``
    of ``d_out`` ``(., )`` and ``pA_out`` / ``pB_out`` ``(., 3)``.  ``q1`` ``(1, n_q)``: scratch.
    ``fns``: :func:`._calls.addresses`.
    Returns 0, else ``err + 4 * m`` for the first failing row ``m`` (``err`` as :func:`detect_rows`).
    Releases the GIL: callers on several threads, each with its own ``SF`` / ``SI`` / ``q1``, run in
    parallel (:func:`pair_rows_held` holds it)."""
    nq = gmap[0]
    n_q = gmap[1]
    n_circ = gmap[2]
    n_sel = gmap[3]
    o_circ = 4 + n_q
    o_sel = o_circ + n_circ
    qidx = gmap[4:o_circ]
    circ = gmap[o_circ:o_sel]
    sel = gmap[o_sel:o_sel + n_sel]
    o_sw = o_sel + n_sel
    summary = seg1(SI, H, _K_summary)
    best = view2(SF, H[2 * _K_best], 1, 4)
    st = summary[SUM_STATUS:SUM_STATUS + 1]
    ev = seg2(SF, H, _K_ev, EV_W)
    for m in range(lo, hi):
        b = m * nq
        for i in range(nq):
            if not np.isfinite(Q[b + i]):
                return 1 + 4 * m
        if not _scene_row(Q, b, qidx, circ, q1[0]):  # a (cos, sin) off the unit circle: check_q says so
            return 1 + 4 * m
        err = call_rows(fns[FN_ROWS], (q1, np.int64(0), np.int64(1), H, MF, MI, SF, SI, prm, iprm, sel, best, st,
                                       fns))
        if err != 0:
            return err + 4 * m
        o = m * n_sel
        for j in range(n_sel):
            r = o + j
            d_out[r] = ev[j, 0]
            if gmap[o_sw + j] != 0:
                for x in range(3):
                    pA_out[r, x] = ev[j, 4 + x]
                    pB_out[r, x] = ev[j, 1 + x]
            else:
                for x in range(3):
                    pA_out[r, x] = ev[j, 1 + x]
                    pB_out[r, x] = ev[j, 4 + x]
    return 0


@njit(cache=True, _nrt=False)
def pair_rows_held(fns, Q, lo, hi, gmap, H, MF, MI, SF, SI, prm, iprm, q1, d_out, pA_out, pB_out):  # pragma: no cover - compiled
    """:func:`pair_rows`, the GIL held: for calls so short that handing the GIL to another thread and
    back costs more than the call (``AnalyticChecker`` picks it by the call's measured time)."""
    return pair_rows(fns, Q, lo, hi, gmap, H, MF, MI, SF, SI, prm, iprm, q1, d_out, pA_out, pB_out)


@njit(cache=True, nogil=True)
def scene_rows(Q, qidx, circ, out):  # pragma: no cover - compiled
    """Pinocchio's rows ``Q`` ``(M, nq)`` into the scene's joint order ``out`` ``(M, n_q)``, as
    :func:`pair_rows` reads them (``qidx``, ``circ`` of its ``gmap``): the scene's joint ``k`` is
    ``Q[:, qidx[k]]``, a continuous joint ``k`` in ``circ`` the angle of the ``(cos, sin)`` there.
    Returns the first row whose ``(cos, sin)`` is off the unit circle (``UNIT_CIRCLE``), else -1 (a
    non-finite value is passed on: the kernel refuses its row).  The Checker's ``collides`` on a
    model with continuous joints, in place of ``check_unit_circle`` and ``Model.scene_q`` (numpy,
    most of a one-row call's Python; its cost now: ``python -m bench backends``, kinova's *Python
    per call* of ``collides``)."""
    for m in range(Q.shape[0]):
        if not _scene_row(Q[m], 0, qidx, circ, out[m]):
            return m
    return -1
