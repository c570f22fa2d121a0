"""Capsule (or sphere) against a sphere-swept convex polytope: GJK apart, Minkowski facets in contact.

Separated cores: GJK (``_pair_gjk``) on the segment's two end points and the polytope's
vertices, started along the centroid difference.

Penetrating cores.  The penetration depth of two convex sets is the distance from the origin
to the boundary of their Minkowski difference ``M = P - S``; for an interior origin it is
``min`` over the *facets* of ``M`` of the facet plane's distance, and the origin's projection on
the nearest facet plane lies on that facet (for any other facet ``g`` the projected point
satisfies ``n_g . y - o_g <= -dist_g + dist_f <= 0``).  The generic kernel (``_pair_sat``) tries
every candidate axis of the separating-axis theorem (face normals and all edge-direction cross
products, ~90 axes for a 20-vertex hull, each projecting every vertex).  For a segment ``S``
with direction ``d`` the facets of ``M`` are known in closed form (Gauss-map overlay of the
two shapes; Ericson, *Real-Time Collision Detection* §5.5.x, and the SAT candidate list of
Gottschalk, Lin & Manocha 1996 restricted to the pairs whose normal arcs meet):

* every face ``f`` of ``P`` (outward unit ``n``, ``n . x <= o``): moving ``S`` out along ``n``
  takes ``o - min(n . p0, n . p1)``;
* every edge ``e`` of ``P`` whose arc of outward normals (between its faces' normals ``n1``,
  ``n2``) crosses the great circle ``d . u = 0``, i.e. ``(d . n1) (d . n2) <= 0``: the facet
  normal is ``u = +-(d x e) / |d x e|`` (the sign that points into the arc, ``u . (n1 + n2) > 0``);
  ``S`` projects on ``u`` to the single value ``u . p0`` and ``P``'s support along ``u`` is attained
  at the edge, so moving ``S`` out takes ``u . (v_e - p0)``.

That is ``F`` plus a handful of silhouette edges, each a few flops, instead of ~90 axes times
``V`` vertices.  When ``d`` and ``e`` are within ``sqrt(eps_par)`` of parallel the rounding of
``u`` could take it out of the edge's arc; such an edge's support is then taken over all
vertices (exact for whatever ``u`` was computed).  The witness points then come as in
``_pair_sat``: the segment is moved out along the facet normal by the depth plus
``penetration_witness_offset`` and GJK (started along that normal) finds the closest points.

Cost: the face loop keeps the sign of ``d . n`` of each face (up to ``_MASK_FACES`` faces) in
two bit masks, so an edge off the silhouette is rejected with two bit tests; a polytope with
more faces recomputes the two dot products per edge.  :func:`capsule_polytope_adj_at` (the batch
and single-call paths) also hands GJK the polytope's vertex graph for hill-climbing supports
on hulls of ``CLIMB_MIN_VERTICES`` or more vertices.
"""

from __future__ import annotations

import math

from numba import njit

from ._pair_gjk import CLIMB_MIN_VERTICES, GJK_INTERSECTING, GJK_NOT_CONVERGED, GJK_SEPARATED, _gjk
from ._pair_segment_segment import write_rounded

_MASK_FACES = 64
"""Polytopes with at most this many faces keep the signs of ``d . n_f`` in two int64 bit masks."""

__all__ = ["segment_polytope_depth", "capsule_polytope_at", "capsule_polytope_adj_at", "capsule_polytope_packed"]


