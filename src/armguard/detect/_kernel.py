"""The detector's hot path: one numba call per check (FK, transforms, broad phase, narrow phase).

Modes (``iprm[0]``):

* ``MODE_EXACT``: branch and bound.  Every pair whose bounding-volume lower bound exceeds its
  category's cut-off ``max(threshold_eff, best distance so far in the category)`` is skipped,
  so the nearest pair of every category and every pair within the threshold are exact.  Static
  obstacles are reached through the BVH, nearest child first.
* ``MODE_LAZY``: the cut-off is ``threshold_eff`` alone: pairs proved beyond it are skipped
  (status and within-threshold pairs stay exact; nearest per category only when within it).
* ``MODE_ANYTIME``: every candidate pair gets a lower bound, the larger of its bounding-volume
  gap and ``last distance - motion bound`` (:mod:`._reach`); pairs are evaluated in increasing
  lower bound (most likely obstacles first: near last time, or moved much since) until
  ``allowance`` evaluations are spent; the rest are reported with their bounds.
* ``MODE_ALL``: no pruning: every candidate pair is evaluated (``pair_distances``).
* ``MODE_YESNO``: like lazy with the cut-off at the collision level, stopping at the first
  collision.

``threshold_eff = max(threshold, stopping_distance)``; the collision level is
``max(0, stopping_distance)``.  Status codes: 0 clear, 1 warning, 2 collision, 3 incomplete.
Pair flags: 0 not evaluated (budget), 1 evaluated, 2 proved beyond the cut-off by a bound.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..kinematics._fk import _fk_kernel
from ._bvh import sphere_box_gap
from ._layout import K, SC, SUM_BEST, SUM_ERR, SUM_NEVAL, SUM_STATUS, seg1, seg2, seg3
from ._narrow import pair_distance, wall_distance

MODE_EXACT, MODE_LAZY, MODE_ANYTIME, MODE_YESNO, MODE_ALL = 0, 1, 2, 3, 4
ST_CLEAR, ST_WARNING, ST_COLLISION, ST_INCOMPLETE = 0, 1, 2, 3
# prm slots
P_THR, P_STOP, P_EPS_LEN, P_EPS_PAR, P_GJK_EPS, P_OFFSET = 0, 1, 2, 3, 4, 5
# iprm slots
I_MODE, I_ALLOW, I_MAXIT, I_STATE, I_LAZY = 0, 1, 2, 3, 4

_K_X_post = K["X_post"]
_K_X_pre = K["X_pre"]
_K_Xs = K["Xs"]
_K_axis = K["axis"]
_K_best = K["best"]
_K_boxW = K["boxW"]
_K_box_L = K["box_L"]
_K_bvh_count = K["bvh_count"]
_K_bvh_hi = K["bvh_hi"]
_K_bvh_items = K["bvh_items"]
_K_bvh_left = K["bvh_left"]
_K_bvh_lo = K["bvh_lo"]
_K_bvh_right = K["bvh_right"]
_K_bvh_start = K["bvh_start"]
_K_core = K["core"]
_K_edW = K["edW"]
_K_ed_L = K["ed_L"]
_K_estart = K["estart"]
_K_fnW = K["fnW"]
_K_fn_L = K["fn_L"]
_K_gap = K["gap"]
_K_glink = K["glink"]
_K_has_last = K["has_last"]
_K_has_post = K["has_post"]
_K_jtype = K["jtype"]
_K_last_d = K["last_d"]
_K_last_q = K["last_q"]
_K_lever = K["lever"]
_K_mov_ids = K["mov_ids"]
_K_mov_idx = K["mov_idx"]
_K_offset = K["offset"]
_K_order = K["order"]
_K_out9 = K["out9"]
_K_pair_a = K["pair_a"]
_K_pair_b = K["pair_b"]
_K_pair_cat = K["pair_cat"]
_K_pair_of = K["pair_of"]
_K_parent = K["parent"]
_K_pd = K["pd"]
_K_pflag = K["pflag"]
_K_plb = K["plb"]
_K_pstart = K["pstart"]
_K_pw = K["pw"]
_K_radius = K["radius"]
_K_sphW = K["sphW"]
_K_sph_L = K["sph_L"]
_K_st_idx = K["st_idx"]
_K_stack = K["stack"]
_K_stamp = K["stamp"]
_K_static_hi = K["static_hi"]
_K_static_lo = K["static_lo"]
_K_summary = K["summary"]
_K_term_coeff = K["term_coeff"]
_K_term_joint = K["term_joint"]
_K_term_start = K["term_start"]
_K_vW = K["vW"]
_K_verts_L = K["verts_L"]
_K_vstart = K["vstart"]
_K_work = K["work"]
_K_ws = K["ws"]
_SC_n_explicit = SC["n_explicit"]
_SC_n_links = SC["n_links"]
_SC_n_q = SC["n_q"]
_SC_n_st = SC["n_st"]


@njit(cache=True, inline="always")
def _move_elem(g, Xs, glink, core, vstart, verts_L, vW, box_L, boxW, pstart, fn_L, fnW, estart, ed_L, edW):  # pragma: no cover
    """Move element ``g`` from its link frame to W (core points, box, face normals, edge directions)."""
    X = Xs[0, glink[g]]
    r00 = X[0, 0]; r01 = X[0, 1]; r02 = X[0, 2]; tx = X[0, 3]
    r10 = X[1, 0]; r11 = X[1, 1]; r12 = X[1, 2]; ty = X[1, 3]
    r20 = X[2, 0]; r21 = X[2, 1]; r22 = X[2, 2]; tz = X[2, 3]
    for k in range(vstart[g], vstart[g + 1]):
        x = verts_L[k, 0]; y = verts_L[k, 1]; z = verts_L[k, 2]
        vW[k, 0] = r00 * x + r01 * y + r02 * z + tx
        vW[k, 1] = r10 * x + r11 * y + r12 * z + ty
        vW[k, 2] = r20 * x + r21 * y + r22 * z + tz
    if core[g] == 2:
        b = box_L[g]
        o = boxW[g]
        x = b[0]; y = b[1]; z = b[2]
        o[0] = r00 * x + r01 * y + r02 * z + tx
        o[1] = r10 * x + r11 * y + r12 * z + ty
        o[2] = r20 * x + r21 * y + r22 * z + tz
        o[3] = b[3]; o[4] = b[4]; o[5] = b[5]
        for j in range(3):  # R_WB = R_WL R_LB, row-major
            a0 = b[6 + j]; a1 = b[9 + j]; a2 = b[12 + j]
            o[6 + j] = r00 * a0 + r01 * a1 + r02 * a2
            o[9 + j] = r10 * a0 + r11 * a1 + r12 * a2
            o[12 + j] = r20 * a0 + r21 * a1 + r22 * a2
    for k in range(pstart[g], pstart[g + 1]):
        x = fn_L[k, 0]; y = fn_L[k, 1]; z = fn_L[k, 2]
        fnW[k, 0] = r00 * x + r01 * y + r02 * z
        fnW[k, 1] = r10 * x + r11 * y + r12 * z
        fnW[k, 2] = r20 * x + r21 * y + r22 * z
    for k in range(estart[g], estart[g + 1]):
        x = ed_L[k, 0]; y = ed_L[k, 1]; z = ed_L[k, 2]
        edW[k, 0] = r00 * x + r01 * y + r02 * z
        edW[k, 1] = r10 * x + r11 * y + r12 * z
        edW[k, 2] = r20 * x + r21 * y + r22 * z


@njit(cache=True)
def detect_one(q, H, MF, MI, SF, SI, prm, iprm):  # pragma: no cover - compiled
    """One check at ``q`` ``(1, n_q)``; results in the SF / SI segments (see the module docstring)."""
    # ---- views
    n_links = H[_SC_n_links]
    n_q = H[_SC_n_q]
    n_explicit = H[_SC_n_explicit]
    n_st = H[_SC_n_st]
    X_pre = seg3(MF, H, _K_X_pre, 4, 4)
    axis = seg2(MF, H, _K_axis, 3)
    X_post = seg3(MF, H, _K_X_post, 4, 4)
    offset = seg1(MF, H, _K_offset)
    term_coeff = seg1(MF, H, _K_term_coeff)
    radius = seg1(MF, H, _K_radius)
    verts_L = seg2(MF, H, _K_verts_L, 3)
    box_L = seg2(MF, H, _K_box_L, 15)
    fn_L = seg2(MF, H, _K_fn_L, 3)
    ed_L = seg2(MF, H, _K_ed_L, 3)
    sph_L = seg2(MF, H, _K_sph_L, 4)
    static_lo = seg2(MF, H, _K_static_lo, 3)
    static_hi = seg2(MF, H, _K_static_hi, 3)
    bvh_lo = seg2(MF, H, _K_bvh_lo, 3)
    bvh_hi = seg2(MF, H, _K_bvh_hi, 3)
    lever = seg2(MF, H, _K_lever, max(n_q, 1))
    ws = seg1(MF, H, _K_ws)
    parent = seg1(MI, H, _K_parent)
    jtype = seg1(MI, H, _K_jtype)
    has_post = seg1(MI, H, _K_has_post)
    term_start = seg1(MI, H, _K_term_start)
    term_joint = seg1(MI, H, _K_term_joint)
    glink = seg1(MI, H, _K_glink)
    core = seg1(MI, H, _K_core)
    vstart = seg1(MI, H, _K_vstart)
    pstart = seg1(MI, H, _K_pstart)
    estart = seg1(MI, H, _K_estart)
    mov_idx = seg1(MI, H, _K_mov_idx)
    st_idx = seg1(MI, H, _K_st_idx)
    bvh_left = seg1(MI, H, _K_bvh_left)
    bvh_right = seg1(MI, H, _K_bvh_right)
    bvh_start = seg1(MI, H, _K_bvh_start)
    bvh_count = seg1(MI, H, _K_bvh_count)
    bvh_items = seg1(MI, H, _K_bvh_items)
    pair_a = seg1(MI, H, _K_pair_a)
    pair_b = seg1(MI, H, _K_pair_b)
    pair_cat = seg1(MI, H, _K_pair_cat)
    pair_of = seg2(MI, H, _K_pair_of, max(n_st, 1))
    mov_ids = seg1(MI, H, _K_mov_ids)
    Xs = seg3(SF, H, _K_Xs, 4, 4).reshape((1, n_links, 4, 4))
    vW = seg2(SF, H, _K_vW, 3)
    boxW = seg2(SF, H, _K_boxW, 15)
    fnW = seg2(SF, H, _K_fnW, 3)
    edW = seg2(SF, H, _K_edW, 3)
    sphW = seg2(SF, H, _K_sphW, 4)
    out9 = seg1(SF, H, _K_out9)
    work = seg1(SF, H, _K_work)
    gapst = seg1(SF, H, _K_gap)
    pd = seg1(SF, H, _K_pd)
    pw = seg2(SF, H, _K_pw, 6)
    plb = seg1(SF, H, _K_plb)
    last_d = seg1(SF, H, _K_last_d)
    last_q = seg2(SF, H, _K_last_q, max(n_q, 1))
    best = seg1(SF, H, _K_best)
    stack = seg1(SI, H, _K_stack)
    order = seg1(SI, H, _K_order)
    pflag = seg1(SI, H, _K_pflag)
    has_last = seg1(SI, H, _K_has_last)
    stamp = seg1(SI, H, _K_stamp)
    summary = seg1(SI, H, _K_summary)

    thr = prm[P_THR]
    stop = prm[P_STOP]
    eps_len = prm[P_EPS_LEN]
    eps_par = prm[P_EPS_PAR]
    gjk_eps = prm[P_GJK_EPS]
    woff = prm[P_OFFSET]
    mode = iprm[I_MODE]
    allowance = iprm[I_ALLOW]
    max_iter = iprm[I_MAXIT]
    use_state = iprm[I_STATE] != 0
    thr_eff = max(thr, stop)
    level = max(0.0, stop)
    P = pair_a.shape[0]

    summary[SUM_ERR] = 0
    for j in range(n_q):
        if not math.isfinite(q[0, j]):
            summary[SUM_ERR] = 1
            return
    # ---- FK and bounding spheres of the moving elements
    _fk_kernel(q, parent, X_pre, axis, jtype, X_post, has_post, offset, term_start, term_joint, term_coeff, Xs)
    stamp_now = stamp[0] + 1  # stamp[0] counts checks; stamp[1 + g] marks moved elements
    stamp[0] = stamp_now
    for i in range(mov_ids.shape[0]):
        g = mov_ids[i]
        X = Xs[0, glink[g]]
        x = sph_L[g, 0]; y = sph_L[g, 1]; z = sph_L[g, 2]
        sphW[g, 0] = X[0, 0] * x + X[0, 1] * y + X[0, 2] * z + X[0, 3]
        sphW[g, 1] = X[1, 0] * x + X[1, 1] * y + X[1, 2] * z + X[1, 3]
        sphW[g, 2] = X[2, 0] * x + X[2, 1] * y + X[2, 2] * z + X[2, 3]
        sphW[g, 3] = sph_L[g, 3]
    s0 = summary[SUM_BEST + 0]
    s1 = summary[SUM_BEST + 1]
    s2 = summary[SUM_BEST + 2]
    s3 = summary[SUM_BEST + 3]
    for c in range(4):
        best[c] = math.inf
        summary[SUM_BEST + c] = -1
    for p in range(P):
        pflag[p] = 2
        plb[p] = -math.inf
    if mode == MODE_ALL:
        cut0 = math.inf
    elif mode == MODE_YESNO:
        cut0 = level
    else:
        cut0 = thr_eff  # exact mode: the cut-off of a category is max(cut0, its best so far)
    n_eval = 0
    collided = False
    ws_lo = ws[0:3]
    ws_hi = ws[3:6]

    if mode == MODE_ANYTIME:
        # lower bounds for every candidate pair, then evaluate in increasing bound
        for p in range(P):
            a = pair_a[p]
            b = pair_b[p]
            if b < 0:
                r = sphW[a, 3]
                lb = min(ws_hi[0] - sphW[a, 0], ws_hi[1] - sphW[a, 1], ws_hi[2] - sphW[a, 2],
                         sphW[a, 0] - ws_lo[0], sphW[a, 1] - ws_lo[1], sphW[a, 2] - ws_lo[2]) - r
            elif mov_idx[b] >= 0:
                dx = sphW[a, 0] - sphW[b, 0]; dy = sphW[a, 1] - sphW[b, 1]; dz = sphW[a, 2] - sphW[b, 2]
                lb = math.sqrt(dx * dx + dy * dy + dz * dz) - sphW[a, 3] - sphW[b, 3]
            else:
                s = st_idx[b]
                lb = sphere_box_gap(sphW[a, 0], sphW[a, 1], sphW[a, 2], sphW[a, 3], static_lo[s], static_hi[s])
            if not lb > 0.0 and b >= 0:
                lb = -math.inf  # overlapping bounding volumes bound nothing
            if use_state and has_last[p] != 0:
                ma = mov_idx[a]
                mb = mov_idx[b] if b >= 0 else -1
                moved = 0.0
                for j in range(n_q):
                    dq = abs(q[0, j] - last_q[p, j])
                    if dq > 0.0:
                        lv = lever[ma, j]
                        if mb >= 0:
                            lv += lever[mb, j]
                        moved += dq * lv
                lb = max(lb, last_d[p] - moved)
            plb[p] = lb
        order[:P] = np.argsort(plb[:P])
        lazy = iprm[I_LAZY] != 0
        for k in range(P):
            p = order[k]
            if lazy and plb[p] > thr_eff:
                break  # sorted: every remaining bound proves the threshold (flag 2)
            if n_eval >= allowance:
                pflag[p] = 0
                continue
            a = pair_a[p]
            b = pair_b[p]
            if stamp[1 + a] != stamp_now:
                _move_elem(a, Xs, glink, core, vstart, verts_L, vW, box_L, boxW, pstart, fn_L, fnW, estart, ed_L, edW)
                stamp[1 + a] = stamp_now
            if b < 0:
                d = wall_distance(a, radius, vW, vstart, ws_lo, ws_hi, out9)
            else:
                if mov_idx[b] >= 0 and stamp[1 + b] != stamp_now:
                    _move_elem(b, Xs, glink, core, vstart, verts_L, vW, box_L, boxW, pstart, fn_L, fnW, estart, ed_L, edW)
                    stamp[1 + b] = stamp_now
                d, err = pair_distance(a, b, core, radius, vW, vstart, boxW, fnW, pstart, edW, estart, out9, work,
                                       eps_len, eps_par, gjk_eps, max_iter, woff)
                if err != 0:
                    summary[SUM_ERR] = err
                    return
            n_eval += 1
            pflag[p] = 1
            pd[p] = d
            for i in range(6):
                pw[p, i] = out9[i]
            c = pair_cat[p]
            if d < best[c]:
                best[c] = d
                summary[SUM_BEST + c] = p
        # pairs beyond the threshold by their bound: flag 2 (proved), bound kept in plb
    else:
        # ---- temporal coherence: last check's nearest pair of each category first, so the
        # category cut-offs are tight from the start (exact mode, single checks only)
        if mode == MODE_EXACT and use_state:
            for c in range(4):
                p = s0 if c == 0 else (s1 if c == 1 else (s2 if c == 2 else s3))
                if p < 0 or p >= P or pflag[p] == 1:
                    continue
                a = pair_a[p]
                b = pair_b[p]
                if stamp[1 + a] != stamp_now:
                    _move_elem(a, Xs, glink, core, vstart, verts_L, vW, box_L, boxW, pstart, fn_L, fnW, estart, ed_L, edW)
                    stamp[1 + a] = stamp_now
                if b < 0:
                    d = wall_distance(a, radius, vW, vstart, ws_lo, ws_hi, out9)
                else:
                    if mov_idx[b] >= 0 and stamp[1 + b] != stamp_now:
                        _move_elem(b, Xs, glink, core, vstart, verts_L, vW, box_L, boxW, pstart, fn_L, fnW, estart, ed_L, edW)
                        stamp[1 + b] = stamp_now
                    d, err = pair_distance(a, b, core, radius, vW, vstart, boxW, fnW, pstart, edW, estart, out9, work,
                                           eps_len, eps_par, gjk_eps, max_iter, woff)
                    if err != 0:
                        summary[SUM_ERR] = err
                        return
                n_eval += 1
                pflag[p] = 1
                pd[p] = d
                for i in range(6):
                    pw[p, i] = out9[i]
                cp = pair_cat[p]
                if d < best[cp]:
                    best[cp] = d
                    summary[SUM_BEST + cp] = p
        # ---- explicit pairs: moving-moving and workspace walls
        for p in range(n_explicit):
            if collided and mode == MODE_YESNO:
                break
            if pflag[p] == 1:
                continue
            a = pair_a[p]
            b = pair_b[p]
            c = pair_cat[p]
            cut = max(cut0, best[c]) if mode == MODE_EXACT else cut0
            if b < 0:
                r = sphW[a, 3]
                lb = min(ws_hi[0] - sphW[a, 0], ws_hi[1] - sphW[a, 1], ws_hi[2] - sphW[a, 2],
                         sphW[a, 0] - ws_lo[0], sphW[a, 1] - ws_lo[1], sphW[a, 2] - ws_lo[2]) - r
            else:
                dx = sphW[a, 0] - sphW[b, 0]; dy = sphW[a, 1] - sphW[b, 1]; dz = sphW[a, 2] - sphW[b, 2]
                lb = math.sqrt(dx * dx + dy * dy + dz * dz) - sphW[a, 3] - sphW[b, 3]
                if not lb > 0.0:
                    lb = -math.inf
            if lb > cut:
                plb[p] = lb
                continue
            if stamp[1 + a] != stamp_now:
                _move_elem(a, Xs, glink, core, vstart, verts_L, vW, box_L, boxW, pstart, fn_L, fnW, estart, ed_L, edW)
                stamp[1 + a] = stamp_now
            if b < 0:
                d = wall_distance(a, radius, vW, vstart, ws_lo, ws_hi, out9)
            else:
                if stamp[1 + b] != stamp_now:
                    _move_elem(b, Xs, glink, core, vstart, verts_L, vW, box_L, boxW, pstart, fn_L, fnW, estart, ed_L, edW)
                    stamp[1 + b] = stamp_now
                d, err = pair_distance(a, b, core, radius, vW, vstart, boxW, fnW, pstart, edW, estart, out9, work,
                                       eps_len, eps_par, gjk_eps, max_iter, woff)
                if err != 0:
                    summary[SUM_ERR] = err
                    return
            n_eval += 1
            pflag[p] = 1
            pd[p] = d
            for i in range(6):
                pw[p, i] = out9[i]
            if d < best[c]:
                best[c] = d
                summary[SUM_BEST + c] = p
            if d <= level:
                collided = True
        # ---- moving-static pairs through the BVH, nearest child first
        if n_st > 0:
            for i in range(mov_ids.shape[0]):
                if collided and mode == MODE_YESNO:
                    break
                a = mov_ids[i]
                ma = mov_idx[a]
                cx = sphW[a, 0]; cy = sphW[a, 1]; cz = sphW[a, 2]; cr = sphW[a, 3]
                top = 0
                stack[0] = 0
                gapst[0] = sphere_box_gap(cx, cy, cz, cr, bvh_lo[0], bvh_hi[0])
                top = 1
                while top > 0:
                    top -= 1
                    node = stack[top]
                    gnode = gapst[top]
                    if mode == MODE_EXACT:
                        cut = max(cut0, max(best[1], best[3]))
                    else:
                        cut = cut0
                    if gnode > cut:
                        continue
                    left = bvh_left[node]
                    if left >= 0:
                        right = bvh_right[node]
                        gl = sphere_box_gap(cx, cy, cz, cr, bvh_lo[left], bvh_hi[left])
                        gr = sphere_box_gap(cx, cy, cz, cr, bvh_lo[right], bvh_hi[right])
                        if gl <= gr:  # push the farther first: the nearer is popped first
                            stack[top] = right; gapst[top] = gr; top += 1
                            stack[top] = left; gapst[top] = gl; top += 1
                        else:
                            stack[top] = left; gapst[top] = gl; top += 1
                            stack[top] = right; gapst[top] = gr; top += 1
                        continue
                    for it in range(bvh_start[node], bvh_start[node] + bvh_count[node]):
                        s = bvh_items[it]
                        p = pair_of[ma, s]
                        if p < 0 or pflag[p] == 1:
                            continue
                        c = pair_cat[p]
                        cutp = max(cut0, best[c]) if mode == MODE_EXACT else cut0
                        lb = sphere_box_gap(cx, cy, cz, cr, static_lo[s], static_hi[s])
                        if not lb > 0.0:
                            lb = -math.inf
                        if lb > cutp:
                            plb[p] = lb
                            continue
                        if stamp[1 + a] != stamp_now:
                            _move_elem(a, Xs, glink, core, vstart, verts_L, vW, box_L, boxW, pstart, fn_L, fnW,
                                       estart, ed_L, edW)
                            stamp[1 + a] = stamp_now
                        b = pair_b[p]
                        d, err = pair_distance(a, b, core, radius, vW, vstart, boxW, fnW, pstart, edW, estart, out9,
                                               work, eps_len, eps_par, gjk_eps, max_iter, woff)
                        if err != 0:
                            summary[SUM_ERR] = err
                            return
                        n_eval += 1
                        pflag[p] = 1
                        pd[p] = d
                        for k in range(6):
                            pw[p, k] = out9[k]
                        if d < best[c]:
                            best[c] = d
                            summary[SUM_BEST + c] = p
                        if d <= level:
                            collided = True
                            if mode == MODE_YESNO:
                                break
                    if collided and mode == MODE_YESNO:
                        break
    # ---- state for the anytime bounds, and the status
    dmin = math.inf
    lbmin = math.inf
    for p in range(P):
        if pflag[p] == 1:
            if pd[p] < dmin:
                dmin = pd[p]
            if use_state:
                last_d[p] = pd[p]
                has_last[p] = 1
                for j in range(n_q):
                    last_q[p, j] = q[0, j]
        elif pflag[p] == 0:
            if plb[p] < lbmin:
                lbmin = plb[p]
    summary[SUM_NEVAL] = n_eval
    if dmin <= level:
        st = ST_COLLISION
    elif lbmin > thr_eff:  # nothing unevaluated can be within the threshold
        st = ST_WARNING if dmin <= thr_eff else ST_CLEAR
    elif dmin <= thr_eff and lbmin > level:
        st = ST_WARNING
    else:
        st = ST_INCOMPLETE
    summary[SUM_STATUS] = st


@njit(cache=True, nogil=True)
def detect_chunk(Q, lo, hi, H, MF, MI, SF, SI, prm, iprm, min_d, status):  # pragma: no cover - compiled
    """``detect_one`` over rows ``lo:hi`` of ``Q`` with one scratch row; returns an error code (0: none)."""
    summ = seg1(SI, H, _K_summary)
    b = seg1(SF, H, _K_best)
    for m in range(lo, hi):
        detect_one(Q[m:m + 1], H, MF, MI, SF, SI, prm, iprm)
        if summ[SUM_ERR] != 0:
            return summ[SUM_ERR]
        for c in range(4):
            min_d[m, c] = b[c]
        status[m] = summ[SUM_STATUS]
    return 0


@njit(cache=True)
def detect_entry(q, H, MF, MI, SF, SI, prm, iprm):  # pragma: no cover - compiled
    """:func:`detect_one`, returning ``(status, n_evaluated, error)`` (saves reads from Python)."""
    detect_one(q, H, MF, MI, SF, SI, prm, iprm)
    summary = seg1(SI, H, _K_summary)
    return summary[SUM_STATUS], summary[SUM_NEVAL], summary[SUM_ERR]
