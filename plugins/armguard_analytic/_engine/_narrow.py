"""Narrow phase of the detector: one element pair's signed distance, dispatched on core kinds.

No distance formula lives here: each branch calls the geometry core's per-pair kernel
(:mod:`armguard.geometry`): capsule-capsule (Ranger §3 link-link and link-edge), capsule-box,
sphere-cylinder (closed form), capsule against a static polytope (GJK + Minkowski facets), GJK and
EPA on support functions for any other pair with a cylinder side
(:func:`armguard.geometry._pair_cylinder.support_pair_graph`), and the exact convex-convex kernel
for every other pair (faces, polyhedra, mesh hulls: GJK climbing the hulls' vertex graphs, EPA for
the depth, the exhaustive SAT as fallback).  The only formula of its own is the distance to the
workspace walls (Ranger §2), which is not a shape pair (for a cylinder: its exact support along
each wall's normal).  Pairs of convex point cores (boxes, hulls, a point or segment against a moving
polytope) and a cylinder against a polytope are checked in their element frames (:func:`narrow_rel`:
GJK and EPA on ``hull(A)`` and ``X_AB hull(B)``, no point moved; two boxes' depth by the SAT there),
unless EPA cannot settle a depth; every other pair reads element data in W (moved there once per
check, ``_step``): ``verts (V, 3)`` core points; ``box (G, 15)`` ``[centre, half extents, R_WB
row-major]`` (a cylinder: ``[c, r, r, h, R_WC row-major]``, the axis the third column; its core
points are its circumscribed prism's corners, for bounds only); ``fnrm (F, 3)`` face normals;
``edir (E, 3)`` unit edge directions; ``*_start`` CSR offsets.
"""

from __future__ import annotations

import math

from numba import njit

from armguard.geometry._pair_segment_box import capsule_box_scalar
from armguard.geometry._pair_segment_polytope import capsule_polytope_at
from armguard.geometry._pair_point_cylinder import point_cylinder_flat
from armguard.geometry._pair_segment_segment import capsule_capsule_scalar, write_rounded
from armguard.geometry._pair_epa import EPA_WORK_SIZE
from armguard.geometry._pair_gjk import GJK_SEPARATED, _inner_point
from armguard.geometry._pair_sat_rel import sat_cost, sat_depth_rel, sat_witnesses_rel
from armguard.geometry.kernels import GJK_NOT_CONVERGED, capsule_box, capsule_capsule

# The segment numbers K come from ._layout and are compiled in as constants; numba's cache keys on
# this file only, so a change of the segment tuples in ._layout must come with an edit here.
from ._calls import (FN_CONVEX, FN_EPA, FN_GJK_REL, FN_SAT_REL, FN_SUPPORT, call_convex, call_epa, call_gjk_rel,
                     call_sat_rel, call_support)
from ._layout import K, iview1, seg1, seg2, view1

__all__ = ["pair_distance", "narrow_flat", "narrow_other", "narrow_rel", "wall_flat", "ERR_GJK", "NOT_SCALAR",
           "LINK_FRAME", "BOUNDED", "WORK_TAIL"]

_K_core, _K_vstart, _K_radius, _K_vW, _K_boxW = K["core"], K["vstart"], K["radius"], K["vW"], K["boxW"]
_K_poly_of, _K_seg, _K_pv, _K_ppl, _K_ped = K["poly_of"], K["seg"], K["pv"], K["ppl"], K["ped"]
_K_pbis, _K_pcen, _K_pvs, _K_pps, _K_pes = K["pbis"], K["pcen"], K["pvs"], K["pps"], K["pes"]
_K_fnW, _K_pstart, _K_edW, _K_estart, _K_work = K["fnW"], K["pstart"], K["edW"], K["estart"], K["work"]
_K_ws, _K_out9 = K["ws"], K["out9"]
_K_gadj, _K_gadjs, _K_gtri, _K_gtris = K["gadj"], K["gadjs"], K["gtri"], K["gtris"]
_K_box_L = K["box_L"]
_K_verts_L, _K_Xs, _K_glink, _K_gdir, _K_gdirs = K["verts_L"], K["Xs"], K["glink"], K["gdir"], K["gdirs"]
_K_fn_L, _K_ed_L = K["fn_L"], K["ed_L"]
_K_spair, _K_sgrid, _K_sdt, _K_fk_q = K["spair"], K["sgrid"], K["sdt"], K["fk_q"]
_K_lseed, _K_coh = K["lseed"], K["coh"]

ERR_GJK = 2  # the convex kernel did not converge: the caller raises, never a verdict
NOT_SCALAR = -1  # narrow_flat: not a capsule-capsule / capsule-box pair, call narrow_other
LINK_FRAME = -2  # polytope cores (boxes, hulls), or one and a cylinder: narrow_rel in their own frames, none moved
BOUNDED = -3  # _step.pair_step: the pair is proved beyond the caller's cut-off (no row)
WORK_TAIL = 24  # the last floats of the "work" scratch: narrow_rel's X_AB and a cylinder's buffer in a hull's frame
SAT_REL_BUDGET = 400
"""Dot products (:func:`armguard.geometry._pair_sat_rel.sat_cost`) up to which :func:`narrow_rel` takes a
penetration depth from the SAT in the link frames rather than from EPA (both cores without a vertex
graph, so with their face normals and edge directions); above it EPA when the scratch has room for
it, else the SAT all the same (the W path would run the same SAT on moved points).  Measured on
overlapping pairs in random poses (medians of 20 poses, the depth's witnesses included): box-box
(cost 240) SAT 0.8 us, EPA 2.7 us; box-octagonal prism (552) 1.1 vs 0.8 us; octagonal-16-gonal
prisms (2,832) 5.0 vs 2.8 us; 20-point hulls (22,560) 31 vs 1.2 us."""

