"""Where EPA starts when GJK ends touching: its simplex completed to a tetrahedron of ``M = A - B``.

GJK stops "touching" when the origin comes within ``eps_len`` of its simplex (a point, a segment or a
triangle of support points), which is no polytope for EPA to expand (:mod:`._pair_epa`).  Such a
pair went to the exhaustive SAT, whose cost on mesh hulls is ``E_A E_B (V_A + V_B)``: a configuration
of kinova with two hulls 3.4e-13 m apart took 58 s.  :func:`complete_simplex` adds support points off
the simplex's span until it is a tetrahedron; EPA then settles the depth (about 0 for a contact).
"""

from __future__ import annotations

import math

from numba import njit

from ._pair_gjk import _b_dir, _b_point, _support

__all__ = ["complete_simplex", "perpendicular_basis", "ring_direction"]


@njit(cache=True, inline="always")
def perpendicular_basis(ex, ey, ez):  # pragma: no cover - compiled
    """``(u, v)``: unit vectors at right angles to the unit ``e`` and to each other, ``u = e x`` (the
    coordinate axis least aligned with ``e``), normalised, ``v = e x u`` (the directions a simplex's
    completion searches about a segment; shared with ``_pair_cylinder_epa._complete``)."""
    if abs(ex) <= abs(ey) and abs(ex) <= abs(ez):
        ux, uy, uz = 0.0, ez, -ey
    elif abs(ey) <= abs(ez):
        ux, uy, uz = -ez, 0.0, ex
    else:
        ux, uy, uz = ey, -ex, 0.0
    un = math.sqrt(ux * ux + uy * uy + uz * uz)
    ux, uy, uz = ux / un, uy / un, uz / un
    return ux, uy, uz, ey * uz - ez * uy, ez * ux - ex * uz, ex * uy - ey * ux


@njit(cache=True, inline="always")
def ring_direction(k, ux, uy, uz, vx, vy, vz):  # pragma: no cover - compiled
    """Direction ``k`` (0 to 5) of six at 60 degrees in the plane of the unit ``u`` and ``v``."""
    t = k * (math.pi / 3.0)
    c, s = math.cos(t), math.sin(t)
    return c * ux + s * vx, c * uy + s * vy, c * uz + s * vz


@njit(cache=True, inline="always")
def _m_point(pa, pb, rot, ox, oy, oz, ia, ib):  # pragma: no cover - compiled
    """The point ``a_ia - (R_AB b_ib + o)`` of ``M``."""
    qx, qy, qz = _b_point(pb, rot, ib)
    return pa[ia, 0] - qx - ox, pa[ia, 1] - qy - oy, pa[ia, 2] - qz - oz


@njit(cache=True, inline="always")
def _m_support(pa, adja, pb, adjb, rot, ox, oy, oz, dx, dy, dz):  # pragma: no cover - compiled
    """Support indices of ``M`` along ``d`` (A's along ``d``, B's along ``-d``; cold climbs) and the point."""
    ia = _support(pa, adja, -1, dx, dy, dz)
    ex, ey, ez = _b_dir(rot, -dx, -dy, -dz)
    ib = _support(pb, adjb, -1, ex, ey, ez)
    wx, wy, wz = _m_point(pa, pb, rot, ox, oy, oz, ia, ib)
    return ia, ib, wx, wy, wz


