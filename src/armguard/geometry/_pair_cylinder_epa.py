"""EPA on support points (van den Bergen, GDC 2001, §4.3.7) for :mod:`._pair_cylinder`: the simplex
GJK leaves completed to a tetrahedron about the origin, the polytope grown face by face, and the
witnesses read from the closest face (the module docstring of :mod:`._pair_cylinder` states the
algorithm and its stopping rules)."""

from __future__ import annotations

import math

from numba import njit

from ._pair_cylinder_support import (_E0, _F0, _INSIDE, _NE, _NF, _NV, _S0, _V0, _VIS, SUPPORT_GAP, _pair_support,
                                     _put)
from ._pair_epa import triangle_normal
from ._pair_epa_start import perpendicular_basis, ring_direction

__all__ = ["epa_support"]

@njit(cache=True, _nrt=False)
def _complete(pa, ga, ca, pb, gb, cb, work, n, eps):  # pragma: no cover - compiled
    """Complete GJK's simplex (``n < 4`` vertices, the origin within ``eps`` of it) to a tetrahedron
    of support points of ``M`` containing the origin: add supports along directions off the
    simplex's span (the axes for a point, six directions about a segment, the two normals of a
    triangle).  Returns False when ``M`` shows no extent off the span (it then has no volume)."""
    if n == 1:
        for k in range(6):
            dx = 1.0 if k == 0 else (-1.0 if k == 1 else 0.0)
            dy = 1.0 if k == 2 else (-1.0 if k == 3 else 0.0)
            dz = 1.0 if k == 4 else (-1.0 if k == 5 else 0.0)
            ax, ay, az, bx, by, bz = _pair_support(pa, ga, ca, pb, gb, cb, dx, dy, dz, work)
            ex = ax - bx - work[_S0]
            ey = ay - by - work[_S0 + 1]
            ez = az - bz - work[_S0 + 2]
            if ex * ex + ey * ey + ez * ez > eps * eps:
                _put(work, _S0 + 9, ax, ay, az, bx, by, bz)
                n = 2
                break
        if n == 1:
            return False
    if n == 2:
        ex = work[_S0 + 9] - work[_S0]
        ey = work[_S0 + 10] - work[_S0 + 1]
        ez = work[_S0 + 11] - work[_S0 + 2]
        en = math.sqrt(ex * ex + ey * ey + ez * ez)
        ex /= en
        ey /= en
        ez /= en
        ux, uy, uz, wx, wy, wz = perpendicular_basis(ex, ey, ez)
        for k in range(6):
            dx, dy, dz = ring_direction(k, ux, uy, uz, wx, wy, wz)
            ax, ay, az, bx, by, bz = _pair_support(pa, ga, ca, pb, gb, cb, dx, dy, dz, work)
            rx = ax - bx - work[_S0]
            ry = ay - by - work[_S0 + 1]
            rz = az - bz - work[_S0 + 2]
            s = rx * ex + ry * ey + rz * ez
            rx -= s * ex
            ry -= s * ey
            rz -= s * ez
            if rx * rx + ry * ry + rz * rz > eps * eps:
                _put(work, _S0 + 18, ax, ay, az, bx, by, bz)
                n = 3
                break
        if n == 2:
            return False
    # a triangle: add the support along the normal on the origin's side (the other if flat there)
    nx, ny, nz, ok = triangle_normal(work, _S0, _S0 + 9, _S0 + 18)
    if not ok:
        return False
    side = -(nx * work[_S0] + ny * work[_S0 + 1] + nz * work[_S0 + 2])  # the origin's offset
    for attempt in range(2):
        sg = 1.0 if (side >= 0.0) == (attempt == 0) else -1.0
        ax, ay, az, bx, by, bz = _pair_support(pa, ga, ca, pb, gb, cb, sg * nx, sg * ny, sg * nz, work)
        off = sg * (nx * (ax - bx - work[_S0]) + ny * (ay - by - work[_S0 + 1]) + nz * (az - bz - work[_S0 + 2]))
        if off > eps:
            _put(work, _S0 + 27, ax, ay, az, bx, by, bz)
            return True
    return False


