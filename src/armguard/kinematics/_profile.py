"""Time laws of one trajectory segment: trapezoidal velocity (Ranger's canned tests) and linear.

A segment of duration ``T`` (s) moves every joint along the straight joint-space line
``q(t) = q0 + s(t - t0) (q1 - q0)`` with a path parameter ``s`` in [0, 1] whose speed is a
trapezoid: constant acceleration for the blend time ``tb`` (s, 0 <= tb <= T/2), cruise, and
symmetric deceleration to rest.  ``tb = 0`` is the linear (constant velocity) law; ``tb = T/2``
the triangular one.  With ``v = 1 / (T - tb)`` the peak path speed and ``a = v / tb``:

    s(t) = a t^2 / 2                  for 0 <= t < tb
           v (t - tb / 2)             for tb <= t <= T - tb
           1 - a (T - t)^2 / 2        for T - tb < t <= T

Synchronising joints (bon & Seraji's canned tests command "a trapezoidal trajectory" of several
coordinates at once; here the joints share one ``s``) makes joint j's peak speed ``D_j v`` and
acceleration ``D_j a`` with ``D_j = |q1_j - q0_j|``.  With ``A = max_j D_j / vmax_j`` (s) and
``B = max_j D_j / amax_j`` (s^2) the shortest feasible segment is (derived here; the seed gives
no formula):  ``T = A + B / A``, ``tb = B / A`` when ``B <= A^2`` (the slowest joint reaches its
speed limit), else ``T = 2 sqrt(B)``, ``tb = T / 2`` (triangular).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["MAX_POSE_SAMPLES", "min_time_trapezoid", "blend_for_duration", "path_s", "path_tau", "path_ds", "pose_samples"]

MAX_POSE_SAMPLES = 100_000
"""Most poses a task-space motion is sampled at (each one an inverse-kinematics solve, tens of µs): a
speed of 1e-300 m/s made a duration whose sample count ``np.linspace`` refused (an internal error),
1e-6 m/s ran for minutes."""

_ROUNDOFF = 1e-12
"""Relative round-off allowed when checking a given duration against the acceleration bound."""


def min_time_trapezoid(D: np.ndarray, vmax: np.ndarray, amax: np.ndarray) -> tuple[float, float]:
    """Shortest synchronised trapezoid: ``(T, tb)`` s for joint distances ``D`` (n,) (rad or m).

    Infinite ``amax`` gives the linear law (``tb = 0``); infinite ``vmax`` the triangular one;
    both infinite raises ValueError (no time scale).
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        A = float(np.max(np.where(D > 0, D / vmax, 0.0), initial=0.0))
        B = float(np.max(np.where(D > 0, D / amax, 0.0), initial=0.0))
    if A == 0.0 and B == 0.0:
        if np.any(D > 0):
            raise ValueError("no finite max_velocity or max_acceleration for the moving joints")
        return 0.0, 0.0
    if B == 0.0:
        return A, 0.0
    if A > 0.0 and B <= A * A:
        return A + B / A, B / A
    T = 2.0 * math.sqrt(B)
    return T, 0.5 * T


def blend_for_duration(T: float, D: np.ndarray, vmax: np.ndarray, amax: np.ndarray) -> float | None:
    """Blend time ``tb`` for a given duration ``T``: the one with the least peak acceleration
    (``tb = min(T/2, T - A)``), or None if no trapezoid of duration ``T`` meets the limits."""
    with np.errstate(divide="ignore", invalid="ignore"):
        A = float(np.max(np.where(D > 0, D / vmax, 0.0), initial=0.0))
        B = float(np.max(np.where(D > 0, D / amax, 0.0), initial=0.0))
    tb = min(0.5 * T, T - A)
    if tb < 0.0 or (B > 0.0 and tb * (T - tb) < B * (1.0 - _ROUNDOFF)):
        return None
    return tb


def path_s(tau: np.ndarray, T: np.ndarray, tb: np.ndarray) -> np.ndarray:
    """Path parameter ``s`` in [0, 1] at times ``tau`` (...) s into segments of duration ``T``, blend ``tb`` (...)."""
    tau, T, tb = np.broadcast_arrays(*(np.asarray(x, dtype=np.float64) for x in (tau, T, tb)))
    tau = np.clip(tau, 0.0, T)
    v = 1.0 / (T - tb)
    with np.errstate(divide="ignore", invalid="ignore"):
        acc = np.where(tb > 0.0, v / tb, 0.0)
    r = T - tau
    s = np.where(tau < tb, 0.5 * acc * tau * tau, np.where(r < tb, 1.0 - 0.5 * acc * r * r, v * (tau - 0.5 * tb)))
    return np.where(tau >= T, 1.0, s)


def path_tau(s: np.ndarray, T: np.ndarray, tb: np.ndarray) -> np.ndarray:
    """The inverse of :func:`path_s`: the time ``tau`` (...) s into a segment of duration ``T``, blend ``tb``,
    at which its path parameter is ``s`` (clipped to [0, 1]): the accelerating parabola's, the cruise's or
    the decelerating parabola's closed form."""
    s, T, tb = np.broadcast_arrays(*(np.asarray(x, dtype=np.float64) for x in (s, T, tb)))
    s = np.clip(s, 0.0, 1.0)
    v = 1.0 / (T - tb)
    sb = 0.5 * v * tb  # s at the end of the acceleration (and 1 - sb at the start of the deceleration)
    with np.errstate(divide="ignore", invalid="ignore"):
        up = np.sqrt(2.0 * s * tb / v)  # s = v tau^2 / (2 tb)
        down = T - np.sqrt(2.0 * (1.0 - s) * tb / v)
    tau = np.where(s < sb, up, np.where(s > 1.0 - sb, down, s / v + 0.5 * tb))
    return np.clip(np.where(s <= 0.0, 0.0, np.where(s >= 1.0, T, tau)), 0.0, T)


def path_ds(tau: np.ndarray, T: np.ndarray, tb: np.ndarray) -> np.ndarray:
    """Path speed ``ds/dt`` (1/s) at times ``tau`` (...) into the segments (0 outside them)."""
    tau, T, tb = np.broadcast_arrays(*(np.asarray(x, dtype=np.float64) for x in (tau, T, tb)))
    v = 1.0 / (T - tb)
    with np.errstate(divide="ignore", invalid="ignore"):
        acc = np.where(tb > 0.0, v / tb, 0.0)
    r = T - tau
    ds = np.where(tau < tb, acc * tau, np.where(r < tb, acc * r, v))
    return np.where((tau < 0.0) | (tau > T), 0.0, ds)


def pose_samples(duration: float, frequency: float, what: str, error) -> int:
    """Samples (>= 1) of a task-space motion of ``duration`` s at ``frequency`` Hz; more than
    :data:`MAX_POSE_SAMPLES` is ``error`` naming ``what`` and the figures that make it so many."""
    n = duration * frequency
    if not n <= MAX_POSE_SAMPLES:  # an infinite or a NaN product too
        raise error(f"{what}: {duration:.4g} s at {frequency:.4g} Hz is {n:.3g} poses to solve, more than "
                    f"{MAX_POSE_SAMPLES}: raise the speed (or lower the frequency)")
    return max(1, int(math.ceil(n)))