@njit(cache=True, _nrt=False)
def complete_simplex(pa, adja, pb, adjb, work, eps, rot=None, ox=0.0, oy=0.0, oz=0.0):  # pragma: no cover - compiled
    """GJK's touching simplex (``work[0] = -n``, ``n < 4`` vertices by support index in ``work[1:9]``
    as ``_pair_gjk._gjk_body`` leaves it, the origin within ``eps_len`` of it) completed to a
    tetrahedron of support points of ``M`` (``work[0] = 1``, as for an overlap) that :func:`epa_depth`
    starts from: supports added along directions off the simplex's span (the axes about a point, six
    directions about a segment, the triangle's normal on the origin's side, else the other), as the
    cylinder kernel's ``_pair_cylinder_epa._complete`` and van den Bergen's SOLID do.  EPA from it
    settles the depth of a touching contact (about 0) or of a deeper one whose GJK simplex happened to
    pass within ``eps_len`` of the origin; without it those pairs went to the exhaustive SAT (58 s on
    kinova's hulls of 1,498 and 1,252 vertices).  Returns False where ``M`` shows no extent off the
    span (``eps``, m)."""
    n = int(-work[0])
    if n < 1 or n > 3:
        return False
    ia0, ia1, ia2 = int(work[1]), int(work[2]), int(work[3])
    ib0, ib1, ib2 = int(work[5]), int(work[6]), int(work[7])
    x0, y0, z0 = _m_point(pa, pb, rot, ox, oy, oz, ia0, ib0)
    if n == 1:
        for k in range(6):
            dx = 1.0 if k == 0 else (-1.0 if k == 1 else 0.0)
            dy = 1.0 if k == 2 else (-1.0 if k == 3 else 0.0)
            dz = 1.0 if k == 4 else (-1.0 if k == 5 else 0.0)
            a, b, wx, wy, wz = _m_support(pa, adja, pb, adjb, rot, ox, oy, oz, dx, dy, dz)
            if (wx - x0) ** 2 + (wy - y0) ** 2 + (wz - z0) ** 2 > eps * eps:
                ia1, ib1 = a, b
                n = 2
                break
        if n == 1:
            return False
    if n == 2:
        x1, y1, z1 = _m_point(pa, pb, rot, ox, oy, oz, ia1, ib1)
        ex, ey, ez = x1 - x0, y1 - y0, z1 - z0
        en = math.sqrt(ex * ex + ey * ey + ez * ez)
        ex, ey, ez = ex / en, ey / en, ez / en
        ux, uy, uz, vx, vy, vz = perpendicular_basis(ex, ey, ez)
        for k in range(6):
            dx, dy, dz = ring_direction(k, ux, uy, uz, vx, vy, vz)
            a, b, wx, wy, wz = _m_support(pa, adja, pb, adjb, rot, ox, oy, oz, dx, dy, dz)
            rx, ry, rz = wx - x0, wy - y0, wz - z0
            sp = rx * ex + ry * ey + rz * ez
            rx, ry, rz = rx - sp * ex, ry - sp * ey, rz - sp * ez
            if rx * rx + ry * ry + rz * rz > eps * eps:
                ia2, ib2 = a, b
                n = 3
                break
        if n == 2:
            return False
    x1, y1, z1 = _m_point(pa, pb, rot, ox, oy, oz, ia1, ib1)
    x2, y2, z2 = _m_point(pa, pb, rot, ox, oy, oz, ia2, ib2)
    ux, uy, uz = x1 - x0, y1 - y0, z1 - z0
    vx, vy, vz = x2 - x0, y2 - y0, z2 - z0
    nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    nn = math.sqrt(nx * nx + ny * ny + nz * nz)
    if not nn > 0.0:
        return False
    nx, ny, nz = nx / nn, ny / nn, nz / nn
    side = -(nx * x0 + ny * y0 + nz * z0)  # the origin's offset from the triangle's plane
    for attempt in range(2):
        sg = 1.0 if (side >= 0.0) == (attempt == 0) else -1.0
        a, b, wx, wy, wz = _m_support(pa, adja, pb, adjb, rot, ox, oy, oz, sg * nx, sg * ny, sg * nz)
        if sg * (nx * (wx - x0) + ny * (wy - y0) + nz * (wz - z0)) > eps:
            work[0] = 1.0
            work[1], work[2], work[3], work[4] = ia0, ia1, ia2, a
            work[5], work[6], work[7], work[8] = ib0, ib1, ib2, b
            return True
    return False
