"""GJK distance between the convex hulls of two point sets (the cores), with witness points.

Gilbert, Johnson & Keerthi (1988).  The sub-algorithm that finds the point of the current
simplex closest to the origin is Johnson's distance sub-algorithm written as the Voronoi-region
tests of Ericson, *Real-Time Collision Detection* §5.1.2-5.1.6 (``ClosestPtPointTriangle``,
``ClosestPtPointTetrahedron`` with the query point at the origin); the simplex keeps only the
vertices with non-zero barycentric weight.  Support points are the hull vertices maximising the
dot product, so on polytopes GJK terminates finitely; we stop when the duality gap
``(|v|^2 - v.w) / |v|`` is below ``gjk_epsilon``, when a support pair repeats, or when ``|v|``
stops decreasing.  Hitting ``max_iterations`` returns ``GJK_NOT_CONVERGED`` (callers raise).

The simplex lives in a caller-supplied ``work`` array (``GJK_WORK_SIZE`` floats), so the kernel
allocates nothing.  Core B may be translated by an offset ``o`` without copying its points.
"""

from __future__ import annotations

import math

from numba import njit

__all__ = ["GJK_WORK_SIZE", "GJK_SEPARATED", "GJK_INTERSECTING", "GJK_NOT_CONVERGED", "gjk_core"]

GJK_WORK_SIZE = 64
"""Length of the ``work`` array the GJK kernels need (float64)."""
GJK_SEPARATED = 0
"""Status: the cores are disjoint; the distance and witnesses are exact to ``gjk_epsilon``."""
GJK_INTERSECTING = 1
"""Status: the cores overlap or touch (core distance <= ``length``)."""
GJK_NOT_CONVERGED = 2
"""Status: ``max_iterations`` reached without meeting the stopping test."""

# work layout: vertex k of the simplex occupies work[9k:9k+9] = [w, a, b]; support indices of
# vertex k at work[36+k] (A) and work[40+k] (B); work[48:64] is free for callers' scratch
# (capsule_polytope keeps its segment there).


@njit(cache=True, inline="always")
def _copy_vertex(work, src, dst):  # pragma: no cover - compiled
    if src != dst:
        for q in range(9):
            work[9 * dst + q] = work[9 * src + q]
        work[36 + dst] = work[36 + src]
        work[40 + dst] = work[40 + src]


@njit(cache=True, inline="always")
def _w(work, k):  # pragma: no cover - compiled
    return work[9 * k], work[9 * k + 1], work[9 * k + 2]


@njit(cache=True)
def _closest_triangle(work, ia, ib, ic):  # pragma: no cover - compiled
    """Ericson ClosestPtPointTriangle with p = 0. Returns (count, i0, i1, i2, l0, l1, l2, vv)."""
    ax, ay, az = _w(work, ia)
    bx, by, bz = _w(work, ib)
    cx, cy, cz = _w(work, ic)
    abx = bx - ax
    aby = by - ay
    abz = bz - az
    acx = cx - ax
    acy = cy - ay
    acz = cz - az
    d1 = -(abx * ax + aby * ay + abz * az)
    d2 = -(acx * ax + acy * ay + acz * az)
    if d1 <= 0.0 and d2 <= 0.0:
        return 1, ia, ia, ia, 1.0, 0.0, 0.0, ax * ax + ay * ay + az * az
    d3 = -(abx * bx + aby * by + abz * bz)
    d4 = -(acx * bx + acy * by + acz * bz)
    if d3 >= 0.0 and d4 <= d3:
        return 1, ib, ib, ib, 1.0, 0.0, 0.0, bx * bx + by * by + bz * bz
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        v = d1 / (d1 - d3)
        px = ax + v * abx
        py = ay + v * aby
        pz = az + v * abz
        return 2, ia, ib, ib, 1.0 - v, v, 0.0, px * px + py * py + pz * pz
    d5 = -(abx * cx + aby * cy + abz * cz)
    d6 = -(acx * cx + acy * cy + acz * cz)
    if d6 >= 0.0 and d5 <= d6:
        return 1, ic, ic, ic, 1.0, 0.0, 0.0, cx * cx + cy * cy + cz * cz
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        w = d2 / (d2 - d6)
        px = ax + w * acx
        py = ay + w * acy
        pz = az + w * acz
        return 2, ia, ic, ic, 1.0 - w, w, 0.0, px * px + py * py + pz * pz
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        px = bx + w * (cx - bx)
        py = by + w * (cy - by)
        pz = bz + w * (cz - bz)
        return 2, ib, ic, ic, 1.0 - w, w, 0.0, px * px + py * py + pz * pz
    denom = 1.0 / (va + vb + vc)
    v = vb * denom
    w = vc * denom
    px = ax + v * abx + w * acx
    py = ay + v * aby + w * acy
    pz = az + v * abz + w * acz
    return 3, ia, ib, ic, 1.0 - v - w, v, w, px * px + py * py + pz * pz


