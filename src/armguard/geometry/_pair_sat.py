"""Penetration depth of polytopal cores by the separating-axis theorem, and the generic
convex-convex signed distance (GJK when apart, SAT when the cores overlap).

For convex polytopes P and Q (points, segments, boxes, polygons and polyhedra are all
polytopes) the facets of the Minkowski difference ``P - Q`` have normals among the face normals
of P, the face normals of Q and the cross products of an edge direction of P with one of Q
(a flat polygon's face normal counts with both signs; a segment has one edge and no face).  So
the shortest translation separating P and Q is the smallest projection overlap over those
axes -- the exhaustive separating-axis test (Gottschalk, Lin & Manocha, "OBBTree", SIGGRAPH 1996,
§4, generalised from boxes' 15 axes to every face normal and edge pair); with the radii of the sphere-swept
shapes it becomes ``depth = core_depth + ra + rb``.  Witness points: B is moved out along the
axis by ``core_depth + offset``, GJK then finds the closest points of the (now separated by
exactly ``offset`` along the axis) cores, and B's witness is moved back.
"""

from __future__ import annotations

import math

from numba import njit

from ._pair_gjk import GJK_INTERSECTING, GJK_NOT_CONVERGED, GJK_SEPARATED, gjk_core
from ._pair_segment_segment import write_rounded

__all__ = ["sat_depth", "convex_convex", "convex_convex_at", "gjk_distance"]


@njit(cache=True, inline="always")
def _extent(p, ux, uy, uz):  # pragma: no cover - compiled
    lo = math.inf
    hi = -math.inf
    for i in range(p.shape[0]):
        s = p[i, 0] * ux + p[i, 1] * uy + p[i, 2] * uz
        lo = min(lo, s)
        hi = max(hi, s)
    return lo, hi


@njit(cache=True, inline="always")
def _axis(pa, pb, ux, uy, uz, depth, nx, ny, nz):  # pragma: no cover - compiled
    alo, ahi = _extent(pa, ux, uy, uz)
    blo, bhi = _extent(pb, ux, uy, uz)
    plus = ahi - blo  # move B along +u by this much to separate
    minus = bhi - alo  # or along -u by this much
    if plus < depth:
        depth, nx, ny, nz = plus, ux, uy, uz
    if minus < depth:
        depth, nx, ny, nz = minus, -ux, -uy, -uz
    return depth, nx, ny, nz


@njit(cache=True)
def sat_depth(pa, fa, ea, pb, fb, eb, eps_par):  # pragma: no cover - compiled
    """Core penetration depth and direction by SAT.

    ``pa, pb : (n, 3) float64, m`` core vertices; ``fa, fb : (F, 3)`` unit face normals (one per
    parallel class; the sign does not matter); ``ea, eb : (E, 3)`` unit edge directions (one per
    parallel class).  Returns ``(depth, nx, ny, nz)``: moving B by ``depth * n`` makes the cores
    touch; ``depth < 0`` means they are separated along ``n`` (then it is a lower bound on the gap).
    """
    depth = math.inf
    nx = 0.0
    ny = 0.0
    nz = 1.0
    for i in range(fa.shape[0]):
        depth, nx, ny, nz = _axis(pa, pb, fa[i, 0], fa[i, 1], fa[i, 2], depth, nx, ny, nz)
    for i in range(fb.shape[0]):
        depth, nx, ny, nz = _axis(pa, pb, fb[i, 0], fb[i, 1], fb[i, 2], depth, nx, ny, nz)
    for i in range(ea.shape[0]):
        e1x = ea[i, 0]
        e1y = ea[i, 1]
        e1z = ea[i, 2]
        for j in range(eb.shape[0]):
            e2x = eb[j, 0]
            e2y = eb[j, 1]
            e2z = eb[j, 2]
            ux = e1y * e2z - e1z * e2y
            uy = e1z * e2x - e1x * e2z
            uz = e1x * e2y - e1y * e2x
            un = math.sqrt(ux * ux + uy * uy + uz * uz)
            if un <= eps_par:
                continue
            depth, nx, ny, nz = _axis(pa, pb, ux / un, uy / un, uz / un, depth, nx, ny, nz)
    return depth, nx, ny, nz