@njit(cache=True, _nrt=False)
def _face(w, f, i0, i1, i2, tol):  # pragma: no cover - compiled
    """Face ``f`` = triangle ``(i0, i1, i2)`` (counter-clockwise seen from outside); False when it is
    degenerate or its plane has the origin outside (by more than ``tol``)."""
    o0 = _V0 + 9 * i0
    nx, ny, nz, ok = triangle_normal(w, o0, _V0 + 9 * i1, _V0 + 9 * i2)
    if not ok:
        return False
    d = nx * w[o0] + ny * w[o0 + 1] + nz * w[o0 + 2]
    if d < -tol:
        return False
    o = _F0 + 8 * f
    w[o] = i0
    w[o + 1] = i1
    w[o + 2] = i2
    w[o + 3] = nx
    w[o + 4] = ny
    w[o + 5] = nz
    w[o + 6] = max(d, 0.0)
    w[o + 7] = 1.0
    return True


@njit(cache=True, _nrt=False)
def _horizon(w, ne, a, b):  # pragma: no cover - compiled
    """Add the directed edge ``a -> b`` to the horizon, or cancel it against ``b -> a``; -1: full."""
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


@njit(cache=True, _nrt=False)
def _witness(w, i0, i1, i2, dbest, nx, ny, nz):  # pragma: no cover - compiled
    """The origin's projection ``p = dbest n`` onto the triangle of vertices ``i0, i1, i2`` in
    barycentric coordinates, applied to the vertices' A and B points.  Returns ``(ok, lmin, ax, ay, az, bx, by, bz)``, ``lmin`` the least
    weight (negative: ``p`` lies outside the triangle, and the points off the cores).

    The weights are ratios of signed areas along the face normal (Ericson §3.4, the triple
    products), not the Gram-matrix solution: on a curved core EPA's faces near the optimum are
    slivers, whose Gram determinant loses the weights to cancellation."""
    o0 = _V0 + 9 * i0
    o1 = _V0 + 9 * i1
    o2 = _V0 + 9 * i2
    px = dbest * nx
    py = dbest * ny
    pz = dbest * nz
    l0 = _area(w[o1] - px, w[o1 + 1] - py, w[o1 + 2] - pz, w[o2] - px, w[o2 + 1] - py, w[o2 + 2] - pz, nx, ny, nz)
    l1 = _area(w[o2] - px, w[o2 + 1] - py, w[o2 + 2] - pz, w[o0] - px, w[o0 + 1] - py, w[o0 + 2] - pz, nx, ny, nz)
    l2 = _area(w[o0] - px, w[o0 + 1] - py, w[o0 + 2] - pz, w[o1] - px, w[o1 + 1] - py, w[o1 + 2] - pz, nx, ny, nz)
    t = l0 + l1 + l2
    if not t > 0.0:
        return False, -math.inf, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    l0 /= t
    l1 /= t
    l2 /= t
    ax = l0 * w[o0 + 3] + l1 * w[o1 + 3] + l2 * w[o2 + 3]
    ay = l0 * w[o0 + 4] + l1 * w[o1 + 4] + l2 * w[o2 + 4]
    az = l0 * w[o0 + 5] + l1 * w[o1 + 5] + l2 * w[o2 + 5]
    bx = l0 * w[o0 + 6] + l1 * w[o1 + 6] + l2 * w[o2 + 6]
    by = l0 * w[o0 + 7] + l1 * w[o1 + 7] + l2 * w[o2 + 7]
    bz = l0 * w[o0 + 8] + l1 * w[o1 + 8] + l2 * w[o2 + 8]
    return True, min(l0, l1, l2), ax, ay, az, bx, by, bz