@njit(cache=True, inline="always")
def _side(work, ia, ib, ic, idd):  # pragma: no cover - compiled
    """(origin side, opposite vertex side) of the plane through a, b, c."""
    ax, ay, az = _w(work, ia)
    bx, by, bz = _w(work, ib)
    cx, cy, cz = _w(work, ic)
    dx, dy, dz = _w(work, idd)
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
    return sp, sd


@njit(cache=True)
def _reduce(work, n):  # pragma: no cover - compiled
    """Closest point of the simplex work[0:n] to the origin; compacts the simplex.

    Returns ``(n_new, vx, vy, vz, ax, ay, az, bx, by, bz)``; ``n_new == 4`` means the origin is
    inside the tetrahedron.
    """
    if n == 1:
        c = 1
        i0, i1, i2 = 0, 0, 0
        l0, l1, l2 = 1.0, 0.0, 0.0
    elif n == 2:
        ax, ay, az = _w(work, 0)
        bx, by, bz = _w(work, 1)
        ex = bx - ax
        ey = by - ay
        ez = bz - az
        ee = ex * ex + ey * ey + ez * ez
        t = -(ax * ex + ay * ey + az * ez)
        if t <= 0.0 or ee == 0.0:
            c, i0, i1, i2, l0, l1, l2 = 1, 0, 0, 0, 1.0, 0.0, 0.0
        elif t >= ee:
            c, i0, i1, i2, l0, l1, l2 = 1, 1, 1, 1, 1.0, 0.0, 0.0
        else:
            t = t / ee
            c, i0, i1, i2, l0, l1, l2 = 2, 0, 1, 1, 1.0 - t, t, 0.0
    elif n == 3:
        c, i0, i1, i2, l0, l1, l2, _vv = _closest_triangle(work, 0, 1, 2)
    else:
        best = math.inf
        c, i0, i1, i2, l0, l1, l2 = 4, 0, 0, 0, 0.0, 0.0, 0.0
        for f in range(4):
            if f == 0:
                fa, fb, fc, fd = 0, 1, 2, 3
            elif f == 1:
                fa, fb, fc, fd = 0, 2, 3, 1
            elif f == 2:
                fa, fb, fc, fd = 0, 3, 1, 2
            else:
                fa, fb, fc, fd = 1, 3, 2, 0
            sp, sd = _side(work, fa, fb, fc, fd)
            if sp * sd < 0.0 or sd == 0.0:
                cc, j0, j1, j2, m0, m1, m2, vv = _closest_triangle(work, fa, fb, fc)
                if vv < best:
                    best = vv
                    c, i0, i1, i2, l0, l1, l2 = cc, j0, j1, j2, m0, m1, m2
        if c == 4:
            return 4, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    # weight per original slot, then a stable compaction (destination <= source: safe in place)
    w0 = w1 = w2 = w3 = 0.0
    for k in range(c):
        idx = i0 if k == 0 else (i1 if k == 1 else i2)
        lam = l0 if k == 0 else (l1 if k == 1 else l2)
        if idx == 0:
            w0 = lam
        elif idx == 1:
            w1 = lam
        elif idx == 2:
            w2 = lam
        else:
            w3 = lam
    vx = vy = vz = ax = ay = az = bx = by = bz = 0.0
    m = 0
    for j in range(n):
        lam = w0 if j == 0 else (w1 if j == 1 else (w2 if j == 2 else w3))
        member = (j == i0) or (c >= 2 and j == i1) or (c >= 3 and j == i2)
        if not member:
            continue
        _copy_vertex(work, j, m)
        vx += lam * work[9 * m]
        vy += lam * work[9 * m + 1]
        vz += lam * work[9 * m + 2]
        ax += lam * work[9 * m + 3]
        ay += lam * work[9 * m + 4]
        az += lam * work[9 * m + 5]
        bx += lam * work[9 * m + 6]
        by += lam * work[9 * m + 7]
        bz += lam * work[9 * m + 8]
        m += 1
    c = m
    return c, vx, vy, vz, ax, ay, az, bx, by, bz


