"""Capsule-box (and sphere-box): exact signed distance between a rounded segment and an OBB.

Separated cores.  In the box frame the segment is ``x(t) = a + t d``, ``t in [0, 1]``, and the
squared distance from ``x(t)`` to the box is ``f(t) = sum_i e_i(t)^2`` with the excess
``e_i = x_i - clamp(x_i, -h_i, h_i)``.  ``f`` is convex and piecewise quadratic; its derivative
``f'(t) / 2 = g(t) = sum_i d_i e_i(t)`` is non-decreasing and piecewise linear with at most six
breakpoints ``t = (+-h_i - a_i) / d_i``.  We bracket the root of ``g`` between breakpoints
(no sorting: each breakpoint inside the current bracket shrinks it) and solve the last linear
piece exactly, so the minimiser is exact up to rounding.

Penetrating cores (the segment meets the box).  The separating-axis theorem over the box's
three face normals ``e_i`` and the three cross products ``d x e_i`` (the segment has no faces)
gives the core penetration depth; we then move the segment out along that axis by the depth
plus a small offset, rerun the closest-point solve (the cores are then separated by exactly the
offset along the axis) and move the segment's witness back.  The radius is then subtracted.
"""

from __future__ import annotations

import math

from numba import njit

from ._pair_segment_segment import write_rounded

__all__ = ["segment_box_closest", "capsule_box", "capsule_box_packed", "capsule_box_scalar"]


@njit(cache=True, inline="always")
def _g(t, ax, ay, az, dx, dy, dz, hx, hy, hz):  # pragma: no cover - compiled
    x = ax + t * dx
    y = ay + t * dy
    z = az + t * dz
    return (
        dx * (x - min(hx, max(-hx, x)))
        + dy * (y - min(hy, max(-hy, y)))
        + dz * (z - min(hz, max(-hz, z)))
    )


@njit(cache=True, inline="always")
def _shrink(tb, lo, glo, hi, ghi, ax, ay, az, dx, dy, dz, hx, hy, hz):  # pragma: no cover
    if tb > lo and tb < hi:
        gb = _g(tb, ax, ay, az, dx, dy, dz, hx, hy, hz)
        if gb <= 0.0:
            return tb, gb, hi, ghi
        return lo, glo, tb, gb
    return lo, glo, hi, ghi


@njit(cache=True, inline="always")
def _crossing(lo, glo, hi, ghi, a, d, h):  # pragma: no cover - compiled
    # breakpoints of coordinate i: t = (-h - a) / d and (h - a) / d
    if d != 0.0:
        return (-h - a) / d, (h - a) / d
    return -1.0, -1.0


@njit(cache=True, inline="always")
def segment_box_closest(ax, ay, az, dx, dy, dz, hx, hy, hz):  # pragma: no cover - compiled
    """Parameter ``t`` in [0, 1] of the point of ``a + t d`` (box frame) closest to the box ``|x_i| <= h_i``."""
    g0 = _g(0.0, ax, ay, az, dx, dy, dz, hx, hy, hz)
    if g0 >= 0.0:
        return 0.0
    g1 = _g(1.0, ax, ay, az, dx, dy, dz, hx, hy, hz)
    if g1 <= 0.0:
        return 1.0
    lo, glo, hi, ghi = 0.0, g0, 1.0, g1
    t1, t2 = _crossing(lo, glo, hi, ghi, ax, dx, hx)
    lo, glo, hi, ghi = _shrink(t1, lo, glo, hi, ghi, ax, ay, az, dx, dy, dz, hx, hy, hz)
    lo, glo, hi, ghi = _shrink(t2, lo, glo, hi, ghi, ax, ay, az, dx, dy, dz, hx, hy, hz)
    t1, t2 = _crossing(lo, glo, hi, ghi, ay, dy, hy)
    lo, glo, hi, ghi = _shrink(t1, lo, glo, hi, ghi, ax, ay, az, dx, dy, dz, hx, hy, hz)
    lo, glo, hi, ghi = _shrink(t2, lo, glo, hi, ghi, ax, ay, az, dx, dy, dz, hx, hy, hz)
    t1, t2 = _crossing(lo, glo, hi, ghi, az, dz, hz)
    lo, glo, hi, ghi = _shrink(t1, lo, glo, hi, ghi, ax, ay, az, dx, dy, dz, hx, hy, hz)
    lo, glo, hi, ghi = _shrink(t2, lo, glo, hi, ghi, ax, ay, az, dx, dy, dz, hx, hy, hz)
    if glo >= 0.0:
        return lo
    # g is linear on [lo, hi]: solve g = 0
    return lo - glo * (hi - lo) / (ghi - glo)


@njit(cache=True, inline="always")
def _project_overlap(ux, uy, uz, ax, ay, az, dx, dy, dz, hx, hy, hz):  # pragma: no cover
    """For unit axis u (box frame): (move-B-along-+u, move-B-along--u) separating translations."""
    s0 = ax * ux + ay * uy + az * uz
    s1 = s0 + dx * ux + dy * uy + dz * uz
    smin = min(s0, s1)
    smax = max(s0, s1)
    rb = hx * abs(ux) + hy * abs(uy) + hz * abs(uz)
    # B (the box) projects to [-rb, rb]; A (the segment) to [smin, smax]
    return smax + rb, rb - smin