_POINT, _SEGMENT, _BOX, _CYLINDER = 0, 1, 2, 4  # armguard.geometry.CoreKind


@njit(cache=True, inline="always")
def _capsule_box(verts, vs, ve, ra, box, gb, out, eps_len, eps_par, offset):  # pragma: no cover
    j = vs if ve - vs == 1 else vs + 1  # a point core is a zero-length segment
    b = box[gb]
    return capsule_box(verts[vs], verts[j], ra, b[0:3], b[3:6], b[6:15].reshape((3, 3)), out, eps_len, eps_par, offset)


@njit(cache=True, _nrt=False)
def pair_distance(
    ga, gb, core, radius, verts, vstart, box, fnrm, fstart, edir, estart, adj, adjs, tri, tris, out, work,
    eps_len, eps_par, gjk_eps, max_iter, offset, level, fns,
):  # pragma: no cover - compiled
    """Signed distance (m) of elements ``ga`` (A) and ``gb`` (B); writes ``out[0:9]`` =
    ``[p_WA, p_WB, nhat_AB_W]``.  Returns ``(distance, error)``; ``error`` is 0 or ``ERR_GJK``.

    Pairs other than capsule-capsule and capsule-box go to the convex kernel
    (:func:`armguard.geometry._pair_epa.convex_convex_fast`: GJK climbing the vertex graphs
    ``adj[adjs[g]:adjs[g + 1]]``, EPA depth, the exhaustive SAT where EPA does not settle it,
    with axes from the face normals and edge directions, or from the triangles
    ``tri[tris[g]:tris[g + 1]]`` and the graph of an element that has them instead);
    A pair with a cylinder side goes to :func:`armguard.geometry._pair_cylinder.support_pair_graph`
    (GJK and EPA on support functions; the cylinder's core is ``box[g]``, the other side's its
    points, climbed over its vertex graph when it has one, and radius).  ``level`` as in :func:`narrow_other`; ``work`` has ``EPA_WORK_SIZE`` floats
    (``SUPPORT_WORK_SIZE`` for the cylinder kernel, fewer)."""
    ka = core[ga]
    kb = core[gb]
    ra = radius[ga]
    rb = radius[gb]
    if ka <= _SEGMENT and kb <= _SEGMENT:
        va = vstart[ga]
        vb = vstart[gb]
        ja = va if vstart[ga + 1] - va == 1 else va + 1
        jb = vb if vstart[gb + 1] - vb == 1 else vb + 1
        return capsule_capsule(verts[va], verts[ja], ra, verts[vb], verts[jb], rb, out, eps_len, eps_par), 0
    if ka <= _SEGMENT and kb == _BOX:
        return _capsule_box(verts, vstart[ga], vstart[ga + 1], ra, box, gb, out, eps_len, eps_par, offset), 0
    if ka == _BOX and kb <= _SEGMENT:
        d = _capsule_box(verts, vstart[gb], vstart[gb + 1], rb, box, ga, out, eps_len, eps_par, offset)
        return _swapped(out, d), 0
    if ka == _CYLINDER or kb == _CYLINDER:
        ca = box[ga] if ka == _CYLINDER else box[ga, 0:0]  # an empty buffer: the hull of the points
        cb = box[gb] if kb == _CYLINDER else box[gb, 0:0]
        none = adj[0:0]  # no support tables on this path (one compiled signature with narrow_rel's calls)
        d, status = call_support(fns[FN_SUPPORT], (verts[vstart[ga]:vstart[ga + 1]], adj[adjs[ga]:adjs[ga + 1]], ca, ra,
                                                   verts[vstart[gb]:vstart[gb + 1]], adj[adjs[gb]:adjs[gb + 1]], cb, rb,
                                                   out, work, eps_len, gjk_eps, max_iter, level, none, none))
        if status == GJK_NOT_CONVERGED:
            return d, ERR_GJK
        return d, 0
    d, status = call_convex(fns[FN_CONVEX], (
        verts[vstart[ga]:vstart[ga + 1]], fnrm[fstart[ga]:fstart[ga + 1]], edir[estart[ga]:estart[ga + 1]],
        adj[adjs[ga]:adjs[ga + 1]], tri[tris[ga]:tris[ga + 1]], ra,
        verts[vstart[gb]:vstart[gb + 1]], fnrm[fstart[gb]:fstart[gb + 1]], edir[estart[gb]:estart[gb + 1]],
        adj[adjs[gb]:adjs[gb + 1]], tri[tris[gb]:tris[gb + 1]], rb,
        out, work, eps_len, eps_par, gjk_eps, max_iter, offset, level,
    ))
    if status == 2:
        return d, ERR_GJK
    return d, 0