@njit(cache=True)
def gjk_core(pa, pb, ox, oy, oz, work, eps_len, gjk_eps, max_iter):  # pragma: no cover - compiled
    """Closest points of hull(pa) and hull(pb) + o.

    ``pa : (nA, 3)``, ``pb : (nB, 3) float64, m``; ``o`` (m) translates B.  Returns
    ``(status, dist, ax, ay, az, bx, by, bz)``: core distance and the witness points (B's includes
    the offset).  ``status`` is one of ``GJK_SEPARATED``, ``GJK_INTERSECTING``,
    ``GJK_NOT_CONVERGED``.
    """
    na = pa.shape[0]
    nb = pb.shape[0]
    # start from the support points along the centroid difference (fewer iterations than an
    # arbitrary vertex pair)
    gx = gy = gz = 0.0
    for i in range(na):
        gx += pa[i, 0]
        gy += pa[i, 1]
        gz += pa[i, 2]
    hx = hy = hz = 0.0
    for i in range(nb):
        hx += pb[i, 0]
        hy += pb[i, 1]
        hz += pb[i, 2]
    dx = gx / na - hx / nb - ox
    dy = gy / na - hy / nb - oy
    dz = gz / na - hz / nb - oz
    ia = 0
    best = -math.inf
    for i in range(na):
        s = -(pa[i, 0] * dx + pa[i, 1] * dy + pa[i, 2] * dz)
        if s > best:
            best = s
            ia = i
    ib = 0
    best = -math.inf
    for i in range(nb):
        s = pb[i, 0] * dx + pb[i, 1] * dy + pb[i, 2] * dz
        if s > best:
            best = s
            ib = i
    ax = pa[ia, 0]
    ay = pa[ia, 1]
    az = pa[ia, 2]
    bx = pb[ib, 0] + ox
    by = pb[ib, 1] + oy
    bz = pb[ib, 2] + oz
    vx = ax - bx
    vy = ay - by
    vz = az - bz
    vv = vx * vx + vy * vy + vz * vz
    n = 0
    eps2 = eps_len * eps_len
    for _it in range(max_iter):
        if vv <= eps2:
            return GJK_INTERSECTING, math.sqrt(vv), ax, ay, az, bx, by, bz
        # support of A along -v, of B along +v
        ia = 0
        best = -math.inf
        for i in range(na):
            s = -(pa[i, 0] * vx + pa[i, 1] * vy + pa[i, 2] * vz)
            if s > best:
                best = s
                ia = i
        ib = 0
        best = -math.inf
        for i in range(nb):
            s = pb[i, 0] * vx + pb[i, 1] * vy + pb[i, 2] * vz
            if s > best:
                best = s
                ib = i
        sax = pa[ia, 0]
        say = pa[ia, 1]
        saz = pa[ia, 2]
        sbx = pb[ib, 0] + ox
        sby = pb[ib, 1] + oy
        sbz = pb[ib, 2] + oz
        wx = sax - sbx
        wy = say - sby
        wz = saz - sbz
        vw = vx * wx + vy * wy + vz * wz
        if vv - vw <= gjk_eps * math.sqrt(vv):
            return GJK_SEPARATED, math.sqrt(vv), ax, ay, az, bx, by, bz
        repeated = False
        for k in range(n):
            if work[36 + k] == ia and work[40 + k] == ib:
                repeated = True
        if repeated:
            return GJK_SEPARATED, math.sqrt(vv), ax, ay, az, bx, by, bz
        base = 9 * n
        work[base] = wx
        work[base + 1] = wy
        work[base + 2] = wz
        work[base + 3] = sax
        work[base + 4] = say
        work[base + 5] = saz
        work[base + 6] = sbx
        work[base + 7] = sby
        work[base + 8] = sbz
        work[36 + n] = ia
        work[40 + n] = ib
        n += 1
        c, nvx, nvy, nvz, nax, nay, naz, nbx, nby, nbz = _reduce(work, n)
        if c == 4:
            return GJK_INTERSECTING, 0.0, ax, ay, az, bx, by, bz
        nvv = nvx * nvx + nvy * nvy + nvz * nvz
        if nvv >= vv and n > 1:
            # no progress (rounding): the previous simplex is the answer
            return GJK_SEPARATED, math.sqrt(vv), ax, ay, az, bx, by, bz
        n = c
        vx, vy, vz, vv = nvx, nvy, nvz, nvv
        ax, ay, az, bx, by, bz = nax, nay, naz, nbx, nby, nbz
    return GJK_NOT_CONVERGED, math.sqrt(vv), ax, ay, az, bx, by, bz
