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
  ``gjk_epsilon``, when a support point repeats, or when ``|v|`` stops decreasing (as
  ``_pair_gjk``: the simplex is then the answer; on two curved cores it stalls so with ``|v|``
  within ~1e-11 m of the distance while the gap, whose lower bound sees the supports jump across
  a rim, may still be ~1e-5 m).  Once a support plane has separated the origin from ``M``
  (``v . w > 0``: a proof that the cores are apart) no later step may call them intersecting: near
  a rim the supports jump between nearly equal points, and rounding can then flatten the simplex
  into a tetrahedron that seems to hold the origin (1 in 1,000 random cylinder-box pairs 18-28 mm
  apart were once reported touching).  On a curved core GJK converges without terminating finitely;
  with ``max_iterations`` spent it is accepted when the gap is below ``SUPPORT_GAP``, else
  reported as ``GJK_NOT_CONVERGED`` (callers raise).
* EPA (van den Bergen, GDC 2001, §4.3.7) on ``M = A - B`` from GJK's final tetrahedron; when GJK
  stops with the origin on a lower-dimensional simplex (touching cores) the simplex is first
  completed to a tetrahedron containing the origin by support points along directions off its
  span (as in van den Bergen's SOLID and coal).  It stops when the support value along the
  closest facet's normal exceeds the facet's distance by at most ``gjk_epsilon``; the depth is
  then exact to that, up to rounding.  On a curved core it converges geometrically; with the
  buffer's vertices spent (or a support repeating) it accepts a gap below ``SUPPORT_GAP``.

A core is ``(p, cyl, r)``: ``cyl`` a Cylinder's 15-float buffer ``[c, r, r, h, R_WC row-major]``
(``_pack``), or empty, and then the core is the hull of the points ``p (n, 3)`` (scanned, or climbed
over their vertex graph when one is given: :func:`support_pair_graph`), swept
by the radius ``r`` (spheres, capsules; 0 for polytopes).  Allocation-free: GJK's simplex and
EPA's polytope live in the caller's ``work`` (``SUPPORT_WORK_SIZE`` float64).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._pair_epa import triangle_normal
from ._pair_gjk import GJK_INTERSECTING, GJK_NOT_CONVERGED, GJK_SEPARATED, _closest_simplex, _support
from ._pair_segment_segment import write_rounded

__all__ = ["CYL_W", "SUPPORT_WORK_SIZE", "SUPPORT_GAP", "support_point", "gjk_support", "epa_support",
           "support_pair", "support_pair_graph"]

CYL_W = 15
"""Floats of a cylinder's buffer: ``[c (3), r, r, h, R_WC (9, row-major)]`` (the box layout)."""
SUPPORT_GAP = 1e-8
"""m per m of distance (plus 1): the duality gap GJK may stop at when its iterations run out, and
EPA when a support repeats or its vertices or faces run out on a curved core before its own test
(``gjk_epsilon``) is met -- a bound on the depth's error (in the tests the depths agree with the
references to ~1e-12 m)."""
_S0 = 1  # work[1:37]: GJK's simplex, vertex k = [w, a, b] at _S0 + 9 k; work[37:41] its weights
_L0 = _S0 + 36
_NV = 160  # EPA: vertices of the expanding polytope
_NF = 640  # face slots
_NE = 160  # horizon edges of one iteration
_V0 = _L0 + 4
_F0 = _V0 + 9 * _NV  # face f: [i0, i1, i2, n (3), d, alive] at _F0 + 8 f
_E0 = _F0 + 8 * _NF
SUPPORT_WORK_SIZE = _E0 + 2 * _NE
_INSIDE = 1e-9  # a barycentric weight this far below 0 still holds the projection (rounding)
_VIS = (4e-14, 1e-15, 1e-12, 1e-13, 1e-11)  # EPA's visibility margins, relative to the coordinates' size
"""Length of the ``work`` array the kernels here need (float64)."""


@njit(cache=True, inline="always")
def support_point(p, adj, cyl, dx, dy, dz):  # pragma: no cover - compiled
    """A point of the core ``(p, cyl)`` farthest along ``d``: the cylinder's ``s(d)``, else a climb
    over the points' vertex graph ``adj`` (``_pair_gjk._support``: a true support vertex of the
    hull, found in a few dozen dot products where a scan of a mesh hull takes thousands), or a
    scan of the points when ``adj`` is empty."""
    if cyl.shape[0] >= CYL_W:
        # d in the cylinder's frame (columns of R_WC): the radial part u R0 + v R1 is orthogonal
        # to the axis by construction (d - (a . d) a loses that to cancellation near the axis)
        u = cyl[6] * dx + cyl[9] * dy + cyl[12] * dz
        v = cyl[7] * dx + cyl[10] * dy + cyl[13] * dz
        s = cyl[8] * dx + cyl[11] * dy + cyl[14] * dz
        h = cyl[5] if s >= 0.0 else -cyl[5]
        x = cyl[0] + h * cyl[8]
        y = cyl[1] + h * cyl[11]
        z = cyl[2] + h * cyl[14]
        pn = math.sqrt(u * u + v * v)
        if pn > 0.0:
            u *= cyl[3] / pn
            v *= cyl[3] / pn
            x += u * cyl[6] + v * cyl[7]
            y += u * cyl[9] + v * cyl[10]
            z += u * cyl[12] + v * cyl[13]
        return x, y, z
    i = _support(p, adj, -1, dx, dy, dz)
    return p[i, 0], p[i, 1], p[i, 2]


@njit(cache=True, inline="always")
def _centre(p, adj, cyl):  # pragma: no cover - compiled
    """A point inside the core (GJK's first direction joins two of these): the cylinder's centre,
    the mean of the six extreme vertices a vertex graph stores, or the points' centroid."""
    if cyl.shape[0] >= CYL_W:
        return cyl[0], cyl[1], cyl[2]
    if adj.shape[0] > 0:
        gx = gy = gz = 0.0
        for k in range(6):
            gx += p[adj[k], 0]
            gy += p[adj[k], 1]
            gz += p[adj[k], 2]
        return gx / 6.0, gy / 6.0, gz / 6.0
    gx = gy = gz = 0.0
    for i in range(p.shape[0]):
        gx += p[i, 0]
        gy += p[i, 1]
        gz += p[i, 2]
    n = p.shape[0]
    return gx / n, gy / n, gz / n


@njit(cache=True, inline="always")
def _put(w, o, ax, ay, az, bx, by, bz):  # pragma: no cover - compiled
    """Vertex ``[a - b, a, b]`` at ``w[o:o + 9]``."""
    w[o] = ax - bx
    w[o + 1] = ay - by
    w[o + 2] = az - bz
    w[o + 3] = ax
    w[o + 4] = ay
    w[o + 5] = az
    w[o + 6] = bx
    w[o + 7] = by
    w[o + 8] = bz


@njit(cache=True, inline="always")
def _pair_support(pa, ga, ca, pb, gb, cb, dx, dy, dz):  # pragma: no cover - compiled
    """Support of ``M = A - B`` along ``d``: A's along ``d``, B's along ``-d``."""
    ax, ay, az = support_point(pa, ga, ca, dx, dy, dz)
    bx, by, bz = support_point(pb, gb, cb, -dx, -dy, -dz)
    return ax, ay, az, bx, by, bz


@njit(cache=True)
def gjk_support(pa, ga, ca, pb, gb, cb, dx, dy, dz, eps_len, gjk_eps, max_iter, work):  # pragma: no cover - compiled
    """GJK on the cores ``(pa, ca)`` and ``(pb, cb)`` from the initial direction ``d`` (B to A).

    Returns ``(status, dist, n, ax, ay, az, bx, by, bz)``: the core distance, the number of simplex
    vertices left in ``work`` (4: the origin is inside their tetrahedron) and the witnesses on the
    cores.  ``status`` as ``_pair_gjk``."""
    eps2 = eps_len * eps_len
    ax, ay, az, bx, by, bz = _pair_support(pa, ga, ca, pb, gb, cb, -dx, -dy, -dz)
    _put(work, _S0, ax, ay, az, bx, by, bz)
    work[_L0] = 1.0
    n = 1
    vx = work[_S0]
    vy = work[_S0 + 1]
    vz = work[_S0 + 2]
    vv = vx * vx + vy * vy + vz * vz
    status = GJK_NOT_CONVERGED
    gap = math.inf
    apart = False
    for _it in range(max_iter):
        if vv <= eps2:
            status = GJK_INTERSECTING
            break
        ax, ay, az, bx, by, bz = _pair_support(pa, ga, ca, pb, gb, cb, -vx, -vy, -vz)
        wx = ax - bx
        wy = ay - by
        wz = az - bz
        vw = vx * wx + vy * wy + vz * wz
        # w is M's point least along v: vw > 0 proves the origin outside M (w's plane separates
        # them), whatever later supports do near a rim (they jump between nearly equal points)
        apart = apart or vw > 0.0
        gap = (vv - vw) / math.sqrt(vv)
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
        if dup:
            # a repeated support point: no progress possible; apart when a support plane separated
            status = GJK_SEPARATED if apart else GJK_INTERSECTING
            break
        _put(work, _S0 + 9 * n, ax, ay, az, bx, by, bz)
        o1 = _S0 + 9
        o2 = _S0 + 18
        o3 = _S0 + 27
        m, k0, k1, k2, k3 = _closest_simplex(
            n + 1, work[_S0], work[_S0 + 1], work[_S0 + 2], work[o1], work[o1 + 1], work[o1 + 2],
            work[o2], work[o2 + 1], work[o2 + 2], work[o3], work[o3 + 1], work[o3 + 2])
        if m == 15:
            if apart:
                # a support plane separated the origin from M (a proof): the "inside" verdict came
                # from the Voronoi tests on a tetrahedron that rounding has made flat; the simplex stands
                status = GJK_SEPARATED
                break
            status = GJK_INTERSECTING
            n = 4
            break
        nvx = nvy = nvz = 0.0
        for j in range(n + 1):
            lam = k0 if j == 0 else (k1 if j == 1 else (k2 if j == 2 else k3))
            o = _S0 + 9 * j
            nvx += lam * work[o]
            nvy += lam * work[o + 1]
            nvz += lam * work[o + 2]
        nvv = nvx * nvx + nvy * nvy + nvz * nvz
        if nvv >= vv:
            # no progress (rounding): the previous simplex is the answer (apart when a support plane separated)
            status = GJK_SEPARATED if apart else GJK_INTERSECTING
            break
        c = 0
        for j in range(n + 1):  # compact the kept vertices into slots 0 .. c-1, in order
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
        return status, math.sqrt(vv), n, ax, ay, az, bx, by, bz
    return status, 0.0, 4, work[_S0 + 3], work[_S0 + 4], work[_S0 + 5], work[_S0 + 6], work[_S0 + 7], work[_S0 + 8]


@njit(cache=True)
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
            ax, ay, az, bx, by, bz = _pair_support(pa, ga, ca, pb, gb, cb, dx, dy, dz)
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
        # u: e x (the coordinate axis least aligned with e), v = e x u
        if abs(ex) <= abs(ey) and abs(ex) <= abs(ez):
            ux, uy, uz = 0.0, ez, -ey
        elif abs(ey) <= abs(ez):
            ux, uy, uz = -ez, 0.0, ex
        else:
            ux, uy, uz = ey, -ex, 0.0
        un = math.sqrt(ux * ux + uy * uy + uz * uz)
        ux /= un
        uy /= un
        uz /= un
        wx = ey * uz - ez * uy
        wy = ez * ux - ex * uz
        wz = ex * uy - ey * ux
        for k in range(6):
            t = k * (math.pi / 3.0)
            dx = math.cos(t) * ux + math.sin(t) * wx
            dy = math.cos(t) * uy + math.sin(t) * wy
            dz = math.cos(t) * uz + math.sin(t) * wz
            ax, ay, az, bx, by, bz = _pair_support(pa, ga, ca, pb, gb, cb, dx, dy, dz)
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
        ax, ay, az, bx, by, bz = _pair_support(pa, ga, ca, pb, gb, cb, sg * nx, sg * ny, sg * nz)
        off = sg * (nx * (ax - bx - work[_S0]) + ny * (ay - by - work[_S0 + 1]) + nz * (az - bz - work[_S0 + 2]))
        if off > eps:
            _put(work, _S0 + 27, ax, ay, az, bx, by, bz)
            return True
    return False


@njit(cache=True)
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


@njit(cache=True)
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


@njit(cache=True)
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


@njit(cache=True)
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


@njit(cache=True, inline="always")
def _area(ux, uy, uz, vx, vy, vz, nx, ny, nz):  # pragma: no cover - compiled
    """``(u x v) . n``: twice the signed area of the triangle (p, p + u, p + v) seen along ``n``."""
    return (uy * vz - uz * vy) * nx + (uz * vx - ux * vz) * ny + (ux * vy - uy * vx) * nz


@njit(cache=True)
def _settle(work, nf, fv, dbest, nx, ny, nz, h, best, tol):  # pragma: no cover - compiled
    """EPA's answer from the closest face (vertices ``fv``) when the polytope cannot grow (rounding on a curved core): its
    distance ``dbest`` when the support value ``h`` along its normal is within ``SUPPORT_GAP``,
    else ``best`` (the tightest such bracket seen before, or not settled)."""
    if h - dbest <= SUPPORT_GAP * (1.0 + dbest):
        res = _answer(work, nf, fv[0], fv[1], fv[2], dbest, nx, ny, nz, tol)
        if res[0]:
            return res
    return best


@njit(cache=True)
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
        ax, ay, az, bx, by, bz = _pair_support(pa, ga, ca, pb, gb, cb, nx, ny, nz)
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


@njit(cache=True)
def support_pair(pa, ca, ra, pb, cb, rb, out, work, eps_len, gjk_eps, max_iter, level):  # pragma: no cover
    """:func:`support_pair_graph` without vertex graphs (point cores are scanned)."""
    none = np.zeros(0, np.int64)
    return support_pair_graph(pa, none, ca, ra, pb, none, cb, rb, out, work, eps_len, gjk_eps, max_iter, level)


@njit(cache=True)
def support_pair_graph(pa, ga, ca, ra, pb, gb, cb, rb, out, work, eps_len, gjk_eps, max_iter, level):  # pragma: no cover
    """Signed distance (m) of the sphere-swept cores ``(pa, ca, ra)`` (A) and ``(pb, cb, rb)`` (B)
    (see the module docstring); writes ``out[0:9] = [p_WA, p_WB, nhat_AB_W]``.  Returns
    ``(distance, status)``, ``status`` as ``_pair_gjk`` (``GJK_NOT_CONVERGED``: the caller raises).

    ``level`` (m) as in ``_pair_epa.convex_convex_fast``: when the cores overlap and
    ``-(ra + rb) <= level`` it returns ``-(ra + rb)`` (an upper bound) without a depth.  EPA's
    polytope can break by rounding near a curved optimum (about 1 in 300 random penetrating pairs
    with a flat core against the cylinder did, and were once reported touching); the depth
    bracketed before that is the answer (:func:`epa_support`).  Only when EPA cannot settle a
    depth under any of its visibility margins (none of 9,000 seeded random pairs of a cylinder
    and a box, polygon or polyhedron, 6,736 of them penetrating, came to this) are the cores reported touching at GJK's witness: ``-(ra + rb)``, the right verdict (overlap), an upper
    bound on the signed distance, not the depth.

    ``ga``, ``gb``: the vertex graphs of the point cores (``_pack.hull_graph`` format, indices into
    ``pa`` / ``pb``; empty: the points are scanned); a cylinder side ignores its own."""
    gx, gy, gz = _centre(pa, ga, ca)
    hx, hy, hz = _centre(pb, gb, cb)
    status, d, n, ax, ay, az, bx, by, bz = gjk_support(pa, ga, ca, pb, gb, cb, gx - hx, gy - hy, gz - hz, eps_len, gjk_eps,
                                                       max_iter, work)
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
    return write_rounded(ax, ay, az, ra, ax, ay, az, rb, 0.0, 0.0, 1.0, 0.0, out, 0), GJK_INTERSECTING
