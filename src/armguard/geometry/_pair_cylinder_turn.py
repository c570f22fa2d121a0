"""GJK's way out of a stall on a cylinder's rim (:func:`_refresh`): the simplex's cylinder points
turned about the axis to one best angle.

On a rim against an edge of a polytope, GJK's simplex keeps, beside its newest supports, an old
vertex whose rim point lies ~1e-4 rad along the rim from the optimum: the support along ``-v``
returns the same end of the edge every step, so the vertex at the edge's other end, found early,
is never replaced.  Its chord holds ``|v|`` 1e-9 to 1e-8 m above the distance.  Each step then
gains ~``gap^2 / L`` (``L`` the simplex's length, ~1 m), below the rounding of Johnson's
sub-algorithm on that thin simplex, and GJK stalled (seeds 2684 and 8402 of
``tests/test_engine_from_model.py::test_random_scenes_compile_alike``: 1.25e-8 and 1.03e-9 m over
the distance).  The support itself is no cure: ``v``'s direction is off by the witness's lateral
error over the distance ``|v|``, and the rim's support along it lands ~``R / |v|`` times farther
from the optimum than the simplex's own rim points (R the radius).

So the refresh turns every cylinder point of the simplex about the axis, keeping its level and its
distance from the axis (a point of the cylinder still: each vertex ``a_k - b_k`` stays a point of
``M = A - B`` and ``|v|`` an upper bound on the distance), to one radial direction ``u(t)``, the
normalised ``(1 - t) u_w + t u_s`` between the radial directions of the cylinder's witness
(``u_w``, the weighted mean of the simplex's rim points) and of the latest support (``u_s``), and
picks ``t`` in ``[-1, 2]`` minimising the turned simplex's distance to the origin by golden-section
search (Kiefer 1953; the distance of a polytope feature to a rim point is convex in the angle near
the optimum).  The turned vertices sharing one angle (one rim point, or a top and a bottom point:
a side line) hold an edge-rim or edge-side optimum exactly; GJK then resumes from them.  A cap's
face against a flat face needs rim points at several angles: there the turn gains nothing and the
caller restores the simplex.
"""

from __future__ import annotations

import math

from numba import njit

from ._pair_cylinder_support import _L0, _S0, _V0, CYL_W, _put
from ._pair_gjk import _closest_simplex

__all__ = ["_combine", "_refresh", "_restore"]

_GOLDEN = 0.6180339887498949
_STEPS = 40  # golden-section steps: the bracket [-1, 2] shrinks to 3 * 0.618^40 = 1.3e-8 in t


@njit(cache=True, inline="always")
def _combine(work, nn, k0, k1, k2, k3):  # pragma: no cover - compiled
    """``v = sum_j k_j w_j`` over the first ``nn`` simplex vertices, and ``|v|^2``."""
    nvx = nvy = nvz = 0.0
    for j in range(nn):
        lam = k0 if j == 0 else (k1 if j == 1 else (k2 if j == 2 else k3))
        o = _S0 + 9 * j
        nvx += lam * work[o]
        nvy += lam * work[o + 1]
        nvz += lam * work[o + 2]
    return nvx, nvy, nvz, nvx * nvx + nvy * nvy + nvz * nvz


@njit(cache=True, inline="always")
def _radial(cyl, x, y, z):  # pragma: no cover - compiled
    """Unit radial direction (W) of the point ``p`` about the cylinder's axis (column 2 of ``R_WC``)
    and ``p``'s level ``t`` along it: ``(ux, uy, uz, r, t)``, ``r`` the distance from the axis (0:
    ``u = 0``).

    ``u`` is built from ``p``'s coordinates along columns 0 and 1 of ``R_WC`` (as the support
    function builds its rim point), so it stays at right angles to the axis however near the axis
    ``p`` lies.  ``p - t a`` normalised, as before, is rounding noise for a point on the axis (a
    cap's centre, the witness of a simplex across a rim diameter) and may lean along the axis: a
    point :func:`_turned` to it left the cylinder by up to its radius (tiago_dual's wrist cylinder,
    1 mm beyond the cap, a distance 0.96 mm short; ``tests/test_geometry_cylinder.py``)."""
    x -= cyl[0]
    y -= cyl[1]
    z -= cyl[2]
    t = x * cyl[8] + y * cyl[11] + z * cyl[14]
    u = x * cyl[6] + y * cyl[9] + z * cyl[12]
    v = x * cyl[7] + y * cyl[10] + z * cyl[13]
    r = math.sqrt(u * u + v * v)
    if r > 0.0:
        u /= r
        v /= r
        return u * cyl[6] + v * cyl[7], u * cyl[9] + v * cyl[10], u * cyl[12] + v * cyl[13], r, t
    return 0.0, 0.0, 0.0, 0.0, t


@njit(cache=True, inline="always")
def _witness_dir(cyl, work, n, off):  # pragma: no cover - compiled
    """Unit radial direction of the cylinder's witness ``sum_k l_k p_k`` (``p_k`` the cylinder
    points of the saved simplex's ``n`` vertices, at ``off`` in each, ``l_k`` their weights)."""
    x = y = z = 0.0
    for k in range(n):
        o = _V0 + 9 * k + off
        lam = work[_V0 + 36 + k]
        x += lam * work[o]
        y += lam * work[o + 1]
        z += lam * work[o + 2]
    ux, uy, uz, _r, _t = _radial(cyl, x, y, z)
    return ux, uy, uz


