"""One pair evaluation of the detector kernel: move its elements into W, its distance, its record.

The kernel (:mod:`._kernel`) reaches a pair from five places (the all-pairs path, the anytime
order, last check's nearest pairs, the explicit pairs, the BVH leaves); each calls
:func:`pair_step`: :func:`evaluate_pair`, the convex kernels where it leaves the pair, then
:func:`record_pair` (inlined into it, as :func:`move_pair`).  These run per pair, a few to a
few hundred times per check, so they read the packed buffers (:mod:`._layout`) by offset and are compiled
without numba's reference counting (``_nrt=False``, a private option): they allocate nothing and
keep no reference, and with it each call of a function taking arrays costs two atomic
increments and decrements per array argument (~40 ns for :func:`record_pair`, more than the
capsule-capsule distance itself).  So is :func:`pair_step`, which calls both narrow phases at their
addresses (:mod:`._calls`), and so are the narrow phases.  Even with the views' meminfo null, a
function with reference counting calls ``NRT_incref`` / ``NRT_decref`` for each array it takes or
makes: with the pair step, the narrow phases and EPA compiled with it, those calls showed in
``perf`` samples of ur3's ``pair_distances``.  Once, when the kernels linked the convex kernels
instead of calling them at their addresses, compiling them without reference counting made LLVM's
code generator crash from a cold cache (a segfault in ``finalize_object``; numba 0.68); a
cold-cache test (``tests/test_detect_cold.py``) guards against its return.  The fused kernel
(:mod:`._kernel`) keeps reference counting: per check, not per pair, its calls cost nothing
measurable.
"""

from __future__ import annotations

from numba import njit

from armguard.geometry._pair_segment_segment import segment_segment_closest

# The segment numbers K come from ._layout and are compiled in as constants; numba's cache keys on
# this file only, so a change of the segment tuples in ._layout must come with an edit here.
from ._layout import EV_W, K, SUM_BEST, SUM_BSLOT
from ._calls import FN_NARROW_OTHER, FN_NARROW_REL, call_narrow_other, call_narrow_rel
from ._narrow import BOUNDED, LINK_FRAME, NOT_SCALAR, narrow_flat, wall_flat

__all__ = ["capsule_step", "constant_step", "evaluate_pair", "move_element", "move_pair", "pair_step", "pair_step_inline", "record_pair",
           "record_row"]

_K_Xs, _K_glink, _K_vstart, _K_verts_L, _K_vW = K["Xs"], K["glink"], K["vstart"], K["verts_L"], K["vW"]
_K_core, _K_box_L, _K_boxW, _K_pstart, _K_estart = K["core"], K["box_L"], K["boxW"], K["pstart"], K["estart"]
_K_fn_L, _K_ed_L, _K_fnW, _K_edW = K["fn_L"], K["ed_L"], K["fnW"], K["edW"]
_K_ev, _K_out9, _K_ev_p, _K_pstamp, _K_best, _K_summary = K["ev"], K["out9"], K["ev_p"], K["pstamp"], K["best"], K["summary"]
_K_stamp, _K_mov_idx, _K_pflag, _K_pair_cat = K["stamp"], K["mov_idx"], K["pflag"], K["pair_cat"]
_K_radius = K["radius"]
_K_cst, _K_cstv = K["cst"], K["cstv"]


@njit(cache=True, _nrt=False, inline="always")
def record_pair(p, c, d, n_eval, H, SF, SI, stamp_now):  # pragma: no cover - compiled
    """Store pair ``p``'s result (``d`` and the witnesses in ``out9``) in row ``n_eval`` of the compact
    outputs and update its category's best (:func:`record_row`)."""
    o = H[2 * _K_ev] + EV_W * n_eval
    o9 = H[2 * _K_out9]
    SF[o] = d
    for i in range(6):
        SF[o + 1 + i] = SF[o9 + i]
    record_row(p, c, d, n_eval, H, SF, SI, stamp_now)


