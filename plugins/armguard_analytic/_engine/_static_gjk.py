"""The exact and min modes' moving-static pairs whose narrow phase is GJK (a moving box, hull or cylinder).

Branch and bound over those pairs, in three steps (:func:`static_gjk_pairs`):

1. Seed: one pair is evaluated first, so its category's cut-off is finite.  Up to ``_FLAT`` static
   elements, every pair is listed with the largest per-axis gap of the two W-aligned boxes (the
   moving element's from its oriented box), and the seed is the pair with the least key (below)
   among those whose W-aligned boxes overlap, or the least gap when that is smaller; beyond, the
   least key among the pairs of each element's nearest-descent BVH leaf (:func:`._cull._near_leaf`).
2. Collect every pair whose lower bounds do not exceed the cut-off (from the list, or walking the
   BVH nearest child first), with its key: the larger of the bounding-sphere gaps and, for an
   obstacle box, the face-axis separation of the element's oriented box and the obstacle's
   (:func:`._cull._face_sep`); each a lower bound on the distance when positive, since the volumes
   contain the elements.
3. Evaluate in increasing key, each pair checked again against its category's cut-off as it
   tightens (the key when positive, the boxes grown by the cut-off, then GJK stopping at it).

The walk of the kernel (:mod:`._kernel`) evaluated each element's pairs in walk order, element by
element: on the iiwa mesh hulls among 20 boxes, 3.9 environment pairs per collision-free check
improved the category's best (each a GJK run to convergence) where one is the least possible.
Exactness is that of the kernel's: a pair is skipped only when a lower bound on its distance
exceeds the cut-off ``max(cut0, best so far)`` of its category.
"""

from __future__ import annotations

import math

import numpy as np

from numba import njit

from ._cull import (_argsort_small, _bb_gap, _face_sep, _near_leaf, _obb_gap, _obb_w, _push_children, _sb_gap,
                    obb_apart_static)
from ._layout import K, seg1, seg2
from ._narrow import BOUNDED
from ._calls import FN_STEP, call_step

__all__ = ["static_gjk_pairs"]

_FLAT = 32  # up to this many static elements, step 2 tests every pair of an element (no tree walk)

# numba's cache keys on this file only: a change of the segment tuples in ._layout must come with an edit here
_K_core, _K_mov_idx, _K_st_mov, _K_st_cat, _K_sphW = K["core"], K["mov_idx"], K["st_mov"], K["st_cat"], K["sphW"]
_K_bvh_left, _K_bvh_right, _K_bvh_start, _K_bvh_count = K["bvh_left"], K["bvh_right"], K["bvh_start"], K["bvh_count"]
_K_bvh_items, _K_pair_of, _K_pair_a, _K_pair_b, _K_pair_cat = (K["bvh_items"], K["pair_of"], K["pair_a"], K["pair_b"],
                                                              K["pair_cat"])
_K_glink, _K_pstamp, _K_plb, _K_pflag, _K_order = K["glink"], K["pstamp"], K["plb"], K["pflag"], K["order"]
_K_stack, _K_gap, _K_best = K["stack"], K["gap"], K["best"]
_K_bvh_lo, _K_bvh_hi, _K_static_lo, _K_static_hi = K["bvh_lo"], K["bvh_hi"], K["static_lo"], K["static_hi"]
_K_obb_L, _K_boxW, _K_Xs, _K_st_idx = K["obb_L"], K["boxW"], K["Xs"], K["st_idx"]


