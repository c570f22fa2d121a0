"""The detector's hot path: one numba call per check (FK, transforms, broad phase, narrow phase).

Modes (``iprm[0]``):

* ``MODE_EXACT``: branch and bound.  Every pair whose bounding-volume lower bound exceeds its
  category's cut-off ``max(threshold_eff, best distance so far in the category)`` is skipped,
  so the nearest pair of every category and every pair within the threshold are exact.  Static
  obstacles are reached through the BVH, nearest child first.
* ``MODE_LAZY``: the cut-off is ``threshold_eff`` alone: pairs proved beyond it are skipped
  (status and within-threshold pairs stay exact; nearest per category only when within it).
* ``MODE_ANYTIME``: every candidate pair gets a lower bound, the larger of its bounding-volume
  gap and ``last distance - motion bound`` (:mod:`armguard.detect._reach`); pairs are evaluated in increasing
  lower bound (most likely obstacles first: near last time, or moved much since) until
  ``allowance`` evaluations are spent; the rest are reported with their bounds.
* ``MODE_ALL``: no pruning: every candidate pair is evaluated (``pair_distances``).
* ``MODE_YESNO``: like lazy with the cut-off at the collision level, stopping at the first
  collision; static obstacles first, self-collision pairs last.
* ``MODE_MIN``: the batch form of exact: the cut-off of a category is its best distance so far
  alone (the per-category minima and the status are exact; pairs within the threshold that are
  not the nearest of their category may be skipped, as the batch reports only the minima).

``threshold_eff = max(threshold, stopping_distance)``; the collision level is
``max(Tolerances.length, stopping_distance)`` (the contact tolerance ``intersects`` uses).  Status codes: 0 clear, 1 warning, 2 collision, 3 incomplete.
Pair flags: 0 not evaluated (budget), 1 evaluated, 2 proved beyond the cut-off by a bound.
"""

from __future__ import annotations

import math

import numpy as np

from numba import carray, njit

# ST_*: the status codes the Detector reads (kn.ST_COLLISION, ...), the framework's
from armguard.detect._common import ST_CLEAR, ST_COLLISION, ST_INCOMPLETE, ST_WARNING, status_code  # noqa: F401
from armguard.kinematics._fk import _fk_kernel
# The segment numbers K come from ._layout and are compiled in as constants; numba's cache keys on
# this file only, so a change of the segment tuples in ._layout must come with an edit here.
from ._layout import COHERENT_STEP, EV_W, K, SC, at, SUM_BEST, SUM_BSLOT, SUM_ERR, SUM_NEVAL, SUM_STATUS, seg1, seg2, seg3
from ._cull import (_argsort_heap, _argsort_small, _bb_gap, _explicit_gap, _gjk_pair, _obb_gap, _push_children, _sb_gap,
                    obb_apart_moving, obb_apart_static)
from ._narrow import BOUNDED
from ._calls import FN_STATIC, call_static
from ._step import capsule_step, constant_step, move_element, pair_step, pair_step_inline

MODE_EXACT, MODE_LAZY, MODE_ANYTIME, MODE_YESNO, MODE_ALL, MODE_MIN = 0, 1, 2, 3, 4, 5
_status_code = njit(cache=True, inline="always")(status_code)  # the framework's rule, compiled
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
_K_bvh_count = K["bvh_count"]
_K_bvh_hi = K["bvh_hi"]
_K_bvh_items = K["bvh_items"]
_K_bvh_left = K["bvh_left"]
_K_bvh_lo = K["bvh_lo"]
_K_bvh_right = K["bvh_right"]
_K_bvh_start = K["bvh_start"]
_K_core = K["core"]
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
_K_pflag = K["pflag"]
_K_plb = K["plb"]
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
_K_vstart = K["vstart"]
_K_ws = K["ws"]
_K_ev = K["ev"]
_K_ev_p = K["ev_p"]
_K_pstamp = K["pstamp"]
_K_st_mov = K["st_mov"]
_K_st_cat = K["st_cat"]
_K_rob_l = K["rob_l"]
_K_yn_mov = K["yn_mov"]
_K_yn_cat = K["yn_cat"]
_K_rob_j = K["rob_j"]
_K_parent_loc = K["parent_loc"]
_K_fk_q = K["fk_q"]
_K_fk_ok = K["fk_ok"]
_K_coh = K["coh"]
_K_obb_L = K["obb_L"]
_K_qlim = K["qlim"]
_SC_n_explicit = SC["n_explicit"]
_SC_n_links = SC["n_links"]
_SC_n_q = SC["n_q"]
_SC_n_st = SC["n_st"]