@njit(cache=True, _nrt=False, inline="always")
def record_row(p, c, d, n_eval, H, SF, SI, stamp_now):  # pragma: no cover - compiled
    """Pair ``p`` is row ``n_eval`` of the compact outputs (its distance ``d`` and witnesses written there):
    its number, its stamp, and its category's best (an equal distance: the lower pair number)."""
    SI[H[2 * _K_ev_p] + n_eval] = p
    SI[H[2 * _K_pstamp] + p] = stamp_now
    ob = H[2 * _K_best] + c
    os = H[2 * _K_summary]
    # a tie goes to the lower pair number: which pair is named nearest does not depend on the order the
    # pairs were evaluated in (last check's nearest pairs first), so not on what was checked before
    if d < SF[ob] or (d == SF[ob] and p < SI[os + SUM_BEST + c]):
        SF[ob] = d
        SI[os + SUM_BEST + c] = p
        SI[os + SUM_BSLOT + c] = n_eval


@njit(cache=True, _nrt=False)
def move_element(g, H, MF, MI, SF):  # pragma: no cover - compiled
    """Move element ``g`` from its link frame to W (core points, box or cylinder pose, face normals, edge
    directions)."""
    oX = H[2 * _K_Xs] + 16 * MI[H[2 * _K_glink] + g]
    r00 = SF[oX]; r01 = SF[oX + 1]; r02 = SF[oX + 2]; tx = SF[oX + 3]
    r10 = SF[oX + 4]; r11 = SF[oX + 5]; r12 = SF[oX + 6]; ty = SF[oX + 7]
    r20 = SF[oX + 8]; r21 = SF[oX + 9]; r22 = SF[oX + 10]; tz = SF[oX + 11]
    ovs = H[2 * _K_vstart]
    oL = H[2 * _K_verts_L]
    oW = H[2 * _K_vW]
    for k in range(MI[ovs + g], MI[ovs + g + 1]):
        i = 3 * k
        x = MF[oL + i]; y = MF[oL + i + 1]; z = MF[oL + i + 2]
        SF[oW + i] = r00 * x + r01 * y + r02 * z + tx
        SF[oW + i + 1] = r10 * x + r11 * y + r12 * z + ty
        SF[oW + i + 2] = r20 * x + r21 * y + r22 * z + tz
    kc = MI[H[2 * _K_core] + g]
    if kc == 2 or kc == 4:  # a box, or a cylinder's [c, r, r, h, R] in the same slots
        b = H[2 * _K_box_L] + 15 * g
        o = H[2 * _K_boxW] + 15 * g
        x = MF[b]; y = MF[b + 1]; z = MF[b + 2]
        SF[o] = r00 * x + r01 * y + r02 * z + tx
        SF[o + 1] = r10 * x + r11 * y + r12 * z + ty
        SF[o + 2] = r20 * x + r21 * y + r22 * z + tz
        SF[o + 3] = MF[b + 3]; SF[o + 4] = MF[b + 4]; SF[o + 5] = MF[b + 5]
        for j in range(3):  # R_WB = R_WL R_LB, row-major
            a0 = MF[b + 6 + j]; a1 = MF[b + 9 + j]; a2 = MF[b + 12 + j]
            SF[o + 6 + j] = r00 * a0 + r01 * a1 + r02 * a2
            SF[o + 9 + j] = r10 * a0 + r11 * a1 + r12 * a2
            SF[o + 12 + j] = r20 * a0 + r21 * a1 + r22 * a2
    for kk in range(2):  # face normals, then edge directions: rotated only
        os_ = H[2 * _K_pstart] if kk == 0 else H[2 * _K_estart]
        oL = H[2 * _K_fn_L] if kk == 0 else H[2 * _K_ed_L]
        oW = H[2 * _K_fnW] if kk == 0 else H[2 * _K_edW]
        for k in range(MI[os_ + g], MI[os_ + g + 1]):
            i = 3 * k
            x = MF[oL + i]; y = MF[oL + i + 1]; z = MF[oL + i + 2]
            SF[oW + i] = r00 * x + r01 * y + r02 * z
            SF[oW + i + 1] = r10 * x + r11 * y + r12 * z
            SF[oW + i + 2] = r20 * x + r21 * y + r22 * z


