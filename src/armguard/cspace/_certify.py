"""Certified forbidden joint-3 bins of one substructure, by box subdivision.

A map cell ``(i1, i2)`` forbids joint-3 bin ``b`` when *some* configuration of the closed box
``cell(i1, i2) × bin(b)`` may come within the stopping distance ``m`` of an obstacle; a bin is
allowed only when every configuration of that box is proven clear.  The proof is the certified
verifier's: every point of the mapped links moves at most ``h . lever`` from its place at the
box centre ``c`` (half-widths ``h`` ``(3,)`` rad, :func:`._clearance.map_links`), so

* ``d(c) - h . lever > m + cspace_contact``: the whole box is free;
* ``d(c) + h . lever < m``: the whole box collides — every (cell, bin) it spans is forbidden;
* otherwise the box is split in two along the joint of largest ``h_j lever_j``: at a cell or
  bin boundary while it spans several, else in halves — at most ``cspace_max_depth`` halvings
  in all below one cell × bin box.  A one-cell, one-bin box whose centre collides is forbidden; one that cannot
  be split further while still inconclusive is forbidden too (conservative, counted as
  *unresolved*).

The search starts from one box over the whole substructure and joint-3 range, so free space far
from the obstacles costs a handful of clearance evaluations; the work concentrates on the
boundary of the forbidden set.  Boxes are integer lattice intervals (``2^depth`` units per cell or
bin), so splits are exact.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._errors import ForbiddenMapError
from ._grid import MapGrid

__all__ = ["SubResult", "certify_substructure", "encode_mask", "decode_intervals"]


@dataclass(frozen=True)
class SubResult:
    """One substructure's certified result.

    Attributes
    ----------
    index : int
        Substructure number.
    pointers : (n_cells + 1,) uint16
        Interval offsets per cell (row-major over the substructure's (i1, i2) cells).
    intervals : (K, 2) uint16
        Forbidden joint-3 bin intervals ``[start, end)``, sorted per cell.
    evaluations : int
        Clearance evaluations made.
    unresolved : int
        Boxes marked forbidden at the depth limit (their bound stayed inconclusive).
    """

    index: int
    pointers: np.ndarray
    intervals: np.ndarray
    evaluations: int
    unresolved: int


def encode_mask(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(pointers (C + 1,) uint16, intervals (K, 2) uint16)`` of the runs of ``mask`` ``(c1, c2, n3) bool``."""
    c1, c2, n3 = mask.shape
    flat = mask.reshape(c1 * c2, n3)
    pad = np.zeros((flat.shape[0], n3 + 2), dtype=np.int8)
    pad[:, 1:-1] = flat
    d = np.diff(pad, axis=1)
    rs, cs = np.nonzero(d == 1)
    re, ce = np.nonzero(d == -1)
    if len(rs) > np.iinfo(np.uint16).max:
        raise ForbiddenMapError(f"a substructure holds {len(rs)} intervals; at most {np.iinfo(np.uint16).max} (use a smaller cell)")
    counts = np.bincount(rs, minlength=flat.shape[0])
    ptr = np.zeros(flat.shape[0] + 1, dtype=np.uint16)
    np.cumsum(counts, out=ptr[1:])
    # np.nonzero is row-major: starts and ends come in the same (row, column) order
    iv = np.stack([cs, ce], axis=1).astype(np.uint16) if len(cs) else np.zeros((0, 2), dtype=np.uint16)
    assert np.array_equal(rs, re)
    return ptr, np.ascontiguousarray(iv)


def decode_intervals(pointers: np.ndarray, intervals: np.ndarray, shape: tuple[int, int, int]) -> np.ndarray:
    """The ``(c1, c2, n3) bool`` forbidden mask of one substructure (inverse of :func:`encode_mask`)."""
    c1, c2, n3 = shape
    out = np.zeros((c1 * c2, n3 + 1), dtype=np.int8)
    rows = np.repeat(np.arange(c1 * c2), np.diff(pointers.astype(np.int64)))
    np.add.at(out, (rows, intervals[:, 0].astype(np.int64)), 1)
    np.add.at(out, (rows, intervals[:, 1].astype(np.int64)), -1)
    return (np.cumsum(out, axis=1)[:, :n3] > 0).reshape(c1, c2, n3)


def certify_substructure(grid: MapGrid, s: int, clearance, lever: np.ndarray, stopping_distance: float,
                         contact: float, depth: int) -> SubResult:
    """Run the subdivision of the module docstring on substructure ``s``.

    Parameters
    ----------
    clearance : callable (Q (M, 3) rad) -> (M,) float64 m
    lever : (3,) float64, m/rad
        Bound on the motion of any point of the mapped links per unit of each joint.
    stopping_distance, contact : float, m
    depth : int
        Halvings allowed below one cell × bin box (summed over the three joints).
    """
    i1a, i1b, i2a, i2b = grid.sub_cells(s)
    n3 = int(grid.counts[2])
    D = int(depth)
    mask = np.zeros((i1b - i1a, i2b - i2a, n3), dtype=bool)
    unit = grid.step / float(1 << D)
    # boxes: integer lattice intervals [a, b) per joint, in units of (cell or bin) / 2^D, from the grid origin
    A = np.array([[i1a << D, i2a << D, 0]], dtype=np.int64)
    B = np.array([[i1b << D, i2b << D, n3 << D]], dtype=np.int64)
    level = np.zeros(1, dtype=np.int64)  # halvings made below one cell or bin (summed over the joints)
    lever = np.asarray(lever, dtype=np.float64)
    m = float(stopping_distance)
    evaluations = 0
    unresolved = 0
    origin = np.array([i1a, i2a, 0], dtype=np.int64)
    ends = np.asarray(grid.counts, dtype=np.int64) << D
    while len(A):
        first = A >> D  # first cell / bin spanned
        last = (B - 1) >> D  # last one
        single = np.all(first == last, axis=1)
        if np.any(single):  # drop one-cell, one-bin boxes already forbidden
            loc = first[single] - origin
            done = mask[loc[:, 0], loc[:, 1], loc[:, 2]]
            if np.any(done):
                keep = np.ones(len(A), dtype=bool)
                keep[np.flatnonzero(single)[done]] = False
                A, B, first, last, single, level = A[keep], B[keep], first[keep], last[keep], single[keep], level[keep]
                if not len(A):
                    break
        # the box's joint interval, clipped to the limits (the last cell or bin reaches the upper limit)
        hi = np.where(B >= ends, grid.upper, np.minimum(grid.lower + B * unit, grid.upper))
        lo = np.minimum(grid.lower + A * unit, hi)
        c = 0.5 * (lo + hi)
        h = 0.5 * (hi - lo)
        d = np.asarray(clearance(c), dtype=np.float64).reshape(-1)
        if d.shape != (len(c),):
            raise ForbiddenMapError(f"the clearance hook returned shape {d.shape} for {len(c)} configurations")
        evaluations += len(c)
        contrib = h * lever  # (K, 3) m
        bound = contrib.sum(axis=1)
        free = d - bound > m + contact  # False for NaN; True for +inf (no pair)
        full = np.isfinite(d) & (d + bound < m)
        hit = np.isfinite(d) & (d <= m) & single  # a colliding centre in a one-cell, one-bin box
        # which undecided boxes can still be split, and along which joint
        undecided = ~(free | full | hit)
        multi = first != last
        sub_span = B - A
        can = multi | ((sub_span > 1) & (level < D)[:, None])
        score = np.where(can, contrib, -1.0)
        axis = np.argmax(score, axis=1)
        rows = np.arange(len(A))
        splittable = can[rows, axis]
        stuck = undecided & ~splittable
        unresolved += int(np.count_nonzero(stuck))
        mark = full | hit | stuck
        if np.any(mark):
            idx = np.flatnonzero(mark)
            one = single[idx]
            loc = first[idx[one]] - origin
            mask[loc[:, 0], loc[:, 1], loc[:, 2]] = True
            for k in idx[~one]:  # boxes over several cells or bins (whole colliding blocks)
                f = first[k] - origin
                t = last[k] - origin + 1
                mask[f[0]:t[0], f[1]:t[1], f[2]:t[2]] = True
        go = np.flatnonzero(undecided & splittable)
        if not len(go):
            break
        ax = axis[go]
        a = A[go, ax]
        b = B[go, ax]
        fa = first[go, ax]
        lb = last[go, ax] + 1
        mid = np.where(lb - fa > 1, ((fa + lb) // 2) << D, (a + b) // 2)
        A1 = A[go].copy()
        B1 = B[go].copy()
        A2 = A[go].copy()
        B2 = B[go].copy()
        B1[np.arange(len(go)), ax] = mid
        A2[np.arange(len(go)), ax] = mid
        A = np.concatenate([A1, A2])
        B = np.concatenate([B1, B2])
        lv = level[go] + (lb - fa == 1)
        level = np.concatenate([lv, lv])
    ptr, iv = encode_mask(mask)
    return SubResult(int(s), ptr, iv, int(evaluations), int(unresolved))