# Compiled WITH numba's reference counting.  Without it (numba's private ``_nrt=False``), LLVM's code
# generator once segfaulted compiling this kernel from a cold cache (numba 0.68), when it linked the
# convex kernels; it now calls them at their addresses and compiles either way, but without it
# neither Ranger's check nor the yes/no rows got faster (timed both ways, within noise):
# its reference counting is per check, and the per-pair helpers it calls are compiled without it
# (._step).  The segment views cost no atomic operation anyway (meminfo-free views, see ._layout).
@njit(cache=True, nogil=True)
def detect_rows(Q, lo, hi, H, MF, MI, SF, SI, prm, iprm, sel, min_d, status_out, fns):  # pragma: no cover - compiled
    """Checks of rows ``lo:hi`` of ``Q`` ``(M, n_q)``; per row the nearest distance per category goes to
    ``min_d[m]`` ``(4,)`` and the status code to ``status_out[m]``; the last row's pairs stay in the
    compact outputs (``ev``, ``ev_p``, ``summary``).  ``sel``: the pairs ``MODE_ALL`` evaluates, in
    that order.  Returns an error code (0 none, 1 non-finite q, 2 GJK did not converge, 3 a joint
    outside its limits (``qlim``): the reach lists and lever-arm bounds hold only within them).
    ``fns``: the kernels' addresses (:func:`._calls.addresses`): the pair step and the static pairs'
    branch and bound are called there, not linked (:mod:`._native`).

    Per check, only the pairs actually evaluated are touched (a per-pair stamp marks them), so the
    cost follows the BVH walk, not the number of candidate pairs; the anytime and lazy modes,
    which report every skipped pair with its bound, keep their O(pairs) flags.
    """
    # ---- the buffers as views without a reference count (numba.carray, see ._layout): every use of
    # an array with one in a helper (an inlined bound, a compiled callee) increments and decrements
    # it atomically -- with the buffers themselves that was half the yes/no batch's time (perf:
    # ``lock incq`` / ``lock decq`` in NRT_incref / NRT_decref); these views make those calls no-ops
    H = carray(at(H, 0), H.shape)
    MF = carray(at(MF, 0), MF.shape)
    MI = carray(at(MI, 0), MI.shape)
    SF = carray(at(SF, 0), SF.shape)
    SI = carray(at(SI, 0), SI.shape)
    fns = carray(at(fns, 0), fns.shape)  # passed on to every pair step
    # ---- views (once per call, not per row)
    n_links = H[_SC_n_links]
    n_q = H[_SC_n_q]
    n_explicit = H[_SC_n_explicit]
    n_st = H[_SC_n_st]
    X_pre = seg3(MF, H, _K_X_pre, 4, 4)
    axis = seg2(MF, H, _K_axis, 3)
    X_post = seg3(MF, H, _K_X_post, 4, 4)
    offset = seg1(MF, H, _K_offset)
    term_coeff = seg1(MF, H, _K_term_coeff)
    sph_L = seg2(MF, H, _K_sph_L, 4)
    lever = seg2(MF, H, _K_lever, max(n_q, 1))
    ws = seg1(MF, H, _K_ws)
    jtype = seg1(MI, H, _K_jtype)
    has_post = seg1(MI, H, _K_has_post)
    term_start = seg1(MI, H, _K_term_start)
    term_joint = seg1(MI, H, _K_term_joint)
    glink = seg1(MI, H, _K_glink)
    core = seg1(MI, H, _K_core)
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
    if iprm[I_MODE] == MODE_YESNO:  # the static walk's element order (see FusedDetector.prepare)
        st_mov = seg1(MI, H, _K_yn_mov)
        st_cat = seg1(MI, H, _K_yn_cat)
    else:
        st_mov = seg1(MI, H, _K_st_mov)
        st_cat = seg1(MI, H, _K_st_cat)
    rob_l = seg1(MI, H, _K_rob_l)
    rob_j = seg1(MI, H, _K_rob_j)
    parent_loc = seg1(MI, H, _K_parent_loc)
    fk_q = seg1(SF, H, _K_fk_q)
    qlim = seg2(MF, H, _K_qlim, 2)
    fk_ok = seg1(SI, H, _K_fk_ok)
    o_coh = H[2 * _K_coh]
    o_Xs = H[2 * _K_Xs]
    Xs = carray(at(SF, o_Xs), (1, n_links, 4, 4))
    sphW = seg2(SF, H, _K_sphW, 4)
    out9 = seg1(SF, H, _K_out9)
    gapst = seg1(SF, H, _K_gap)
    ev = seg2(SF, H, _K_ev, EV_W)
    plb = seg1(SF, H, _K_plb)
    last_d = seg1(SF, H, _K_last_d)
    last_q = seg2(SF, H, _K_last_q, max(n_q, 1))
    best = seg1(SF, H, _K_best)
    stack = seg1(SI, H, _K_stack)
    order = seg1(SI, H, _K_order)
    pflag = seg1(SI, H, _K_pflag)
    has_last = seg1(SI, H, _K_has_last)
    stamp = seg1(SI, H, _K_stamp)
    pstamp = seg1(SI, H, _K_pstamp)
    summary = seg1(SI, H, _K_summary)
    ev_p = seg1(SI, H, _K_ev_p)

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
    lazy = iprm[I_LAZY] != 0
    thr_eff = max(thr, stop)
    level = max(eps_len, stop)  # Tolerances.length: the contact tolerance (a distance <= it is a contact, as intersects)
    lvl = level if mode == MODE_YESNO else -math.inf  # pair_step / narrow_other: only d <= level matters
    P = pair_a.shape[0]
    track = mode == MODE_LAZY or mode == MODE_ANYTIME  # per-pair flags and bounds for the report
    # pair_step's flag as runtime booleans: a literal True/False argument makes numba compile a
    # separate specialisation of pair_step (and everything it inlines) for each, on a cold cache
    flag_no = track != track
    flag_yes = track == track
    ws_lo = ws[0:3]
    ws_hi = ws[3:6]
    if mode == MODE_ALL:
        cut0 = math.inf
    elif mode == MODE_YESNO:
        cut0 = level
    elif mode == MODE_MIN:
        cut0 = -math.inf  # the cut-off of a category is its best so far
    else:
        cut0 = thr_eff  # exact mode: the cut-off of a category is max(cut0, its best so far)
    by_best = mode == MODE_EXACT or mode == MODE_MIN
    o_slo = H[2 * _K_static_lo]
    o_shi = H[2 * _K_static_hi]
    o_blo = H[2 * _K_bvh_lo]
    o_bhi = H[2 * _K_bvh_hi]
    o_box = H[2 * _K_boxW]
    o_vs = H[2 * _K_vstart]
    o_vW = H[2 * _K_vW]
    o_rad = H[2 * _K_radius]
    o_obb = H[2 * _K_obb_L]  # the moving polytopes' boxes (flag in column 15): a cull before GJK
    # in yes/no mode (cut-off: the collision level); in the exact and min modes (cut-off: the
    # category's best so far) for pairs with a moving box, hull or cylinder only, whose narrow phase
    # is GJK (~1 us): for capsule pairs (tens of ns) the test costs more than it saves (measured)
    box_cull = mode == MODE_YESNO
    # the exact and min modes order the GJK pairs (a moving box, hull or cylinder: ~1 us each; the sort costs more than
    # capsule pairs save): iiwa hulls in world20 23 -> 17 us per check; their moving-static pairs: ._static_gjk
    by_order = by_best

    for m in range(lo, hi):
        q = Q[m:m + 1]
        summary[SUM_ERR] = 0
        for j in range(n_q):
            x = q[0, j]
            if not math.isfinite(x):
                summary[SUM_ERR] = 1
                return 1
            if x < qlim[j, 0] or x > qlim[j, 1]:
                summary[SUM_ERR] = 3
                return 3
        # ---- warm start (on) and near this thread's previous check (FK done, each joint within COHERENT_STEP)?
        coh = SF[o_coh]
        for r in range(rob_l.shape[0] - 1):
            coh = coh if fk_ok[r] != 0 else 0.0
        if coh != 0.0:
            for j in range(n_q):
                if abs(q[0, j] - fk_q[j]) > COHERENT_STEP:
                    coh = 0.0
                    break
        SF[o_coh + 1] = coh
        # ---- FK and bounding spheres of the moving elements
        # FK per robot block, only for the robots whose joint values changed since the last check
        # (exact equality: an unchanged block's poses are the ones FK would compute again)
        for r in range(rob_l.shape[0] - 1):
            j0 = rob_j[r]
            j1 = rob_j[r + 1]
            if fk_ok[r] != 0:
                same = True
                for j in range(j0, j1):
                    if q[0, j] != fk_q[j]:
                        same = False
                        break
                if same:
                    continue
            l0 = rob_l[r]
            l1 = rob_l[r + 1]
            Xb = carray(at(SF, o_Xs + 16 * l0), (1, l1 - l0, 4, 4))
            _fk_kernel(q, parent_loc[l0:l1], X_pre[l0:l1], axis[l0:l1], jtype[l0:l1], X_post[l0:l1],
                       has_post[l0:l1], offset[l0:l1], term_start[l0:l1 + 1], term_joint, term_coeff, Xb)
            for j in range(j0, j1):
                fk_q[j] = q[0, j]
            fk_ok[r] = 1
        stamp_now = stamp[0] + 1  # stamp[0] counts checks; stamp[1 + g] marks moved elements, pstamp evaluated pairs
        stamp[0] = stamp_now
        # the moving elements' bounding spheres in W, for the other modes' culls (MODE_ALL reads none)
        for i in range(mov_ids.shape[0] if mode != MODE_ALL else 0):
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
            summary[SUM_BSLOT + c] = -1
        if track:
            for p in range(P):
                pflag[p] = 2
                plb[p] = -math.inf
        n_eval = np.int64(0)  # int64, not a literal 0: one compiled pair_step and static_gjk_pairs, not two
        collided = False
        err = 0

        if mode == MODE_ALL:
            for k in range(sel.shape[0]):
                p = sel[k]
                a = pair_a[p]; b = pair_b[p]
                if not (constant_step(p, H, MF, MI, SF, SI, n_eval, stamp_now)  # inlined: an edit of it, one here
                        or capsule_step(p, a, b, H, MF, MI, SF, SI, eps_len, eps_par, n_eval, stamp_now)):
                    d, err = pair_step_inline(p, a, b, flag_no, H, MF, MI, SF, SI, out9, eps_len, eps_par, gjk_eps,
                                              max_iter, woff, lvl, math.inf, n_eval, stamp_now, fns)
                    if err != 0:
                        break
                n_eval += 1
        elif mode == MODE_ANYTIME:
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
                    lb = _sb_gap(sphW[a, 0], sphW[a, 1], sphW[a, 2], sphW[a, 3], MF, o_slo + 3 * s, o_shi + 3 * s)
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
            _argsort_heap(plb, order, P)
            for k in range(P):
                p = order[k]
                if lazy and plb[p] > thr_eff:
                    break  # sorted: every remaining bound proves the threshold (flag 2)
                if n_eval >= allowance:
                    pflag[p] = 0
                    continue
                a = pair_a[p]
                b = pair_b[p]
                d, err = pair_step(p, a, b, flag_yes, H, MF, MI, SF, SI, out9, eps_len, eps_par, gjk_eps,
                                   max_iter, woff, lvl, math.inf, n_eval, stamp_now, fns)
                if err != 0:
                    break
                n_eval += 1
            # pairs beyond the threshold by their bound: flag 2 (proved), bound kept in plb
        else:
            # ---- temporal coherence: last check's nearest pair of each category first, so the
            # category cut-offs are tight from the start (exact mode, single checks only)
            if mode == MODE_EXACT and use_state:
                for c in range(4):
                    p = s0 if c == 0 else (s1 if c == 1 else (s2 if c == 2 else s3))
                    if p < 0 or p >= P or pstamp[p] == stamp_now:
                        continue
                    a = pair_a[p]
                    b = pair_b[p]
                    d, err = pair_step(p, a, b, track, H, MF, MI, SF, SI, out9, eps_len, eps_par, gjk_eps,
                                       max_iter, woff, lvl, math.inf, n_eval, stamp_now, fns)
                    if err != 0:
                        break
                    n_eval += 1
            # yes/no: the static obstacles first (self-collision pairs last); otherwise explicit pairs first
            for phase in range(2):
                if err != 0 or (collided and mode == MODE_YESNO):
                    break
                if (phase == 0) != (mode == MODE_YESNO):
                    # ---- explicit pairs: moving-moving and workspace walls.  The exact and min
                    # modes take the GJK pairs (a box, hull or cylinder side) after the others, in
                    # increasing bounding-sphere gap (keys in plb, pair numbers in pflag, the sort in
                    # order: scratch only the tracked modes report), so a category's best tightens
                    # early and GJK proves the later pairs beyond it sooner (or the spheres cull them)
                    n_x = 0
                    if by_order:
                        for p in range(n_explicit):
                            if pair_b[p] >= 0 and _gjk_pair(core[pair_a[p]], core[pair_b[p]]):
                                plb[n_x] = _explicit_gap(p, pair_a, pair_b, sphW, ws_lo, ws_hi)
                                pflag[n_x] = p
                                n_x += 1
                        _argsort_small(plb, order, n_x)
                    for k in range(n_explicit + n_x):
                        if collided and mode == MODE_YESNO:
                            break
                        if k < n_explicit:
                            p = k
                            if n_x > 0 and pair_b[p] >= 0 and _gjk_pair(core[pair_a[p]], core[pair_b[p]]):
                                continue  # a GJK pair: in the sorted pass
                        else:
                            p = pflag[order[k - n_explicit]]
                        if pstamp[p] == stamp_now:
                            continue
                        a = pair_a[p]
                        b = pair_b[p]
                        c = pair_cat[p]
                        cut = max(cut0, best[c]) if by_best else cut0
                        if k < n_explicit:
                            lb = _explicit_gap(p, pair_a, pair_b, sphW, ws_lo, ws_hi)
                        else:
                            lb = plb[order[k - n_explicit]]  # the sorted pass's key is this gap
                        if b >= 0 and not lb > 0.0:
                            lb = -math.inf  # overlapping spheres bound nothing
                        if lb > cut:
                            if track:
                                plb[p] = lb
                            continue
                        if ((box_cull or (by_best and b >= 0 and _gjk_pair(core[a], core[b]))) and b >= 0
                                and cut < math.inf and MF[o_obb + 16 * a + 15] != 0.0
                                and MF[o_obb + 16 * b + 15] != 0.0
                                and obb_apart_moving(MF, o_obb + 16 * a, o_Xs + 16 * glink[a], o_obb + 16 * b,
                                                     o_Xs + 16 * glink[b], SF, max(cut, 0.0), eps_par)):
                            continue  # boxes containing both, one grown by the cut-off, apart: d > cut
                        d, err = pair_step(p, a, b, track, H, MF, MI, SF, SI, out9, eps_len, eps_par, gjk_eps,
                                           max_iter, woff, lvl, cut if by_best else math.inf, n_eval,
                                           stamp_now, fns)
                        if err == BOUNDED:
                            err = 0
                            continue
                        if err != 0:
                            break
                        n_eval += 1
                        if d <= level:
                            collided = True
                elif n_st > 0:
                    # ---- moving-static pairs through the BVH, nearest child first.  The exact and min
                    # modes take the GJK elements last (._static_gjk: a seed pair, then every pair not
                    # culled, in increasing key, so the category's best tightens early)
                    n_sm = st_mov.shape[0]
                    for i in range(n_sm):
                        if err != 0 or (collided and mode == MODE_YESNO):
                            break
                        if by_order and core[st_mov[i]] >= 2:
                            continue  # after the others, best first (._static_gjk)
                        a = st_mov[i]
                        sc_a = st_cat[i]
                        ma = mov_idx[a]
                        cx = sphW[a, 0]; cy = sphW[a, 1]; cz = sphW[a, 2]; cr = sphW[a, 3]
                        # yes/no: a sphere or capsule core also gets its segment's W-aligned box
                        # (see _bb_gap), a tighter cull than the bounding sphere for long links
                        v0 = MI[o_vs + a]
                        use_bb = mode == MODE_YESNO and MI[o_vs + a + 1] - v0 <= 2 and core[a] <= 1
                        bx0 = by0 = bz0 = bx1 = by1 = bz1 = br = 0.0
                        if use_bb:
                            if stamp[1 + a] != stamp_now:
                                move_element(a, H, MF, MI, SF)
                                stamp[1 + a] = stamp_now
                            ov = o_vW + 3 * v0
                            bx0 = bx1 = SF[ov]; by0 = by1 = SF[ov + 1]; bz0 = bz1 = SF[ov + 2]
                            if MI[o_vs + a + 1] - v0 == 2:
                                x = SF[ov + 3]; y = SF[ov + 4]; z = SF[ov + 5]
                                bx0 = min(bx0, x); bx1 = max(bx1, x)
                                by0 = min(by0, y); by1 = max(by1, y)
                                bz0 = min(bz0, z); bz1 = max(bz1, z)
                            br = MF[o_rad + a]
                        use_obb = (box_cull or (by_best and core[a] >= 2)) and MF[o_obb + 16 * a + 15] != 0.0
                        o_Xa = o_Xs + 16 * glink[a]
                        stack[0] = 0
                        gapst[0] = _sb_gap(cx, cy, cz, cr, MF, o_blo, o_bhi)
                        if use_bb:
                            gapst[0] = max(gapst[0], _bb_gap(bx0, by0, bz0, bx1, by1, bz1, br, MF, o_blo, o_bhi))
                        top = 1
                        while top > 0:
                            top -= 1
                            node = stack[top]
                            gnode = gapst[top]
                            if by_best:  # the category of this element's static pairs (both when mixed)
                                cut = max(cut0, best[sc_a] if sc_a >= 0 else max(best[1], best[3]))
                            else:
                                cut = cut0
                            if gnode > 0.0 and gnode > cut:  # an overlapping node bounds nothing
                                continue
                            left = bvh_left[node]
                            if left >= 0:
                                right = bvh_right[node]
                                gl = _sb_gap(cx, cy, cz, cr, MF, o_blo + 3 * left, o_bhi + 3 * left)
                                gr = _sb_gap(cx, cy, cz, cr, MF, o_blo + 3 * right, o_bhi + 3 * right)
                                if use_bb:
                                    gl = max(gl, _bb_gap(bx0, by0, bz0, bx1, by1, bz1, br, MF, o_blo + 3 * left,
                                                         o_bhi + 3 * left))
                                    gr = max(gr, _bb_gap(bx0, by0, bz0, bx1, by1, bz1, br, MF, o_blo + 3 * right,
                                                         o_bhi + 3 * right))
                                top = _push_children(stack, gapst, top, left, gl, right, gr)  # the nearer popped first
                                continue
                            for it in range(bvh_start[node], bvh_start[node] + bvh_count[node]):
                                s = bvh_items[it]
                                p = pair_of[ma, s]
                                if p < 0 or pstamp[p] == stamp_now:
                                    continue
                                c = pair_cat[p]
                                cutp = max(cut0, best[c]) if by_best else cut0
                                b = pair_b[p]
                                lb = _sb_gap(cx, cy, cz, cr, MF, o_slo + 3 * s, o_shi + 3 * s)
                                if use_bb:
                                    lb = max(lb, _bb_gap(bx0, by0, bz0, bx1, by1, bz1, br, MF, o_slo + 3 * s,
                                                         o_shi + 3 * s))
                                kb = core[b]  # a box, or a cylinder (its own box in the same slots):
                                if lb > 0.0 and (kb == 2 or kb == 4):  # the sphere-OBB gap is tighter
                                    lb = max(lb, _obb_gap(cx, cy, cz, cr, SF, o_box + 15 * b))
                                if not lb > 0.0:
                                    lb = -math.inf
                                if lb > cutp:
                                    if track:
                                        plb[p] = lb
                                    continue
                                if (use_obb and (kb == 2 or kb == 4) and cutp < math.inf
                                        and obb_apart_static(MF, o_obb + 16 * a, o_Xa, SF, o_box + 15 * b,
                                                             max(cutp, 0.0), eps_par)):
                                    continue  # a's box grown by the cut-off misses the obstacle box: d > cut
                                d, err = pair_step(p, a, b, track, H, MF, MI, SF, SI, out9, eps_len, eps_par, gjk_eps,
                                                   max_iter, woff, lvl, cutp if by_best else math.inf,
                                                   n_eval, stamp_now, fns)
                                if err == BOUNDED:
                                    err = 0
                                    continue
                                if err != 0:
                                    break
                                n_eval += 1
                                if d <= level:
                                    collided = True
                                    if mode == MODE_YESNO:
                                        break
                            if err != 0 or (collided and mode == MODE_YESNO):
                                break
                    has_gjk = False  # (no call, no views, for a model without GJK elements: the Ranger cycle)
                    for i in range(n_sm):
                        has_gjk = has_gjk or core[st_mov[i]] >= 2
                    if by_order and err == 0 and has_gjk:
                        n_eval, err, hit = call_static(fns[FN_STATIC], (H, MF, MI, SF, SI, out9, n_st, cut0, track, eps_len,
                                                                        eps_par, gjk_eps, max_iter, woff, lvl, level, n_eval,
                                                                        stamp_now, fns))
                        collided = collided or hit
        if err != 0:
            summary[SUM_ERR] = err
            return err
        # ---- state for the anytime bounds, and the status
        dmin = math.inf
        for k in range(n_eval):
            d = ev[k, 0]
            if d < dmin:
                dmin = d
            if use_state:
                p = ev_p[k]
                last_d[p] = d
                has_last[p] = 1
                for j in range(n_q):
                    last_q[p, j] = q[0, j]
        lbmin = math.inf
        if mode == MODE_ANYTIME:
            for p in range(P):
                if pflag[p] == 0 and plb[p] < lbmin:
                    lbmin = plb[p]
        summary[SUM_NEVAL] = n_eval
        st = _status_code(dmin, lbmin, level, thr_eff)  # never CLEAR by omission
        summary[SUM_STATUS] = st
        for c in range(4):
            min_d[m, c] = best[c]
        status_out[m] = st
    return 0
