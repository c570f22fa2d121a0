"""Penetration depth of two polytopal cores by the Expanding Polytope Algorithm, and the
convex-convex signed distance built on it (the fast path of the exhaustive SAT of ``_pair_sat``).

EPA (van den Bergen, "Proximity Queries and Penetration Depth Computation on 3D Game
Objects", GDC 2001; *Collision Detection in Interactive 3D Environments* §4.3.7): when GJK
ends with the origin inside a tetrahedron of support points of the Minkowski difference
``M = A - B``, that tetrahedron is a polytope ``P ⊂ M`` containing the origin.  Each iteration
takes the face of ``P`` closest to the origin (distance ``d``, outward unit normal ``n``),
queries the support point ``w`` of ``M`` along ``n`` (``h = n . w``) and, unless
``h - d <= gjk_epsilon``, adds ``w`` to ``P`` (the faces seen from ``w`` are removed, their
horizon edges are joined to ``w``).  Throughout, ``d <= depth(M) <= h``: ``P ⊂ M`` contains
the origin (lower bound), and every direction's support value bounds the depth from above
(``depth = min_n h_M(n)``).  On polytopes every iteration adds a new vertex of ``M``, so it
terminates; the returned depth is the lower bound ``d``, within ``gjk_epsilon`` (m) of the
exact depth (up to rounding).  Supports climb the vertex graphs (``_pair_gjk._support``), so
an iteration costs a face scan and two short climbs instead of the SAT's
``O(E_A E_B (V_A + V_B))`` projections.

When rounding stops EPA after its bracket on the depth has closed to ``EPA_BRACKET``, the face it
kept is the answer.  GJK stopped at touching (no tetrahedron) has its simplex completed to one
(:mod:`._pair_epa_start`); a settled depth, however small, is the answer (a gap of up to ``eps_len``
between touching cores may then come back as a depth of 0: within ``Tolerances.length``).  Every
other case EPA does not settle falls back to the exhaustive SAT (:func:`sat_depth_graph`: the
reference :func:`._pair_sat.sat_depth` with the axes of a triangulated hull taken from its
triangles and vertex graph, so that hulls need not carry face normals and edge directions): a
degenerate face, a full buffer, no convergence within the buffer's vertices.

The kernel is allocation-free: the expanding polytope lives in the caller's ``work`` array
(``EPA_WORK_SIZE`` float64; indices stored as floats, exact below 2^53).  So it is compiled without
numba's reference counting (``_nrt=False``): with it, each helper call paid an ``NRT_incref`` / ``NRT_decref`` pair per array.  Its vertex, face and
horizon helpers are inlined.
"""

from __future__ import annotations

import math

from numba import njit

from ._pair_gjk import (GJK_INTERSECTING, GJK_NOT_CONVERGED, GJK_SEPARATED, _b_dir, _b_point, _support, gjk_core,
                        gjk_dir_adj2, inner_difference, table_size, warm_start)
from ._pair_epa_start import complete_simplex
from ._pair_sat import _axis
from ._pair_segment_segment import write_rounded

__all__ = ["EPA_WORK_SIZE", "EPA_MAX_VERTICES", "epa_depth", "complete_simplex", "sat_depth_graph", "convex_convex_fast"]

EPA_MAX_VERTICES = 256
"""Vertices of the expanding polytope (EPA iterations are at most this minus 4)."""
EPA_BRACKET = 1e-6
"""m: once the least support value seen is within this of the closest face's distance, that face
is kept (the latest such face); if rounding then stops EPA (a degenerate or origin-outside face, a
repeated vertex, a full buffer) before ``gjk_epsilon`` is reached, the kept face is the answer --
its depth is a lower bound within the bracket of the exact depth -- rather than the exhaustive SAT,
which on dense hulls (thousands of vertices) runs for hours.  On so101's hulls (800-4,262
vertices), where rounding stops EPA on 2-6 % of rotations of a penetrating pair, the bracket when
it stopped was 1.4e-10 to 6.9e-9 m.  The cylinder EPA (``_pair_cylinder_epa``) keeps its tightest
bracket the same way, within ``SUPPORT_GAP`` (1e-8 m per m); this bound is wider because the
alternative here is a SAT that does not return, not a refusal."""
_NV = EPA_MAX_VERTICES
_TOUCH = 1e-9  # m: how far outside a face of the starting tetrahedron the origin may lie (complete_simplex)
_VISIBLE = 1e-14  # m: a face is seen from a new vertex w when w is more than this above its plane (see epa_depth)
_COPLANAR = 1e-10  # m: faces of the expanding polytope this near the closest face's plane distance ...
_COPLANAR_WEIGHT = 1e-9  # ... and normal (cos >= 1 - this): the same facet of M; a weight this far below 0 still holds
_NF = 1024  # face slots (kept packed: a removed face's slot takes the last face)
_NE = 256  # horizon edges of one iteration
_V0 = 9  # work[0:9]: GJK's final simplex (see _pair_gjk._gjk)
_F0 = _V0 + 5 * _NV  # vertex k: [w (3), ia, ib] at _V0 + 5 k
_E0 = _F0 + 8 * _NF  # face f: [i0, i1, i2, n (3), d, alive] at _F0 + 8 f; horizon edges after
EPA_WORK_SIZE = _E0 + 2 * _NE
"""Length of the ``work`` array :func:`convex_convex_fast` needs for EPA (float64); with a shorter
one it always takes the SAT path."""


