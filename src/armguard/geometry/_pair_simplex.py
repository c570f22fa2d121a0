"""Johnson's distance sub-algorithm for GJK: the point of a simplex (1 to 4 vertices) closest to the
origin, as Ericson's Voronoi-region tests (*Real-Time Collision Detection* §5.1.2-5.1.6,
``ClosestPtPointTriangle`` and ``ClosestPtPointTetrahedron`` with the query point at the origin).
Used by the GJK kernels (``._pair_gjk``) and the cylinder kernels' GJK (``._pair_cylinder``,
``._pair_cylinder_turn``)."""

from __future__ import annotations

import math

from numba import njit

__all__ = ["_closest_simplex", "_closest_tetra", "_closest_triangle", "_origin_outside"]


@njit(cache=True)
def _closest_triangle(ax, ay, az, bx, by, bz, cx, cy, cz):  # pragma: no cover - compiled
    """Ericson ``ClosestPtPointTriangle`` (§5.1.5) with the query point at the origin.

    Returns ``(mask, la, lb, lc, vv)``: the vertices with non-zero weight (bits 1 = a, 2 = b,
    4 = c), their barycentric weights and the squared distance of the closest point.
    """
    abx = bx - ax
    aby = by - ay
    abz = bz - az
    acx = cx - ax
    acy = cy - ay
    acz = cz - az
    d1 = -(abx * ax + aby * ay + abz * az)
    d2 = -(acx * ax + acy * ay + acz * az)
    if d1 <= 0.0 and d2 <= 0.0:
        return 1, 1.0, 0.0, 0.0, ax * ax + ay * ay + az * az
    d3 = -(abx * bx + aby * by + abz * bz)
    d4 = -(acx * bx + acy * by + acz * bz)
    if d3 >= 0.0 and d4 <= d3:
        return 2, 0.0, 1.0, 0.0, bx * bx + by * by + bz * bz
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        v = d1 / (d1 - d3)
        px = ax + v * abx
        py = ay + v * aby
        pz = az + v * abz
        return 3, 1.0 - v, v, 0.0, px * px + py * py + pz * pz
    d5 = -(abx * cx + aby * cy + abz * cz)
    d6 = -(acx * cx + acy * cy + acz * cz)
    if d6 >= 0.0 and d5 <= d6:
        return 4, 0.0, 0.0, 1.0, cx * cx + cy * cy + cz * cz
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        w = d2 / (d2 - d6)
        px = ax + w * acx
        py = ay + w * acy
        pz = az + w * acz
        return 5, 1.0 - w, 0.0, w, px * px + py * py + pz * pz
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        px = bx + w * (cx - bx)
        py = by + w * (cy - by)
        pz = bz + w * (cz - bz)
        return 6, 0.0, 1.0 - w, w, px * px + py * py + pz * pz
    denom = 1.0 / (va + vb + vc)
    v = vb * denom
    w = vc * denom
    px = ax + v * abx + w * acx
    py = ay + v * aby + w * acy
    pz = az + v * abz + w * acz
    return 7, 1.0 - v - w, v, w, px * px + py * py + pz * pz


@njit(cache=True)
def _origin_outside(ax, ay, az, bx, by, bz, cx, cy, cz, dx, dy, dz):  # pragma: no cover
    """True when the origin is not on ``d``'s side of the plane through ``a, b, c`` (Ericson
    ``PointOutsideOfPlane``; a degenerate face, ``d`` on its plane, counts as outside)."""
    ux = bx - ax
    uy = by - ay
    uz = bz - az
    vx = cx - ax
    vy = cy - ay
    vz = cz - az
    nx = uy * vz - uz * vy
    ny = uz * vx - ux * vz
    nz = ux * vy - uy * vx
    sp = -(nx * ax + ny * ay + nz * az)
    sd = nx * (dx - ax) + ny * (dy - ay) + nz * (dz - az)
    return sp * sd < 0.0 or sd == 0.0