@njit(cache=True, inline="always")
def _depth_facets(
    p0x, p0y, p0z, p1x, p1y, p1z, verts, planes, edges, bis, eps_len, eps_par
):  # pragma: no cover - compiled
    """Minimum over the facets of ``P - S``: ``(depth, qx, qy, qz, kind, index)`` with ``kind``
    0 for face ``index`` of P and 1 for the facet of P's edge ``index`` and the segment."""
    dx = p1x - p0x
    dy = p1y - p0y
    dz = p1z - p0z
    dd = dx * dx + dy * dy + dz * dz
    depth = math.inf
    qx = 0.0
    qy = 0.0
    qz = 1.0
    kind = 0
    best = 0
    # signs of d . n_f per face as bit masks (faces 0..63), so that the edge loop below skips
    # the edges off the silhouette (both faces on one side of d) with two bit tests
    nf = planes.shape[0]
    masked = nf <= _MASK_FACES
    pos = 0
    neg = 0
    for f in range(nf):
        nx = planes[f, 0]
        ny = planes[f, 1]
        nz = planes[f, 2]
        g = planes[f, 3] - min(nx * p0x + ny * p0y + nz * p0z, nx * p1x + ny * p1y + nz * p1z)
        if g < depth:
            depth = g
            best = f
        c = dx * nx + dy * ny + dz * nz
        bit = 1 << f
        pos |= bit if c > 0.0 else 0  # selects, not branches: the signs are unpredictable
        neg |= bit if c < 0.0 else 0
    qx = planes[best, 0]
    qy = planes[best, 1]
    qz = planes[best, 2]
    if dd <= eps_len * eps_len:
        return depth, qx, qy, qz, kind, best  # a point core: the faces are all the facets
    par2 = eps_par * eps_par * dd
    near2 = eps_par * dd  # (sqrt(eps_par))^2 |d|^2
    for k in range(edges.shape[0]):
        f1 = edges[k, 2]
        f2 = edges[k, 3]
        if masked:
            if ((pos >> f1) & (pos >> f2) & 1) | ((neg >> f1) & (neg >> f2) & 1):
                continue  # the circle d . u = 0 misses the edge's normal arc: no facet
        else:
            c1 = dx * planes[f1, 0] + dy * planes[f1, 1] + dz * planes[f1, 2]
            c2 = dx * planes[f2, 0] + dy * planes[f2, 1] + dz * planes[f2, 2]
            if c1 * c2 > 0.0:
                continue
        i0 = edges[k, 0]
        i1 = edges[k, 1]
        vx = verts[i0, 0]
        vy = verts[i0, 1]
        vz = verts[i0, 2]
        ex = verts[i1, 0] - vx
        ey = verts[i1, 1] - vy
        ez = verts[i1, 2] - vz
        wx = dy * ez - dz * ey
        wy = dz * ex - dx * ez
        wz = dx * ey - dy * ex
        ww = wx * wx + wy * wy + wz * wz
        ee = ex * ex + ey * ey + ez * ez
        if ww <= par2 * ee or ww == 0.0:
            continue  # parallel: the facets are the adjacent faces, already counted
        if wx * bis[k, 0] + wy * bis[k, 1] + wz * bis[k, 2] < 0.0:
            wx = -wx
            wy = -wy
            wz = -wz
        # g = w . (v - p0) / |w|; decide g < depth without the root where possible
        num = wx * (vx - p0x) + wy * (vy - p0y) + wz * (vz - p0z)
        if ww < near2 * ee:
            # near-parallel: rounding may take w out of the edge's arc; use the true support
            h = -math.inf
            for i in range(verts.shape[0]):
                h = max(h, wx * (verts[i, 0] - p0x) + wy * (verts[i, 1] - p0y) + wz * (verts[i, 2] - p0z))
            num = h
        if num >= depth * math.sqrt(ww):
            continue
        wn = math.sqrt(ww)
        depth = num / wn
        qx = wx / wn
        qy = wy / wn
        qz = wz / wn
        kind = 1
        best = k
    return depth, qx, qy, qz, kind, best


@njit(cache=True)
def segment_polytope_depth(
    p0x, p0y, p0z, p1x, p1y, p1z, verts, planes, edges, bis, eps_len, eps_par
):  # pragma: no cover - compiled
    """Core penetration depth of segment ``p0-p1`` (m) in a polytope, by the facets of ``P - S``.

    ``verts (V, 3)`` m, ``planes (F, 4)`` ``[n, o]``, ``edges (E, 4)`` ``[v0, v1, f1, f2]`` int64,
    ``bis (E, 3)`` (see ``_pack.polytope_data``).  Returns ``(depth, qx, qy, qz)``: moving the
    segment by ``depth * q`` makes the cores touch (``q`` the polytope's outward facet normal);
    ``depth < 0`` when the segment is outside the facet's plane (then ``-depth`` is a lower
    bound on the gap).
    """
    depth, qx, qy, qz, _kind, _best = _depth_facets(
        p0x, p0y, p0z, p1x, p1y, p1z, verts, planes, edges, bis, eps_len, eps_par
    )
    return depth, qx, qy, qz