@njit(cache=True, inline="always")
def _put_vertex(w, k, pa, pb, ia, ib, rot, ox, oy, oz):  # pragma: no cover - compiled
    o = _V0 + 5 * k
    qx, qy, qz = _b_point(pb, rot, ib)  # B's point as GJK saw it: R_AB pb + o (rot None: pb + o)
    w[o] = pa[ia, 0] - qx - ox
    w[o + 1] = pa[ia, 1] - qy - oy
    w[o + 2] = pa[ia, 2] - qz - oz
    w[o + 3] = ia
    w[o + 4] = ib


@njit(cache=True, inline="always")
def triangle_normal(w, o0, o1, o2):  # pragma: no cover - compiled
    """Unit normal ``(nx, ny, nz, ok)`` of the triangle whose corners are ``w[o0:o0+3]``,
    ``w[o1:o1+3]``, ``w[o2:o2+3]`` (right-handed: ``(v1 - v0) x (v2 - v0)``); ``ok`` False when it
    is degenerate.  Shared by both EPA variants (vertex graphs here, support functions in
    ``_pair_cylinder``)."""
    ux = w[o1] - w[o0]
    uy = w[o1 + 1] - w[o0 + 1]
    uz = w[o1 + 2] - w[o0 + 2]
    vx = w[o2] - w[o0]
    vy = w[o2 + 1] - w[o0 + 1]
    vz = w[o2 + 2] - w[o0 + 2]
    nx = uy * vz - uz * vy
    ny = uz * vx - ux * vz
    nz = ux * vy - uy * vx
    nn = math.sqrt(nx * nx + ny * ny + nz * nz)
    if not nn > 0.0:
        return 0.0, 0.0, 0.0, False
    return nx / nn, ny / nn, nz / nn, True


@njit(cache=True, inline="always")
def _put_face(w, f, i0, i1, i2, slack=0.0):  # pragma: no cover - compiled
    """Face ``f`` = triangle ``(i0, i1, i2)`` (counter-clockwise seen from outside).  Returns
    False when it is degenerate (no normal) or its plane does not have the origin inside (by more
    than ``slack``, m: a face of a tetrahedron completed about a touching contact may pass that
    close the other side of the origin; its distance is then taken as 0)."""
    o0 = _V0 + 5 * i0
    nx, ny, nz, ok = triangle_normal(w, o0, _V0 + 5 * i1, _V0 + 5 * i2)
    if not ok:
        return False
    d = nx * w[o0] + ny * w[o0 + 1] + nz * w[o0 + 2]
    if d < -slack:
        return False
    d = max(d, 0.0)
    o = _F0 + 8 * f
    w[o] = i0
    w[o + 1] = i1
    w[o + 2] = i2
    w[o + 3] = nx
    w[o + 4] = ny
    w[o + 5] = nz
    w[o + 6] = d
    w[o + 7] = 1.0
    return True


@njit(cache=True, inline="always")
def _horizon_edge(w, ne, a, b):  # pragma: no cover - compiled
    """Add the directed edge ``a -> b`` of a removed face to the horizon list, or cancel it against
    ``b -> a`` (shared by two removed faces).  Returns the new count, ``-1`` when the list is full."""
    for k in range(ne):
        o = _E0 + 2 * k
        if w[o] == b and w[o + 1] == a:
            last = _E0 + 2 * (ne - 1)
            w[o] = w[last]
            w[o + 1] = w[last + 1]
            return ne - 1
    if ne == _NE:
        return -1
    o = _E0 + 2 * ne
    w[o] = a
    w[o + 1] = b
    return ne + 1