@njit(cache=True, _nrt=False)  # a plain call: inlined at each call site it doubled the cold compile
def _key(cx, cy, cz, cr, A, has_obb, kb, s, b, MF, o_slo, o_shi, SF, o_box, cut):  # pragma: no cover - compiled
    """Sort key (m) of the pair of a moving element (sphere ``c, r``, box ``A`` when ``has_obb``) and
    static element ``b`` (number ``s`` among the static ones, core kind ``kb``): the larger of the
    sphere's gap to ``b``'s axis-aligned box, to its own box (a box or cylinder), and the two boxes'
    face-axis separation; a lower bound on the distance when positive, and of any sign when the two
    boxes' separation is in it (:func:`_signed`).  Cheapest first: once one exceeds ``cut`` (> 0)
    the rest are not computed (the pair is culled either way)."""
    key = _sb_gap(cx, cy, cz, cr, MF, o_slo + 3 * s, o_shi + 3 * s)
    if key > 0.0 and key > cut:
        return key
    if kb == 2 or kb == 4:  # a box, or a cylinder's own box
        if key > 0.0:  # the sphere-OBB gap
            key = max(key, _obb_gap(cx, cy, cz, cr, SF, o_box + 15 * b))
            if key > cut:
                return key
        if has_obb:  # the boxes' face-axis separation: tighter for long links, a bound of any sign
            fs = _face_sep(A, SF, o_box + 15 * b)
            key = max(key, fs) if key > 0.0 else fs  # (a sphere gap <= 0 bounds nothing)
    return key


@njit(cache=True, inline="always")
def _signed(has_obb, kb):  # pragma: no cover - compiled
    """Whether :func:`_key` bounds the signed distance whatever its sign: the moving element has its
    box and the static one is a box (or a cylinder's box).  A face-axis separation ``s`` < 0 of two
    boxes bounds their penetration depth: ``depth = min_u h(u) <= min over the six face normals`` of
    the overlap, ``-s`` (``h`` the Minkowski difference's support function; van den Bergen 2003,
    §4.3.7), and containing boxes are at least as deep as the elements they contain (the depth is
    monotone under inclusion).  So ``d >= s``: a pair whose key exceeds a negative cut-off cannot be
    deeper than its category's best (no GJK, no EPA)."""
    return has_obb and (kb == 2 or kb == 4)


@njit(cache=True, inline="always")
def _elem_box(a, MF, SF, o_obb, o_Xs, glink, sphW):  # pragma: no cover - compiled
    """Moving element ``a``'s oriented box in W (:func:`._cull._obb_w`, 15 scalars), whether it has one,
    and the W-aligned box ``[l, h]`` that contains it (without a box: its bounding sphere's)."""
    has_obb = MF[o_obb + 16 * a + 15] != 0.0
    A = _obb_w(MF, o_obb + 16 * a, SF, o_Xs + 16 * glink[a], 0.0)
    if has_obb:
        ex = A[3] * abs(A[6]) + A[4] * abs(A[7]) + A[5] * abs(A[8])
        ey = A[3] * abs(A[9]) + A[4] * abs(A[10]) + A[5] * abs(A[11])
        ez = A[3] * abs(A[12]) + A[4] * abs(A[13]) + A[5] * abs(A[14])
        return A, has_obb, A[0] - ex, A[1] - ey, A[2] - ez, A[0] + ex, A[1] + ey, A[2] + ez
    cx = sphW[a, 0]; cy = sphW[a, 1]; cz = sphW[a, 2]; cr = sphW[a, 3]
    return A, has_obb, cx - cr, cy - cr, cz - cr, cx + cr, cy + cr, cz + cr


@njit(cache=True, inline="always")
def _axis_gap(lx, ly, lz, hx, hy, hz, MF, olo, ohi):  # pragma: no cover - compiled
    """The largest per-axis gap (m) between the W-aligned boxes ``[l, h]`` and ``[MF[olo:olo + 3],
    MF[ohi:ohi + 3]]``: a lower bound on their distance when positive (no square root)."""
    gx = max(MF[olo] - hx, lx - MF[ohi])
    gy = max(MF[olo + 1] - hy, ly - MF[ohi + 1])
    gz = max(MF[olo + 2] - hz, lz - MF[ohi + 2])
    return max(gx, gy, gz)


