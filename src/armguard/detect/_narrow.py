"""Narrow phase of the detector: one element pair's signed distance, dispatched on core kinds.

No distance formula lives here: each branch calls the geometry core's per-pair kernel
(:mod:`armguard.geometry`): capsule-capsule (Ranger §3 link-link and link-edge),
capsule-box, and the exact convex-convex GJK + SAT kernel for every other pair (faces,
polyhedra, mesh hulls).  The only formula of its own is the distance to the workspace
walls (Ranger §2, "link-to-bounding box distances"), which is not a shape pair.

Element data are in W (the detector kernel moves link elements there once per check):
``verts (V, 3)`` core points; ``box (G, 15)`` ``[centre, half extents, R_WB row-major]``;
``fnrm (F, 3)`` face normals; ``edir (E, 3)`` unit edge directions; ``*_start`` CSR offsets.
"""

from __future__ import annotations

import math

from numba import njit

from ..geometry.kernels import capsule_box, capsule_capsule, convex_convex

__all__ = ["pair_distance", "wall_distance", "ERR_GJK"]

ERR_GJK = 2  # the convex kernel did not converge: the caller raises, never a verdict

_POINT, _SEGMENT, _BOX = 0, 1, 2


@njit(cache=True, inline="always")
def _capsule_box(verts, vs, ve, ra, box, gb, out, eps_len, eps_par, offset):  # pragma: no cover
    j = vs if ve - vs == 1 else vs + 1  # a point core is a zero-length segment
    b = box[gb]
    return capsule_box(verts[vs], verts[j], ra, b[0:3], b[3:6], b[6:15].reshape((3, 3)), out, eps_len, eps_par, offset)


@njit(cache=True)
def pair_distance(
    ga, gb, core, radius, verts, vstart, box, fnrm, fstart, edir, estart, out, work,
    eps_len, eps_par, gjk_eps, max_iter, offset,
):  # pragma: no cover - compiled
    """Signed distance (m) of elements ``ga`` (A) and ``gb`` (B); writes ``out[0:9]`` =
    ``[p_WA, p_WB, nhat_AB_W]``.  Returns ``(distance, error)``; ``error`` is 0 or ``ERR_GJK``."""
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
    d, status = convex_convex(
        verts[vstart[ga]:vstart[ga + 1]], fnrm[fstart[ga]:fstart[ga + 1]], edir[estart[ga]:estart[ga + 1]], ra,
        verts[vstart[gb]:vstart[gb + 1]], fnrm[fstart[gb]:fstart[gb + 1]], edir[estart[gb]:estart[gb + 1]], rb,
        out, work, eps_len, eps_par, gjk_eps, max_iter, offset,
    )
    if status == 2:
        return d, ERR_GJK
    return d, 0


@njit(cache=True)
def wall_distance(g, radius, verts, vstart, lo, hi, out):  # pragma: no cover - compiled
    """Distance (m) from element ``g`` to the walls of the box ``[lo, hi]`` (W).

    Ranger §2: for each of the six limits, the gap between the limit and the element's extreme
    point along that axis (core vertex plus radius); the least gap is the distance (> 0 inside,
    < 0 when some point is beyond a wall).  ``p_WA`` is that extreme point, ``p_WB`` the same
    point with the wall's coordinate; ``nhat_AB_W`` the outward wall normal.
    """
    r = radius[g]
    best = math.inf
    bi = vstart[g]
    baxis = 0
    bsign = 1.0
    for k in range(vstart[g], vstart[g + 1]):
        for ax in range(3):
            x = verts[k, ax]
            gap = hi[ax] - (x + r)
            if gap < best:
                best, bi, baxis, bsign = gap, k, ax, 1.0
            gap = (x - r) - lo[ax]
            if gap < best:
                best, bi, baxis, bsign = gap, k, ax, -1.0
    for ax in range(3):
        out[ax] = verts[bi, ax]
        out[6 + ax] = 0.0
    out[baxis] += bsign * r
    for ax in range(3):
        out[3 + ax] = out[ax]
    out[3 + baxis] = hi[baxis] if bsign > 0.0 else lo[baxis]
    out[6 + baxis] = bsign
    return best