@njit(cache=True, _nrt=False)
def _capsule_polytope(seg, ra, k, pv, ppl, ped, pbis, pcen, pvs, pps, pes, rb, out, eps_len, eps_par, gjk_eps, max_iter,
                      offset):  # pragma: no cover - compiled
    """Capsule (core ``seg (2, 3)``, radius ``ra``) against static polytope number ``k`` of the packed
    polytope data (``_pack.polytope_data`` of each static polytope, concatenated; ``p*s`` CSR offsets)."""
    return capsule_polytope_at(seg, ra, pv[pvs[k]:pvs[k + 1]], ppl[pps[k]:pps[k + 1]], ped[pes[k]:pes[k + 1]],
                               pbis[pes[k]:pes[k + 1]], pcen[k], rb, out, 0, eps_len, eps_par, gjk_eps, max_iter, offset)


@njit(cache=True, inline="always")
def _swapped(out, d):  # pragma: no cover - compiled
    """``d``, with ``out``'s witnesses swapped and its normal negated (a kernel ran with B as A)."""
    for i in range(3):
        t = out[i]
        out[i] = out[3 + i]
        out[3 + i] = t
        out[6 + i] = -out[6 + i]
    return d


@njit(cache=True, _nrt=False)
def narrow_flat(ga, gb, H, MF, MI, SF, out, eps_len, eps_par, offset):  # pragma: no cover
    """:func:`pair_distance` on the detector's packed buffers (:mod:`._layout`), same outputs and errors.

    The common pairs read their cores straight from the flat buffers into registers and call the
    geometry core's scalar entry points (capsule-capsule, capsule-box, sphere-cylinder: ~30 ns per
    pair, against ~200 ns when a dozen array views are passed around).  Returns ``(distance,
    error)``, or ``(0, NOT_SCALAR)`` for any other pair: the caller then calls :func:`narrow_other`
    (kept apart so that this function creates no array view: views cost reference counting)."""
    oc, ovs, orad, ov, obox = H[2 * _K_core], H[2 * _K_vstart], H[2 * _K_radius], H[2 * _K_vW], H[2 * _K_boxW]
    ka, kb = MI[oc + ga], MI[oc + gb]
    if ka <= _SEGMENT:
        va = MI[ovs + ga]
        ja = va if MI[ovs + ga + 1] - va == 1 else va + 1
        a0 = ov + 3 * va
        a1 = ov + 3 * ja
        if kb <= _SEGMENT:
            vb = MI[ovs + gb]
            jb = vb if MI[ovs + gb + 1] - vb == 1 else vb + 1
            b0 = ov + 3 * vb
            b1 = ov + 3 * jb
            return capsule_capsule_scalar(
                SF[a0], SF[a0 + 1], SF[a0 + 2], SF[a1], SF[a1 + 1], SF[a1 + 2], MF[orad + ga],
                SF[b0], SF[b0 + 1], SF[b0 + 2], SF[b1], SF[b1 + 1], SF[b1 + 2], MF[orad + gb],
                out, 0, eps_len, eps_par), 0
        if kb == _CYLINDER and ja == va:  # a sphere and a cylinder: closed form
            return point_cylinder_flat(SF[a0], SF[a0 + 1], SF[a0 + 2], MF[orad + ga], SF, obox + 15 * gb, MF[orad + gb],
                                       out, 0), 0
        if kb == _BOX:
            o = obox + 15 * gb
            return capsule_box_scalar(
                SF[a0], SF[a0 + 1], SF[a0 + 2], SF[a1], SF[a1 + 1], SF[a1 + 2], MF[orad + ga],
                SF[o], SF[o + 1], SF[o + 2], SF[o + 3], SF[o + 4], SF[o + 5], SF[o + 6], SF[o + 7], SF[o + 8],
                SF[o + 9], SF[o + 10], SF[o + 11], SF[o + 12], SF[o + 13], SF[o + 14],
                out, 0, eps_len, eps_par, offset), 0
    elif ka == _CYLINDER and kb <= _SEGMENT and MI[ovs + gb + 1] - MI[ovs + gb] == 1:  # a cylinder and a sphere
        b0 = ov + 3 * MI[ovs + gb]
        d = point_cylinder_flat(SF[b0], SF[b0 + 1], SF[b0 + 2], MF[orad + gb], SF, obox + 15 * ga, MF[orad + ga], out, 0)
        return _swapped(out, d), 0
    elif ka == _BOX and kb <= _SEGMENT:
        vb = MI[ovs + gb]
        jb = vb if MI[ovs + gb + 1] - vb == 1 else vb + 1
        b0 = ov + 3 * vb
        b1 = ov + 3 * jb
        o = obox + 15 * ga
        d = capsule_box_scalar(
            SF[b0], SF[b0 + 1], SF[b0 + 2], SF[b1], SF[b1 + 1], SF[b1 + 2], MF[orad + gb],
            SF[o], SF[o + 1], SF[o + 2], SF[o + 3], SF[o + 4], SF[o + 5], SF[o + 6], SF[o + 7], SF[o + 8],
            SF[o + 9], SF[o + 10], SF[o + 11], SF[o + 12], SF[o + 13], SF[o + 14],
            out, 0, eps_len, eps_par, offset)
        return _swapped(out, d), 0
    return 0.0, NOT_SCALAR


