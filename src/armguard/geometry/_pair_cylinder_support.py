"""Support points of the cores :mod:`._pair_cylinder` runs GJK and EPA on (a cylinder's buffer, or a
point set scanned or climbed over its vertex graph), and the layout of the ``work`` buffer they share."""

from __future__ import annotations

import math

from numba import njit

from ._pair_gjk import _inner_point, _support, table_size, warm_start

__all__ = ["CYL_W", "SUPPORT_WORK_SIZE", "SUPPORT_GAP", "support_point"]

CYL_W = 15
"""Floats of a cylinder's buffer: ``[c (3), r, r, h, R_WC (9, row-major)]`` (the box layout)."""
SUPPORT_GAP = 1e-8
"""m per m of distance (plus 1): the duality gap GJK may stop at when its iterations run out, and
EPA when a support repeats or its vertices or faces run out on a curved core before its own test
(``gjk_epsilon``) is met -- a bound on the depth's error (in the tests the depths agree with the
references to ~1e-12 m)."""
_WA = 1  # work[1], work[2]: the last support vertex of A's and B's point core (-1: none yet), where
_WB = 2  # the next climb starts (Cameron, "Enhancing GJK", ICRA 1997); support_pair_graph resets them
_S0 = 3  # work[3:39]: GJK's simplex, vertex k = [w, a, b] at _S0 + 9 k; work[39:43] its weights
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
    return _inner_point(p, adj)


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
def _warm_point(p, adj, cyl, dx, dy, dz, work, slot, tab=None):  # pragma: no cover - compiled
    """:func:`support_point`, a point core's climb starting at the vertex ``work[slot]`` (the last
    support found on that core; < 0: a cold start) and storing the vertex it finds there.  A climb
    from any vertex returns a true support vertex (``_pair_gjk._climb``); GJK's and EPA's
    successive directions are close, so the warm climb is a few steps where a cold one, from the
    stored extremes, took ~15 on a 6,877-vertex gripper hull.  ``tab`` (``None``: none, pruned at
    compile time; or the core's support table, empty: none): the climb starts from the better of
    ``work[slot]`` and the table's entry for ``d`` (``_pair_gjk.warm_start``)."""
    if cyl.shape[0] >= CYL_W:
        return support_point(p, adj, cyl, dx, dy, dz)
    i = int(work[slot])
    if i >= p.shape[0]:
        i = -1  # not a vertex of this core (a buffer not reset by gjk_support): a cold start
    if i >= 0:
        i = warm_start(p, tab, table_size(tab), i, dx, dy, dz)
    i = _support(p, adj, i, dx, dy, dz)
    work[slot] = i
    return p[i, 0], p[i, 1], p[i, 2]


@njit(cache=True, _nrt=False)  # a plain call (not inlined at its 8 call sites: cold compile time); allocates nothing
def _pair_support(pa, ga, ca, pb, gb, cb, dx, dy, dz, work, ta=None, tb=None):  # pragma: no cover - compiled
    """Support of ``M = A - B`` along ``d``: A's along ``d``, B's along ``-d`` (point cores climbed
    from their last supports, ``work[_WA]`` and ``work[_WB]``, or their support tables' entries
    ``ta``, ``tb`` where those are farther along: :func:`_warm_point`)."""
    ax, ay, az = _warm_point(pa, ga, ca, dx, dy, dz, work, _WA, ta)
    bx, by, bz = _warm_point(pb, gb, cb, -dx, -dy, -dz, work, _WB, tb)
    return ax, ay, az, bx, by, bz
