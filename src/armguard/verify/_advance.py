"""The per-evaluation arithmetic of conservative advancement, as small numba kernels.

One call of :func:`advance_step` does, in one pass over the ``P`` pairs, what the certified loop
of :mod:`._verify` needs after every clearance evaluation (see its module docstring):

* the smallest gap ``g = min_p (d_p - m)`` and its pair (the collision test ``g <= contact``);
* the next step ``min over pairs with rate_p > 0 of (d_p - m) / rate_p`` (fraction of the
  segment): on it every pair's clearance stays above ``m`` because it shrinks by at most
  ``rate_p`` per unit of the segment fraction (:mod:`._motion`);
* the certified lower bound on the interval just crossed, of length ``L`` from the previous
  evaluation ``d'``: the clearance of pair ``p`` on it is at least
  ``min(d'_p, d_p, (d'_p + d_p - rate_p L) / 2)`` — the lowest point of two lines of slope
  ``-rate_p`` and ``+rate_p`` through the two ends (the Lipschitz bound).

:func:`advance_step_reference` is the NumPy statement of the same three quantities; the tests
check that they agree bit for bit.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["advance_step", "advance_step_reference", "owner_rows", "owner_rows_reference"]


@njit(cache=True)
def advance_step(d, d_prev, rates, margin, length, has_prev):
    """Gap, its pair, next step and interval lower bound in one pass (scalar style).

    Parameters
    ----------
    d : (P,) float64, m
        Clearances at the evaluation just made.
    d_prev : (P,) float64, m
        Clearances at the previous evaluation of the same segment (read only when ``has_prev``).
    rates : (P,) float64, m
        Bound on how much each clearance can shrink per unit of segment fraction.
    margin : float, m
        The stopping distance of the segment.
    length : float, 1
        Segment fraction from the previous evaluation to this one (read only when ``has_prev``).
    has_prev : bool

    Returns
    -------
    (g m, pair int, step 1, lb m)
        ``g`` is NaN (and ``pair`` -1) when a clearance is NaN; ``step`` is inf when no pair
        moves; ``lb`` is inf without ``has_prev``.
    """
    g = math.inf
    imin = -1
    step = math.inf
    lb = math.inf
    for p in range(d.shape[0]):
        dp = d[p]
        if dp != dp:
            return math.nan, -1, math.nan, math.nan
        r = rates[p]
        gap = dp - margin
        if imin < 0 or gap < g:
            g = gap
            imin = p
        if r > 0.0:
            st = gap / r
            if st < step:
                step = st
        if has_prev:
            a = d_prev[p]
            lo = a if a < dp else dp
            mid = 0.5 * (a + dp - r * length)
            if mid < lo:
                lo = mid
            if lo < lb:
                lb = lo
    return g, imin, step, lb


def advance_step_reference(d, d_prev, rates, margin, length, has_prev):
    """NumPy statement of :func:`advance_step` (slow, obviously correct; for the tests)."""
    d = np.asarray(d, dtype=np.float64)
    rates = np.asarray(rates, dtype=np.float64)
    if np.any(np.isnan(d)):
        return math.nan, -1, math.nan, math.nan
    gap = d - margin
    pos = rates > 0.0
    with np.errstate(over="ignore"):  # a tiny rate gives an infinite step, as in the kernel
        step = float(np.min(gap[pos] / rates[pos])) if np.any(pos) else math.inf
    lb = math.inf
    if has_prev:
        d_prev = np.asarray(d_prev, dtype=np.float64)
        lb = float(np.min(np.minimum(np.minimum(d_prev, d), 0.5 * (d_prev + d - rates * length))))
    return float(gap.min()), int(np.argmin(gap)), step, lb


@njit(cache=True)
def owner_rows(ev, owner, d, wit):  # pragma: no cover - compiled
    """The clearance of each owner pair (two links, bodies or payloads) from its shape pairs' rows.

    ``ev`` ``(n, 7)``: a detector's rows ``[d, p_WA, p_WB]``; ``owner`` ``(n,)``: each row's owner pair.
    Writes ``d[o]`` (which the caller set to +inf) the smallest distance of owner pair ``o``'s rows, the
    first of them on a tie (as the general path's stable ``lexsort``), NaN where any of its rows is
    NaN (never a verdict from it), and ``wit[o]`` ``(P, 6)`` that row's witnesses ``[p_WA, p_WB]``.
    Rows and owners of other lengths, or an owner pair out of range: ValueError (never a write past
    the arrays)."""
    if ev.shape[0] != owner.shape[0] or ev.shape[1] < 7 or wit.shape[0] != d.shape[0] or wit.shape[1] < 6:
        raise ValueError("owner_rows: rows, owners and outputs of mismatched shapes")
    for k in range(owner.shape[0]):
        if owner[k] < 0 or owner[k] >= d.shape[0]:
            raise ValueError("owner_rows: an owner pair out of range")
    for k in range(ev.shape[0]):
        o = owner[k]
        dk = ev[k, 0]
        if dk != dk or dk < d[o]:
            if d[o] != d[o]:
                continue  # NaN already: it stays
            d[o] = dk
            for j in range(6):
                wit[o, j] = ev[k, 1 + j]


def owner_rows_reference(ev, owner, P):
    """NumPy statement of :func:`owner_rows` over ``P`` owner pairs: ``(d (P,), wit (P, 6))``."""
    d = np.full(P, np.inf)
    wit = np.zeros((P, 6))
    for o in range(P):
        ks = np.flatnonzero(owner == o)
        if not len(ks):
            continue
        dd = ev[ks, 0]
        if np.isnan(dd).any():
            d[o] = math.nan
            wit[o] = ev[ks[np.flatnonzero(np.isnan(dd))[0]], 1:7]
            continue
        k = ks[int(np.argmin(dd))]  # argmin: the first of equal minima
        d[o] = ev[k, 0]
        wit[o] = ev[k, 1:7]
    return d, wit