@njit(cache=True, _nrt=False)
def narrow_other(ga, gb, H, MF, MI, SF, out, eps_len, eps_par, gjk_eps, max_iter, offset, level, fns):  # pragma: no cover
    """The pairs :func:`narrow_flat` leaves (``NOT_SCALAR``): capsule against a static polytope through
    the capsule-polytope kernel, everything else through :func:`pair_distance`.

    ``level``: the caller only needs to know whether the distance is <= ``level`` (the yes/no
    mode's collision level; ``-inf`` when the distance itself is reported), so for a pair within
    it any value <= ``level`` may be returned (an intersection verdict without a depth), and for a
    pair proved beyond it any value > ``level`` (convex_convex_fast's GJK stops at that proof)."""
    oc = H[2 * _K_core]
    k = MI[H[2 * _K_poly_of] + gb]
    if MI[oc + ga] <= _SEGMENT and k >= 0:
        ovs = H[2 * _K_vstart]
        orad = H[2 * _K_radius]
        ov = H[2 * _K_vW]
        va = MI[ovs + ga]
        ja = va if MI[ovs + ga + 1] - va == 1 else va + 1
        seg = seg2(SF, H, _K_seg, 3)
        for i in range(3):
            seg[0, i] = SF[ov + 3 * va + i]
            seg[1, i] = SF[ov + 3 * ja + i]
        d, status = _capsule_polytope(
            seg, MF[orad + ga], k, seg2(MF, H, _K_pv, 3), seg2(MF, H, _K_ppl, 4), seg2(MI, H, _K_ped, 4),
            seg2(MF, H, _K_pbis, 3), seg2(MF, H, _K_pcen, 3), seg1(MI, H, _K_pvs), seg1(MI, H, _K_pps),
            seg1(MI, H, _K_pes), MF[orad + gb], out, eps_len, eps_par, gjk_eps, max_iter, offset)
        if status == GJK_NOT_CONVERGED:
            return d, ERR_GJK
        return d, 0
    return pair_distance(ga, gb, seg1(MI, H, _K_core), seg1(MF, H, _K_radius), seg2(SF, H, _K_vW, 3),
                         seg1(MI, H, _K_vstart), seg2(SF, H, _K_boxW, 15), seg2(SF, H, _K_fnW, 3), seg1(MI, H, _K_pstart),
                         seg2(SF, H, _K_edW, 3), seg1(MI, H, _K_estart), seg1(MI, H, _K_gadj), seg1(MI, H, _K_gadjs),
                         seg2(MI, H, _K_gtri, 3), seg1(MI, H, _K_gtris), out, seg1(SF, H, _K_work),
                         eps_len, eps_par, gjk_eps, max_iter, offset, level, fns)


@njit(cache=True, inline="always")
def _pose(SF, H, MI, g):  # pragma: no cover - compiled
    """Offset of element ``g``'s link pose ``X_WL`` in the scratch (``Xs``), or -1 for a static element
    (its frame is W)."""
    link = MI[H[2 * _K_glink] + g]
    return H[2 * _K_Xs] + 16 * link if link >= 0 else -1


@njit(cache=True, inline="always")
def _rt(SF, o, i, j):  # pragma: no cover - compiled
    """Entry ``(i, j)`` of the 4 x 4 pose at offset ``o`` (-1: the identity)."""
    if o < 0:
        return 1.0 if i == j else 0.0
    return SF[o + 4 * i + j]


@njit(cache=True, inline="always")
def _relative(SF, oA, oB, rot):  # pragma: no cover - compiled
    """``X_AB = X_WA^-1 X_WB`` of the poses at offsets ``oA``, ``oB`` (-1: W): ``R_AB`` row-major into
    ``rot[0:9]``, returns ``t_AB``."""
    for i in range(3):
        for j in range(3):
            rot[3 * i + j] = (_rt(SF, oA, 0, i) * _rt(SF, oB, 0, j) + _rt(SF, oA, 1, i) * _rt(SF, oB, 1, j)
                              + _rt(SF, oA, 2, i) * _rt(SF, oB, 2, j))
    dx = _rt(SF, oB, 0, 3) - _rt(SF, oA, 0, 3)
    dy = _rt(SF, oB, 1, 3) - _rt(SF, oA, 1, 3)
    dz = _rt(SF, oB, 2, 3) - _rt(SF, oA, 2, 3)
    return (_rt(SF, oA, 0, 0) * dx + _rt(SF, oA, 1, 0) * dy + _rt(SF, oA, 2, 0) * dz,
            _rt(SF, oA, 0, 1) * dx + _rt(SF, oA, 1, 1) * dy + _rt(SF, oA, 2, 1) * dz,
            _rt(SF, oA, 0, 2) * dx + _rt(SF, oA, 1, 2) * dy + _rt(SF, oA, 2, 2) * dz)


@njit(cache=True, inline="always")
def _to_world(SF, o, x, y, z, w):  # pragma: no cover - compiled
    """``R_WF p + w t_WF`` for the pose at offset ``o`` (-1: W): a point (``w = 1``) or a direction (0)."""
    return (_rt(SF, o, 0, 0) * x + _rt(SF, o, 0, 1) * y + _rt(SF, o, 0, 2) * z + w * _rt(SF, o, 0, 3),
            _rt(SF, o, 1, 0) * x + _rt(SF, o, 1, 1) * y + _rt(SF, o, 1, 2) * z + w * _rt(SF, o, 1, 3),
            _rt(SF, o, 2, 0) * x + _rt(SF, o, 2, 1) * y + _rt(SF, o, 2, 2) * z + w * _rt(SF, o, 2, 3))