@njit(cache=True, inline="always")
def _kept(kept, d, nx, ny, nz, ax, ay, az, bx, by, bz):  # pragma: no cover - compiled
    """EPA's answer when rounding stops it: the face kept once its bracket was within
    ``EPA_BRACKET``, else not settled."""
    if kept:
        return True, d, nx, ny, nz, ax, ay, az, bx, by, bz
    return False, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0


@njit(cache=True, inline="always")
def _barycentric(work, j0, j1, j2, px, py, pz):  # pragma: no cover - compiled
    """``(ok, l0, l1, l2)``: barycentric coordinates of the point ``p`` (in the face's plane) in the face
    ``(j0, j1, j2)`` of the expanding polytope; ``ok`` False for a degenerate face."""
    o0 = _V0 + 5 * j0
    o1 = _V0 + 5 * j1
    o2 = _V0 + 5 * j2
    e0x = work[o1] - work[o0]
    e0y = work[o1 + 1] - work[o0 + 1]
    e0z = work[o1 + 2] - work[o0 + 2]
    e1x = work[o2] - work[o0]
    e1y = work[o2 + 1] - work[o0 + 1]
    e1z = work[o2 + 2] - work[o0 + 2]
    px -= work[o0]
    py -= work[o0 + 1]
    pz -= work[o0 + 2]
    d00 = e0x * e0x + e0y * e0y + e0z * e0z
    d01 = e0x * e1x + e0y * e1y + e0z * e1z
    d11 = e1x * e1x + e1y * e1y + e1z * e1z
    d20 = px * e0x + py * e0y + pz * e0z
    d21 = px * e1x + py * e1y + pz * e1z
    den = d00 * d11 - d01 * d01
    if not den > 0.0:
        return False, 0.0, 0.0, 0.0
    l1 = (d11 * d20 - d01 * d21) / den
    l2 = (d00 * d21 - d01 * d20) / den
    return True, 1.0 - l1 - l2, l1, l2


@njit(cache=True, inline="always")
def _face_witnesses(work, nf, j0, j1, j2, dbest, nx, ny, nz, pa, pb, rot, ox, oy, oz):  # pragma: no cover - compiled
    """The witnesses on the cores of the face ``(j0, j1, j2)`` at distance ``dbest`` along ``n``:
    the origin's projection ``dbest n`` onto the face, in barycentric coordinates of its support
    pairs.  ``(ok, ax, ay, az, bx, by, bz, j0, j1, j2)``; ``ok`` False for a degenerate face.

    Where a facet of ``M`` is a polygon split into coplanar triangles (an edge of one core flat on a
    face of the other), the closest triangle by distance may not be the one holding the projection:
    its weights then extrapolate, and the witness left the core along one of its edges (rover's
    link 3 on the chassis, 5.85 mm beyond the edge's end).  The live faces in the same plane (within
    ``_COPLANAR``) are then searched for the one that holds the projection, whose weights are all
    >= ``-_COPLANAR_WEIGHT``; ``j0 .. j2`` return the face used."""
    px = dbest * nx
    py = dbest * ny
    pz = dbest * nz
    ok, l0, l1, l2 = _barycentric(work, j0, j1, j2, px, py, pz)
    if not ok:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, j0, j1, j2
    if min(l0, l1, l2) < -_COPLANAR_WEIGHT:
        for f in range(nf):
            o = _F0 + 8 * f
            if (abs(work[o + 6] - dbest) <= _COPLANAR
                    and work[o + 3] * nx + work[o + 4] * ny + work[o + 5] * nz >= 1.0 - _COPLANAR_WEIGHT):
                k0, k1, k2 = int(work[o]), int(work[o + 1]), int(work[o + 2])
                good, m0, m1, m2 = _barycentric(work, k0, k1, k2, px, py, pz)
                if good and min(m0, m1, m2) >= -_COPLANAR_WEIGHT:
                    j0, j1, j2, l0, l1, l2 = k0, k1, k2, m0, m1, m2
                    break
    ax = ay = az = bx = by = bz = 0.0
    for k in range(3):
        j = j0 if k == 0 else (j1 if k == 1 else j2)
        lam = l0 if k == 0 else (l1 if k == 1 else l2)
        ka = int(work[_V0 + 5 * j + 3])
        kb = int(work[_V0 + 5 * j + 4])
        ax += lam * pa[ka, 0]
        ay += lam * pa[ka, 1]
        az += lam * pa[ka, 2]
        qx, qy, qz = _b_point(pb, rot, kb)
        bx += lam * qx
        by += lam * qy
        bz += lam * qz
    return True, ax, ay, az, bx + ox, by + oy, bz + oz, j0, j1, j2


