"""Culling bounds of the detector's hot path (scalar, on flat buffers) and its allocation-free sort.

Each ``*_gap`` is a lower bound on the distance between a moving element and anything inside a
box: ``<= 0`` when the volumes overlap (then it bounds nothing).  Closed forms: the distance from
a point to an axis-aligned box is the norm of the per-axis excess ``max(lo - x, 0, x - hi)``; to
an oriented box, the same in the box's frame; between two axis-aligned boxes, the norm of the
per-axis gaps.
"""

from __future__ import annotations

import math

from numba import njit

@njit(cache=True, inline="always")
def _obb_gap(cx, cy, cz, r, B, o):  # pragma: no cover - compiled
    """Distance (m) from the sphere ``(c, r)`` to the box ``B[o:o + 15]`` = ``[centre, half extents, R_WB
    row-major]`` (<= 0 when they overlap): the exact sphere-OBB gap, a lower bound for anything in the sphere."""
    wx = cx - B[o]
    wy = cy - B[o + 1]
    wz = cz - B[o + 2]
    x = B[o + 6] * wx + B[o + 9] * wy + B[o + 12] * wz  # x_B = R_WB^T (c - o)
    y = B[o + 7] * wx + B[o + 10] * wy + B[o + 13] * wz
    z = B[o + 8] * wx + B[o + 11] * wy + B[o + 14] * wz
    dx = max(abs(x) - B[o + 3], 0.0)
    dy = max(abs(y) - B[o + 4], 0.0)
    dz = max(abs(z) - B[o + 5], 0.0)
    return math.sqrt(dx * dx + dy * dy + dz * dz) - r


@njit(cache=True, inline="always")
def _sb_gap(cx, cy, cz, r, B, olo, ohi):  # pragma: no cover - compiled
    """Distance (m) between the sphere ``(c, r)`` and the box ``[B[olo:olo + 3], B[ohi:ohi + 3]]``; <= 0 if
    they overlap (:func:`._bvh.sphere_box_gap` on a flat buffer: no array views in the hot loop)."""
    dx = max(B[olo] - cx, 0.0, cx - B[ohi])
    dy = max(B[olo + 1] - cy, 0.0, cy - B[ohi + 1])
    dz = max(B[olo + 2] - cz, 0.0, cz - B[ohi + 2])
    return math.sqrt(dx * dx + dy * dy + dz * dz) - r


@njit(cache=True, inline="always")
def _bb_gap(lx, ly, lz, hx, hy, hz, r, B, olo, ohi):  # pragma: no cover - compiled
    """Distance (m) between the box ``[l, h]`` grown by ``r`` and the box ``[B[olo:olo + 3], B[ohi:ohi + 3]]``;
    <= 0 if they overlap.  With ``[l, h]`` the W-aligned box of a capsule's segment and ``r`` its
    radius, a lower bound on the capsule's distance to anything in the second box (both sets lie in
    their boxes), much tighter than the bounding sphere for a long link."""
    dx = max(B[olo] - hx, 0.0, lx - B[ohi])
    dy = max(B[olo + 1] - hy, 0.0, ly - B[ohi + 1])
    dz = max(B[olo + 2] - hz, 0.0, lz - B[ohi + 2])
    return math.sqrt(dx * dx + dy * dy + dz * dz) - r


@njit(cache=True, inline="always")
def _before(key, i, j):  # pragma: no cover - compiled
    """Order of :func:`_argsort_heap`: by key, ties by index (deterministic)."""
    return key[i] < key[j] or (key[i] == key[j] and i < j)


@njit(cache=True)
def _argsort_heap(key, order, n):  # pragma: no cover - compiled
    """``order[:n]`` <- the indices ``0..n-1`` in increasing ``key`` (ties by index): heapsort in
    place, nothing allocated (``detect_rows`` runs without reference counting)."""
    for i in range(n):
        order[i] = i
    for start in range(n // 2 - 1, -1, -1):  # max-heap
        root = start
        while True:
            child = 2 * root + 1
            if child >= n:
                break
            if child + 1 < n and _before(key, order[child], order[child + 1]):
                child += 1
            if _before(key, order[root], order[child]):
                t = order[root]; order[root] = order[child]; order[child] = t
                root = child
            else:
                break
    for end in range(n - 1, 0, -1):
        t = order[0]; order[0] = order[end]; order[end] = t
        root = 0
        while True:
            child = 2 * root + 1
            if child >= end:
                break
            if child + 1 < end and _before(key, order[child], order[child + 1]):
                child += 1
            if _before(key, order[root], order[child]):
                t = order[root]; order[root] = order[child]; order[child] = t
                root = child
            else:
                break