@njit(cache=True, _nrt=False)
def _cylinder_rel(ga, gb, H, MF, MI, SF, out, eps_len, gjk_eps, max_iter, level, fns):  # pragma: no cover - compiled
    """:func:`narrow_rel` for a cylinder against a polytope core: the cylinder's 15-float buffer is
    mapped into the polytope's element frame F (``X_FC = X_WF^-1 X_WL X_LC``), GJK and EPA on support
    functions run there (:func:`armguard.geometry._pair_cylinder.support_pair_graph`, the polytope's
    points as stored, its first climb from its support table), and ``out`` is mapped back to W.  Same outputs and errors as :func:`pair_distance`."""
    cyl_a = MI[H[2 * _K_core] + ga] == _CYLINDER
    h = gb if cyl_a else ga
    c = ga if cyl_a else gb
    ovs = H[2 * _K_vstart]
    ogs = H[2 * _K_gadjs]
    vL = seg2(MF, H, _K_verts_L, 3)
    gadj = seg1(MI, H, _K_gadj)
    work = seg1(SF, H, _K_work)
    nw = work.shape[0] - WORK_TAIL
    rot = work[nw:nw + 9]
    cyl = work[nw + 9:nw + 24]
    oF = _pose(SF, H, MI, h)
    tx, ty, tz = _relative(SF, oF, _pose(SF, H, MI, c), rot)  # X_FL of the cylinder's link
    b = H[2 * _K_box_L] + 15 * c  # [c_L, r, r, h, R_LC row-major]
    x = MF[b]
    y = MF[b + 1]
    z = MF[b + 2]
    cyl[0] = rot[0] * x + rot[1] * y + rot[2] * z + tx
    cyl[1] = rot[3] * x + rot[4] * y + rot[5] * z + ty
    cyl[2] = rot[6] * x + rot[7] * y + rot[8] * z + tz
    for k in range(3):
        cyl[3 + k] = MF[b + 3 + k]
    for j in range(3):  # R_FC = R_FL R_LC, row-major
        a0 = MF[b + 6 + j]
        a1 = MF[b + 9 + j]
        a2 = MF[b + 12 + j]
        cyl[6 + j] = rot[0] * a0 + rot[1] * a1 + rot[2] * a2
        cyl[9 + j] = rot[3] * a0 + rot[4] * a1 + rot[5] * a2
        cyl[12 + j] = rot[6] * a0 + rot[7] * a1 + rot[8] * a2
    ph = vL[MI[ovs + h]:MI[ovs + h + 1]]
    pc = vL[MI[ovs + c]:MI[ovs + c + 1]]  # the cylinder's own points: not read (its buffer is its core)
    gh = gadj[MI[ogs + h]:MI[ogs + h + 1]]
    gc = gadj[0:0]
    ots = H[2 * _K_gdirs]
    th = seg1(MI, H, _K_gdir)[MI[ots + h]:MI[ots + h + 1]]
    none = cyl[0:0]
    ra = MF[H[2 * _K_radius] + ga]
    rb = MF[H[2 * _K_radius] + gb]
    if cyl_a:
        d, status = call_support(fns[FN_SUPPORT], (pc, gc, cyl, ra, ph, gh, none, rb, out, work[0:nw], eps_len, gjk_eps,
                                                   max_iter, level, th[0:0], th))
    else:
        d, status = call_support(fns[FN_SUPPORT], (ph, gh, none, ra, pc, gc, cyl, rb, out, work[0:nw], eps_len, gjk_eps,
                                                   max_iter, level, th, th[0:0]))
    if status == GJK_NOT_CONVERGED:
        return d, ERR_GJK
    out[0], out[1], out[2] = _to_world(SF, oF, out[0], out[1], out[2], 1.0)
    out[3], out[4], out[5] = _to_world(SF, oF, out[3], out[4], out[5], 1.0)
    out[6], out[7], out[8] = _to_world(SF, oF, out[6], out[7], out[8], 0.0)
    return d, 0


@njit(cache=True)
def _sat_rel(pa, fa, ea, adja, taba, ra, pb, fb, eb, adjb, tabb, rb, rot, tx, ty, tz, SF, oA, out, simp, eps_len, eps_par,
             gjk_eps, max_iter, offset, cap):  # pragma: no cover - compiled
    """:func:`narrow_rel`'s depth for overlapping cores by the exhaustive SAT in A's frame
    (:func:`armguard.geometry._pair_sat_rel.sat_depth_rel`, B's axes rotated, no point moved) with
    the W path's witnesses (B pushed out along the axis, GJK:
    :func:`armguard.geometry._pair_sat_rel.sat_witnesses_rel`).  Returns as :func:`narrow_rel`:
    ``(lower bound, BOUNDED)`` when the depth is below ``cap``, ``(0, NOT_SCALAR)`` when the
    witnesses' GJK does not converge (the W path then decides), else ``(distance, 0)``."""
    depth, nx, ny, nz = sat_depth_rel(pa, fa, ea, pb, fb, eb, rot, tx, ty, tz, eps_par)
    if not depth < math.inf:
        depth = 0.0  # no axis at all: point cores that coincide
    if depth < cap:
        return -depth - (ra + rb), BOUNDED
    st, ax, ay, az, bx, by, bz = sat_witnesses_rel(pa, adja, taba, pb, adjb, tabb, rot, tx, ty, tz, depth, nx, ny, nz,
                                                   simp, eps_len, gjk_eps, max_iter, offset)
    if st == GJK_NOT_CONVERGED:
        return 0.0, NOT_SCALAR
    wax, way, waz = _to_world(SF, oA, ax, ay, az, 1.0)
    wbx, wby, wbz = _to_world(SF, oA, bx, by, bz, 1.0)
    wnx, wny, wnz = _to_world(SF, oA, nx, ny, nz, 0.0)
    # depth < 0: GJK stopped within its tolerance of touching, an axis shows a gap (as the W path)
    return write_rounded(wax, way, waz, ra, wbx, wby, wbz, rb, wnx, wny, wnz, -depth, out, 0), 0