@njit(cache=True)
def gjk_distance(pa, ra, pb, rb, out, work, eps_len, gjk_eps, max_iter):  # pragma: no cover
    """Signed distance of two sphere-swept hulls *when their cores are disjoint* (GJK only).

    ``pa : (nA, 3)``, ``pb : (nB, 3) float64, m`` core points; ``ra, rb`` m; ``out`` (>= 9) gets
    ``[p_WA, p_WB, nhat_AB_W]``; ``work`` (>= ``GJK_WORK_SIZE``) is scratch.  Returns
    ``(distance, status)``.  With status ``GJK_INTERSECTING`` the cores overlap, ``out`` holds
    a common point and ``distance = -(ra + rb)`` is only an upper bound on the signed distance
    (use :func:`convex_convex` for the exact depth).
    """
    status, d, ax, ay, az, bx, by, bz = gjk_core(pa, pb, 0.0, 0.0, 0.0, work, eps_len, gjk_eps, max_iter)
    if status == GJK_INTERSECTING:
        return write_rounded(ax, ay, az, ra, bx, by, bz, rb, 0.0, 0.0, 1.0, 0.0, out, 0), status
    return write_rounded(ax, ay, az, ra, bx, by, bz, rb, (bx - ax) / d, (by - ay) / d, (bz - az) / d, d, out, 0), status


@njit(cache=True)
def convex_convex(
    pa, fa, ea, ra, pb, fb, eb, rb, out, work, eps_len, eps_par, gjk_eps, max_iter, offset
):  # pragma: no cover - compiled
    """Exact signed distance between two sphere-swept convex polytopes (any core kinds).

    Core A: vertices ``pa (nA, 3)``, face normals ``fa (FA, 3)``, edge directions ``ea (EA, 3)``
    (see :func:`sat_depth`), radius ``ra`` (m); likewise B.  Writes ``out[0:9]`` =
    ``[p_WA, p_WB, nhat_AB_W]`` and returns ``(distance, status)`` (status from GJK; callers
    raise on ``GJK_NOT_CONVERGED``).  ``offset`` (m) is ``Tolerances.penetration_witness_offset``.
    """
    return convex_convex_at(
        pa, fa, ea, ra, pb, fb, eb, rb, out, 0, work, eps_len, eps_par, gjk_eps, max_iter, offset
    )


@njit(cache=True)
def convex_convex_at(
    pa, fa, ea, ra, pb, fb, eb, rb, out, base, work, eps_len, eps_par, gjk_eps, max_iter, offset
):  # pragma: no cover - compiled
    """:func:`convex_convex` writing ``out[base:base + 9]``."""
    status, d, ax, ay, az, bx, by, bz = gjk_core(pa, pb, 0.0, 0.0, 0.0, work, eps_len, gjk_eps, max_iter)
    if status == GJK_SEPARATED:
        return write_rounded(ax, ay, az, ra, bx, by, bz, rb, (bx - ax) / d, (by - ay) / d, (bz - az) / d, d, out, base), status
    if status == GJK_NOT_CONVERGED:
        return 0.0, status
    depth, nx, ny, nz = sat_depth(pa, fa, ea, pb, fb, eb, eps_par)
    if not depth < math.inf:
        # no axis at all: both cores are points (or collinear segments handled elsewhere);
        # the cores coincide, any direction separates by ra + rb
        depth = 0.0
    if depth < 0.0:
        # GJK stopped within its tolerance of touching, but the exhaustive SAT found an axis
        # with a positive gap: the cores are disjoint (SAT is exact), separated by at least
        # -depth and by at most GJK's tolerance more.  Report them apart, never as touching
        # (the sign must agree with intersects()); witnesses from B pushed clear along n.
        gap = -depth
        status2, d2, ax, ay, az, bx, by, bz = gjk_core(
            pa, pb, offset * nx, offset * ny, offset * nz, work, eps_len, gjk_eps, max_iter
        )
        if status2 == GJK_NOT_CONVERGED:
            return 0.0, status2
        bx -= offset * nx
        by -= offset * ny
        bz -= offset * nz
        return write_rounded(ax, ay, az, ra, bx, by, bz, rb, nx, ny, nz, gap, out, base), GJK_SEPARATED
    shift = depth + offset
    status2, d2, ax, ay, az, bx, by, bz = gjk_core(
        pa, pb, shift * nx, shift * ny, shift * nz, work, eps_len, gjk_eps, max_iter
    )
    if status2 == GJK_NOT_CONVERGED:
        return 0.0, status2
    bx -= shift * nx
    by -= shift * ny
    bz -= shift * nz
    return write_rounded(ax, ay, az, ra, bx, by, bz, rb, nx, ny, nz, -depth, out, base), GJK_INTERSECTING
