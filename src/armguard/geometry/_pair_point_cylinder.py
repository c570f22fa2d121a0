"""Signed distance of a sphere-swept point (a Sphere) and a cylinder, in closed form.

The distance from a point ``p`` to the solid right circular cylinder ``C`` (centre ``c``, unit axis
``a``, radius ``r``, half length ``h``) is that to its nearest point: with ``p - c`` split into the
axial coordinate ``s = a . (p - c)`` and the radial part ``w`` (``rho = |w|``), the nearest point of
``C`` is ``c + min(1, r / rho) w + clamp(s, -h, h) a`` (Ericson, *Real-Time Collision Detection*
§5.1: a closest point on a convex set is the clamped coordinates where the set is a product of
intervals, here a disk times a segment).  Inside ``C`` the nearest boundary point is on the wall
(``r - rho`` away, radially) or on the nearer cap (``h - |s|``), whichever is nearer.  A sphere of
radius ``rp`` around ``p`` against ``C`` swept by ``rb`` is then ``d(p, C) - rp - rb`` apart (the
depth when negative: the swept sets' distance function is ``d(p, C) - rb`` outside ``C`` and
``-(depth to the boundary) - rb`` inside).  The general cylinder kernels (``_pair_cylinder``: GJK and
EPA on support functions) answer the same to their tolerance wherever EPA settles a depth (for a
sphere deep on the axis it may not, and reports the cores touching: ``-(rp + rb)``, an upper
bound); this one is exact to rounding and has no iterations (``tests/test_geometry_point_cylinder.py``
holds them together).
"""

from __future__ import annotations

import math

from numba import njit

from ._pair_segment_segment import write_rounded

__all__ = ["point_cylinder_flat"]


@njit(cache=True, inline="always")
def point_cylinder_flat(px, py, pz, rp, cyl, o, rb, out, base):  # pragma: no cover - compiled
    """Signed distance (m) of the sphere ``(p, rp)`` (A) and the cylinder whose 15-float buffer
    ``[c, r, r, h, R_WC row-major]`` (the axis its third column, ``_pair_cylinder``'s layout) starts
    at ``cyl[o]``, swept by ``rb`` (B).  Writes ``out[base:base + 9] = [p_WA, p_WB, nhat_AB_W]``
    (as :func:`._pair_segment_segment.write_rounded`: ``p_WB = p_WA + distance nhat``)."""
    cx = cyl[o]
    cy = cyl[o + 1]
    cz = cyl[o + 2]
    r = cyl[o + 3]
    h = cyl[o + 5]
    ux, uy, uz = cyl[o + 6], cyl[o + 9], cyl[o + 12]  # x_C, y_C, a: the columns of R_WC
    vx, vy, vz = cyl[o + 7], cyl[o + 10], cyl[o + 13]
    ax, ay, az = cyl[o + 8], cyl[o + 11], cyl[o + 14]
    dx = px - cx
    dy = py - cy
    dz = pz - cz
    u = ux * dx + uy * dy + uz * dz
    v = vx * dx + vy * dy + vz * dz
    s = ax * dx + ay * dy + az * dz
    rho = math.sqrt(u * u + v * v)
    if rho <= r and abs(s) <= h:  # p in the solid cylinder: out through the wall or the nearer cap
        side = 1.0 if s >= 0.0 else -1.0
        if r - rho <= h - abs(s):
            m = r - rho
            if rho > 0.0:
                nx = (u * ux + v * vx) / rho
                ny = (u * uy + v * vy) / rho
                nz = (u * uz + v * vz) / rho
            else:
                nx, ny, nz = ux, uy, uz
        else:
            m = h - abs(s)
            nx, ny, nz = side * ax, side * ay, side * az
        # n: the outward normal of that feature; the nearest boundary point is p + m n, and A's
        # normal towards B is -n (as the separated case's, continuously across the surface)
        return write_rounded(px, py, pz, rp, px + m * nx, py + m * ny, pz + m * nz, rb, -nx, -ny, -nz, -m, out, base)
    k = r / rho if rho > r else 1.0
    sc = min(max(s, -h), h)
    qx = cx + k * (u * ux + v * vx) + sc * ax
    qy = cy + k * (u * uy + v * vy) + sc * ay
    qz = cz + k * (u * uz + v * vz) + sc * az
    ex = qx - px
    ey = qy - py
    ez = qz - pz
    d = math.sqrt(ex * ex + ey * ey + ez * ez)  # > 0: p is outside the closed cylinder
    if not d > 0.0:  # on the surface to rounding: the normal of the feature p is beyond
        if rho > r:
            nx, ny, nz = (u * ux + v * vx) / rho, (u * uy + v * vy) / rho, (u * uz + v * vz) / rho
        else:
            side = 1.0 if s >= 0.0 else -1.0
            nx, ny, nz = side * ax, side * ay, side * az
        return write_rounded(px, py, pz, rp, px, py, pz, rb, -nx, -ny, -nz, 0.0, out, base)
    return write_rounded(px, py, pz, rp, qx, qy, qz, rb, ex / d, ey / d, ez / d, d, out, base)