@njit(cache=True, inline="always")
def _seed(H, MF, MI, SF, p):  # pragma: no cover - compiled
    """Pair ``p``'s seed: the row of its seed table (``"sdt"``, 7 ints) at the node nearest the joint
    values of the last forward kinematics, or an empty view (no table).  ``"spair"`` row ``p``:
    ``[first row of the table, nodes per joint, joints (1 to 3) + 4 << m for each periodic joint m,
    joint i, j, k]``, ``"sgrid"`` row ``p``: ``[lower, 1 / step]`` of each (``._seeds``)."""
    osp = H[2 * _K_spair] + 6 * p
    if p < 0 or p >= H[2 * _K_spair + 1] or MI[osp] < 0:
        return view1(MI, 0, 0)
    osg = H[2 * _K_sgrid] + 6 * p
    ofq = H[2 * _K_fk_q]
    n = MI[osp + 1]
    kk = MI[osp + 2]
    c = 0
    for k in range(kk & 3):
        x = (SF[ofq + MI[osp + 3 + k]] - MF[osg + 2 * k]) * MF[osg + 2 * k + 1]
        if (kk >> (2 + k)) & 1:  # a periodic grid: the nearest node wrapped onto it (n a power of two, ._seeds.NODES:
            c = c * n + (int(math.floor(x + 0.5)) & (n - 1))  # a mask, where % n was an integer division)
        else:
            c = c * n + int(min(max(x + 0.5, 0.0), n - 1.0))
    return view1(MI, H[2 * _K_sdt] + 7 * (MI[osp] + c), 7)


@njit(cache=True, inline="always")
def _last_seed(H, SF, p):  # pragma: no cover - compiled
    """Pair ``p``'s final simplex at this thread's previous check ("lseed" row ``p``, 7 ints in a seed
    row's layout, ``n = 0``: none kept), or an empty view (no such pair)."""
    if p < 0 or p >= H[2 * _K_lseed + 1]:
        return iview1(SF, 0, 0)
    return iview1(SF, H[2 * _K_lseed] + 7 * p, 7)