@njit(cache=True, _nrt=False)  # a plain call: inlined at each call site it doubled the cold compile
def _collect(s, p, cx, cy, cz, cr, A, has_obb, lx, ly, lz, hx, hy, hz, cutp, kb, b, MF, o_slo, o_shi, SF, o_box, plb,
             pflag, n_c):  # pragma: no cover - compiled
    """Step 2 for one pair ``p`` (moving element: sphere ``c, r``, box ``A``, its W-aligned box
    ``[l, h]``; static element ``b``, number ``s``): kept as ``plb[n_c]``, ``pflag[n_c]`` unless a
    lower bound exceeds ``cutp``.  Returns the new count.  The first test is the largest per-axis
    gap of the two W-aligned boxes (a lower bound on the distance, no square root)."""
    olo = o_slo + 3 * s
    ohi = o_shi + 3 * s
    g = _axis_gap(lx, ly, lz, hx, hy, hz, MF, olo, ohi)
    if g > 0.0 and g > cutp:
        return n_c
    if has_obb:
        g = _bb_gap(lx, ly, lz, hx, hy, hz, 0.0, MF, olo, ohi)
        if g > 0.0 and g > cutp:
            return n_c
    key = _key(cx, cy, cz, cr, A, has_obb, kb, s, b, MF, o_slo, o_shi, SF, o_box, cutp)
    if key > cutp and (key > 0.0 or _signed(has_obb, kb)):
        return n_c
    plb[n_c] = key
    pflag[n_c] = p
    return n_c + 1