@njit(cache=True, _nrt=False)
def epa_depth(pa, adja, pb, adjb, work, eps, rot=None, ox=0.0, oy=0.0, oz=0.0, taba=None, tabb=None,
              cap=-math.inf):  # pragma: no cover - compiled
    """EPA on ``M = hull(pa) - hull(pb)`` from the tetrahedron GJK left in ``work[0:9]``.

    ``adja``, ``adjb``: vertex graphs (``_pack.polytope_adjacency`` format; empty: scan);
    ``eps`` (m): stop when the support value along the closest face's normal exceeds the face's
    distance by at most this.  Returns ``(ok, depth, nx, ny, nz, ax, ay, az, bx, by, bz)``:
    moving B by ``depth * n`` makes the cores touch (``n`` the outward normal of ``M``'s facet);
    ``a`` and ``b`` the witness points on the cores (``a - b = depth * n`` to rounding).
    ``ok`` False: EPA did not settle it (see the module docstring), the rest is meaningless.

    ``rot`` (``R_AB`` row-major, or None), ``o``: B's points are ``R_AB pb + o`` in A's frame, as for
    GJK (``_pair_gjk.gjk_dir_rel``); everything returned is in A's frame.  ``taba``, ``tabb`` (``None``
    or empty: none): the hulls' support tables; each climb starts from the better of the face's
    first vertex and the table's entry for the face normal (``_pair_gjk.warm_start``; on ur3's
    hulls 540 -> 240 dot products per depth).

    ``cap`` (m; ``-inf``: off): the caller only needs the depth when it is at least ``cap``.  Once
    a support value ``h < cap`` is seen (``depth <= h``, see the module docstring) EPA stops and
    returns ``(True, h, n, 0, ...)``: ``h`` an upper bound on the depth below ``cap``, not the depth,
    witnesses not computed.  A depth returned below ``cap`` is therefore a bound in any case.

    A face is removed when the new vertex lies more than ``_VISIBLE`` (1e-14 m) above its plane: with
    every face seen from ``w`` removed (a margin of 0), faces nearly in a plane with ``w`` -- on a
    gripper hull of 4,262 vertices against another of 453 (so101), from 13 of 32 GJK start
    tetrahedra -- were seen by rounding in a set that is no cap, and a new face left the origin
    outside by 15.7 mm: EPA gave up, and the exhaustive SAT took 110 s.  The margin is below
    ``eps``, so a face kept by it changes the depth by less than the stopping test allows.

    When EPA settles the depth on its stopping test, it leaves the facet of ``M`` it ended on in
    ``work[0:9]``: ``work[0] = 2``, ``work[1:4]`` A's and ``work[5:8]`` B's support indices of its three
    vertices (the analytic engine's seed tables start GJK from them at nearby configurations,
    ``armguard_analytic._engine._seeds``); else ``work[0:9]`` is as GJK left it.
    """
    if work.shape[0] < EPA_WORK_SIZE or work[0] != 1.0:
        return False, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    for k in range(4):
        _put_vertex(work, k, pa, pb, int(work[1 + k]), int(work[5 + k]), rot, ox, oy, oz)
    # the tetrahedron's faces, each oriented away from the opposite vertex
    nf = 0
    for t in range(4):
        i0 = (t + 1) % 4
        i1 = (t + 2) % 4
        i2 = (t + 3) % 4
        o0 = _V0 + 5 * i0
        o1 = _V0 + 5 * i1
        o2 = _V0 + 5 * i2
        ot = _V0 + 5 * t
        ux = work[o1] - work[o0]
        uy = work[o1 + 1] - work[o0 + 1]
        uz = work[o1 + 2] - work[o0 + 2]
        vx = work[o2] - work[o0]
        vy = work[o2 + 1] - work[o0 + 1]
        vz = work[o2 + 2] - work[o0 + 2]
        s = ((uy * vz - uz * vy) * (work[ot] - work[o0]) + (uz * vx - ux * vz) * (work[ot + 1] - work[o0 + 1])
             + (ux * vy - uy * vx) * (work[ot + 2] - work[o0 + 2]))
        ok = _put_face(work, nf, i0, i2, i1, _TOUCH) if s > 0.0 else _put_face(work, nf, i0, i1, i2, _TOUCH)
        if not ok:
            return False, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        nf += 1
    nv = 4
    na_t = table_size(taba)
    nb_t = table_size(tabb)
    hmin = math.inf  # the least support value seen: depth <= hmin
    kept = False
    kd = knx = kny = knz = kax = kay = kaz = kbx = kby = kbz = 0.0
    while True:
        # the face closest to the origin
        fi = -1
        dbest = math.inf
        for f in range(nf):
            o = _F0 + 8 * f
            if work[o + 6] < dbest:
                dbest = work[o + 6]
                fi = f
        if fi < 0:
            break
        of = _F0 + 8 * fi
        nx = work[of + 3]
        ny = work[of + 4]
        nz = work[of + 5]
        j0 = int(work[of])
        j1 = int(work[of + 1])
        j2 = int(work[of + 2])
        ha = int(work[_V0 + 5 * j0 + 3])
        hb = int(work[_V0 + 5 * j0 + 4])
        ia = _support(pa, adja, warm_start(pa, taba, na_t, ha, nx, ny, nz), nx, ny, nz)
        ex, ey, ez = _b_dir(rot, -nx, -ny, -nz)
        ib = _support(pb, adjb, warm_start(pb, tabb, nb_t, hb, ex, ey, ez), ex, ey, ez)
        qx, qy, qz = _b_point(pb, rot, ib)
        wx = pa[ia, 0] - qx - ox
        wy = pa[ia, 1] - qy - oy
        wz = pa[ia, 2] - qz - oz
        h = nx * wx + ny * wy + nz * wz
        repeated = False
        for j in (j0, j1, j2):
            if work[_V0 + 5 * j + 3] == ia and work[_V0 + 5 * j + 4] == ib:
                repeated = True
        if h < hmin:
            hmin = h
        if hmin < cap:  # depth <= hmin < cap: the caller's cut-off is proved, the depth is not wanted
            return True, hmin, nx, ny, nz, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        if h - dbest <= eps or repeated:
            ok, ax, ay, az, bx, by, bz, j0, j1, j2 = _face_witnesses(work, nf, j0, j1, j2, dbest, nx, ny, nz, pa, pb,
                                                                     rot, ox, oy, oz)
            if not ok:
                break
            for k, j in enumerate((j0, j1, j2)):  # the face, for a seed table (see the docstring)
                work[1 + k] = work[_V0 + 5 * j + 3]
                work[5 + k] = work[_V0 + 5 * j + 4]
            work[0] = 2.0
            return True, dbest, nx, ny, nz, ax, ay, az, bx, by, bz
        if hmin - dbest <= EPA_BRACKET:  # kept in case rounding stops EPA before eps
            ok, ax, ay, az, bx, by, bz, _j0, _j1, _j2 = _face_witnesses(work, nf, j0, j1, j2, dbest, nx, ny, nz, pa, pb,
                                                                        rot, ox, oy, oz)
            if ok:
                kept = True
                kd, knx, kny, knz, kax, kay, kaz, kbx, kby, kbz = dbest, nx, ny, nz, ax, ay, az, bx, by, bz
        if nv == _NV:
            break
        for k in range(nv):  # w beyond the face yet already a vertex: rounding has broken convexity
            if work[_V0 + 5 * k + 3] == ia and work[_V0 + 5 * k + 4] == ib:
                return _kept(kept, kd, knx, kny, knz, kax, kay, kaz, kbx, kby, kbz)
        _put_vertex(work, nv, pa, pb, ia, ib, rot, ox, oy, oz)
        # remove the faces seen from w (the last face moves into a removed one's slot, so the faces
        # stay packed and the scans above read live faces only: on ur3's and so101's hulls, where the
        # dead faces were kept until the slots ran out, EPA took 25-30 % longer); their unshared
        # edges form the horizon
        ne = 0
        f = 0
        while f < nf:
            o = _F0 + 8 * f
            if work[o + 3] * wx + work[o + 4] * wy + work[o + 5] * wz - work[o + 6] > _VISIBLE:
                a0 = work[o]
                a1 = work[o + 1]
                a2 = work[o + 2]
                ne = _horizon_edge(work, ne, a0, a1)
                if ne >= 0:
                    ne = _horizon_edge(work, ne, a1, a2)
                if ne >= 0:
                    ne = _horizon_edge(work, ne, a2, a0)
                if ne < 0:
                    return _kept(kept, kd, knx, kny, knz, kax, kay, kaz, kbx, kby, kbz)
                nf -= 1  # the last face into this slot (the faces stay packed: every slot live)
                ol = _F0 + 8 * nf
                for q in range(8):
                    work[o + q] = work[ol + q]
            else:
                f += 1
        if ne < 3:
            break
        if nf + ne > _NF:
            break
        for k in range(ne):
            o = _E0 + 2 * k
            # a face through a vertex the origin sits on (an exact vertex contact) has a plane distance
            # of -0.0 or -1e-17 by rounding: within eps it is 0, not an origin outside
            if not _put_face(work, nf, int(work[o]), int(work[o + 1]), nv, eps):
                return _kept(kept, kd, knx, kny, knz, kax, kay, kaz, kbx, kby, kbz)
            nf += 1
        nv += 1
    return _kept(kept, kd, knx, kny, knz, kax, kay, kaz, kbx, kby, kbz)