@njit(cache=True, _nrt=False)
def narrow_rel(ga, gb, H, MF, MI, SF, out, eps_len, eps_par, gjk_eps, max_iter, offset, level,
               beyond, fns, p):  # pragma: no cover - compiled
    """Two convex point cores (boxes, hulls; a point or segment against a polytope) whose points stay
    in their element frames: GJK in A's frame
    on hull(A) and ``X_AB hull(B)``, ``X_AB = X_WA^-1 X_WB`` (:func:`armguard.geometry._pair_gjk.gjk_dir_rel`),
    supports climbing each hull's vertex graph (from its support table's entry or the previous support); only the support
    points GJK visits are rotated, where :func:`pair_distance` needs every point, face normal and edge
    direction of both moved to W first (on so101's hulls of 2,100 to 4,900 vertices, a quarter of a
    check).

    Returns ``(distance, 0)`` with ``out[0:9]`` in W when the cores are apart (GJK's answer, exact to
    ``gjk_eps`` like the W path's), when they overlap and ``level`` is at least ``-(ra + rb)`` (as
    :func:`armguard.geometry._pair_epa.convex_convex_fast`: an upper bound without a depth), or when
    they overlap and EPA settles the depth (``_pair_epa.epa_depth`` in A's frame, as the W path's) or,
    for two cores without vertex graphs whose SAT costs at most ``SAT_REL_BUDGET`` dot products (two
    boxes), the exhaustive SAT in A's frame does (:func:`_sat_rel`); else ``(0, NOT_SCALAR)``: the caller moves both elements and calls :func:`narrow_other` (its
    exhaustive SAT works on W points).  ``level`` as in :func:`narrow_other`; ``beyond`` (m, ``inf``:
    off): GJK may stop once the distance is proved above it, returning an upper bound > ``beyond``
    (not a distance: ``_step.pair_step`` keeps no row of it), and so may EPA once the depth is
    proved below ``-(beyond + ra + rb)`` (returns ``(lower bound, BOUNDED)``).  A cylinder against a
    polytope: :func:`_cylinder_rel` (the whole pair in the polytope's frame, depth included).

    ``p``: the pair's number (-1: none).  A pair with a seed table (``._seeds``) starts GJK from the
    simplex of the table's node nearest the joint values of this check's forward kinematics
    (``fk_q``): fewer iterations, the same answer (``_pair_gjk._gjk_body``); with the Checker's option
    ``warm_start``, a check near this thread's previous one (``"coh"``, ``._layout.COHERENT_STEP``)
    starts from the simplex the pair ended with there (``"lseed"``, kept after every GJK)."""
    oc = H[2 * _K_core]
    if MI[oc + ga] == _CYLINDER or MI[oc + gb] == _CYLINDER:
        return _cylinder_rel(ga, gb, H, MF, MI, SF, out, eps_len, gjk_eps, max_iter, level, fns)
    ovs = H[2 * _K_vstart]
    ov = H[2 * _K_verts_L]
    ogs = H[2 * _K_gadjs]
    orad = H[2 * _K_radius]
    vL = seg2(MF, H, _K_verts_L, 3)
    gadj = seg1(MI, H, _K_gadj)
    work = seg1(SF, H, _K_work)
    pa = vL[MI[ovs + ga]:MI[ovs + ga + 1]]
    pb = vL[MI[ovs + gb]:MI[ovs + gb + 1]]
    adja = gadj[MI[ogs + ga]:MI[ogs + ga + 1]]
    adjb = gadj[MI[ogs + gb]:MI[ogs + gb + 1]]
    gdir = seg1(MI, H, _K_gdir)
    ots = H[2 * _K_gdirs]
    taba = gdir[MI[ots + ga]:MI[ots + ga + 1]]
    tabb = gdir[MI[ots + gb]:MI[ots + gb + 1]]
    ra = MF[orad + ga]
    rb = MF[orad + gb]
    oA = _pose(SF, H, MI, ga)
    simp = work[0:16]  # [0:9] EPA's start where the cores overlap, [9:16] the final simplex as a seed row
    nw = work.shape[0] - WORK_TAIL
    rot = work[nw:nw + 9]
    tx, ty, tz = _relative(SF, oA, _pose(SF, H, MI, gb), rot)
    last = _last_seed(H, SF, p)
    if SF[H[2 * _K_coh] + 1] != 0.0 and last.shape[0] == 7 and last[0] > 0:
        seed = last  # warm start, near this thread's previous check: that check's final simplex
    else:
        seed = _seed(H, MF, MI, SF, p)
    gx, gy, gz = -tx, -ty, -tz  # GJK's first direction, unused from a seed (it reads no support along it)
    sx = sy = sz = 0.0
    if seed.shape[0] == 0 or seed[0] == 0:  # a cold start: inner point of A minus that of X_AB B
        gx, gy, gz = _inner_point(pa, adja)
        hx, hy, hz = _inner_point(pb, adjb)
        sx = rot[0] * hx + rot[1] * hy + rot[2] * hz + tx
        sy = rot[3] * hx + rot[4] * hy + rot[5] * hz + ty
        sz = rot[6] * hx + rot[7] * hy + rot[8] * hz + tz
    lim = level if beyond == math.inf else max(level, beyond)
    sep = lim + (ra + rb) if lim > -math.inf else math.inf
    status, d, ax, ay, az, bx, by, bz = call_gjk_rel(fns[FN_GJK_REL], (pa, adja, taba, pb, adjb, tabb, rot, tx, ty, tz,
                                                                       gx - sx, gy - sy, gz - sz, eps_len, gjk_eps,
                                                                       max_iter, simp, max(sep, 0.0), seed))
    inside = status != GJK_SEPARATED and status != GJK_NOT_CONVERGED and simp[0] == 1.0
    if last.shape[0] == 7:  # keep the final simplex (n = 0 unless apart) for the next check on this thread
        for k in range(7):
            last[k] = int(simp[9 + k])
    if inside and -(ra + rb) > level:  # overlapping cores, a depth wanted: EPA in A's frame as well
        # a depth below cap would leave the signed distance above ``beyond``: EPA may stop at that proof
        cap = -(beyond + (ra + rb)) if beyond < math.inf else -math.inf
        if adja.shape[0] == 0 and adjb.shape[0] == 0:  # both keep their face normals and edge directions
            ops = H[2 * _K_pstart]
            oes = H[2 * _K_estart]
            fL = seg2(MF, H, _K_fn_L, 3)
            eL = seg2(MF, H, _K_ed_L, 3)
            fa = fL[MI[ops + ga]:MI[ops + ga + 1]]
            fb = fL[MI[ops + gb]:MI[ops + gb + 1]]
            ea = eL[MI[oes + ga]:MI[oes + ga + 1]]
            eb = eL[MI[oes + gb]:MI[oes + gb + 1]]
            if nw < EPA_WORK_SIZE or sat_cost(pa.shape[0], fa.shape[0], ea.shape[0], pb.shape[0], fb.shape[0],
                                               eb.shape[0]) <= SAT_REL_BUDGET:
                return call_sat_rel(fns[FN_SAT_REL], (pa, fa, ea, adja, taba, ra, pb, fb, eb, adjb, tabb, rb, rot, tx, ty,
                                                      tz, SF, oA, out, simp, eps_len, eps_par, gjk_eps, max_iter, offset,
                                                      cap))
        ok, depth, nx, ny, nz, ax, ay, az, bx, by, bz = call_epa(fns[FN_EPA], (pa, adja, pb, adjb, work[0:nw], gjk_eps,
                                                                               rot, tx, ty, tz, taba, tabb, cap))
        if ok and depth < cap:
            return -depth - (ra + rb), BOUNDED  # depth < cap: distance > beyond (an upper bound, no witnesses)
        if ok:  # settled, a depth below eps_len included (the exhaustive SAT of the W path took 0.55 s on iiwa)
            wax, way, waz = _to_world(SF, oA, ax, ay, az, 1.0)
            wbx, wby, wbz = _to_world(SF, oA, bx, by, bz, 1.0)
            wnx, wny, wnz = _to_world(SF, oA, nx, ny, nz, 0.0)
            return write_rounded(wax, way, waz, ra, wbx, wby, wbz, rb, wnx, wny, wnz, -depth, out, 0), 0
        return 0.0, NOT_SCALAR  # EPA did not settle it: the W path (its exhaustive SAT)
    if status != GJK_SEPARATED and not inside:
        return 0.0, NOT_SCALAR  # touching (EPA from the completed simplex), or not converged: the W path
    wax, way, waz = _to_world(SF, oA, ax, ay, az, 1.0)  # the core witnesses to W
    if inside:  # a point of A's core as both core witnesses (p_WB - p_WA = distance * nhat holds)
        return write_rounded(wax, way, waz, ra, wax, way, waz, rb, 0.0, 0.0, 1.0, 0.0, out, 0), 0
    wbx, wby, wbz = _to_world(SF, oA, bx, by, bz, 1.0)
    r = 1.0 / d  # one division for the three components of the unit normal
    return write_rounded(wax, way, waz, ra, wbx, wby, wbz, rb, (wbx - wax) * r, (wby - way) * r, (wbz - waz) * r, d,
                         out, 0), 0


