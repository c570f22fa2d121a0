"""A trajectory's segments and the inversion of their time laws (shared by verification and terrain).

Every segment moves on the straight joint-space line ``q(s) = q0 + s (q1 - q0)``; its time law
(a trapezoid, or any ``trajectory.at``) says when it is at fraction ``s``.  Conservative
advancement works in ``s``; a reported collision's time inverts the law in closed form (a plain
Trajectory's trapezoid), else by bisection on the joint that moves most (:func:`segment_times`);
the clearance profile's time axis likewise, else by tabulating it (:func:`profile_times`).
"""

from __future__ import annotations

import numpy as np

from .._errors import VerificationError
from .._values import refuse_complex_or_bool

__all__ = ["segments_of", "segment_times", "profile_times", "finite_array", "TIME_BISECTIONS", "PROFILE_TABLE"]

TIME_BISECTIONS = 60
"""Bisection steps inverting a segment's time law (2^-60 of the segment time)."""
PROFILE_TABLE = 65
"""Time-law samples per segment for the clearance profile's time axis."""


def finite_array(x, name: str) -> np.ndarray:
    refuse_complex_or_bool(x, name, VerificationError)
    a = np.asarray(x, dtype=np.float64)
    if not np.all(np.isfinite(a)):
        raise VerificationError(f"{name}: contains NaN or infinite values")
    return a


def segments_of(trajectory) -> list:
    """The trajectory's segments ``(t0, t1, q0, q1)``; NaN or infinite knots are refused."""
    from ..kinematics import Trajectory

    if type(trajectory).segments is Trajectory.segments:  # the arrays behind Trajectory.segments, without the generator
        T = np.asarray(trajectory.times, dtype=np.float64).tolist()
        W = np.asarray(trajectory.waypoints, dtype=np.float64)
        finite_array(W, "trajectory knot")
        return [(T[k], T[k + 1], W[k], W[k + 1]) for k in range(len(T) - 1)]
    segs = []
    for t0, t1, q0, q1 in trajectory.segments():
        segs.append((float(t0), float(t1), np.asarray(q0, dtype=np.float64), np.asarray(q1, dtype=np.float64)))
    if not segs:
        raise VerificationError("the trajectory has no segment")
    finite_array(np.stack([sg[2] for sg in segs] + [sg[3] for sg in segs]), "trajectory knot")
    return segs


def segment_times(trajectory, segs, seg_idx, s) -> np.ndarray:
    """Invert the time laws: the time at which segment ``seg_idx[i]`` is at fraction ``s[i]`` (vectorised bisection)."""
    seg_idx = np.asarray(seg_idx, dtype=np.int64)
    s = np.asarray(s, dtype=np.float64)
    if s.size == 0:
        return np.zeros(0)
    closed = _closed_form(trajectory, segs, seg_idx, s)
    if closed is not None:
        return closed
    t0 = np.array([segs[i][0] for i in seg_idx])
    t1 = np.array([segs[i][1] for i in seg_idx])
    dq = np.array([segs[i][3] - segs[i][2] for i in seg_idx])
    q0 = np.array([segs[i][2] for i in seg_idx])
    k = np.argmax(np.abs(dq), axis=1)
    rows = np.arange(len(s))
    span = dq[rows, k]
    moving = np.abs(span) > 0.0
    lo, hi = t0.copy(), t1.copy()
    for _ in range(TIME_BISECTIONS):
        mid = 0.5 * (lo + hi)
        qm = np.asarray(trajectory.at(mid))
        frac = np.where(moving, (qm[rows, k] - q0[rows, k]) / np.where(moving, span, 1.0), 0.0)
        below = frac < s
        lo = np.where(below, mid, lo)
        hi = np.where(below, hi, mid)
    t = 0.5 * (lo + hi)
    t = np.where(s <= 0.0, t0, np.where(s >= 1.0, t1, t))
    return np.where(~moving & (s > 0.0) & (s < 1.0), t0 + s * (t1 - t0), t)


def _closed_form(trajectory, segs, seg_idx: np.ndarray, s: np.ndarray):
    """:func:`segment_times` of a plain :class:`~armguard.kinematics.Trajectory` (its ``at`` not overridden:
    every joint moves by ``path_s`` of the segment's trapezoid) by the law's closed-form inverse
    (:func:`armguard.kinematics._profile.path_tau`; a still segment: its time line), or None (a time law
    of its own: bisection).  The bisection's 60 calls of ``trajectory.at`` took ~5 ms of a colliding
    verification's report."""
    from ..kinematics import Trajectory
    from ..kinematics._profile import path_tau

    if type(trajectory).at is not Trajectory.at:
        return None
    t0 = np.array([segs[i][0] for i in seg_idx], dtype=np.float64)
    t1 = np.array([segs[i][1] for i in seg_idx], dtype=np.float64)
    times = np.asarray(trajectory.times, dtype=np.float64)
    seg = np.clip(np.searchsorted(times, t0, side="right") - 1, 0, len(times) - 2)
    if not (np.array_equal(times[seg], t0) and np.array_equal(times[seg + 1], t1)):
        return None  # not this trajectory's segments
    still = np.array([not np.any(segs[i][3] - segs[i][2]) for i in seg_idx], dtype=bool)
    return np.where(still, t0 + s * (t1 - t0), t0 + path_tau(s, t1 - t0, np.asarray(trajectory._blend)[seg]))


def profile_times(trajectory, segs, seg_idx: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Times of the profile points: each segment's time law tabulated at ``PROFILE_TABLE`` points
    (one ``trajectory.at`` call) and inverted by monotone interpolation — for plotting; the
    reported collision time is inverted exactly (:func:`segment_times`).  A plain Trajectory's times are
    the closed form's, exact (:func:`_closed_form`)."""
    seg_idx = np.asarray(seg_idx, dtype=np.int64)
    s = np.asarray(s, dtype=np.float64)
    closed = _closed_form(trajectory, segs, seg_idx, s) if len(s) else None
    if closed is not None:
        return closed
    used = np.unique(seg_idx)
    u = np.linspace(0.0, 1.0, PROFILE_TABLE)
    T = np.concatenate([segs[i][0] + u * (segs[i][1] - segs[i][0]) for i in used])
    Q = np.asarray(trajectory.at(T)).reshape(len(used), PROFILE_TABLE, -1)
    out = np.empty(len(s))
    for row, i in enumerate(used):
        t0, t1, q0, q1 = segs[i]
        dq = q1 - q0
        k = int(np.argmax(np.abs(dq)))
        sel = seg_idx == i
        if dq[k] == 0.0:
            out[sel] = t0 + s[sel] * (t1 - t0)
            continue
        frac = np.maximum.accumulate((Q[row, :, k] - q0[k]) / dq[k])
        out[sel] = np.interp(s[sel], frac, T[row * PROFILE_TABLE : (row + 1) * PROFILE_TABLE])
    return out