@njit(cache=True)
def _tri_axis(p, tri, t, pa, pb, depth, nx, ny, nz):  # pragma: no cover - compiled
    """The SAT axis of triangle ``t`` of ``tri`` (points ``p``), skipped when degenerate."""
    i0 = tri[t, 0]
    i1 = tri[t, 1]
    i2 = tri[t, 2]
    ux = p[i1, 0] - p[i0, 0]
    uy = p[i1, 1] - p[i0, 1]
    uz = p[i1, 2] - p[i0, 2]
    vx = p[i2, 0] - p[i0, 0]
    vy = p[i2, 1] - p[i0, 1]
    vz = p[i2, 2] - p[i0, 2]
    cx = uy * vz - uz * vy
    cy = uz * vx - ux * vz
    cz = ux * vy - uy * vx
    cn = math.sqrt(cx * cx + cy * cy + cz * cz)
    if cn > 0.0:
        return _axis(pa, pb, cx / cn, cy / cn, cz / cn, depth, nx, ny, nz)
    return depth, nx, ny, nz


@njit(cache=True)
def _edge_axes(e1x, e1y, e1z, pb, eb, adjb, pa, depth, nx, ny, nz, eps_par):  # pragma: no cover - compiled
    """The SAT axes ``e1 x e2`` for every edge direction ``e2`` of B: the rows of ``eb``, then the
    edges ``i < j`` of its vertex graph ``adjb`` (unit ``e1``; near-parallel pairs skipped)."""
    nb = pb.shape[0] if adjb.shape[0] > 0 else 0
    for k in range(eb.shape[0] + nb):
        if k < eb.shape[0]:
            depth, nx, ny, nz = _cross_axis(e1x, e1y, e1z, eb[k, 0], eb[k, 1], eb[k, 2], pa, pb, depth, nx, ny, nz, eps_par)
            continue
        i = k - eb.shape[0]
        for q in range(adjb[6 + i], adjb[7 + i]):
            j = adjb[q]
            if j <= i:
                continue
            ex = pb[j, 0] - pb[i, 0]
            ey = pb[j, 1] - pb[i, 1]
            ez = pb[j, 2] - pb[i, 2]
            en = math.sqrt(ex * ex + ey * ey + ez * ez)
            if en > 0.0:
                depth, nx, ny, nz = _cross_axis(e1x, e1y, e1z, ex / en, ey / en, ez / en, pa, pb, depth, nx, ny, nz,
                                                eps_par)
    return depth, nx, ny, nz