@njit(cache=True, inline="always")
def _direct_witness(
    p0x, p0y, p0z, p1x, p1y, p1z, verts, planes, edges, depth, qx, qy, qz, kind, best, eps_len
):  # pragma: no cover - compiled
    """Core witnesses ``(ok, ax, ay, az, bx, by, bz)`` read off the nearest facet of ``P - S``:
    the segment point and the polytope point that touch after moving the segment by
    ``depth * q``.  ``ok`` is False when rounding put the point off its facet by more than
    ``eps_len`` (a near tie between almost parallel facets): the caller then solves for them."""
    if kind == 0:
        if planes.shape[0] <= 2:  # a polygon: its two planes bound nothing sideways (a segment across it in its
            return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0  # plane had a witness 1 m off it): the caller solves for them
        # face facet: the segment's lowest end point along q, pushed onto the face's plane
        s0 = qx * p0x + qy * p0y + qz * p0z
        s1 = qx * p1x + qy * p1y + qz * p1z
        if s1 < s0:
            ax, ay, az = p1x, p1y, p1z
        else:
            ax, ay, az = p0x, p0y, p0z
        bx = ax + depth * qx
        by = ay + depth * qy
        bz = az + depth * qz
        worst = -math.inf
        for f in range(planes.shape[0]):
            worst = max(worst, planes[f, 0] * bx + planes[f, 1] * by + planes[f, 2] * bz - planes[f, 3])
        return worst <= eps_len, ax, ay, az, bx, by, bz
    # edge facet: the points of the segment's and the edge's lines that face each other
    # across q (Ericson §5.1.8 closest points of two lines)
    vx = verts[edges[best, 0], 0]
    vy = verts[edges[best, 0], 1]
    vz = verts[edges[best, 0], 2]
    ex = verts[edges[best, 1], 0] - vx
    ey = verts[edges[best, 1], 1] - vy
    ez = verts[edges[best, 1], 2] - vz
    dx = p1x - p0x
    dy = p1y - p0y
    dz = p1z - p0z
    rx = p0x - vx
    ry = p0y - vy
    rz = p0z - vz
    a = dx * dx + dy * dy + dz * dz
    b = dx * ex + dy * ey + dz * ez
    c = ex * ex + ey * ey + ez * ez
    f = ex * rx + ey * ry + ez * rz
    g = dx * rx + dy * ry + dz * rz
    den = a * c - b * b
    s = min(1.0, max(0.0, (b * f - c * g) / den))
    t = min(1.0, max(0.0, (a * f - b * g) / den))
    ax = p0x + s * dx
    ay = p0y + s * dy
    az = p0z + s * dz
    bx = vx + t * ex
    by = vy + t * ey
    bz = vz + t * ez
    mx = bx - ax - depth * qx
    my = by - ay - depth * qy
    mz = bz - az - depth * qz
    return mx * mx + my * my + mz * mz <= eps_len * eps_len, ax, ay, az, bx, by, bz


@njit(cache=True, inline="always")
def capsule_polytope_at(
    seg, ra, verts, planes, edges, bis, cen, rb, out, base, eps_len, eps_par, gjk_eps, max_iter, offset
):  # pragma: no cover - compiled
    """Signed distance of capsule A (core ``seg (2, 3)`` m: its end points, equal for a sphere;
    radius ``ra``) and polytope B (``verts, planes, edges, bis`` as ``_pack.polytope_data``,
    vertex centroid ``cen (3,)``, radius ``rb``).  Writes ``out[base:base + 9]`` =
    ``[p_WA, p_WB, nhat_AB_W]``; returns ``(distance, status)`` (``GJK_*``; callers raise on
    ``GJK_NOT_CONVERGED``).  ``offset`` is ``Tolerances.penetration_witness_offset``.
    B's GJK supports scan its vertices; :func:`capsule_polytope_adj_at` climbs its vertex graph.
    """
    return _capsule_polytope(
        seg, ra, verts, planes, edges, bis, cen, None, rb, out, base, eps_len, eps_par, gjk_eps, max_iter, offset
    )


