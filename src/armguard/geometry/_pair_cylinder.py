"""Signed distance of a Cylinder against any shape: GJK and EPA on support functions.

The vertex-graph GJK of ``_pair_gjk`` and the EPA of ``_pair_epa`` address support points by
vertex index (finite point sets, exact termination); a cylinder's support ``s(d)`` (see
``_cylinder``) is a continuous function of ``d``, so this module keeps the support *points*:
each simplex or polytope vertex stores ``w = a - b`` with ``a`` and ``b`` the supports of the two
cores, and the witnesses are the barycentric combinations of those.  The algorithms are the same:

* GJK (Gilbert, Johnson & Keerthi 1988; van den Bergen, *Collision Detection in Interactive 3D
  Environments* §4.3) with Johnson's sub-algorithm as Ericson's Voronoi-region tests (*Real-Time
  Collision Detection* §5.1, ``_pair_gjk._closest_simplex``); it stops when the duality gap
  ``(|v|^2 - v . w) / |v|`` (an upper minus a lower bound on the core distance) is below
  ``gjk_epsilon``, when a support point repeats, or when ``|v|`` stops decreasing.  On a
  cylinder's rim against a polytope's edge it used to stall so with ``|v|`` 1e-9 to 1.25e-8 m
  above the distance (an old vertex's rim point left behind, each step's gain below rounding);
  there the simplex's cylinder points are first turned to one best angle and GJK resumes
  (``_pair_cylinder_turn``, up to ``_REFRESHES`` times), after which such pairs met the gap test.
  A stop with the bounds still apart by more than ``gjk_epsilon`` (cores proven apart) reports the
  proven lower bound ``max v . w / |v|`` over the iterations, never ``|v|``: the separated
  distance is never above the exact one by more than ``gjk_epsilon`` plus rounding (the
  witnesses, ``|v|`` apart, are then each drawn ``(|v| - bound) / 2`` towards the other, so that
  they are the reported distance apart, within that of their surfaces).  Once a support plane has
  separated the origin from ``M`` (``v . w > 0``: a proof that the cores are apart) no later step
  may call them intersecting: near a rim the supports jump between nearly equal points, and
  rounding can then flatten the simplex into a tetrahedron that seems to hold the origin (1 in
  1,000 random cylinder-box pairs 18-28 mm apart were once reported touching).  On a curved core
  GJK converges without terminating finitely; with ``max_iterations`` spent it is accepted (with
  its lower bound) when the gap is below ``SUPPORT_GAP``, else reported as ``GJK_NOT_CONVERGED``
  (callers raise).
* EPA (van den Bergen, GDC 2001, §4.3.7) on ``M = A - B`` from GJK's final tetrahedron; when GJK
  stops with the origin on a lower-dimensional simplex (touching cores) the simplex is first
  completed to a tetrahedron containing the origin by support points along directions off its
  span (as in van den Bergen's SOLID and coal).  It stops when the support value along the
  closest facet's normal exceeds the facet's distance by at most ``gjk_epsilon``; the depth is
  then exact to that, up to rounding.  On a curved core it converges geometrically; with the
  buffer's vertices spent (or a support repeating) it accepts a gap below ``SUPPORT_GAP``.

Considered and not built: an exact shortcut where the nearest point of a cylinder is on its side
(the other core's distance to the axis segment less the radius, exact when that segment's nearest
point is inside it).  On z1's squat cylinders (radius 20-32 mm, half length 25-118 mm), at 300 random
configurations, the nearest points of the separated pairs were on a rim in 6,736 of 8,038 (rim-hull
3,281, rim-rim 1,985, side-rim 1,364), on two sides or a side and a hull in 1,036 and on a cap's face
(the rim excepted) in 266.

Measured and not kept: entering the simplex's witnesses projected onto the cylinder(s) as a vertex
of ``M`` once the cores were proved apart (the nearest point of a solid cylinder to a point is
closed form; between two cylinders three rounds of alternating projections), GJK still stopping
only on its own gap test, and running again without them where they left it stalled before that
test (5 % of the pairs; 0 of 1,620 separated pairs on z1 then differed from this kernel by more
than 1e-12 m).  Supports per separated pair on z1 (60 random configurations): cylinder-cylinder
9.1 -> 4.7, cylinder-hull 10.1 -> 7.8 (the gripper hulls of 3,193 and 6,877 vertices are curved
too, and a hull's nearest point to a point is a GJK of its own); yet z1's ``pair_distances`` took
44 us against 37 (each projection step about as dear as a support with the tetrahedron's Johnson
test), and once or twice per run, below a gap of 1e-2 or 1e-3 of ``|v|``, or replacing the
simplex by the projected vertex, the supports saved were at most 25 % and paid for by the
projections.

A core is ``(p, cyl, r)``: ``cyl`` a Cylinder's 15-float buffer ``[c, r, r, h, R_WC row-major]``
(``_pack``), or empty, and then the core is the hull of the points ``p (n, 3)`` (scanned, or climbed
over their vertex graph when one is given: :func:`support_pair_graph`), swept
by the radius ``r`` (spheres, capsules; 0 for polytopes).  Allocation-free: GJK's simplex and
EPA's polytope live in the caller's ``work`` (``SUPPORT_WORK_SIZE`` float64), so these kernels are
compiled without numba's reference counting (``_nrt=False``, as ``_pair_epa``), except
:func:`support_pair`, which makes its empty graphs.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._pair_cylinder_epa import _complete, epa_support
from ._pair_cylinder_search import depth_search, witnesses
from ._pair_cylinder_turn import _combine, _refresh, _restore
from ._pair_cylinder_support import (  # noqa: F401  (CYL_W, support_point: part of this module's interface)
    _L0, _S0, _V0, _VIS, _WA, _WB, CYL_W, SUPPORT_GAP, SUPPORT_WORK_SIZE, _centre, _pair_support, _put, support_point,
)
from ._pair_gjk import GJK_INTERSECTING, GJK_NOT_CONVERGED, GJK_SEPARATED, _closest_simplex, table_start
from ._pair_segment_segment import write_rounded

_REFRESHES = 16  # stalls gjk_support resumes by _refresh, at most

__all__ = ["CYL_W", "SUPPORT_WORK_SIZE", "SUPPORT_GAP", "support_point", "gjk_support", "epa_support",
           "support_pair", "support_pair_graph"]


@njit(cache=True, inline="always")
def _plane_bound(pa, ga, ca, pb, gb, cb, work, n, vx, vy, vz, ta, tb):  # pragma: no cover - compiled
    """A lower bound on the core distance along the final simplex's own normal: its triangle's
    (``n == 3``) or ``v`` made orthogonal to its segment (``n == 2``), turned towards ``v``.

    ``v . w / |v|`` is a lower bound whose error is first order in ``v``'s direction error, and
    that is the rounding of ``v`` (~1e-16 of the simplex's size) over ``|v|``: at 8e-9 m between
    a box's face and a cap it was 2.4e-9 m.  When ``v`` lies inside a triangle the nearest points'
    normal is the triangle's, whose cross product of edges is exact to rounding of the edges, not
    of ``v``.  Returns ``u . w(-u)`` for that unit ``u`` (``-inf`` where it is undefined)."""
    o1 = _S0 + 9
    ex = work[o1] - work[_S0]
    ey = work[o1 + 1] - work[_S0 + 1]
    ez = work[o1 + 2] - work[_S0 + 2]
    if n == 3:
        o2 = _S0 + 18
        fx = work[o2] - work[_S0]
        fy = work[o2 + 1] - work[_S0 + 1]
        fz = work[o2 + 2] - work[_S0 + 2]
        ux = ey * fz - ez * fy
        uy = ez * fx - ex * fz
        uz = ex * fy - ey * fx
        if ux * vx + uy * vy + uz * vz < 0.0:
            ux, uy, uz = -ux, -uy, -uz
    else:
        ee = ex * ex + ey * ey + ez * ez
        if ee == 0.0:
            return -math.inf
        t = (vx * ex + vy * ey + vz * ez) / ee
        ux = vx - t * ex
        uy = vy - t * ey
        uz = vz - t * ez
    un = math.sqrt(ux * ux + uy * uy + uz * uz)
    if un == 0.0:
        return -math.inf
    ux /= un
    uy /= un
    uz /= un
    ax, ay, az, bx, by, bz = _pair_support(pa, ga, ca, pb, gb, cb, -ux, -uy, -uz, work, ta, tb)
    return ux * (ax - bx) + uy * (ay - by) + uz * (az - bz)


@njit(cache=True, _nrt=False)
def gjk_support(pa, ga, ca, pb, gb, cb, dx, dy, dz, eps_len, gjk_eps, max_iter, work, sa=-1, sb=-1, ta=None,
                tb=None):  # pragma: no cover
    """GJK on the cores ``(pa, ca)`` and ``(pb, cb)`` from the initial direction ``d`` (B to A).

    Returns ``(status, dist, n, ax, ay, az, bx, by, bz)``: the core distance (``|v|`` where the
    gap test met ``gjk_eps``, else, when apart, the proven lower bound; see the module docstring),
    the number of simplex vertices left in ``work`` (4: the origin is inside their tetrahedron) and the witnesses on the
    cores.  ``status`` as ``_pair_gjk``.  ``sa``, ``sb``: where the point cores' first climbs start
    (-1: from their stored extremes; a caller with a support table passes its entries, see
    ``_pair_gjk.table_start``); ``ta``, ``tb`` (None or empty: none): their support tables, where the
    later climbs may start (``_pair_cylinder_support._warm_point``: on z1's gripper hulls of 3,193 and
    6,877 vertices a climb from the previous support took ~10 moves)."""
    eps2 = eps_len * eps_len
    work[_WA] = float(sa)  # the point cores' first climbs (-1: cold, from their stored extremes)
    work[_WB] = float(sb)
    ax, ay, az, bx, by, bz = _pair_support(pa, ga, ca, pb, gb, cb, -dx, -dy, -dz, work)
    _put(work, _S0, ax, ay, az, bx, by, bz)
    work[_L0] = 1.0
    n = 1
    vx = work[_S0]
    vy = work[_S0 + 1]
    vz = work[_S0 + 2]
    vv = vx * vx + vy * vy + vz * vz
    status = GJK_NOT_CONVERGED
    gap = math.inf
    lower = -math.inf  # the best lower bound on |v|'s limit seen: max v . w / |v|
    apart = False
    refresh = 0  # stalls resumed by _refresh (at most _REFRESHES)
    for _it in range(max_iter):
        if vv <= eps2:
            status = GJK_INTERSECTING
            break
        ax, ay, az, bx, by, bz = _pair_support(pa, ga, ca, pb, gb, cb, -vx, -vy, -vz, work, ta, tb)
        wx = ax - bx
        wy = ay - by
        wz = az - bz
        vw = vx * wx + vy * wy + vz * wz
        # w is M's point least along v: vw > 0 proves the origin outside M (w's plane separates
        # them), whatever later supports do near a rim (they jump between nearly equal points)
        apart = apart or vw > 0.0
        gap = (vv - vw) / math.sqrt(vv)
        lower = max(lower, vw / math.sqrt(vv))
        if gap <= gjk_eps:
            status = GJK_SEPARATED
            break
        dup = False
        for k in range(n):
            o = _S0 + 9 * k
            ex = wx - work[o]
            ey = wy - work[o + 1]
            ez = wz - work[o + 2]
            if ex * ex + ey * ey + ez * ez <= eps2:
                dup = True
        m = 0
        nn = n + 1
        k0 = k1 = k2 = k3 = nvx = nvy = nvz = 0.0
        if not dup:
            _put(work, _S0 + 9 * n, ax, ay, az, bx, by, bz)
            o1 = _S0 + 9
            o2 = _S0 + 18
            o3 = _S0 + 27
            m, k0, k1, k2, k3 = _closest_simplex(
                n + 1, work[_S0], work[_S0 + 1], work[_S0 + 2], work[o1], work[o1 + 1], work[o1 + 2],
                work[o2], work[o2 + 1], work[o2 + 2], work[o3], work[o3 + 1], work[o3 + 2])
            if m == 15 and not apart:
                status = GJK_INTERSECTING
                n = 4
                break
        if dup or m == 15:
            # a repeated support point, or an "inside" verdict after a support plane separated the
            # origin from M (a proof: rounding has made the tetrahedron flat): no progress possible
            # on this simplex
            nvv = math.inf
        else:
            nvx, nvy, nvz, nvv = _combine(work, nn, k0, k1, k2, k3)
        if nvv >= vv and apart and refresh < _REFRESHES:
            # a stall with the gap still open: the simplex's cylinder points turned to one best
            # angle (_pair_cylinder_turn: the rim's optimum an old vertex's chord had missed)
            refresh += 1
            nn, m, k0, k1, k2, k3, nvv = _refresh(work, n, ca, cb, ax, ay, az, bx, by, bz, eps2,
                                                  work[_V0 + 40:_V0 + 52])
            if m != 15:
                nvx, nvy, nvz, nvv = _combine(work, nn, k0, k1, k2, k3)
            if nvv >= vv:
                _restore(work)
        if nvv >= vv:
            # no progress (rounding): the previous simplex is the answer (apart when a support plane separated)
            status = GJK_SEPARATED if apart else GJK_INTERSECTING
            break
        c = 0
        for j in range(nn):  # compact the kept vertices into slots 0 .. c-1, in order
            if (m >> j) & 1:
                if c != j:
                    for q in range(9):
                        work[_S0 + 9 * c + q] = work[_S0 + 9 * j + q]
                work[_L0 + c] = k0 if j == 0 else (k1 if j == 1 else (k2 if j == 2 else k3))
                c += 1
        n = c
        vx, vy, vz, vv = nvx, nvy, nvz, nvv
    if status == GJK_NOT_CONVERGED and gap <= SUPPORT_GAP * (1.0 + math.sqrt(vv)):
        status = GJK_SEPARATED  # a curved core: iterations spent, the error bound met
    dist, lowered = math.sqrt(vv), False
    if status == GJK_SEPARATED and apart and dist - lower > gjk_eps and 2 <= n <= 3:
        lower = max(lower, _plane_bound(pa, ga, ca, pb, gb, cb, work, n, vx, vy, vz, ta, tb))
    if status == GJK_SEPARATED and apart and dist - lower > gjk_eps:
        # stopped (a stall, or iterations spent) before the bounds met: |v| may overstate the
        # distance by up to their difference; the proven lower bound is the answer (the error on
        # the safe side; the witnesses are drawn together below to be that far apart)
        dist, lowered = lower, True
    ax = ay = az = bx = by = bz = 0.0
    if n < 4:
        for k in range(n):
            lam = work[_L0 + k]
            o = _S0 + 9 * k
            ax += lam * work[o + 3]
            ay += lam * work[o + 4]
            az += lam * work[o + 5]
            bx += lam * work[o + 6]
            by += lam * work[o + 7]
            bz += lam * work[o + 8]
        gx, gy, gz = bx - ax, by - ay, bz - az
        g = math.sqrt(gx * gx + gy * gy + gz * gz)
        if lowered and g > dist >= 0.0:  # the lower bound reported: each witness moves (g - dist) / 2 towards the other
            t = 0.5 * (g - dist) / g
            ax, ay, az, bx, by, bz = ax + t * gx, ay + t * gy, az + t * gz, bx - t * gx, by - t * gy, bz - t * gz
        return status, dist, n, ax, ay, az, bx, by, bz
    return status, 0.0, 4, work[_S0 + 3], work[_S0 + 4], work[_S0 + 5], work[_S0 + 6], work[_S0 + 7], work[_S0 + 8]


@njit(cache=True)
def support_pair(pa, ca, ra, pb, cb, rb, out, work, eps_len, gjk_eps, max_iter, level):  # pragma: no cover
    """:func:`support_pair_graph` without vertex graphs (point cores are scanned)."""
    none = np.zeros(0, np.int64)
    return support_pair_graph(pa, none, ca, ra, pb, none, cb, rb, out, work, eps_len, gjk_eps, max_iter, level)


@njit(cache=True, _nrt=False)
def support_pair_graph(pa, ga, ca, ra, pb, gb, cb, rb, out, work, eps_len, gjk_eps, max_iter, level, ta=None,
                       tb=None):  # pragma: no cover
    """Signed distance (m) of the sphere-swept cores ``(pa, ca, ra)`` (A) and ``(pb, cb, rb)`` (B)
    (see the module docstring); writes ``out[0:9] = [p_WA, p_WB, nhat_AB_W]``.  Returns
    ``(distance, status)``, ``status`` as ``_pair_gjk`` (``GJK_NOT_CONVERGED``: the caller raises).

    ``level`` (m) as in ``_pair_epa.convex_convex_fast``: when the cores overlap and
    ``-(ra + rb) <= level`` it returns ``-(ra + rb)`` (an upper bound) without a depth.  EPA's
    polytope can break by rounding near a curved optimum (about 1 in 300 random penetrating pairs
    with a flat core against the cylinder did, and were once reported touching); the depth
    bracketed before that is the answer (:func:`epa_support`).  Where EPA cannot settle a
    depth under any of its visibility margins (none of 9,000 seeded random pairs of a cylinder
    and a box, polygon or polyhedron, 6,736 of them penetrating, came to this; a shape on or near
    a cylinder's axis does: every radial direction is nearly optimal) the depth is the direction
    search's (:mod:`._pair_cylinder_search`): realised along its normal, never shallower than the
    true depth.

    ``ga``, ``gb``: the vertex graphs of the point cores (``_pack.hull_graph`` format, indices into
    ``pa`` / ``pb``; empty: the points are scanned); a cylinder side ignores its own.  ``ta``, ``tb``
    (None, or a point core's ``_pack.support_table``; empty: none): where its first climb starts."""
    gx, gy, gz = _centre(pa, ga, ca)
    hx, hy, hz = _centre(pb, gb, cb)
    sa = sb = -1
    if ta is not None:  # the first supports: A's along -d, B's along +d (d from B's centre to A's)
        sa = table_start(ta, hx - gx, hy - gy, hz - gz)
    if tb is not None:
        sb = table_start(tb, gx - hx, gy - hy, gz - hz)
    status, d, n, ax, ay, az, bx, by, bz = gjk_support(pa, ga, ca, pb, gb, cb, gx - hx, gy - hy, gz - hz, eps_len, gjk_eps,
                                                       max_iter, work, sa, sb, ta, tb)
    if status == GJK_NOT_CONVERGED:
        return 0.0, status
    if status == GJK_SEPARATED and d > 0.0:
        ex = bx - ax
        ey = by - ay
        ez = bz - az
        en = math.sqrt(ex * ex + ey * ey + ez * ez)  # |b - a| = d to rounding; unit at any d
        if en > 0.0:
            return write_rounded(ax, ay, az, ra, bx, by, bz, rb, ex / en, ey / en, ez / en, d, out, 0), status
        return write_rounded(ax, ay, az, ra, bx, by, bz, rb, 0.0, 0.0, 1.0, d, out, 0), status
    if -(ra + rb) <= level:
        return write_rounded(ax, ay, az, ra, ax, ay, az, rb, 0.0, 0.0, 1.0, 0.0, out, 0), GJK_INTERSECTING
    scale = 1.0
    for k in range(n):
        for q in range(3):
            scale = max(scale, abs(work[_S0 + 9 * k + 3 + q]), abs(work[_S0 + 9 * k + 6 + q]))
    tol = 4e-15 * scale + eps_len
    ok = n == 4 or _complete(pa, ga, ca, pb, gb, cb, work, n, tol)
    if ok:
        # a face's plane may pass the origin by rounding of the sliver faces near a curved optimum;
        # the visibility margin decides how coplanar supports (caps, flat faces) are merged, and a
        # polytope that rounding has broken under one margin is usually whole under another
        for k in range(len(_VIS)):
            ok, depth, nx, ny, nz, cax, cay, caz, cbx, cby, cbz = epa_support(pa, ga, ca, pb, gb, cb, work, gjk_eps, 1e-9 * scale,
                                                                               _VIS[k] * scale)
            if ok:
                return write_rounded(cax, cay, caz, ra, cbx, cby, cbz, rb, nx, ny, nz, -depth, out, 0), GJK_INTERSECTING
    # EPA settled no depth (its optimal directions a continuum: a shape on or near a cylinder's axis):
    # the least support value a direction search finds, an upper bound on the depth (_pair_cylinder_search)
    depth, nx, ny, nz, cax, cay, caz = depth_search(pa, ga, ca, pb, gb, cb, work)
    if depth < math.inf:
        cax, cay, caz, cbx, cby, cbz = witnesses(pa, ga, ca, pb, gb, cb, nx, ny, nz, depth, work)
        return write_rounded(cax, cay, caz, ra, cbx, cby, cbz, rb, nx, ny, nz, -depth, out, 0), GJK_INTERSECTING
    return write_rounded(ax, ay, az, ra, ax, ay, az, rb, 0.0, 0.0, 1.0, 0.0, out, 0), GJK_INTERSECTING