@njit(cache=True, _nrt=False)
def _wall_cylinder(g, H, MF, SF):  # pragma: no cover - compiled
    """:func:`wall_flat` for cylinder element ``g`` (its W buffer ``[c, r, r, h, R_WC row-major]`` in
    ``boxW``): along each wall's outward normal ``n = +-e_k`` the extreme point is the cylinder's
    exact support ``s(n) = c + h sign(a . n) a + r (u x_C + v y_C) / hypot(u, v)``, ``u = x_C . n``,
    ``v = y_C . n`` (see :mod:`armguard.geometry._cylinder`; the radial term dropped when ``n`` is
    along the axis), and the gap is the wall's coordinate minus that point's.  Same outputs."""
    ows = H[2 * _K_ws]
    o = H[2 * _K_boxW] + 15 * g
    rc = SF[o + 3]
    h = SF[o + 5]
    best = math.inf
    bx = by = bz = 0.0
    baxis = 0
    bsign = 1.0
    for ax in range(3):
        u0 = SF[o + 6 + 3 * ax]  # row ax of R_WC: the k-th components of x_C, y_C and the axis
        v0 = SF[o + 7 + 3 * ax]
        s0 = SF[o + 8 + 3 * ax]
        for side in range(2):
            sg = 1.0 if side == 0 else -1.0
            u = sg * u0
            v = sg * v0
            hh = h if sg * s0 >= 0.0 else -h
            x = SF[o] + hh * SF[o + 8]
            y = SF[o + 1] + hh * SF[o + 11]
            z = SF[o + 2] + hh * SF[o + 14]
            pn = math.sqrt(u * u + v * v)
            if pn > 0.0:
                u *= rc / pn
                v *= rc / pn
                x += u * SF[o + 6] + v * SF[o + 7]
                y += u * SF[o + 9] + v * SF[o + 10]
                z += u * SF[o + 12] + v * SF[o + 13]
            c = x if ax == 0 else (y if ax == 1 else z)
            gap = MF[ows + 3 + ax] - c if side == 0 else c - MF[ows + ax]
            if gap < best:
                best, bx, by, bz, baxis, bsign = gap, x, y, z, ax, sg
    oo = H[2 * _K_out9]
    SF[oo] = bx; SF[oo + 1] = by; SF[oo + 2] = bz
    SF[oo + 3] = bx; SF[oo + 4] = by; SF[oo + 5] = bz
    for ax in range(3):
        SF[oo + 6 + ax] = 0.0
    SF[oo + 3 + baxis] = MF[ows + 3 + baxis] if bsign > 0.0 else MF[ows + baxis]
    SF[oo + 6 + baxis] = bsign
    return best


@njit(cache=True, _nrt=False)
def wall_flat(g, H, MF, MI, SF):  # pragma: no cover - compiled
    """Distance (m) from element ``g`` to the walls of the workspace box ``ws = [lo, hi]`` (W).

    Ranger §2: for each of the six limits, the gap between the limit and the element's extreme
    point along that axis (core vertex plus radius); the least gap is the distance (> 0 inside,
    < 0 when some point is beyond a wall).  ``out9``: ``p_WA`` is that extreme point, ``p_WB``
    the same point with the wall's coordinate, ``nhat_AB_W`` the outward wall normal.  Reads the
    packed buffers by offset (:mod:`._layout`); the slow reference is
    :func:`armguard.detect._reference._wall_distance`.  A cylinder: :func:`_wall_cylinder`.
    """
    if MI[H[2 * _K_core] + g] == _CYLINDER:
        return _wall_cylinder(g, H, MF, SF)
    ows = H[2 * _K_ws]
    ov = H[2 * _K_vW]
    ovs = H[2 * _K_vstart]
    r = MF[H[2 * _K_radius] + g]
    best = math.inf
    bi = MI[ovs + g]
    baxis = 0
    bsign = 1.0
    for k in range(MI[ovs + g], MI[ovs + g + 1]):
        for ax in range(3):
            x = SF[ov + 3 * k + ax]
            gap = MF[ows + 3 + ax] - (x + r)
            if gap < best:
                best, bi, baxis, bsign = gap, k, ax, 1.0
            gap = (x - r) - MF[ows + ax]
            if gap < best:
                best, bi, baxis, bsign = gap, k, ax, -1.0
    o = H[2 * _K_out9]
    for ax in range(3):
        SF[o + ax] = SF[ov + 3 * bi + ax]
        SF[o + 6 + ax] = 0.0
    SF[o + baxis] += bsign * r
    for ax in range(3):
        SF[o + 3 + ax] = SF[o + ax]
    SF[o + 3 + baxis] = MF[ows + 3 + baxis] if bsign > 0.0 else MF[ows + baxis]
    SF[o + 6 + baxis] = bsign
    return best