@njit(cache=True, _nrt=False, inline="always")
def evaluate_pair(a, b, H, MF, MI, SF, SI, out9, eps_len, eps_par, offset, stamp_now):  # pragma: no cover - compiled
    """Signed distance of pair ``(a, b)`` (``b < 0``: the workspace walls), witnesses in ``out9``.

    Moves ``a`` (and ``b`` when it is a link element) into W first unless this check already did
    (``stamp[1 + g] == stamp_now``), except for two polytope cores: those return ``(0, LINK_FRAME)``
    unmoved (the caller calls :func:`._narrow.narrow_rel`).  Returns ``(distance, 0)``, or ``(0, NOT_SCALAR)`` for a pair
    that is neither workspace walls, capsule-capsule nor capsule-box (a cylinder side among
    them): the caller then calls
    :func:`._narrow.narrow_other` (not called from here: linking the convex kernels into a
    function compiled with ``_nrt=False`` makes LLVM crash as described above).  A point or segment
    against a static polytope returns so before :func:`._narrow.narrow_flat`, which has no case for it:
    ranger's 60 capsule-hull pairs took 159-172 ns a pair in the all-pairs call, against 167-181 through
    ``narrow_flat`` (``pair_distances(q)`` less ``pair_distances(q, pairs=<the other rows>)``, thread-time
    medians over 200 random configurations, over the pairs left out; this file and its parent run in turn, 3
    rounds; the same bits)."""
    if b >= 0:
        oc = H[2 * _K_core]
        ka = MI[oc + a]
        kb = MI[oc + b]
        if (((ka == 2 or ka == 3) and (kb == 2 or kb == 3)) or (ka == 4 and kb == 3) or (ka == 3 and kb == 4)
                or (ka == 3 and kb <= 1) or (ka <= 1 and kb == 3 and MI[H[2 * _K_mov_idx] + b] >= 0)):
            # polytope cores, a cylinder and a polytope, a point or segment and a moving polytope (one
            # against a static polytope has the capsule-polytope kernel): narrow_rel, in their own frames
            return 0.0, LINK_FRAME
        if ka <= 1 and kb == 3:  # a point or segment and a static polytope: narrow_other's capsule-polytope kernel
            move_pair(a, b, H, MF, MI, SF, SI, stamp_now)
            return 0.0, NOT_SCALAR
    move_pair(a, b, H, MF, MI, SF, SI, stamp_now)
    if b < 0:
        return wall_flat(a, H, MF, MI, SF), 0
    return narrow_flat(a, b, H, MF, MI, SF, out9, eps_len, eps_par, offset)


@njit(cache=True, _nrt=False, inline="always")
def move_pair(a, b, H, MF, MI, SF, SI, stamp_now):  # pragma: no cover - compiled
    """Move ``a`` and (a link element) ``b`` into W unless this check already did (``stamp[1 + g]``)."""
    ost = H[2 * _K_stamp] + 1
    if SI[ost + a] != stamp_now:
        move_element(a, H, MF, MI, SF)
        SI[ost + a] = stamp_now
    if b >= 0 and MI[H[2 * _K_mov_idx] + b] >= 0 and SI[ost + b] != stamp_now:
        move_element(b, H, MF, MI, SF)
        SI[ost + b] = stamp_now