@njit(cache=True)
def static_gjk_pairs(H, MF, MI, SF, SI, out9, n_st, cut0, flag, eps_len, eps_par, gjk_eps, max_iter, woff, lvl, level,
                     n_eval, stamp_now, fns):  # pragma: no cover - compiled
    """The moving-static pairs of the GJK elements of ``st_mov`` (see the module docstring); the
    kernel's buffers (meminfo-free views), ``cut0`` its base cut-off (``-inf`` in the min mode, the
    effective threshold in the exact mode).  Returns ``(n_eval, error, collided)``.  ``fns``: the
    kernels' addresses (:func:`._calls.addresses`; the pair step is called at ``fns[FN_STEP]``)."""
    core = seg1(MI, H, _K_core)
    mov_idx = seg1(MI, H, _K_mov_idx)
    st_mov = seg1(MI, H, _K_st_mov)
    st_cat = seg1(MI, H, _K_st_cat)
    glink = seg1(MI, H, _K_glink)
    bvh_left = seg1(MI, H, _K_bvh_left)
    bvh_right = seg1(MI, H, _K_bvh_right)
    bvh_start = seg1(MI, H, _K_bvh_start)
    bvh_count = seg1(MI, H, _K_bvh_count)
    bvh_items = seg1(MI, H, _K_bvh_items)
    pair_of = seg2(MI, H, _K_pair_of, max(n_st, 1))
    pair_a = seg1(MI, H, _K_pair_a)
    pair_b = seg1(MI, H, _K_pair_b)
    pair_cat = seg1(MI, H, _K_pair_cat)
    sphW = seg2(SF, H, _K_sphW, 4)
    best = seg1(SF, H, _K_best)
    plb = seg1(SF, H, _K_plb)
    gapst = seg1(SF, H, _K_gap)
    pflag = seg1(SI, H, _K_pflag)
    order = seg1(SI, H, _K_order)
    stack = seg1(SI, H, _K_stack)
    pstamp = seg1(SI, H, _K_pstamp)
    st_idx = seg1(MI, H, _K_st_idx)
    o_blo = H[2 * _K_bvh_lo]
    o_bhi = H[2 * _K_bvh_hi]
    o_slo = H[2 * _K_static_lo]
    o_shi = H[2 * _K_static_hi]
    o_obb = H[2 * _K_obb_L]
    o_box = H[2 * _K_boxW]
    o_Xs = H[2 * _K_Xs]
    n_sm = st_mov.shape[0]
    err = 0
    collided = False
    g_seed = math.inf
    p_seed = np.int64(-1)  # not a literal -1: pair_step compiled once
    n_c = 0
    flat = n_st <= _FLAT
    if flat:
        # ---- 1. (a few obstacles) every pair's per-axis gap, listed; the seed: the least key among the
        # pairs whose W-aligned boxes overlap, or the least gap when smaller
        g_ax = math.inf
        p_ax = -1
        for i in range(n_sm):
            a = st_mov[i]
            if core[a] < 2:
                continue
            ma = mov_idx[a]
            cx = sphW[a, 0]; cy = sphW[a, 1]; cz = sphW[a, 2]; cr = sphW[a, 3]
            A, has_obb, lx, ly, lz, hx, hy, hz = _elem_box(a, MF, SF, o_obb, o_Xs, glink, sphW)
            for s in range(n_st):
                p = pair_of[ma, s]
                if p < 0 or pstamp[p] == stamp_now:
                    continue
                g = _axis_gap(lx, ly, lz, hx, hy, hz, MF, o_slo + 3 * s, o_shi + 3 * s)
                plb[n_c] = g
                pflag[n_c] = p
                n_c += 1
                if g <= 0.0:
                    b = pair_b[p]
                    key = _key(cx, cy, cz, cr, A, has_obb, core[b], s, b, MF, o_slo, o_shi, SF, o_box, math.inf)
                    if key < g_seed:
                        g_seed = key
                        p_seed = p
                elif g < g_ax:
                    g_ax = g
                    p_ax = p
        if p_ax >= 0 and g_ax < g_seed:
            p_seed = p_ax
    # ---- 1. seed: the least key among the pairs of each GJK element's nearest-descent leaf
    for i in range(n_sm if not flat else 0):
        a = st_mov[i]
        if core[a] < 2:
            continue
        ma = mov_idx[a]
        cx = sphW[a, 0]; cy = sphW[a, 1]; cz = sphW[a, 2]; cr = sphW[a, 3]
        has_obb = MF[o_obb + 16 * a + 15] != 0.0
        A = _obb_w(MF, o_obb + 16 * a, SF, o_Xs + 16 * glink[a], 0.0)
        node = _near_leaf(cx, cy, cz, cr, MF, o_blo, o_bhi, bvh_left, bvh_right)
        for it in range(bvh_start[node], bvh_start[node] + bvh_count[node]):
            s = bvh_items[it]
            p = pair_of[ma, s]
            if p >= 0:
                b = pair_b[p]
                g = _key(cx, cy, cz, cr, A, has_obb, core[b], s, b, MF, o_slo, o_shi, SF, o_box, math.inf)
                if g < g_seed:
                    g_seed = g
                    p_seed = p
    if p_seed >= 0 and pstamp[p_seed] != stamp_now:
        d, err = call_step(fns[FN_STEP], (p_seed, pair_a[p_seed], pair_b[p_seed], flag, H, MF, MI, SF, SI, out9, eps_len,
                                          eps_par, gjk_eps, max_iter, woff, lvl, max(cut0, best[pair_cat[p_seed]]), n_eval,
                                          stamp_now, fns))
        if err == BOUNDED:
            err = 0
        elif err != 0:
            return n_eval, err, collided
        else:
            n_eval += 1
            collided = d <= level
    # ---- 2. collect the pairs whose lower bound does not exceed the cut-off, with their keys
    if flat:  # from the list, in place (entry k is read before any write at n_c <= k)
        n_k = n_c
        n_c = 0
        a_prev = -1
        for k in range(n_k):
            p = pflag[k]
            g = plb[k]
            cutp = max(cut0, best[pair_cat[p]])
            if pstamp[p] == stamp_now or (g > 0.0 and g > cutp):
                continue
            a = pair_a[p]
            if a != a_prev:  # the list holds each element's pairs together
                a_prev = a
                cx = sphW[a, 0]; cy = sphW[a, 1]; cz = sphW[a, 2]; cr = sphW[a, 3]
                A, has_obb, lx, ly, lz, hx, hy, hz = _elem_box(a, MF, SF, o_obb, o_Xs, glink, sphW)
            b = pair_b[p]
            n_c = _collect(st_idx[b], p, cx, cy, cz, cr, A, has_obb, lx, ly, lz, hx, hy, hz, cutp, core[b], b, MF,
                           o_slo, o_shi, SF, o_box, plb, pflag, n_c)
    for i in range(n_sm if not flat else 0):
        a = st_mov[i]
        if core[a] < 2:
            continue
        sc_a = st_cat[i]
        ma = mov_idx[a]
        cx = sphW[a, 0]; cy = sphW[a, 1]; cz = sphW[a, 2]; cr = sphW[a, 3]
        # the W-aligned box of a's box (it contains a): a tighter node bound than the sphere for long links
        A, has_obb, lx, ly, lz, hx, hy, hz = _elem_box(a, MF, SF, o_obb, o_Xs, glink, sphW)
        stack[0] = 0
        gapst[0] = _sb_gap(cx, cy, cz, cr, MF, o_blo, o_bhi)
        if has_obb:
            gapst[0] = max(gapst[0], _bb_gap(lx, ly, lz, hx, hy, hz, 0.0, MF, o_blo, o_bhi))
        top = 1
        while top > 0:
            top -= 1
            node = stack[top]
            gnode = gapst[top]
            cut = max(cut0, best[sc_a] if sc_a >= 0 else max(best[1], best[3]))
            if gnode > 0.0 and gnode > cut:  # an overlapping node bounds nothing
                continue
            left = bvh_left[node]
            if left >= 0:
                right = bvh_right[node]
                gl = _sb_gap(cx, cy, cz, cr, MF, o_blo + 3 * left, o_bhi + 3 * left)
                gr = _sb_gap(cx, cy, cz, cr, MF, o_blo + 3 * right, o_bhi + 3 * right)
                if has_obb:
                    gl = max(gl, _bb_gap(lx, ly, lz, hx, hy, hz, 0.0, MF, o_blo + 3 * left, o_bhi + 3 * left))
                    gr = max(gr, _bb_gap(lx, ly, lz, hx, hy, hz, 0.0, MF, o_blo + 3 * right, o_bhi + 3 * right))
                top = _push_children(stack, gapst, top, left, gl, right, gr)  # the nearer popped first
                continue
            for it in range(bvh_start[node], bvh_start[node] + bvh_count[node]):
                s = bvh_items[it]
                p = pair_of[ma, s]
                if p < 0 or pstamp[p] == stamp_now:
                    continue
                b = pair_b[p]
                n_c = _collect(s, p, cx, cy, cz, cr, A, has_obb, lx, ly, lz, hx, hy, hz, max(cut0, best[pair_cat[p]]),
                               core[b], b, MF, o_slo, o_shi, SF, o_box, plb, pflag, n_c)
    # ---- 3. evaluate in increasing key
    _argsort_small(plb, order, n_c)
    for k in range(n_c):
        p = pflag[order[k]]
        key = plb[order[k]]
        a = pair_a[p]
        b = pair_b[p]
        cutp = max(cut0, best[pair_cat[p]])
        kb = core[b]
        if key > cutp and (key > 0.0 or _signed(MF[o_obb + 16 * a + 15] != 0.0, kb)):
            continue
        if ((kb == 2 or kb == 4) and cutp < math.inf and MF[o_obb + 16 * a + 15] != 0.0
                and obb_apart_static(MF, o_obb + 16 * a, o_Xs + 16 * glink[a], SF, o_box + 15 * b, max(cutp, 0.0),
                                     eps_par)):
            continue  # a's box grown by the cut-off misses the obstacle box: d > cut
        d, err = call_step(fns[FN_STEP], (p, a, b, flag, H, MF, MI, SF, SI, out9, eps_len, eps_par, gjk_eps, max_iter, woff,
                                          lvl, cutp, n_eval, stamp_now, fns))
        if err == BOUNDED:
            err = 0
            continue
        if err != 0:
            break
        n_eval += 1
        if d <= level:
            collided = True
    return n_eval, err, collided
