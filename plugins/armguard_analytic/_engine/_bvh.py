"""A bounding-volume hierarchy of axis-aligned boxes over the static obstacles.

Built once (top-down, median split of the box centres along the widest axis, ``LEAF_SIZE``
items per leaf) and stored as flat arrays; the detector kernel walks it nearest-child first
with an explicit stack and prunes every node whose box is farther from a link's bounding
sphere than the current cut-off, so a query costs about ``log N`` node visits when the
obstacles are spread out.  A brute-force list walk is kept beside it for the tests.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["BVH", "build_bvh", "sphere_box_gap", "LEAF_SIZE"]

LEAF_SIZE = 4
"""Items per leaf: small leaves keep the per-item sphere test count low."""


class BVH:
    """Flat BVH arrays.

    ``lo``, ``hi`` ``(N, 3) float64, m``: node boxes in W; ``left``, ``right`` ``(N,) int64``:
    children (-1 for a leaf); ``start``, ``count`` ``(N,) int64``: a leaf's items are
    ``items[start:start + count]``; ``items`` ``(n,) int64``: static element numbers (0-based
    among the static elements); ``depth``: height of the tree (the query stack needs
    ``2 * depth + 2`` entries at most).
    """

    def __init__(self, lo, hi, left, right, start, count, items, depth):
        self.lo, self.hi, self.left, self.right = lo, hi, left, right
        self.start, self.count, self.items, self.depth = start, count, items, depth

    @property
    def n_nodes(self) -> int:
        return int(self.lo.shape[0])


def build_bvh(box_lo: np.ndarray, box_hi: np.ndarray) -> BVH:
    """BVH over ``n`` boxes ``box_lo``, ``box_hi`` ``(n, 3) float64, m`` (W)."""
    n = int(box_lo.shape[0])
    lo_l, hi_l, left_l, right_l, start_l, count_l = [], [], [], [], [], []
    items = np.arange(n, dtype=np.int64)
    centres = 0.5 * (box_lo + box_hi)
    depth = 0
    if n == 0:
        z = np.zeros((0, 3))
        e = np.zeros(0, dtype=np.int64)
        return BVH(z, z.copy(), e, e.copy(), e.copy(), e.copy(), items, 0)

    def make(s: int, e: int, d: int) -> int:
        nonlocal depth
        depth = max(depth, d)
        idx = items[s:e]
        node = len(lo_l)
        lo_l.append(box_lo[idx].min(axis=0))
        hi_l.append(box_hi[idx].max(axis=0))
        left_l.append(-1), right_l.append(-1), start_l.append(s), count_l.append(e - s)
        if e - s > LEAF_SIZE:
            c = centres[idx]
            axis = int(np.argmax(c.max(axis=0) - c.min(axis=0)))
            order = np.argsort(c[:, axis], kind="stable")
            items[s:e] = idx[order]
            mid = (s + e) // 2
            left_l[node] = make(s, mid, d + 1)
            right_l[node] = make(mid, e, d + 1)
        return node

    make(0, n, 0)
    f = lambda a: np.ascontiguousarray(np.asarray(a, dtype=np.float64).reshape(-1, 3))  # noqa: E731
    i = lambda a: np.ascontiguousarray(np.asarray(a, dtype=np.int64))  # noqa: E731
    return BVH(f(lo_l), f(hi_l), i(left_l), i(right_l), i(start_l), i(count_l), items, depth)


@njit(cache=True, inline="always")
def sphere_box_gap(cx, cy, cz, r, lo, hi):  # pragma: no cover - compiled
    """Distance (m) between the sphere ``(c, r)`` and the box ``[lo, hi]`` (``(3,)`` each); <= 0 if they overlap.

    A lower bound on the signed distance between anything inside the sphere and anything
    inside the box only when positive (overlapping bounding volumes bound nothing).
    """
    dx = max(lo[0] - cx, 0.0, cx - hi[0])
    dy = max(lo[1] - cy, 0.0, cy - hi[1])
    dz = max(lo[2] - cz, 0.0, cz - hi[2])
    return math.sqrt(dx * dx + dy * dy + dz * dz) - r
