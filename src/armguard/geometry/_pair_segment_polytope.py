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
"""

from __future__ import annotations

import math

from numba import njit

from ._pair_gjk import GJK_INTERSECTING, GJK_NOT_CONVERGED, GJK_SEPARATED, gjk_dir
from ._pair_segment_segment import write_rounded

__all__ = ["segment_polytope_depth", "capsule_polytope_at", "capsule_polytope_packed"]


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
    dx = p1x - p0x
    dy = p1y - p0y
    dz = p1z - p0z
    ld = math.sqrt(dx * dx + dy * dy + dz * dz)
    depth = math.inf
    qx = 0.0
    qy = 0.0
    qz = 1.0
    for f in range(planes.shape[0]):
        nx = planes[f, 0]
        ny = planes[f, 1]
        nz = planes[f, 2]
        s = min(nx * p0x + ny * p0y + nz * p0z, nx * p1x + ny * p1y + nz * p1z)
        g = planes[f, 3] - s
        if g < depth:
            depth = g
            qx = nx
            qy = ny
            qz = nz
    if ld <= eps_len:
        return depth, qx, qy, qz  # a point core: the faces are all the facets
    near_parallel = math.sqrt(eps_par)
    for k in range(edges.shape[0]):
        f1 = edges[k, 2]
        f2 = edges[k, 3]
        c1 = dx * planes[f1, 0] + dy * planes[f1, 1] + dz * planes[f1, 2]
        c2 = dx * planes[f2, 0] + dy * planes[f2, 1] + dz * planes[f2, 2]
        if c1 * c2 > 0.0:
            continue  # the circle d . u = 0 misses the edge's normal arc: no facet
        i0 = edges[k, 0]
        i1 = edges[k, 1]
        vx = verts[i0, 0]
        vy = verts[i0, 1]
        vz = verts[i0, 2]
        ex = verts[i1, 0] - vx
        ey = verts[i1, 1] - vy
        ez = verts[i1, 2] - vz
        ux = dy * ez - dz * ey
        uy = dz * ex - dx * ez
        uz = dx * ey - dy * ex
        un = math.sqrt(ux * ux + uy * uy + uz * uz)
        le = math.sqrt(ex * ex + ey * ey + ez * ez)
        if un <= eps_par * ld * le or un == 0.0:
            continue  # parallel: the facets are the adjacent faces, already counted
        if ux * bis[k, 0] + uy * bis[k, 1] + uz * bis[k, 2] < 0.0:
            un = -un
        ux /= un
        uy /= un
        uz /= un
        h = ux * vx + uy * vy + uz * vz
        if un < near_parallel * ld * le and un > -near_parallel * ld * le:
            for i in range(verts.shape[0]):
                h = max(h, ux * verts[i, 0] + uy * verts[i, 1] + uz * verts[i, 2])
        g = h - (ux * p0x + uy * p0y + uz * p0z)
        if g < depth:
            depth = g
            qx = ux
            qy = uy
            qz = uz
    return depth, qx, qy, qz


@njit(cache=True)
def capsule_polytope_at(
    seg, ra, verts, planes, edges, bis, cen, rb, out, base, eps_len, eps_par, gjk_eps, max_iter, offset
):  # pragma: no cover - compiled
    """Signed distance of capsule A (core ``seg (2, 3)`` m: its end points, equal for a sphere;
    radius ``ra``) and polytope B (``verts, planes, edges, bis`` as ``_pack.polytope_data``,
    vertex centroid ``cen (3,)``, radius ``rb``).  Writes ``out[base:base + 9]`` =
    ``[p_WA, p_WB, nhat_AB_W]``; returns ``(distance, status)`` (``GJK_*``; callers raise on
    ``GJK_NOT_CONVERGED``).  ``offset`` is ``Tolerances.penetration_witness_offset``.
    """
    p0x = seg[0, 0]
    p0y = seg[0, 1]
    p0z = seg[0, 2]
    p1x = seg[1, 0]
    p1y = seg[1, 1]
    p1z = seg[1, 2]
    status, d, ax, ay, az, bx, by, bz = gjk_dir(
        seg, verts, 0.0, 0.0, 0.0,
        0.5 * (p0x + p1x) - cen[0], 0.5 * (p0y + p1y) - cen[1], 0.5 * (p0z + p1z) - cen[2],
        eps_len, gjk_eps, max_iter,
    )
    if status == GJK_SEPARATED:
        return write_rounded(ax, ay, az, ra, bx, by, bz, rb, (bx - ax) / d, (by - ay) / d, (bz - az) / d, d, out, base), status
    if status == GJK_NOT_CONVERGED:
        return 0.0, status
    depth, qx, qy, qz = segment_polytope_depth(p0x, p0y, p0z, p1x, p1y, p1z, verts, planes, edges, bis, eps_len, eps_par)
    depth = max(depth, 0.0)
    # B moves along nhat = -q; the cores are then `offset` apart along q
    shift = depth + offset
    status2, _d2, ax, ay, az, bx, by, bz = gjk_dir(
        seg, verts, -shift * qx, -shift * qy, -shift * qz, qx, qy, qz, eps_len, gjk_eps, max_iter
    )
    if status2 == GJK_NOT_CONVERGED:
        return 0.0, status2
    bx += shift * qx
    by += shift * qy
    bz += shift * qz
    return write_rounded(ax, ay, az, ra, bx, by, bz, rb, -qx, -qy, -qz, -depth, out, base), GJK_INTERSECTING


@njit(cache=True)
def capsule_polytope_packed(
    a, verts, planes, edges, bis, cen, rb, out, eps_len, eps_par, gjk_eps, max_iter, offset
):  # pragma: no cover - compiled
    """Capsule ``[p0, p1, r]`` (7,) against a polytope: the single-call path (see
    :func:`capsule_polytope_at`)."""
    return capsule_polytope_at(a[0:6].reshape((2, 3)), a[6], verts, planes, edges, bis, cen, rb, out, 0, eps_len, eps_par, gjk_eps, max_iter, offset)