@njit(cache=True, _nrt=False)
def pair_step(p, a, b, flag, H, MF, MI, SF, SI, out9, eps_len, eps_par, gjk_eps, max_iter, offset, level, beyond, n_eval,
              stamp_now, fns):  # pragma: no cover - compiled
    """One pair of the kernel: :func:`evaluate_pair`, :func:`._narrow.narrow_other` for the pairs it
    leaves, then (no error) :func:`record_pair` as row ``n_eval`` and, when ``flag``, the pair's
    report flag 1 (evaluated).  ``level`` as in ``narrow_other``.  Returns ``(distance, error)``.

    ``beyond`` (m; ``inf``: off): the caller's cut-off (the exact and min modes: a category's best so
    far, or the threshold).  A pair checked in its link frames (:func:`._narrow.narrow_rel`) whose GJK
    proves it farther than that (or whose EPA proves its depth too shallow to reach it) stops there
    and returns ``(bound, BOUNDED)`` without a row:
    like a pair its bounding volumes cull, it can be neither its category's nearest nor within the
    threshold, and its bound is kept nowhere (the anytime state would read it as a distance).

    ``fns``: the kernels' addresses (:func:`._calls.addresses`): both narrow phases are called at
    theirs (:mod:`._native`); :func:`evaluate_pair`, :func:`move_pair` and :func:`record_pair` are
    inlined (numba's ``inline="always"``: as linked calls each passed its five to seven arrays as
    seven fields apiece, ~60 arguments a call, three calls a pair; the kernel's time per model:
    ``python -m bench backends``, *bare kernel call*), :func:`._narrow.narrow_flat` is linked, and the fused kernel links this
    function.  Compiled without reference counting (see the module docstring): it links
    nothing that has it."""
    d, err = evaluate_pair(a, b, H, MF, MI, SF, SI, out9, eps_len, eps_par, offset, stamp_now)
    if err == LINK_FRAME:
        d, err = call_narrow_rel(fns[FN_NARROW_REL], (a, b, H, MF, MI, SF, out9, eps_len, eps_par, gjk_eps, max_iter, offset,
                                                      level, beyond, fns, p))
        if err == BOUNDED or (err == 0 and d > beyond):
            return d, BOUNDED  # proved beyond the caller's cut-off: not a row of this check
        if err < 0:  # overlapping cores with a depth wanted (or GJK unsettled): EPA / SAT on W points
            move_pair(a, b, H, MF, MI, SF, SI, stamp_now)
    if err < 0:
        d, err = call_narrow_other(fns[FN_NARROW_OTHER], (a, b, H, MF, MI, SF, out9, eps_len, eps_par, gjk_eps, max_iter,
                                                          offset, level, fns))
    if err == 0:
        if flag:
            SI[H[2 * _K_pflag] + p] = 1
        record_pair(p, MI[H[2 * _K_pair_cat] + p], d, n_eval, H, SF, SI, stamp_now)
    return d, err


