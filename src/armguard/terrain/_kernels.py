"""Division-free overlap kernels for the terrain pyramid: terrain box (axis-aligned in W) vs link OBB / OBP.

Leger, JPL NASA Tech Brief NPO-30356 (seed ``002``): the manipulator's links are OBPs (an
octagonal prism is the union of four OBBs, the brief's Figure 1), the terrain a pyramid of OBBs,
and every test runs "without any divisions or transcendental functions".

The test is the separating-axis theorem with 15 candidate axes (Gottschalk, Lin & Manocha,
OBBTree, 1996): the terrain box's three face axes (W's x, y, z: the map's grid is aligned with
W), the link box's three axes, and the nine cross products ``e_i x B_j``.  Along an axis ``L`` the
boxes are disjoint when ``|t . L| > r_A(L) + r_B(L)``; both sides are homogeneous of degree one
in ``|L|``, so the cross-product axes are used unnormalised -- no square root, no division, only
products, sums and ``abs``.  ``eps_par`` is added to each ``|R_ij|`` (the usual robustness term:
near-parallel axes, whose cross product vanishes, cannot report a false separation), which only
ever turns a separation into an overlap (conservative).  Touching counts as overlapping.

A link row is 36 floats, precomputed once per query by :func:`pack_rows` in ``_volumes.py``:
``[c (3), h (3), R (9, row-major, columns the box axes), Q = |R| + eps_par (9), E (3), C (9)]``
where ``E_i = sum_j h_j Q_ij`` (the link box's half extent along W's axis ``i``) and ``C`` holds
the link's radius along the nine cross axes.  A terrain box is 6 floats ``[c (3), h (3)]``.

``tests/test_terrain_kernels.py`` reads the LLVM IR of the compiled kernels and asserts that it
contains no floating-point division, square root or transcendental call.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["ROW", "BOX", "aabb_obb_overlap", "aabb_obp_overlap", "descend", "flat_hits"]

ROW = 36  # floats per link row
BOX = 6  # floats per terrain box


@njit(cache=True, inline="always")
def aabb_obb_overlap(boxes, i, rows, k):  # pragma: no cover - compiled
    """True when terrain box ``boxes[i] = [c, h]`` (axis-aligned in W, m) and link row ``rows[k]``
    (an OBB in W, see the module docstring) overlap or touch.  Products, sums and ``abs`` only."""
    r = rows[k]
    ax = boxes[i, 3]
    ay = boxes[i, 4]
    az = boxes[i, 5]
    t0 = r[0] - boxes[i, 0]
    t1 = r[1] - boxes[i, 1]
    t2 = r[2] - boxes[i, 2]
    # W's axes (the terrain box's faces): the link's half extents along them are E
    if abs(t0) > ax + r[24]:
        return False
    if abs(t1) > ay + r[25]:
        return False
    if abs(t2) > az + r[26]:
        return False
    b0 = r[3]
    b1 = r[4]
    b2 = r[5]
    # R[i][j] = r[6 + 3 i + j] (row i: W axis, column j: link axis); Q likewise at 15
    # the link's face axes B_j
    if abs(t0 * r[6] + t1 * r[9] + t2 * r[12]) > ax * r[15] + ay * r[18] + az * r[21] + b0:
        return False
    if abs(t0 * r[7] + t1 * r[10] + t2 * r[13]) > ax * r[16] + ay * r[19] + az * r[22] + b1:
        return False
    if abs(t0 * r[8] + t1 * r[11] + t2 * r[14]) > ax * r[17] + ay * r[20] + az * r[23] + b2:
        return False
    # e_0 x B_j: |t2 R1j - t1 R2j| > ay Q2j + az Q1j + C[0 j]
    if abs(t2 * r[9] - t1 * r[12]) > ay * r[21] + az * r[18] + r[27]:
        return False
    if abs(t2 * r[10] - t1 * r[13]) > ay * r[22] + az * r[19] + r[28]:
        return False
    if abs(t2 * r[11] - t1 * r[14]) > ay * r[23] + az * r[20] + r[29]:
        return False
    # e_1 x B_j: |t0 R2j - t2 R0j| > ax Q2j + az Q0j + C[1 j]
    if abs(t0 * r[12] - t2 * r[6]) > ax * r[21] + az * r[15] + r[30]:
        return False
    if abs(t0 * r[13] - t2 * r[7]) > ax * r[22] + az * r[16] + r[31]:
        return False
    if abs(t0 * r[14] - t2 * r[8]) > ax * r[23] + az * r[17] + r[32]:
        return False
    # e_2 x B_j: |t1 R0j - t0 R1j| > ax Q1j + ay Q0j + C[2 j]
    if abs(t1 * r[6] - t0 * r[9]) > ax * r[18] + ay * r[15] + r[33]:
        return False
    if abs(t1 * r[7] - t0 * r[10]) > ax * r[19] + ay * r[16] + r[34]:
        return False
    if abs(t1 * r[8] - t0 * r[11]) > ax * r[20] + ay * r[17] + r[35]:
        return False
    return True


@njit(cache=True, inline="always")
def aabb_obp_overlap(boxes, i, rows, r0, r1):  # pragma: no cover - compiled
    """True when terrain box ``boxes[i]`` overlaps the OBP made of link rows ``rows[r0:r1]`` (the
    union of its OBBs, the brief's Figure 1): any of its boxes overlapping suffices."""
    for k in range(r0, r1):
        if aabb_obb_overlap(boxes, i, rows, k):
            return True
    return False


@njit(cache=True)
def descend(boxes, off, nx, ny, rows, rstart, mask0, first, out_cell, out_mask, per_level):  # pragma: no cover
    """Coarse-to-fine test of the links in ``mask0`` against the pyramid, depth first.

    ``boxes (total, 6)``: every level's boxes, level 0 (one box, the coarsest) first, level ``l``
    at rows ``off[l]:off[l + 1]`` in row-major ``(ny[l], nx[l])`` order.  ``rows (R, 36)``: the
    links' OBB rows, link ``k`` at ``rows[rstart[k]:rstart[k+1]]``.  ``mask0``: bit ``k`` set for
    each link to test (at most 63 links).  A box's four children are tested only against the links
    that hit it.  With ``first`` the descent stops at the first hit on the finest level.  Writes the
    finest-level hits (cell index within the finest level, mask of the links hitting it) into
    ``out_cell``/``out_mask`` up to their capacity and the link tests run per level into
    ``per_level (L,)``; returns ``(n_hits, boxes_visited, deepest_level)``.  The stack holds at most
    ``3 L + 1`` entries (each pop pushes at most four), so nothing is allocated per box.
    """
    L = nx.shape[0]
    depth_cap = 3 * L + 2
    st_lvl = np.empty(depth_cap, np.int64)
    st_iy = np.empty(depth_cap, np.int64)
    st_ix = np.empty(depth_cap, np.int64)
    st_mask = np.empty(depth_cap, np.int64)
    st_lvl[0] = 0
    st_iy[0] = 0
    st_ix[0] = 0
    st_mask[0] = mask0
    sp = 1
    n_hits = 0
    visited = 0
    deepest = 0
    cap = out_cell.shape[0]
    nlinks = rstart.shape[0] - 1
    while sp > 0:
        sp -= 1
        lvl = st_lvl[sp]
        iy = st_iy[sp]
        ix = st_ix[sp]
        mask = st_mask[sp]
        idx = iy * nx[lvl] + ix
        gi = off[lvl] + idx
        visited += 1
        if lvl > deepest:
            deepest = lvl
        hit = np.int64(0)
        for k in range(nlinks):
            bit = np.int64(1) << k
            if mask & bit:
                per_level[lvl] += 1
                if aabb_obp_overlap(boxes, gi, rows, rstart[k], rstart[k + 1]):
                    hit |= bit
        if hit == 0:
            continue
        if lvl == L - 1:
            if n_hits < cap:
                out_cell[n_hits] = idx
                out_mask[n_hits] = hit
            n_hits += 1
            if first:
                return n_hits, visited, deepest
            continue
        # children: rows 2 iy, 2 iy + 1 and columns 2 ix, 2 ix + 1 of the level below, clipped
        cw = nx[lvl + 1]
        ch = ny[lvl + 1]
        for dy in range(1, -1, -1):
            cy = 2 * iy + dy
            if cy >= ch:
                continue
            for dx in range(1, -1, -1):
                cx = 2 * ix + dx
                if cx >= cw:
                    continue
                st_lvl[sp] = lvl + 1
                st_iy[sp] = cy
                st_ix[sp] = cx
                st_mask[sp] = hit
                sp += 1
    return n_hits, visited, deepest


@njit(cache=True)
def flat_hits(boxes, lo, hi, rows, rstart, mask0, out_cell, out_mask):  # pragma: no cover - compiled
    """Brute-force reference: every box ``boxes[lo:hi]`` (the finest level) against every link in
    ``mask0``.  Writes hits as :func:`descend` does (cell index relative to ``lo``); returns the
    number of hits and of OBB tests run."""
    nlinks = rstart.shape[0] - 1
    cap = out_cell.shape[0]
    n_hits = 0
    tests = 0
    for gi in range(lo, hi):
        hit = np.int64(0)
        for k in range(nlinks):
            bit = np.int64(1) << k
            if mask0 & bit:
                tests += 1
                if aabb_obp_overlap(boxes, gi, rows, rstart[k], rstart[k + 1]):
                    hit |= bit
        if hit != 0:
            if n_hits < cap:
                out_cell[n_hits] = gi - lo
                out_mask[n_hits] = hit
            n_hits += 1
    return n_hits, tests