@njit(cache=True)
def _cross_axis(e1x, e1y, e1z, e2x, e2y, e2z, pa, pb, depth, nx, ny, nz, eps_par):  # pragma: no cover
    ux = e1y * e2z - e1z * e2y
    uy = e1z * e2x - e1x * e2z
    uz = e1x * e2y - e1y * e2x
    un = math.sqrt(ux * ux + uy * uy + uz * uz)
    if un <= eps_par:
        return depth, nx, ny, nz
    return _axis(pa, pb, ux / un, uy / un, uz / un, depth, nx, ny, nz)


@njit(cache=True)
def sat_depth_graph(pa, fa, ea, adja, tria, pb, fb, eb, adjb, trib, eps_par):  # pragma: no cover - compiled
    """:func:`._pair_sat.sat_depth` (the exhaustive SAT, same outputs) over the face normals
    ``fa`` and the normals of the triangles ``tria`` (indices into ``pa``) as A's faces, the edge
    directions ``ea`` and the edges of the vertex graph ``adja`` as A's edges; likewise B.  A
    triangulated hull's triangle normals are its face normals and its graph's edges include its
    edges, so the axes include every facet normal of ``A - B``: the depth is exact (extra axes,
    each a valid separating direction, cannot lower it)."""
    depth = math.inf
    nx = 0.0
    ny = 0.0
    nz = 1.0
    for i in range(fa.shape[0]):
        depth, nx, ny, nz = _axis(pa, pb, fa[i, 0], fa[i, 1], fa[i, 2], depth, nx, ny, nz)
    for t in range(tria.shape[0]):
        depth, nx, ny, nz = _tri_axis(pa, tria, t, pa, pb, depth, nx, ny, nz)
    for i in range(fb.shape[0]):
        depth, nx, ny, nz = _axis(pa, pb, fb[i, 0], fb[i, 1], fb[i, 2], depth, nx, ny, nz)
    for t in range(trib.shape[0]):
        depth, nx, ny, nz = _tri_axis(pb, trib, t, pa, pb, depth, nx, ny, nz)
    for k in range(ea.shape[0]):
        depth, nx, ny, nz = _edge_axes(ea[k, 0], ea[k, 1], ea[k, 2], pb, eb, adjb, pa, depth, nx, ny, nz, eps_par)
    if adja.shape[0] > 0:
        for i in range(pa.shape[0]):
            for q in range(adja[6 + i], adja[7 + i]):
                j = adja[q]
                if j <= i:
                    continue
                ex = pa[j, 0] - pa[i, 0]
                ey = pa[j, 1] - pa[i, 1]
                ez = pa[j, 2] - pa[i, 2]
                en = math.sqrt(ex * ex + ey * ey + ez * ez)
                if en > 0.0:
                    depth, nx, ny, nz = _edge_axes(ex / en, ey / en, ez / en, pb, eb, adjb, pa, depth, nx, ny, nz, eps_par)
    return depth, nx, ny, nz