@njit(cache=True, inline="always")
def capsule_polytope_adj_at(
    seg, ra, verts, planes, edges, bis, cen, adj, rb, out, base, eps_len, eps_par, gjk_eps, max_iter, offset
):  # pragma: no cover - compiled
    """:func:`capsule_polytope_at` with B's vertex graph ``adj`` (``_pack.polytope_adjacency``):
    for a polytope of at least ``CLIMB_MIN_VERTICES`` vertices GJK's supports on B climb the
    graph from the previous support instead of scanning every vertex."""
    if verts.shape[0] < CLIMB_MIN_VERTICES:
        return _capsule_polytope(
            seg, ra, verts, planes, edges, bis, cen, None, rb, out, base, eps_len, eps_par, gjk_eps, max_iter, offset
        )
    return _capsule_polytope(
        seg, ra, verts, planes, edges, bis, cen, adj, rb, out, base, eps_len, eps_par, gjk_eps, max_iter, offset
    )


@njit(cache=True, inline="always")
def _capsule_polytope(
    seg, ra, verts, planes, edges, bis, cen, adj, rb, out, base, eps_len, eps_par, gjk_eps, max_iter, offset
):  # pragma: no cover - compiled
    p0x = seg[0, 0]
    p0y = seg[0, 1]
    p0z = seg[0, 2]
    p1x = seg[1, 0]
    p1y = seg[1, 1]
    p1z = seg[1, 2]
    status, d, ax, ay, az, bx, by, bz = _gjk(
        seg, None, verts, adj, None, 0.0, 0.0, 0.0,
        0.5 * (p0x + p1x) - cen[0], 0.5 * (p0y + p1y) - cen[1], 0.5 * (p0z + p1z) - cen[2],
        eps_len, gjk_eps, max_iter, None,
    )
    if status == GJK_SEPARATED:
        return write_rounded(ax, ay, az, ra, bx, by, bz, rb, (bx - ax) / d, (by - ay) / d, (bz - az) / d, d, out, base), status
    if status == GJK_NOT_CONVERGED:
        return 0.0, status
    depth, qx, qy, qz, kind, best = _depth_facets(p0x, p0y, p0z, p1x, p1y, p1z, verts, planes, edges, bis, eps_len, eps_par)
    depth = max(depth, 0.0)
    ok, ax, ay, az, bx, by, bz = _direct_witness(
        p0x, p0y, p0z, p1x, p1y, p1z, verts, planes, edges, depth, qx, qy, qz, kind, best, eps_len
    )
    if ok:
        return write_rounded(ax, ay, az, ra, bx, by, bz, rb, -qx, -qy, -qz, -depth, out, base), GJK_INTERSECTING
    # B moves along nhat = -q; the cores are then `offset` apart along q
    shift = depth + offset
    status2, _d2, ax, ay, az, bx, by, bz = _gjk(
        seg, None, verts, adj, None, -shift * qx, -shift * qy, -shift * qz, qx, qy, qz, eps_len, gjk_eps, max_iter, None
    )
    if status2 == GJK_NOT_CONVERGED:
        return 0.0, status2
    bx += shift * qx
    by += shift * qy
    bz += shift * qz
    return write_rounded(ax, ay, az, ra, bx, by, bz, rb, -qx, -qy, -qz, -depth, out, base), GJK_INTERSECTING


@njit(cache=True, _nrt=False)
def capsule_polytope_packed(
    a, fbuf, ibuf, out, eps_len, eps_par, gjk_eps, max_iter, offset
):  # pragma: no cover - compiled
    """Capsule ``[p0, p1, r]`` (7,) against a polytope given by its two packed buffers
    (``_pack.polytope_buffers``): the single-call path, three arrays to unbox instead of eight
    (see :func:`capsule_polytope_adj_at`).  No reference counting: it only takes views."""
    nv = ibuf[0]
    nf = ibuf[1]
    ne = ibuf[2]
    i = 3 * nv
    verts = fbuf[0:i].reshape((nv, 3))
    planes = fbuf[i:i + 4 * nf].reshape((nf, 4))
    i += 4 * nf
    bis = fbuf[i:i + 3 * ne].reshape((ne, 3))
    i += 3 * ne
    cen = fbuf[i:i + 3]
    rb = fbuf[i + 3]
    edges = ibuf[3:3 + 4 * ne].reshape((ne, 4))
    adj = ibuf[3 + 4 * ne:]
    return capsule_polytope_adj_at(
        a[0:6].reshape((2, 3)), a[6], verts, planes, edges, bis, cen, adj, rb, out, 0, eps_len, eps_par, gjk_eps,
        max_iter, offset,
    )
