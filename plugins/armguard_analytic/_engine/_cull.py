"""Culling bounds of the detector's hot path (scalar, on flat buffers) and its allocation-free sort.

Each ``*_gap`` is a lower bound on the distance between a moving element and anything inside a
box: ``<= 0`` when the volumes overlap (then it bounds nothing).  Closed forms: the distance from
a point to an axis-aligned box is the norm of the per-axis excess ``max(lo - x, 0, x - hi)``; to
an oriented box, the same in the box's frame; between two axis-aligned boxes, the norm of the
per-axis gaps.  The yes/no mode also has a boolean cull: two oriented boxes that do not overlap
(JPL's division-free separating-axis test, :mod:`armguard.geometry._pair_box_box`).
"""

from __future__ import annotations

import math

from numba import njit

from armguard.geometry._pair_box_box import box_box_overlap_scalar

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


@njit(cache=True, inline="always")
def _obb_w(MF, o, SF, oX, grow):  # pragma: no cover - compiled
    """The box ``MF[o:o + 15]`` = ``[c_L, h, R_LB row-major]`` (a link frame) moved by the link pose
    ``SF[oX:oX + 16]`` (``X_WL`` row-major), half extents grown by ``grow``: ``c_W``, ``h``, ``R_WB``
    (row-major) as 15 scalars."""
    r00 = SF[oX]; r01 = SF[oX + 1]; r02 = SF[oX + 2]; tx = SF[oX + 3]
    r10 = SF[oX + 4]; r11 = SF[oX + 5]; r12 = SF[oX + 6]; ty = SF[oX + 7]
    r20 = SF[oX + 8]; r21 = SF[oX + 9]; r22 = SF[oX + 10]; tz = SF[oX + 11]
    x = MF[o]; y = MF[o + 1]; z = MF[o + 2]
    b00 = MF[o + 6]; b01 = MF[o + 7]; b02 = MF[o + 8]
    b10 = MF[o + 9]; b11 = MF[o + 10]; b12 = MF[o + 11]
    b20 = MF[o + 12]; b21 = MF[o + 13]; b22 = MF[o + 14]
    return (r00 * x + r01 * y + r02 * z + tx, r10 * x + r11 * y + r12 * z + ty, r20 * x + r21 * y + r22 * z + tz,
            MF[o + 3] + grow, MF[o + 4] + grow, MF[o + 5] + grow,
            r00 * b00 + r01 * b10 + r02 * b20, r00 * b01 + r01 * b11 + r02 * b21, r00 * b02 + r01 * b12 + r02 * b22,
            r10 * b00 + r11 * b10 + r12 * b20, r10 * b01 + r11 * b11 + r12 * b21, r10 * b02 + r11 * b12 + r12 * b22,
            r20 * b00 + r21 * b10 + r22 * b20, r20 * b01 + r21 * b11 + r22 * b21, r20 * b02 + r21 * b12 + r22 * b22)


@njit(cache=True)
def obb_apart_static(MF, oa, oXa, SF, ob, grow, eps_par):  # pragma: no cover - compiled
    """True when the box of a moving element (``MF[oa:oa + 15]``, link pose ``SF[oXa:oXa + 16]``) grown
    by ``grow`` and the box ``SF[ob:ob + 15]`` (W, ``[c, h, R_WB row-major]``) do not overlap."""
    a = _obb_w(MF, oa, SF, oXa, grow)
    return not box_box_overlap_scalar(
        a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11], a[12], a[13], a[14],
        SF[ob], SF[ob + 1], SF[ob + 2], SF[ob + 3], SF[ob + 4], SF[ob + 5], SF[ob + 6], SF[ob + 7], SF[ob + 8],
        SF[ob + 9], SF[ob + 10], SF[ob + 11], SF[ob + 12], SF[ob + 13], SF[ob + 14], eps_par)