@njit(cache=True)
def _closest_tetra(x0, y0, z0, x1, y1, z1, x2, y2, z2, x3, y3, z3):  # pragma: no cover - compiled
    """:func:`_closest_simplex` of a tetrahedron: a plain compiled call (its four inlined triangle
    tests are most of GJK's code; GJK reaches four vertices only near contact)."""
    # tetrahedron (Ericson ClosestPtPointTetrahedron): the best face whose plane separates the
    # origin from the opposite vertex; none means the origin is inside
    best = math.inf
    mask = 15
    l0 = l1 = l2 = l3 = 0.0
    if _origin_outside(x0, y0, z0, x1, y1, z1, x2, y2, z2, x3, y3, z3):
        m, la, lb, lc, vv = _closest_triangle(x0, y0, z0, x1, y1, z1, x2, y2, z2)
        if vv < best:
            best = vv
            mask = m
            l0, l1, l2, l3 = la, lb, lc, 0.0
    if _origin_outside(x0, y0, z0, x2, y2, z2, x3, y3, z3, x1, y1, z1):
        m, la, lb, lc, vv = _closest_triangle(x0, y0, z0, x2, y2, z2, x3, y3, z3)
        if vv < best:
            best = vv
            mask = (m & 1) | ((m & 2) << 1) | ((m & 4) << 1)
            l0, l1, l2, l3 = la, 0.0, lb, lc
    if _origin_outside(x0, y0, z0, x3, y3, z3, x1, y1, z1, x2, y2, z2):
        m, la, lb, lc, vv = _closest_triangle(x0, y0, z0, x3, y3, z3, x1, y1, z1)
        if vv < best:
            best = vv
            mask = (m & 1) | ((m & 2) << 2) | ((m & 4) >> 1)
            l0, l1, l2, l3 = la, lc, 0.0, lb
    if _origin_outside(x1, y1, z1, x3, y3, z3, x2, y2, z2, x0, y0, z0):
        m, la, lb, lc, vv = _closest_triangle(x1, y1, z1, x3, y3, z3, x2, y2, z2)
        if vv < best:
            best = vv
            mask = ((m & 1) << 1) | ((m & 2) << 2) | m & 4
            l0, l1, l2, l3 = 0.0, la, lc, lb
    return mask, l0, l1, l2, l3


@njit(cache=True, inline="always")
def _closest_simplex(n, x0, y0, z0, x1, y1, z1, x2, y2, z2, x3, y3, z3):  # pragma: no cover
    """Johnson's sub-algorithm as Ericson's Voronoi-region tests, on the simplex ``w0 .. w(n-1)``.

    Returns ``(mask, l0, l1, l2, l3)``: bit ``k`` of ``mask`` is set when ``w_k`` keeps a
    non-zero weight ``l_k`` in the point of the simplex closest to the origin; ``mask == 15``
    means the origin is inside the tetrahedron.

    The signed-volume sub-algorithm (Montanari, Petrinic & Barbieri, ACM TOG 36(3) 2017, S1D-S3D)
    was measured against this on the simplices GJK solves on ur3's and so101's hulls: same
    regions, 14-15 ns per triangle against 7 and 39-44 ns per tetrahedron against 30 (the
    projection onto the largest-area plane costs more than Ericson's tests); not used.
    """
    if n == 1:
        return 1, 1.0, 0.0, 0.0, 0.0
    if n == 2:
        ex = x1 - x0
        ey = y1 - y0
        ez = z1 - z0
        ee = ex * ex + ey * ey + ez * ez
        t = -(x0 * ex + y0 * ey + z0 * ez)
        if t <= 0.0 or ee == 0.0:
            return 1, 1.0, 0.0, 0.0, 0.0
        if t >= ee:
            return 2, 0.0, 1.0, 0.0, 0.0
        t = t / ee
        return 3, 1.0 - t, t, 0.0, 0.0
    if n == 3:
        m, la, lb, lc, _vv = _closest_triangle(x0, y0, z0, x1, y1, z1, x2, y2, z2)
        return m, la, lb, lc, 0.0
    return _closest_tetra(x0, y0, z0, x1, y1, z1, x2, y2, z2, x3, y3, z3)
