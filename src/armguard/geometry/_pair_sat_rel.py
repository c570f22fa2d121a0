"""Penetration depth of two polytopal cores by the exhaustive SAT with B in a frame of its own, and
the witness points of that depth: the link-frame counterpart of :func:`._pair_sat.sat_depth` and of
the SAT path of :func:`._pair_sat.convex_convex_at`.

The separating-axis theorem for convex polytopes (Gottschalk, Lin & Manocha, "OBBTree", SIGGRAPH
1996, §4; Ericson, *Real-Time Collision Detection* §5.2.1): the facet normals of the Minkowski
difference ``M = A - B`` are among the face normals of A, those of B and the cross products
``e_A x e_B`` of an edge direction of each, so the penetration depth -- the shortest translation of
B that separates the cores, ``min_u h_M(u)`` over unit ``u`` -- is the least projection overlap

    ``depth = min_u min(max_A u - min_B u, max_B u - min_A u)``   (Ericson eq. 5.2 per axis)

over those axes.  Here A's points ``pa`` are in A's frame and B's ``pb`` in B's, placed by
``X_AB = (R_AB, t_AB)``: B's extent along an axis ``u`` (A's frame) is that of ``pb`` along
``R_AB^T u`` plus ``u . t_AB``, so no point of B is moved, only B's face normals and edge
directions are rotated (one rotation each).  The axes are the same as :func:`._pair_sat.sat_depth`'s
on the cores moved to one frame, in the same order, so the depth and the axis agree with it to
rounding (the reference; ``tests/test_geometry_sat_rel.py`` holds them to the tolerance).

Cost: ``(F_A + F_B + E_A E_B) (V_A + V_B)`` dot products (``F``, ``E``: face-normal and edge-direction
classes, ``V``: points), against EPA's iterations of a face scan and two support scans
(:func:`._pair_epa.epa_depth`); :func:`sat_cost` lets a caller pick the cheaper one.
"""

from __future__ import annotations

import math

from numba import njit

from ._pair_gjk import GJK_INTERSECTING, GJK_NOT_CONVERGED, GJK_SEPARATED, _b_dir, gjk_dir_rel
from ._pair_sat import _extent

__all__ = ["sat_cost", "sat_depth_rel", "sat_witnesses_rel"]


@njit(cache=True, inline="always")
def sat_cost(na, fa, ea, nb, fb, eb):  # pragma: no cover - compiled
    """Dot products :func:`sat_depth_rel` takes for cores of ``na``, ``nb`` points with ``fa``, ``fb``
    face-normal and ``ea``, ``eb`` edge-direction classes."""
    return (fa + fb + ea * eb) * (na + nb)


@njit(cache=True, inline="always")
def _axis_rel(pa, pb, rot, tx, ty, tz, ux, uy, uz, depth, nx, ny, nz):  # pragma: no cover - compiled
    """:func:`._pair_sat._axis` with B's points ``R_AB pb + t``: B's extent along ``u`` is that of
    ``pb`` along ``R_AB^T u``, shifted by ``u . t``."""
    alo, ahi = _extent(pa, ux, uy, uz)
    vx, vy, vz = _b_dir(rot, ux, uy, uz)
    s = ux * tx + uy * ty + uz * tz
    blo, bhi = _extent(pb, vx, vy, vz)
    plus = ahi - (blo + s)  # move B along +u by this much to separate
    minus = (bhi + s) - alo  # or along -u by this much
    if plus < depth:
        depth, nx, ny, nz = plus, ux, uy, uz
    if minus < depth:
        depth, nx, ny, nz = minus, -ux, -uy, -uz
    return depth, nx, ny, nz


