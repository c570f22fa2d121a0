"""One avoidance step without per-call NumPy: the damper's rows and the answer's checks in numba.

:func:`armguard.avoidance.avoid` is the reference: plain NumPy on a
:class:`~armguard.backends.PairDistances`, a dozen small array operations (each ~1 µs) around the
QP.  :func:`filter_velocity` does the same on bare arrays with two compiled calls, one before DAQP
(which pairs are within the influence distance with a Jacobian row longer than ``Tolerances.avoid_row``, their bounds (1) of
:mod:`armguard.avoidance`, the command clipped to the limits, whether any constraint binds) and one
after it (the largest constraint violation, the closing speeds, the status's maxima); DAQP gets the
same matrices, so the answers are the reference's (``tests/test_avoidance.py`` holds them equal).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["filter_velocity"]

_BIG = 1e30  # DAQP's "no bound"


@njit(cache=True, nogil=True)
def _rows(d, J, v_cmd, lo, hi, influence, stand_off, rate, row_min2, rows, A, b, clipped, upper, lower):  # pragma: no cover
    """The damper's constraint rows of ``d`` ``(n,)``, ``J`` ``(n, nv)``: writes ``rows``, ``A``,
    ``b`` (the first ``k`` entries), ``clipped`` ``(nv,)`` (the command within ``[lo, hi]``, the velocity
    bounds: ``lo <= 0 <= hi``) and DAQP's bounds ``upper`` / ``lower``
    ``(nv + k,)``; returns ``(k, binds, bad, near)`` (``binds``: some row has ``A clipped < b``; ``bad``:
    1 a non-finite command, 2 a non-finite distance, 3 a non-finite Jacobian entry in any row, as
    :func:`armguard.avoidance.avoid` refuses it; ``near``: the pairs within influence, moving or not)."""
    n, nv = J.shape
    for c in range(nv):
        if not math.isfinite(v_cmd[c]):
            return 0, False, 1, 0
        x = min(max(v_cmd[c], lo[c]), hi[c])
        clipped[c] = x
        upper[c] = min(hi[c], _BIG)
        lower[c] = max(lo[c], -_BIG)
    k = near = 0
    binds = False
    for i in range(n):
        di = d[i]
        if not math.isfinite(di):
            return 0, False, 2, 0
        norm2 = 0.0
        for c in range(nv):
            x = J[i, c]
            if not math.isfinite(x):
                return 0, False, 3, 0
            norm2 += x * x
        if not di < influence:
            continue
        near += 1
        if not norm2 > row_min2:  # no joint moves this distance (Tolerances.avoid_row)
            continue
        s = 0.0
        for c in range(nv):
            A[k, c] = J[i, c]
            s += J[i, c] * clipped[c]
        bk = -rate * max(di - stand_off, 0.0)
        b[k] = bk
        if not s >= bk:  # a closing that overflowed (NaN) binds too: never FREE on it
            binds = True
        rows[k] = i
        upper[nv + k] = _BIG
        lower[nv + k] = bk
        k += 1
    return k, binds, 0, near


@njit(cache=True, nogil=True)
def _check(v, v_cmd, lo, hi, A, b, k, closing):  # pragma: no cover - numba
    """``(worst, |v|_max, |v_cmd|_max, |v - v_cmd|_max, finite)`` of the answer ``v``: the largest
    violation of a damper row or a limit (0 if none); writes ``closing[:k] = A[:k] v``."""
    nv = v.shape[0]
    worst = 0.0
    vmax = cmax = dmax = 0.0
    finite = True
    for c in range(nv):
        x = v[c]
        if not math.isfinite(x):
            finite = False
        worst = max(worst, x - hi[c], lo[c] - x)
        vmax = max(vmax, abs(x))
        cmax = max(cmax, abs(v_cmd[c]))
        dmax = max(dmax, abs(x - v_cmd[c]))
    for r in range(k):
        s = 0.0
        for c in range(nv):
            s += A[r, c] * v[c]
        closing[r] = s
        worst = max(worst, b[r] - s)
    return worst, vmax, cmax, dmax, finite


class _Buffers:
    """Per ``(n, nv)``: the work arrays of one step (fresh per call: an answer holds views of them)."""

    __slots__ = ("eye", "sense")

    def __init__(self, n: int, nv: int) -> None:
        self.eye = np.eye(nv)
        self.sense = np.zeros(nv + n, dtype=np.intc)


_BUFFERS: dict = {}


def filter_velocity(v_cmd: np.ndarray, d: np.ndarray, J: np.ndarray, lo: np.ndarray, hi: np.ndarray, damper,
                    tol) -> tuple:
    """``(velocity, rows, rate, closing, status, note)`` of :func:`armguard.avoidance.avoid` for
    the distances ``d`` ``(n,)`` and Jacobian rows ``J`` ``(n, nv)`` (float64, C-contiguous),
    the command ``v_cmd`` ``(nv,)`` and the velocity bounds ``lo <= 0 <= hi`` ``(nv,)`` (the damper's
    limits, tightened by the joint limits: :func:`armguard.avoidance.velocity_bounds`); ``rows`` index ``d``.  A non-finite
    input is a :class:`~armguard.AvoidanceError` (no velocity from NaN)."""
    from .._errors import AvoidanceError
    from . import AvoidanceStatus, _quiet_note

    n, nv = J.shape
    rows = np.empty(n, np.int64)
    A = np.empty((n, nv))
    b = np.empty(n)
    clipped = np.empty(nv)
    upper = np.empty(nv + n)
    lower = np.empty(nv + n)
    k, binds, bad, near = _rows(d, J, v_cmd, lo, hi, damper.influence, damper.stand_off, damper.rate(), tol.avoid_row ** 2, rows,
                          A, b, clipped, upper, lower)
    if bad:
        what = {1: "v_cmd: contains NaN or infinite values", 2: "avoid: a distance is NaN or infinite",
                3: "avoid: a Jacobian entry is NaN or infinite"}[bad]
        raise AvoidanceError(f"{what}; no velocity can be given" if bad > 1 else f"{what}: {v_cmd.tolist()}")
    rows, A, b = rows[:k], A[:k], b[:k]
    closing = np.empty(k)
    if not binds:
        v = clipped
        note = _quiet_note(k, near)
    else:
        import daqp

        buf = _BUFFERS.get((n, nv))
        if buf is None:
            buf = _BUFFERS[(n, nv)] = _Buffers(n, nv)
        x, _, flag, _ = daqp.solve(buf.eye, -v_cmd, A, upper[:nv + k], lower[:nv + k], buf.sense[:nv + k])
        # the limits exactly: DAQP meets a bound to its own tolerance (1.9e-34 rad/s was seen on a column
        # whose limit is 0, another robot's under a Guard); the constraint check below reads this velocity
        v = np.clip(np.asarray(x, dtype=np.float64), lo, hi)
        note = "daqp: optimal"
        if flag != 1:
            v, note = np.zeros(nv), f"daqp: exit flag {flag}; stopped"
    worst, vmax, cmax, dmax, finite = _check(v, v_cmd, lo, hi, A, b, k, closing)
    if binds and note == "daqp: optimal":
        if not finite:
            v, note = np.zeros(nv), "daqp: exit flag 1; stopped"
        elif worst > tol.avoid_feasibility:
            v, note = np.zeros(nv), f"daqp: a constraint broken by {worst:.3g}; stopped"
        if not note == "daqp: optimal":
            worst, vmax, cmax, dmax, finite = _check(v, v_cmd, lo, hi, A, b, k, closing)
    still = tol.avoid_still
    if nv and vmax <= still and cmax > still:
        status = AvoidanceStatus.STOPPED
    elif not nv or dmax <= still:
        status = AvoidanceStatus.FREE
    else:
        status = AvoidanceStatus.SLOWED
    return v, rows, b, closing, status, note