@njit(cache=True, _nrt=False)
def _answer(w, nf, i0, i1, i2, dbest, nx, ny, nz, tol):  # pragma: no cover - compiled
    """EPA's answer ``(ok, depth, nx, ny, nz, ax, ay, az, bx, by, bz)`` at the closest face (vertices
    ``i0, i1, i2``; passed by vertex, as the face's slot may be reused once it is removed).

    The origin's projection onto the closest face's plane lies on the polytope (every other face's
    plane is at least as far), but not always in that face: a cap against a parallel box face makes
    a flat region of ``M``, coplanar triangles at one distance, and the one picked may not hold it
    (negative weights: witnesses off the cores, 0.50 m off a cylinder in a seeded search, the depth
    right).  Then the face within ``tol`` of ``dbest`` holding it answers, with its distance and normal."""
    ok, lmin, ax, ay, az, bx, by, bz = _witness(w, i0, i1, i2, dbest, nx, ny, nz)
    if ok and lmin >= -_INSIDE:
        return True, dbest, nx, ny, nz, ax, ay, az, bx, by, bz
    found = (ok, dbest, nx, ny, nz, ax, ay, az, bx, by, bz)
    top = lmin if ok else -math.inf
    for f in range(nf):
        o = _F0 + 8 * f
        if w[o + 7] == 0.0 or w[o + 6] > dbest + tol:
            continue
        ok, lmin, ax, ay, az, bx, by, bz = _witness(w, int(w[o]), int(w[o + 1]), int(w[o + 2]), w[o + 6], w[o + 3],
                                                     w[o + 4], w[o + 5])
        if ok and lmin > top:
            top = lmin
            found = (True, w[o + 6], w[o + 3], w[o + 4], w[o + 5], ax, ay, az, bx, by, bz)
    return found


@njit(cache=True, _nrt=False)
def _area(ux, uy, uz, vx, vy, vz, nx, ny, nz):  # pragma: no cover - compiled
    """``(u x v) . n``: twice the signed area of the triangle (p, p + u, p + v) seen along ``n``."""
    return (uy * vz - uz * vy) * nx + (uz * vx - ux * vz) * ny + (ux * vy - uy * vx) * nz


@njit(cache=True, _nrt=False)
def _settle(work, nf, fv, dbest, nx, ny, nz, h, best, tol):  # pragma: no cover - compiled
    """EPA's answer from the closest face (vertices ``fv``) when the polytope cannot grow (rounding on a curved core): its
    distance ``dbest`` when the support value ``h`` along its normal is within ``SUPPORT_GAP``,
    else ``best`` (the tightest such bracket seen before, or not settled)."""
    if h - dbest <= SUPPORT_GAP * (1.0 + dbest):
        res = _answer(work, nf, fv[0], fv[1], fv[2], dbest, nx, ny, nz, tol)
        if res[0]:
            return res
    return best