@njit(cache=True, inline="always")
def _turned(cyl, work, o, t, wx, wy, wz, sx, sy, sz):  # pragma: no cover - compiled
    """The cylinder point ``work[o:o + 3]`` turned about the axis to the radial direction
    ``u(t)``, the normalised ``(1 - t) u_w + t u_s`` (itself where that is 0)."""
    ux = (1.0 - t) * wx + t * sx
    uy = (1.0 - t) * wy + t * sy
    uz = (1.0 - t) * wz + t * sz
    un = math.sqrt(ux * ux + uy * uy + uz * uz)
    if un == 0.0:
        return work[o], work[o + 1], work[o + 2]
    _x, _y, _z, r, h = _radial(cyl, work[o], work[o + 1], work[o + 2])
    r /= un
    return (cyl[0] + h * cyl[8] + r * ux, cyl[1] + h * cyl[11] + r * uy, cyl[2] + h * cyl[14] + r * uz)


@njit(cache=True, _nrt=False)
def _turn(work, n, ca, cb, t, da, db, eps2):  # pragma: no cover - compiled
    """The saved simplex (``_V0``) with its cylinder points turned to ``u(t)`` (``da``, ``db``: each
    side's ``[u_w, u_s]``; an empty ``ca`` / ``cb``: not a cylinder, kept), repeated points (within
    ``sqrt(eps2)``) dropped, written at ``_S0``.  Returns ``(c, mask, l0, l1, l2, l3, |v|^2)`` as
    ``_pair_gjk._closest_simplex`` on its ``c`` vertices (``|v|^2`` infinite where it holds the origin)."""
    c = 0
    for j in range(n):
        o = _V0 + 9 * j
        px, py, pz = work[o + 3], work[o + 4], work[o + 5]
        qx, qy, qz = work[o + 6], work[o + 7], work[o + 8]
        if ca.shape[0] >= CYL_W:
            px, py, pz = _turned(ca, work, o + 3, t, da[0], da[1], da[2], da[3], da[4], da[5])
        if cb.shape[0] >= CYL_W:
            qx, qy, qz = _turned(cb, work, o + 6, t, db[0], db[1], db[2], db[3], db[4], db[5])
        dup = False
        for k in range(c):
            ok = _S0 + 9 * k
            ex = work[ok] - (px - qx)
            ey = work[ok + 1] - (py - qy)
            ez = work[ok + 2] - (pz - qz)
            if ex * ex + ey * ey + ez * ez <= eps2:
                dup = True
        if not dup:
            _put(work, _S0 + 9 * c, px, py, pz, qx, qy, qz)
            c += 1
    o1 = _S0 + 9
    o2 = _S0 + 18
    o3 = _S0 + 27
    m, k0, k1, k2, k3 = _closest_simplex(
        c, work[_S0], work[_S0 + 1], work[_S0 + 2], work[o1], work[o1 + 1], work[o1 + 2],
        work[o2], work[o2 + 1], work[o2 + 2], work[o3], work[o3 + 1], work[o3 + 2])
    if m == 15:
        return c, m, k0, k1, k2, k3, math.inf
    return c, m, k0, k1, k2, k3, _combine(work, c, k0, k1, k2, k3)[3]


@njit(cache=True, _nrt=False)
def _refresh(work, n, ca, cb, ax, ay, az, bx, by, bz, eps2, dirs):  # pragma: no cover - compiled
    """The simplex ``work[_S0:]`` (``n`` vertices, weights at ``_L0``) with its cylinder points
    turned to the best common angle (the module docstring); ``a``, ``b``: the latest supports of A
    (along ``-v``) and B (along ``+v``); ``dirs``: 12 floats of scratch.  The old simplex is saved
    at ``_V0`` (EPA's area, unused by GJK) for :func:`_restore`.  Returns ``(c, mask, l0 .. l3,
    |v|^2)`` of the turned simplex, written at ``_S0`` (the caller keeps it only when ``|v|``
    drops)."""
    for q in range(36):
        work[_V0 + q] = work[_S0 + q]
    for q in range(4):
        work[_V0 + 36 + q] = work[_L0 + q]
    da = dirs[0:6]
    db = dirs[6:12]
    for q in range(12):
        dirs[q] = 0.0
    if ca.shape[0] >= CYL_W:
        da[0], da[1], da[2] = _witness_dir(ca, work, n, 3)
        da[3], da[4], da[5], _r, _t = _radial(ca, ax, ay, az)
    if cb.shape[0] >= CYL_W:
        db[0], db[1], db[2] = _witness_dir(cb, work, n, 6)
        db[3], db[4], db[5], _r, _t = _radial(cb, bx, by, bz)
    lo = -1.0
    hi = 2.0
    x1 = hi - _GOLDEN * (hi - lo)
    x2 = lo + _GOLDEN * (hi - lo)
    f1 = _turn(work, n, ca, cb, x1, da, db, eps2)[6]
    f2 = _turn(work, n, ca, cb, x2, da, db, eps2)[6]
    for _ in range(_STEPS):
        if f1 <= f2:
            hi = x2
            x2 = x1
            f2 = f1
            x1 = hi - _GOLDEN * (hi - lo)
            f1 = _turn(work, n, ca, cb, x1, da, db, eps2)[6]
        else:
            lo = x1
            x1 = x2
            f1 = f2
            x2 = lo + _GOLDEN * (hi - lo)
            f2 = _turn(work, n, ca, cb, x2, da, db, eps2)[6]
    t = x1 if f1 <= f2 else x2
    if _turn(work, n, ca, cb, 0.0, da, db, eps2)[6] <= min(f1, f2):
        t = 0.0  # the witness's own angle
    return _turn(work, n, ca, cb, t, da, db, eps2)


@njit(cache=True, inline="always")
def _restore(work):  # pragma: no cover - compiled
    """Undo :func:`_refresh`: the saved simplex and weights back at ``_S0`` and ``_L0``."""
    for q in range(36):
        work[_S0 + q] = work[_V0 + q]
    for q in range(4):
        work[_L0 + q] = work[_V0 + 36 + q]
