"""Narrow phase of the detector: one element pair's signed distance, dispatched on core kinds.

No distance formula lives here: each branch calls the geometry core's per-pair kernel
(:mod:`armguard.geometry`): capsule-capsule (Ranger §3 link-link and link-edge),
capsule-box, capsule against a static polytope (GJK + Minkowski facets), GJK and EPA on support
functions for any pair with a cylinder side (:func:`armguard.geometry._pair_cylinder.support_pair_graph`),
and the exact convex-convex kernel for every other pair (faces, polyhedra, mesh hulls: GJK climbing
the hulls' vertex graphs, EPA for the depth, the exhaustive SAT as fallback).  The only formula of
its own is the distance to the workspace walls (Ranger §2, "link-to-bounding box distances"), which
is not a shape pair (for a cylinder: its exact support along each wall's normal).

Element data are in W (the detector kernel moves link elements there once per check):
``verts (V, 3)`` core points; ``box (G, 15)`` ``[centre, half extents, R_WB row-major]`` (a
cylinder: ``[c, r, r, h, R_WC row-major]``, the axis the third column, ``_pair_cylinder``'s buffer;
its core points are its circumscribed prism's corners, used for bounds only); ``fnrm (F, 3)``
face normals; ``edir (E, 3)`` unit edge directions; ``*_start`` CSR offsets.
"""

from __future__ import annotations

import math

from numba import njit

from armguard.geometry._pair_segment_box import capsule_box_scalar
from armguard.geometry._pair_segment_polytope import capsule_polytope_at
from armguard.geometry._pair_segment_segment import capsule_capsule_scalar
from armguard.geometry._pair_cylinder import support_pair_graph
from armguard.geometry._pair_epa import convex_convex_fast
from armguard.geometry.kernels import GJK_NOT_CONVERGED, capsule_box, capsule_capsule

# The segment numbers K come from ._layout and are compiled in as constants; numba's cache keys on
# this file only, so a change of the segment tuples in ._layout must come with an edit here.
from ._layout import K, seg1, seg2

__all__ = ["pair_distance", "narrow_flat", "narrow_other", "wall_flat", "ERR_GJK", "NOT_SCALAR"]

_K_core, _K_vstart, _K_radius, _K_vW, _K_boxW = K["core"], K["vstart"], K["radius"], K["vW"], K["boxW"]
_K_poly_of, _K_seg, _K_pv, _K_ppl, _K_ped = K["poly_of"], K["seg"], K["pv"], K["ppl"], K["ped"]
_K_pbis, _K_pcen, _K_pvs, _K_pps, _K_pes = K["pbis"], K["pcen"], K["pvs"], K["pps"], K["pes"]
_K_fnW, _K_pstart, _K_edW, _K_estart, _K_work = K["fnW"], K["pstart"], K["edW"], K["estart"], K["work"]
_K_ws, _K_out9 = K["ws"], K["out9"]
_K_gadj, _K_gadjs, _K_gtri, _K_gtris = K["gadj"], K["gadjs"], K["gtri"], K["gtris"]

ERR_GJK = 2  # the convex kernel did not converge: the caller raises, never a verdict
NOT_SCALAR = -1  # narrow_flat: not a capsule-capsule / capsule-box pair, call narrow_other

_POINT, _SEGMENT, _BOX, _CYLINDER = 0, 1, 2, 4  # armguard.geometry.CoreKind


@njit(cache=True, inline="always")
def _capsule_box(verts, vs, ve, ra, box, gb, out, eps_len, eps_par, offset):  # pragma: no cover
    j = vs if ve - vs == 1 else vs + 1  # a point core is a zero-length segment
    b = box[gb]
    return capsule_box(verts[vs], verts[j], ra, b[0:3], b[3:6], b[6:15].reshape((3, 3)), out, eps_len, eps_par, offset)