@njit(cache=True)
def sat_depth_rel(pa, fa, ea, pb, fb, eb, rot, tx, ty, tz, eps_par):  # pragma: no cover - compiled
    """:func:`._pair_sat.sat_depth` of core A (``pa``, face normals ``fa``, edge directions ``ea``, in
    A's frame) and core B (``pb``, ``fb``, ``eb`` in B's frame, placed in A's by ``rot`` = ``R_AB``
    row-major and ``t_AB = (tx, ty, tz)``).  Returns ``(depth, nx, ny, nz)`` in A's frame: moving B
    by ``depth * n`` makes the cores touch; ``depth < 0``: separated along ``n`` (a lower bound on the
    gap); ``depth = inf``: no axis (two point cores)."""
    depth = math.inf
    nx = 0.0
    ny = 0.0
    nz = 1.0
    for i in range(fa.shape[0]):
        depth, nx, ny, nz = _axis_rel(pa, pb, rot, tx, ty, tz, fa[i, 0], fa[i, 1], fa[i, 2], depth, nx, ny, nz)
    for j in range(fb.shape[0]):
        x = fb[j, 0]
        y = fb[j, 1]
        z = fb[j, 2]
        ux = rot[0] * x + rot[1] * y + rot[2] * z  # R_AB f: B's face normal in A's frame
        uy = rot[3] * x + rot[4] * y + rot[5] * z
        uz = rot[6] * x + rot[7] * y + rot[8] * z
        depth, nx, ny, nz = _axis_rel(pa, pb, rot, tx, ty, tz, ux, uy, uz, depth, nx, ny, nz)
    for i in range(ea.shape[0]):  # A's edges outer, B's inner: sat_depth's order (same ties)
        e1x = ea[i, 0]
        e1y = ea[i, 1]
        e1z = ea[i, 2]
        for j in range(eb.shape[0]):
            x = eb[j, 0]
            y = eb[j, 1]
            z = eb[j, 2]
            e2x = rot[0] * x + rot[1] * y + rot[2] * z
            e2y = rot[3] * x + rot[4] * y + rot[5] * z
            e2z = rot[6] * x + rot[7] * y + rot[8] * z
            ux = e1y * e2z - e1z * e2y
            uy = e1z * e2x - e1x * e2z
            uz = e1x * e2y - e1y * e2x
            un = math.sqrt(ux * ux + uy * uy + uz * uz)
            if un <= eps_par:
                continue
            depth, nx, ny, nz = _axis_rel(pa, pb, rot, tx, ty, tz, ux / un, uy / un, uz / un, depth, nx, ny, nz)
    return depth, nx, ny, nz


@njit(cache=True)
def sat_witnesses_rel(pa, adja, taba, pb, adjb, tabb, rot, tx, ty, tz, depth, nx, ny, nz, simp, eps_len, gjk_eps,
                      max_iter, offset):  # pragma: no cover - compiled
    """Witness points of the SAT depth ``depth`` along ``n`` (A's frame, from :func:`sat_depth_rel`),
    as :func:`._pair_sat.convex_convex_at` finds them: B pushed out along ``n`` by ``depth + offset``
    (``offset``: ``Tolerances.penetration_witness_offset``; by ``offset`` alone when ``depth < 0``),
    GJK in A's frame (:func:`._pair_gjk.gjk_dir_rel`, ``simp`` its 9-float simplex) finds the closest
    points of the now-separated cores, and B's witness is moved back.

    Returns ``(status, ax, ay, az, bx, by, bz)`` in A's frame: ``GJK_INTERSECTING`` (the cores
    overlap by ``depth``), ``GJK_SEPARATED`` (``depth < 0``: apart by ``-depth``; the caller reports
    the gap), or ``GJK_NOT_CONVERGED`` (the rest meaningless)."""
    shift = depth + offset if depth >= 0.0 else offset
    ox = tx + shift * nx
    oy = ty + shift * ny
    oz = tz + shift * nz
    status, d, ax, ay, az, bx, by, bz = gjk_dir_rel(pa, adja, taba, pb, adjb, tabb, rot, ox, oy, oz, -nx, -ny, -nz,
                                                    eps_len, gjk_eps, max_iter, simp, math.inf, adja[0:0])
    if status == GJK_NOT_CONVERGED:
        return GJK_NOT_CONVERGED, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    return (GJK_INTERSECTING if depth >= 0.0 else GJK_SEPARATED), ax, ay, az, bx - shift * nx, by - shift * ny, \
        bz - shift * nz