@njit(cache=True, _nrt=False)
def epa_support(pa, ga, ca, pb, gb, cb, work, eps, tol, vis):  # pragma: no cover - compiled
    """EPA on ``M = A - B`` from the tetrahedron in ``work`` (GJK's, or :func:`_complete`'s).

    ``eps`` (m): stop when the support value along the closest face's normal exceeds the face's
    distance by at most this; ``tol`` (m): how far outside a face's plane the origin may be found
    (rounding of a touching contact); ``vis`` (m): how far beyond a face's plane a new support point
    must be for the face to be seen from it (the closest face always is).  A cap or a polytope's
    face gives many coplanar support points: without the margin, rounding removes some of the
    coplanar faces and keeps others, and the horizon is no longer one loop.  Returns ``(ok, depth, nx, ny, nz, ax, ay, az, bx, by, bz)``
    as ``_pair_epa.epa_depth``: ``a - b = depth n`` on the cores; ``ok`` False: not settled.

    On a curved core the faces near the optimum become slivers, and rounding can break the
    polytope after the depth has already been bracketed (a face's distance is a lower bound on the
    depth while the polytope is convex, the support value along its normal an upper bound
    always): the closest face's distance of a growing polytope never decreases, so a drop marks a
    broken polytope.  The iteration with the tightest bracket is kept, and when the polytope breaks
    (or cannot grow) it is the answer if its bracket is within ``SUPPORT_GAP`` -- else not settled."""
    fail = (False, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    best = fail  # the tightest bracket within SUPPORT_GAP seen so far (its face's answer)
    best_gap = math.inf
    last = 0.0  # the closest face's distance at the previous iteration
    for k in range(4):
        for q in range(9):
            work[_V0 + 9 * k + q] = work[_S0 + 9 * k + q]
    nf = 0
    for t in range(4):  # the tetrahedron's faces, each oriented away from the opposite vertex
        i0 = (t + 1) % 4
        i1 = (t + 2) % 4
        i2 = (t + 3) % 4
        o0 = _V0 + 9 * i0
        o1 = _V0 + 9 * i1
        o2 = _V0 + 9 * i2
        ot = _V0 + 9 * t
        ux = work[o1] - work[o0]
        uy = work[o1 + 1] - work[o0 + 1]
        uz = work[o1 + 2] - work[o0 + 2]
        vx = work[o2] - work[o0]
        vy = work[o2 + 1] - work[o0 + 1]
        vz = work[o2 + 2] - work[o0 + 2]
        s = ((uy * vz - uz * vy) * (work[ot] - work[o0]) + (uz * vx - ux * vz) * (work[ot + 1] - work[o0 + 1])
             + (ux * vy - uy * vx) * (work[ot + 2] - work[o0 + 2]))
        ok = _face(work, nf, i0, i2, i1, tol) if s > 0.0 else _face(work, nf, i0, i1, i2, tol)
        if not ok:
            return fail
        nf += 1
    nv = 4
    while True:
        fi = -1
        dbest = math.inf
        for f in range(nf):
            o = _F0 + 8 * f
            if work[o + 7] != 0.0 and work[o + 6] < dbest:
                dbest = work[o + 6]
                fi = f
        if fi < 0:
            return best
        if dbest < last - tol:
            return best  # the polytope shrank: rounding broke it; the bracket kept before that stands
        last = dbest
        of = _F0 + 8 * fi
        nx = work[of + 3]
        ny = work[of + 4]
        nz = work[of + 5]
        fv = (int(work[of]), int(work[of + 1]), int(work[of + 2]))
        ax, ay, az, bx, by, bz = _pair_support(pa, ga, ca, pb, gb, cb, nx, ny, nz, work)
        wx = ax - bx
        wy = ay - by
        wz = az - bz
        h = nx * wx + ny * wy + nz * wz
        repeated = False
        for k in range(nv):
            o = _V0 + 9 * k
            ex = wx - work[o]
            ey = wy - work[o + 1]
            ez = wz - work[o + 2]
            if ex * ex + ey * ey + ez * ez <= tol * tol:
                repeated = True
                break
        if h - dbest <= eps or ((repeated or nv == _NV) and h - dbest <= SUPPORT_GAP * (1.0 + dbest)):
            res = _answer(work, nf, fv[0], fv[1], fv[2], dbest, nx, ny, nz, tol)
            return res if res[0] else best
        if h - dbest < best_gap and h - dbest <= SUPPORT_GAP * (1.0 + dbest):
            res = _answer(work, nf, fv[0], fv[1], fv[2], dbest, nx, ny, nz, tol)
            if res[0]:
                best_gap = h - dbest
                best = res
        if repeated or nv == _NV:
            return best
        _put(work, _V0 + 9 * nv, ax, ay, az, bx, by, bz)
        ne = 0  # remove the faces seen from w; their unshared edges form the horizon
        for f in range(nf):
            o = _F0 + 8 * f
            if work[o + 7] != 0.0 and (f == fi or work[o + 3] * wx + work[o + 4] * wy + work[o + 5] * wz
                                       - work[o + 6] > vis):
                work[o + 7] = 0.0
                a0 = work[o]
                a1 = work[o + 1]
                a2 = work[o + 2]
                ne = _horizon(work, ne, a0, a1)
                if ne >= 0:
                    ne = _horizon(work, ne, a1, a2)
                if ne >= 0:
                    ne = _horizon(work, ne, a2, a0)
                if ne < 0:
                    return _settle(work, nf, fv, dbest, nx, ny, nz, h, best, tol)
        if ne < 3:
            return _settle(work, nf, fv, dbest, nx, ny, nz, h, best, tol)
        if nf + ne > _NF:  # compact: keep the live faces only
            m = 0
            for f in range(nf):
                o = _F0 + 8 * f
                if work[o + 7] != 0.0:
                    om = _F0 + 8 * m
                    for q in range(8):
                        work[om + q] = work[o + q]
                    m += 1
            nf = m
            if nf + ne > _NF:
                return _settle(work, nf, fv, dbest, nx, ny, nz, h, best, tol)
        for k in range(ne):
            o = _E0 + 2 * k
            if not _face(work, nf, int(work[o]), int(work[o + 1]), nv, tol):
                return _settle(work, nf, fv, dbest, nx, ny, nz, h, best, tol)
            nf += 1
        nv += 1