@njit(cache=True)
def _sat_path(pa, fa, ea, adja, tria, ra, pb, fb, eb, adjb, trib, rb, out, work, eps_len, eps_par, gjk_eps, max_iter,
              offset):  # pragma: no cover - compiled
    """The exhaustive-SAT path of :func:`._pair_sat.convex_convex_at` (after GJK found the cores
    overlapping or touching) with :func:`sat_depth_graph`'s axes: depth, then witnesses from GJK on
    the cores with B pushed out along the axis by the depth plus ``offset``."""
    depth, nx, ny, nz = sat_depth_graph(pa, fa, ea, adja, tria, pb, fb, eb, adjb, trib, eps_par)
    if not depth < math.inf:
        depth = 0.0  # no axis at all: point cores that coincide
    if depth < 0.0:
        # GJK stopped within its tolerance of touching but an axis shows a positive gap: the
        # cores are disjoint; report them apart (the sign agrees with intersects())
        gap = -depth
        status2, d2, ax, ay, az, bx, by, bz = gjk_core(
            pa, pb, offset * nx, offset * ny, offset * nz, work, eps_len, gjk_eps, max_iter
        )
        if status2 == GJK_NOT_CONVERGED:
            return 0.0, status2
        return write_rounded(ax, ay, az, ra, bx - offset * nx, by - offset * ny, bz - offset * nz, rb, nx, ny, nz, gap,
                             out, 0), GJK_SEPARATED
    shift = depth + offset
    status2, d2, ax, ay, az, bx, by, bz = gjk_core(
        pa, pb, shift * nx, shift * ny, shift * nz, work, eps_len, gjk_eps, max_iter
    )
    if status2 == GJK_NOT_CONVERGED:
        return 0.0, status2
    return write_rounded(ax, ay, az, ra, bx - shift * nx, by - shift * ny, bz - shift * nz, rb, nx, ny, nz, -depth,
                         out, 0), GJK_INTERSECTING