@njit(cache=True)
def obb_apart_moving(MF, oa, oXa, ob, oXb, SF, grow, eps_par):  # pragma: no cover - compiled
    """True when the boxes of two moving elements (``MF[o:o + 15]`` each, link poses ``SF[oX:oX + 16]``),
    the first grown by ``grow``, do not overlap."""
    a = _obb_w(MF, oa, SF, oXa, grow)
    b = _obb_w(MF, ob, SF, oXb, 0.0)
    return not box_box_overlap_scalar(
        a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11], a[12], a[13], a[14],
        b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7], b[8], b[9], b[10], b[11], b[12], b[13], b[14], eps_par)


@njit(cache=True, inline="always")
def _sift_down(key, order, root, end):  # pragma: no cover - compiled
    """Restore the max-heap below ``root`` in ``order[:end]`` (ordered by :func:`_before`)."""
    while True:
        child = 2 * root + 1
        if child >= end:
            return
        if child + 1 < end and _before(key, order[child], order[child + 1]):
            child += 1
        if not _before(key, order[root], order[child]):
            return
        t = order[root]; order[root] = order[child]; order[child] = t
        root = child


@njit(cache=True)
def _argsort_heap(key, order, n):  # pragma: no cover - compiled
    """``order[:n]`` <- the indices ``0..n-1`` in increasing ``key`` (ties by index): heapsort in
    place, nothing allocated (one pass of the anytime check sorts every pair's bound)."""
    for i in range(n):
        order[i] = i
    for start in range(n // 2 - 1, -1, -1):  # max-heap
        _sift_down(key, order, start, n)
    for end in range(n - 1, 0, -1):
        t = order[0]; order[0] = order[end]; order[end] = t
        _sift_down(key, order, 0, end)


@njit(cache=True)
def _argsort_small(key, order, n):  # pragma: no cover - compiled
    """:func:`_argsort_heap`'s result (ties by index) by insertion sort up to 32 keys (fewer
    branches and moves than the heap for the few pairs a check sorts), the heap beyond."""
    if n > 32:
        _argsort_heap(key, order, n)
        return
    for i in range(n):
        j = i
        while j > 0 and _before(key, i, order[j - 1]):
            order[j] = order[j - 1]
            j -= 1
        order[j] = i


@njit(cache=True, inline="always")
def _explicit_gap(p, pair_a, pair_b, sphW, ws_lo, ws_hi):  # pragma: no cover - compiled
    """Bounding-sphere gap of explicit pair ``p`` (m): to the workspace walls (``b < 0``), or between the
    two elements' spheres (<= 0 when they overlap: then it bounds nothing, only orders)."""
    a = pair_a[p]
    b = pair_b[p]
    if b < 0:
        return min(ws_hi[0] - sphW[a, 0], ws_hi[1] - sphW[a, 1], ws_hi[2] - sphW[a, 2],
                   sphW[a, 0] - ws_lo[0], sphW[a, 1] - ws_lo[1], sphW[a, 2] - ws_lo[2]) - sphW[a, 3]
    dx = sphW[a, 0] - sphW[b, 0]; dy = sphW[a, 1] - sphW[b, 1]; dz = sphW[a, 2] - sphW[b, 2]
    return math.sqrt(dx * dx + dy * dy + dz * dz) - sphW[a, 3] - sphW[b, 3]


@njit(cache=True, inline="always")
def _near_leaf(cx, cy, cz, cr, MF, o_blo, o_bhi, bvh_left, bvh_right):  # pragma: no cover - compiled
    """The BVH leaf reached from the root by always descending to the child whose box is nearer the
    sphere ``(c, r)`` (:func:`_sb_gap`): O(depth), a likely home of the sphere's nearest boxes."""
    node = 0
    while bvh_left[node] >= 0:
        left = bvh_left[node]
        right = bvh_right[node]
        gl = _sb_gap(cx, cy, cz, cr, MF, o_blo + 3 * left, o_bhi + 3 * left)
        gr = _sb_gap(cx, cy, cz, cr, MF, o_blo + 3 * right, o_bhi + 3 * right)
        node = left if gl <= gr else right
    return node


@njit(cache=True, inline="always")
def _face_sep(A, B, o):  # pragma: no cover - compiled
    """Separation (m) of the box ``A`` (15 scalars ``[c, h, R row-major]``, :func:`_obb_w`) and the box
    ``B[o:o + 15]`` (same layout) along their six face normals: ``max_u |t . u| - r_A(u) - r_B(u)``,
    ``t`` the centres' offset, ``r(u) = sum_k h_k |axis_k . u|`` a box's projected radius (the
    separating-axis test's quantities, Gottschalk, Lin & Manocha, "OBBTree", SIGGRAPH 1996, §4).
    Each axis is a unit vector, and projection onto it shortens no distance, so when positive this
    is a lower bound on the distance between the boxes (and between anything inside them)."""
    tx = B[o] - A[0]
    ty = B[o + 1] - A[1]
    tz = B[o + 2] - A[2]
    sep = -math.inf
    # C[i][j] = a_i . b_j, a_i / b_j the columns of R_A / R_B
    c00 = A[6] * B[o + 6] + A[9] * B[o + 9] + A[12] * B[o + 12]
    c01 = A[6] * B[o + 7] + A[9] * B[o + 10] + A[12] * B[o + 13]
    c02 = A[6] * B[o + 8] + A[9] * B[o + 11] + A[12] * B[o + 14]
    c10 = A[7] * B[o + 6] + A[10] * B[o + 9] + A[13] * B[o + 12]
    c11 = A[7] * B[o + 7] + A[10] * B[o + 10] + A[13] * B[o + 13]
    c12 = A[7] * B[o + 8] + A[10] * B[o + 11] + A[13] * B[o + 14]
    c20 = A[8] * B[o + 6] + A[11] * B[o + 9] + A[14] * B[o + 12]
    c21 = A[8] * B[o + 7] + A[11] * B[o + 10] + A[14] * B[o + 13]
    c22 = A[8] * B[o + 8] + A[11] * B[o + 11] + A[14] * B[o + 14]
    ha0 = A[3]; ha1 = A[4]; ha2 = A[5]
    hb0 = B[o + 3]; hb1 = B[o + 4]; hb2 = B[o + 5]
    # A's axes
    sep = max(sep, abs(A[6] * tx + A[9] * ty + A[12] * tz) - ha0 - (hb0 * abs(c00) + hb1 * abs(c01) + hb2 * abs(c02)))
    sep = max(sep, abs(A[7] * tx + A[10] * ty + A[13] * tz) - ha1 - (hb0 * abs(c10) + hb1 * abs(c11) + hb2 * abs(c12)))
    sep = max(sep, abs(A[8] * tx + A[11] * ty + A[14] * tz) - ha2 - (hb0 * abs(c20) + hb1 * abs(c21) + hb2 * abs(c22)))
    # B's axes
    sep = max(sep, abs(B[o + 6] * tx + B[o + 9] * ty + B[o + 12] * tz) - hb0
              - (ha0 * abs(c00) + ha1 * abs(c10) + ha2 * abs(c20)))
    sep = max(sep, abs(B[o + 7] * tx + B[o + 10] * ty + B[o + 13] * tz) - hb1
              - (ha0 * abs(c01) + ha1 * abs(c11) + ha2 * abs(c21)))
    sep = max(sep, abs(B[o + 8] * tx + B[o + 11] * ty + B[o + 14] * tz) - hb2
              - (ha0 * abs(c02) + ha1 * abs(c12) + ha2 * abs(c22)))
    return sep


@njit(cache=True, inline="always")
def _gjk_pair(ka, kb):  # pragma: no cover - compiled
    """Whether two moving elements of core kinds ``ka``, ``kb`` go to GJK (``_step.evaluate_pair``'s link-frame
    pairs: two boxes or hulls, a hull and anything; a capsule and a box is a scalar kernel, tens of ns)."""
    return ka == 3 or kb == 3 or (ka >= 2 and kb >= 2)


@njit(cache=True, inline="always")
def _push_children(stack, gapst, top, left, gl, right, gr):  # pragma: no cover - compiled
    """Push a BVH node's two children with their gaps, the farther first so that the nearer is
    popped first; returns the new stack top."""
    if gl <= gr:
        stack[top] = right
        gapst[top] = gr
        stack[top + 1] = left
        gapst[top + 1] = gl
    else:
        stack[top] = left
        gapst[top] = gl
        stack[top + 1] = right
        gapst[top + 1] = gr
    return top + 2
