"""3-vectors as tuples for the ``fidelity = "paper"`` kernels (compiled, inlined): the arithmetic the
papers' modules are written in, shared by Ranger's (:mod:`._paper_kernels`) and Hermes's
(:mod:`._paper_hermes`) kernels."""

from __future__ import annotations

import math

from numba import njit


# ---------------------------------------------------------------- 3-vectors as tuples
@njit(cache=True, inline="always")
def _v(a, i):  # pragma: no cover - compiled
    return (a[i, 0], a[i, 1], a[i, 2])


@njit(cache=True, inline="always")
def _sub(a, b):  # pragma: no cover - compiled
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@njit(cache=True, inline="always")
def _dot(a, b):  # pragma: no cover - compiled
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True, inline="always")
def _axpy(p, t, a):  # pragma: no cover - compiled
    return (p[0] + t * a[0], p[1] + t * a[1], p[2] + t * a[2])


@njit(cache=True, inline="always")
def _cross(a, b):  # pragma: no cover - compiled
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@njit(cache=True, inline="always")
def _dist(a, b):  # pragma: no cover - compiled
    d = _sub(b, a)
    return math.sqrt(_dot(d, d))


@njit(cache=True, inline="always")
def _on_segment(P, A, l, X):  # pragma: no cover - compiled
    """The point of segment ``P + t A``, ``t`` in [0, l] (A unit), nearest to ``X``."""
    return _axpy(P, min(max(_dot(_sub(X, P), A), 0.0), l), A)