@njit(cache=True)
def convex_convex_fast(
    pa, fa, ea, adja, tria, ra, pb, fb, eb, adjb, trib, rb, out, work, eps_len, eps_par, gjk_eps, max_iter, offset, level
):  # pragma: no cover - compiled
    """:func:`._pair_sat.convex_convex` (same outputs and statuses) with GJK climbing the vertex
    graphs ``adja``, ``adjb`` (empty: scan), the penetration depth by EPA (:func:`epa_depth`,
    within ``gjk_eps`` of the SAT's) when ``work`` holds ``EPA_WORK_SIZE`` floats, and the
    exhaustive SAT (:func:`sat_depth_graph`) where EPA does not settle it.  Core A: points ``pa``,
    face normals ``fa``, edge directions ``ea`` (see ``sat_depth``), graph ``adja`` and triangles
    ``tria`` (``hull_graph``; a hull may give either or both), radius ``ra``; likewise B.

    ``level`` (m): the caller only needs to know whether the distance is <= ``level`` (``-inf``:
    the distance itself is wanted).  When GJK proves the cores farther apart than
    ``level + ra + rb`` it stops there and returns an upper bound on the distance (> ``level``).  When GJK finds the cores overlapping (origin inside a
    tetrahedron) and ``-(ra + rb) <= level``, it returns ``-(ra + rb)`` (an upper bound on the
    signed distance) with a point of A's core as both core witnesses, without a depth.
    """
    dx, dy, dz = inner_difference(pa, adja, pb, adjb)
    simp = work[0:9]
    # yes/no (level > -inf): GJK may stop once the core distance is proved above level + ra + rb
    # (the signed distance, core distance - ra - rb, then exceeds level)
    sep = level + (ra + rb) if level > -math.inf else math.inf
    status, d, ax, ay, az, bx, by, bz = gjk_dir_adj2(
        pa, adja, pb, adjb, 0.0, 0.0, 0.0, dx, dy, dz,
        eps_len, gjk_eps, max_iter, simp, max(sep, 0.0),
    )
    if status == GJK_SEPARATED:
        return write_rounded(ax, ay, az, ra, bx, by, bz, rb, (bx - ax) / d, (by - ay) / d, (bz - az) / d, d, out, 0), status
    if status == GJK_NOT_CONVERGED:
        return 0.0, status
    if simp[0] == 1.0:  # the origin is inside a tetrahedron of M: the cores overlap
        if -(ra + rb) <= level:
            # a point of A's core as both core witnesses (p_WB - p_WA = distance * nhat holds)
            return write_rounded(ax, ay, az, ra, ax, ay, az, rb, 0.0, 0.0, 1.0, 0.0, out, 0), GJK_INTERSECTING
        ok, depth, nx, ny, nz, ax, ay, az, bx, by, bz = epa_depth(pa, adja, pb, adjb, work, gjk_eps)
        if ok:  # settled, a depth below eps_len included (iiwa's hulls 1e-13 m deep: the SAT took 0.55 s)
            return write_rounded(ax, ay, az, ra, bx, by, bz, rb, nx, ny, nz, -depth, out, 0), GJK_INTERSECTING
    elif simp[0] < 0.0:  # touching: the origin within eps_len of a smaller simplex of M
        if d - (ra + rb) <= level:  # the signed distance is at most d - ra - rb: an upper bound will do
            gx, gy, gz = 0.0, 0.0, 1.0
            if d > 0.0:  # |b - a| = d: the witnesses' own direction (p_WB - p_WA = distance * nhat holds)
                gx, gy, gz = (bx - ax) / d, (by - ay) / d, (bz - az) / d
            return write_rounded(ax, ay, az, ra, bx, by, bz, rb, gx, gy, gz, d, out, 0), GJK_INTERSECTING
        if complete_simplex(pa, adja, pb, adjb, work, eps_len):
            ok, depth, nx, ny, nz, ax, ay, az, bx, by, bz = epa_depth(pa, adja, pb, adjb, work, gjk_eps)
            if ok:  # settled, a depth of about 0 included (the cores touch)
                return write_rounded(ax, ay, az, ra, bx, by, bz, rb, nx, ny, nz, -depth, out, 0), GJK_INTERSECTING
    return _sat_path(pa, fa, ea, adja, tria, ra, pb, fb, eb, adjb, trib, rb, out, work, eps_len, eps_par, gjk_eps,
                     max_iter, offset)