@njit(cache=True)
def pair_distance(
    ga, gb, core, radius, verts, vstart, box, fnrm, fstart, edir, estart, adj, adjs, tri, tris, out, work,
    eps_len, eps_par, gjk_eps, max_iter, offset, level,
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
        for i in range(3):  # swap the witnesses, negate the normal
            t = out[i]
            out[i] = out[3 + i]
            out[3 + i] = t
            out[6 + i] = -out[6 + i]
        return d, 0
    if ka == _CYLINDER or kb == _CYLINDER:
        ca = box[ga] if ka == _CYLINDER else box[ga, 0:0]  # an empty buffer: the hull of the points
        cb = box[gb] if kb == _CYLINDER else box[gb, 0:0]
        d, status = support_pair_graph(verts[vstart[ga]:vstart[ga + 1]], adj[adjs[ga]:adjs[ga + 1]], ca, ra,
                                       verts[vstart[gb]:vstart[gb + 1]], adj[adjs[gb]:adjs[gb + 1]], cb, rb,
                                       out, work, eps_len, gjk_eps, max_iter, level)
        if status == GJK_NOT_CONVERGED:
            return d, ERR_GJK
        return d, 0
    d, status = convex_convex_fast(
        verts[vstart[ga]:vstart[ga + 1]], fnrm[fstart[ga]:fstart[ga + 1]], edir[estart[ga]:estart[ga + 1]],
        adj[adjs[ga]:adjs[ga + 1]], tri[tris[ga]:tris[ga + 1]], ra,
        verts[vstart[gb]:vstart[gb + 1]], fnrm[fstart[gb]:fstart[gb + 1]], edir[estart[gb]:estart[gb + 1]],
        adj[adjs[gb]:adjs[gb + 1]], tri[tris[gb]:tris[gb + 1]], rb,
        out, work, eps_len, eps_par, gjk_eps, max_iter, offset, level,
    )
    if status == 2:
        return d, ERR_GJK
    return d, 0


@njit(cache=True)
def _capsule_polytope(seg, ra, k, pv, ppl, ped, pbis, pcen, pvs, pps, pes, rb, out, eps_len, eps_par, gjk_eps, max_iter,
                      offset):  # pragma: no cover - compiled
    """Capsule (core ``seg (2, 3)``, radius ``ra``) against static polytope number ``k`` of the packed
    polytope data (``_pack.polytope_data`` of each static polytope, concatenated; ``p*s`` CSR offsets)."""
    return capsule_polytope_at(seg, ra, pv[pvs[k]:pvs[k + 1]], ppl[pps[k]:pps[k + 1]], ped[pes[k]:pes[k + 1]],
                               pbis[pes[k]:pes[k + 1]], pcen[k], rb, out, 0, eps_len, eps_par, gjk_eps, max_iter, offset)


@njit(cache=True, _nrt=False)
def narrow_flat(ga, gb, H, MF, MI, SF, out, eps_len, eps_par, offset):  # pragma: no cover
    """:func:`pair_distance` on the detector's packed buffers (:mod:`._layout`), same outputs and errors.

    The common pairs read their cores straight from the flat buffers into registers and call the
    geometry core's scalar entry points (capsule-capsule, capsule-box: ~30 ns per pair, against
    ~200 ns when a dozen array views are passed around).  Returns ``(distance, error)``, or
    ``(0, NOT_SCALAR)`` for any other pair: the caller then calls :func:`narrow_other` (kept apart
    so that this function creates no array view: views cost reference counting on every call).
    """
    oc = H[2 * _K_core]
    ovs = H[2 * _K_vstart]
    orad = H[2 * _K_radius]
    ov = H[2 * _K_vW]
    obox = H[2 * _K_boxW]
    ka = MI[oc + ga]
    kb = MI[oc + gb]
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
        if kb == _BOX:
            o = obox + 15 * gb
            return capsule_box_scalar(
                SF[a0], SF[a0 + 1], SF[a0 + 2], SF[a1], SF[a1 + 1], SF[a1 + 2], MF[orad + ga],
                SF[o], SF[o + 1], SF[o + 2], SF[o + 3], SF[o + 4], SF[o + 5], SF[o + 6], SF[o + 7], SF[o + 8],
                SF[o + 9], SF[o + 10], SF[o + 11], SF[o + 12], SF[o + 13], SF[o + 14],
                out, 0, eps_len, eps_par, offset), 0
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
        for i in range(3):  # swap the witnesses, negate the normal
            t = out[i]
            out[i] = out[3 + i]
            out[3 + i] = t
            out[6 + i] = -out[6 + i]
        return d, 0
    return 0.0, NOT_SCALAR


@njit(cache=True)
def narrow_other(ga, gb, H, MF, MI, SF, out, eps_len, eps_par, gjk_eps, max_iter, offset, level):  # pragma: no cover
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
                         eps_len, eps_par, gjk_eps, max_iter, offset, level)


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