@njit(cache=True, _nrt=False, inline="always")
def capsule_step(p, a, b, H, MF, MI, SF, SI, eps_len, eps_par, n_eval, stamp_now) -> bool:  # pragma: no cover
    """The all-pairs loop's capsule-capsule pair (points and segments, each swept by its radius): its
    row straight into ``ev`` row ``n_eval``, as :func:`pair_step` would write it, with no call.  False,
    nothing written, for any other pair and where the cores meet (then :func:`pair_step` gives the
    depth's direction).  ``capsule_capsule_scalar``'s closed form (Ericson §5.1.9,
    ``segment_segment_closest``) and its operations, so the same bits; inlined, it leaves out the
    linked narrow-phase call, its dispatch on the cores' kinds and the copy through ``out9``: on
    ranger's 94 capsule pairs, 62 ns a pair in the all-pairs call before, 52-56 after (``pair_distances(q)``
    less ``pair_distances(q, pairs=<the other rows>)``, thread-time medians over 200 random configurations,
    over the pairs left out; this file and its parent run in turn, 3 rounds).
    Their clamps as selects, every candidate
    computed, took as long (54-55 ns): not kept."""
    oc = H[2 * _K_core]
    if b < 0 or MI[oc + a] > 1 or MI[oc + b] > 1:  # CoreKind: 0 a point, 1 a segment
        return False
    move_pair(a, b, H, MF, MI, SF, SI, stamp_now)
    ovs = H[2 * _K_vstart]
    ov = H[2 * _K_vW]
    va = MI[ovs + a]
    a0 = ov + 3 * va
    a1 = a0 if MI[ovs + a + 1] - va == 1 else a0 + 3
    vb = MI[ovs + b]
    b0 = ov + 3 * vb
    b1 = b0 if MI[ovs + b + 1] - vb == 1 else b0 + 3
    ax, ay, az, bx, by, bz, vx, vy, vz, dcore = segment_segment_closest(
        SF[a0], SF[a0 + 1], SF[a0 + 2], SF[a1], SF[a1 + 1], SF[a1 + 2], SF[b0], SF[b0 + 1], SF[b0 + 2], SF[b1], SF[b1 + 1],
        SF[b1 + 2], eps_len, eps_par)
    if not dcore > eps_len:
        return False
    orad = H[2 * _K_radius]
    ra = MF[orad + a]
    rb = MF[orad + b]
    nx = vx / dcore
    ny = vy / dcore
    nz = vz / dcore
    o = H[2 * _K_ev] + EV_W * n_eval  # as write_rounded's first six values
    d = dcore - ra - rb
    SF[o] = d
    SF[o + 1] = ax + ra * nx
    SF[o + 2] = ay + ra * ny
    SF[o + 3] = az + ra * nz
    SF[o + 4] = bx - rb * nx
    SF[o + 5] = by - rb * ny
    SF[o + 6] = bz - rb * nz
    record_row(p, MI[H[2 * _K_pair_cat] + p], d, n_eval, H, SF, SI, stamp_now)
    return True


@njit(cache=True, _nrt=False, inline="always")
def constant_step(p, H, MF, MI, SF, SI, n_eval, stamp_now) -> bool:  # pragma: no cover - compiled
    """The all-pairs loop's pair ``p`` when its relative pose never changes (``._constant``): its row,
    computed by this kernel once per build, copied into ``ev`` row ``n_eval`` (a pair fixed in W: the same
    bits :func:`pair_step` would write; a rigid pair: its witness points, kept in link A's frame, moved
    by that link's pose ``Xs``) and recorded as :func:`record_row`.  False, nothing written, for any
    other pair.  ``"cstv"`` rows: ``[frame, d, p_A (3), p_B (3)]`` (``._constant.CST_W``)."""
    oc = H[2 * _K_cst]
    if p >= H[2 * _K_cst + 1] or MI[oc + p] < 0:
        return False
    s = H[2 * _K_cstv] + 8 * MI[oc + p]
    o = H[2 * _K_ev] + EV_W * n_eval
    link = int(MF[s])
    SF[o] = MF[s + 1]
    if link < 0:
        for i in range(6):
            SF[o + 1 + i] = MF[s + 2 + i]
    else:
        oX = H[2 * _K_Xs] + 16 * link
        for k in range(2):
            x = MF[s + 2 + 3 * k]
            y = MF[s + 3 + 3 * k]
            z = MF[s + 4 + 3 * k]
            for i in range(3):
                SF[o + 1 + 3 * k + i] = SF[oX + 4 * i] * x + SF[oX + 4 * i + 1] * y + SF[oX + 4 * i + 2] * z + SF[oX + 4 * i + 3]
    record_row(p, MI[H[2 * _K_pair_cat] + p], SF[o], n_eval, H, SF, SI, stamp_now)
    return True


pair_step_inline = njit(cache=True, _nrt=False, inline="always")(pair_step.py_func)
"""The same body inlined at its call site: the all-pairs loop (``pair_distances``), where the linked
call passed ~65 arguments (seven arrays of seven fields each) for every pair.  Built from the body's own Python function (as ``_pair_gjk._gjk``), so one source serves both; the
kernel's other call sites keep the linked call (five inlined copies would lengthen its cold
compile)."""