@njit(cache=True)
def capsule_box_scalar(
    p0x, p0y, p0z, p1x, p1y, p1z, r, cx, cy, cz, hx, hy, hz,
    r00, r01, r02, r10, r11, r12, r20, r21, r22, out, base, eps_len, eps_par, offset,
):  # pragma: no cover - compiled
    """Signed distance capsule A = ``(p0, p1, r)`` to box B = ``(c, h, R_WB)``; see :func:`capsule_box`."""
    # box frame: x_B = R^T (p_W - c)
    wx = p0x - cx
    wy = p0y - cy
    wz = p0z - cz
    ax = r00 * wx + r10 * wy + r20 * wz
    ay = r01 * wx + r11 * wy + r21 * wz
    az = r02 * wx + r12 * wy + r22 * wz
    ex = p1x - p0x
    ey = p1y - p0y
    ez = p1z - p0z
    dx = r00 * ex + r10 * ey + r20 * ez
    dy = r01 * ex + r11 * ey + r21 * ez
    dz = r02 * ex + r12 * ey + r22 * ez
    t = segment_box_closest(ax, ay, az, dx, dy, dz, hx, hy, hz)
    xx = ax + t * dx
    xy = ay + t * dy
    xz = az + t * dz
    qx = min(hx, max(-hx, xx))
    qy = min(hy, max(-hy, xy))
    qz = min(hz, max(-hz, xz))
    vx = qx - xx
    vy = qy - xy
    vz = qz - xz
    dcore = math.sqrt(vx * vx + vy * vy + vz * vz)
    sx = 0.0
    sy = 0.0
    sz = 0.0
    if dcore > eps_len:
        nx = vx / dcore
        ny = vy / dcore
        nz = vz / dcore
        depth = -dcore
    else:
        # SAT over e_x, e_y, e_z and d x e_i (box frame).
        depth = math.inf
        nx = 0.0
        ny = 0.0
        nz = 1.0
        dn = math.sqrt(dx * dx + dy * dy + dz * dz)
        for k in range(6):
            if k == 0:
                ux, uy, uz = 1.0, 0.0, 0.0
            elif k == 1:
                ux, uy, uz = 0.0, 1.0, 0.0
            elif k == 2:
                ux, uy, uz = 0.0, 0.0, 1.0
            elif k == 3:
                ux, uy, uz = 0.0, dz, -dy
            elif k == 4:
                ux, uy, uz = -dz, 0.0, dx
            else:
                ux, uy, uz = dy, -dx, 0.0
            if k >= 3:
                un = math.sqrt(ux * ux + uy * uy + uz * uz)
                if un <= eps_par * dn or un == 0.0:
                    continue
                ux /= un
                uy /= un
                uz /= un
            plus, minus = _project_overlap(ux, uy, uz, ax, ay, az, dx, dy, dz, hx, hy, hz)
            if plus < depth:
                depth = plus
                nx, ny, nz = ux, uy, uz
            if minus < depth:
                depth = minus
                nx, ny, nz = -ux, -uy, -uz
        # move the segment (A) by -(depth + offset) n; then the cores are `offset` apart along n
        shift = depth + offset
        sx = -shift * nx
        sy = -shift * ny
        sz = -shift * nz
        t = segment_box_closest(ax + sx, ay + sy, az + sz, dx, dy, dz, hx, hy, hz)
        xx = ax + sx + t * dx
        xy = ay + sy + t * dy
        xz = az + sz + t * dz
        qx = min(hx, max(-hx, xx))
        qy = min(hy, max(-hy, xy))
        qz = min(hz, max(-hz, xz))
        xx -= sx
        xy -= sy
        xz -= sz
    # back to W
    cax = cx + r00 * xx + r01 * xy + r02 * xz
    cay = cy + r10 * xx + r11 * xy + r12 * xz
    caz = cz + r20 * xx + r21 * xy + r22 * xz
    cbx = cx + r00 * qx + r01 * qy + r02 * qz
    cby = cy + r10 * qx + r11 * qy + r12 * qz
    cbz = cz + r20 * qx + r21 * qy + r22 * qz
    mx = r00 * nx + r01 * ny + r02 * nz
    my = r10 * nx + r11 * ny + r12 * nz
    mz = r20 * nx + r21 * ny + r22 * nz
    return write_rounded(cax, cay, caz, r, cbx, cby, cbz, 0.0, mx, my, mz, -depth, out, base)


@njit(cache=True)
def capsule_box(p0, p1, r, center, half_extents, R_WB, out, eps_len, eps_par, offset):  # pragma: no cover
    """Signed distance between capsule A ``(p0, p1, r)`` and box B ``(center, half_extents, R_WB)``.

    ``p0, p1, center : (3,) float64, m``; ``half_extents : (3,) m``; ``R_WB : (3, 3)`` (columns
    are the box axes in W); ``r`` m.  Writes ``out[0:9] = [p_WA, p_WB, nhat_AB_W]``, returns the
    signed distance (m).  ``offset`` (m) is ``Tolerances.penetration_witness_offset``.
    A zero-length capsule is a sphere.  Allocation-free; callable from njit code.
    """
    return capsule_box_scalar(
        p0[0], p0[1], p0[2], p1[0], p1[1], p1[2], r, center[0], center[1], center[2],
        half_extents[0], half_extents[1], half_extents[2],
        R_WB[0, 0], R_WB[0, 1], R_WB[0, 2], R_WB[1, 0], R_WB[1, 1], R_WB[1, 2],
        R_WB[2, 0], R_WB[2, 1], R_WB[2, 2], out, 0, eps_len, eps_par, offset,
    )


@njit(cache=True)
def capsule_box_packed(a, b, out, eps_len, eps_par, offset):  # pragma: no cover - compiled
    """Capsule ``[p0, p1, r]`` (7,) against box ``[c, h, R_WB row-major]`` (15,): the single-call path."""
    return capsule_box_scalar(
        a[0], a[1], a[2], a[3], a[4], a[5], a[6], b[0], b[1], b[2], b[3], b[4], b[5],
        b[6], b[7], b[8], b[9], b[10], b[11], b[12], b[13], b[14], out, 0, eps_len, eps_par, offset,
    )
