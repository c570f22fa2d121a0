"""Segment-segment closest points: capsule-capsule, sphere-capsule and sphere-sphere kernels.

Ranger (seed ``000``) §3 derives the closest points of two infinite lines (eqs. 1-6:
``t1 = a + t2 b``, ``t2 = (a b - c) / (1 - b^2)`` with unit directions) and then corrects them
for finite segments (§3.2: clamp one, re-project the other, two-stage when both are outside).
Hermes (seed ``001``, link-link module) does the same with "eight cases" (end-points against
the other link's interior and against its end-points) and a separate parallel branch.  We use
the clamped closed form of Ericson, *Real-Time Collision Detection* §5.1.9
(``ClosestPtSegmentSegment``), which is the same stationary-point solution written with
un-normalised directions (``s = (b f - c e) / (a e - b^2)``) followed by exactly Ranger's
correction rule (clamp ``s``, recompute ``t``, clamp ``t`` and recompute ``s``); it handles the
parallel (``a e - b^2 = 0``) and degenerate (zero-length) cases without a special branch for
each of Hermes's eight cases.  Ericson's variable names are kept.

All kernels are ``@njit(cache=True)``, scalar style, allocation-free; they write
``out[0:3] = p_WA``, ``out[3:6] = p_WB``, ``out[6:9] = nhat_AB_W`` and return the signed distance.
"""

from __future__ import annotations

import math

from numba import njit

__all__ = [
    "segment_segment_params",
    "segment_segment_closest",
    "segment_segment",
    "capsule_capsule",
    "write_rounded",
    "perpendicular_unit",
]


@njit(cache=True, inline="always")
def segment_segment_params(
    p1x, p1y, p1z, q1x, q1y, q1z, p2x, p2y, p2z, q2x, q2y, q2z, eps_len2, eps_par2
):  # pragma: no cover - compiled
    """Parameters ``(s, t)`` in [0, 1] of the closest points ``p1 + s (q1 - p1)`` and ``p2 + t (q2 - p2)``.

    Ericson §5.1.9.  ``eps_len2`` (m^2): a squared length below which a segment is a point;
    ``eps_par2``: squared sine below which the segments are parallel (then ``s = 0``, which
    still yields a correct closest pair, as Ericson shows).
    """
    d1x = q1x - p1x
    d1y = q1y - p1y
    d1z = q1z - p1z
    d2x = q2x - p2x
    d2y = q2y - p2y
    d2z = q2z - p2z
    rx = p1x - p2x
    ry = p1y - p2y
    rz = p1z - p2z
    a = d1x * d1x + d1y * d1y + d1z * d1z
    e = d2x * d2x + d2y * d2y + d2z * d2z
    f = d2x * rx + d2y * ry + d2z * rz
    if a <= eps_len2 and e <= eps_len2:
        return 0.0, 0.0
    if a <= eps_len2:
        t = f / e
        return 0.0, min(1.0, max(0.0, t))
    c = d1x * rx + d1y * ry + d1z * rz
    if e <= eps_len2:
        s = -c / a
        return min(1.0, max(0.0, s)), 0.0
    b = d1x * d2x + d1y * d2y + d1z * d2z
    denom = a * e - b * b
    if denom > eps_par2 * a * e:
        s = min(1.0, max(0.0, (b * f - c * e) / denom))
    else:
        s = 0.0
    t = (b * s + f) / e
    if t < 0.0:
        t = 0.0
        s = min(1.0, max(0.0, -c / a))
    elif t > 1.0:
        t = 1.0
        s = min(1.0, max(0.0, (b - c) / a))
    return s, t


@njit(cache=True, inline="always")
def perpendicular_unit(dx, dy, dz):  # pragma: no cover - compiled
    """A unit vector perpendicular to ``d`` (any unit vector when ``d`` is zero)."""
    ax = abs(dx)
    ay = abs(dy)
    az = abs(dz)
    # cross d with the coordinate axis it is least aligned with
    if ax <= ay and ax <= az:
        nx, ny, nz = 0.0, dz, -dy
    elif ay <= az:
        nx, ny, nz = -dz, 0.0, dx
    else:
        nx, ny, nz = dy, -dx, 0.0
    n = math.sqrt(nx * nx + ny * ny + nz * nz)
    if n == 0.0:
        return 0.0, 0.0, 1.0
    return nx / n, ny / n, nz / n


@njit(cache=True, inline="always")
def write_rounded(cax, cay, caz, ra, cbx, cby, cbz, rb, nx, ny, nz, dcore, out, base):  # pragma: no cover
    """Write witness points of two rounded cores with core witnesses ``ca``, ``cb`` and unit ``n``.

    ``p_WA = ca + ra n``; ``p_WB = p_WA + distance n`` with ``distance = dcore - ra - rb`` so the
    witness relation holds to rounding.  Writes ``out[base:base + 9]``.  Returns the signed distance.
    """
    dist = dcore - ra - rb
    ax = cax + ra * nx
    ay = cay + ra * ny
    az = caz + ra * nz
    out[base + 0] = ax
    out[base + 1] = ay
    out[base + 2] = az
    out[base + 3] = cbx - rb * nx
    out[base + 4] = cby - rb * ny
    out[base + 5] = cbz - rb * nz
    out[base + 6] = nx
    out[base + 7] = ny
    out[base + 8] = nz
    return dist


@njit(cache=True)
def segment_segment(p0, p1, q0, q1, out, eps_len, eps_par):  # pragma: no cover - compiled
    """Closest points of segments ``p0-p1`` and ``q0-q1`` (each ``(3,) float64, m``, W).

    Writes ``out[0:3]`` (on the first segment), ``out[3:6]`` (on the second) and returns the
    (unsigned) distance in m.  ``eps_len`` (m) and ``eps_par`` (sine) as in ``Tolerances``.
    """
    s, t = segment_segment_params(
        p0[0], p0[1], p0[2], p1[0], p1[1], p1[2], q0[0], q0[1], q0[2], q1[0], q1[1], q1[2],
        eps_len * eps_len, eps_par * eps_par,
    )
    ax = p0[0] + s * (p1[0] - p0[0])
    ay = p0[1] + s * (p1[1] - p0[1])
    az = p0[2] + s * (p1[2] - p0[2])
    bx = q0[0] + t * (q1[0] - q0[0])
    by = q0[1] + t * (q1[1] - q0[1])
    bz = q0[2] + t * (q1[2] - q0[2])
    out[0] = ax
    out[1] = ay
    out[2] = az
    out[3] = bx
    out[4] = by
    out[5] = bz
    return math.sqrt((bx - ax) ** 2 + (by - ay) ** 2 + (bz - az) ** 2)


@njit(cache=True, inline="always")
def segment_segment_closest(p0x, p0y, p0z, p1x, p1y, p1z, q0x, q0y, q0z, q1x, q1y, q1z, eps_len, eps_par):  # pragma: no cover
    """The closest points ``a`` of segment ``p0-p1`` and ``b`` of ``q0-q1`` (:func:`segment_segment_params`),
    ``v = b - a`` and ``|v|``: ``(ax, ay, az, bx, by, bz, vx, vy, vz, |v|)``."""
    s, t = segment_segment_params(
        p0x, p0y, p0z, p1x, p1y, p1z, q0x, q0y, q0z, q1x, q1y, q1z, eps_len * eps_len, eps_par * eps_par
    )
    ax = p0x + s * (p1x - p0x)
    ay = p0y + s * (p1y - p0y)
    az = p0z + s * (p1z - p0z)
    bx = q0x + t * (q1x - q0x)
    by = q0y + t * (q1y - q0y)
    bz = q0z + t * (q1z - q0z)
    vx = bx - ax
    vy = by - ay
    vz = bz - az
    return ax, ay, az, bx, by, bz, vx, vy, vz, math.sqrt(vx * vx + vy * vy + vz * vz)


@njit(cache=True, inline="always")
def capsule_capsule_scalar(
    p0x, p0y, p0z, p1x, p1y, p1z, ra, q0x, q0y, q0z, q1x, q1y, q1z, rb, out, base, eps_len, eps_par
):  # pragma: no cover - compiled
    """Scalar-argument capsule-capsule (see :func:`capsule_capsule`)."""
    ax, ay, az, bx, by, bz, vx, vy, vz, dcore = segment_segment_closest(
        p0x, p0y, p0z, p1x, p1y, p1z, q0x, q0y, q0z, q1x, q1y, q1z, eps_len, eps_par
    )
    if dcore > eps_len:
        return write_rounded(ax, ay, az, ra, bx, by, bz, rb, vx / dcore, vy / dcore, vz / dcore, dcore, out, base)
    # Cores meet: the Minkowski difference of two segments is flat (a parallelogram), so the
    # shortest separating translation is along its normal d1 x d2, of length ra + rb.
    d1x = p1x - p0x
    d1y = p1y - p0y
    d1z = p1z - p0z
    d2x = q1x - q0x
    d2y = q1y - q0y
    d2z = q1z - q0z
    nx = d1y * d2z - d1z * d2y
    ny = d1z * d2x - d1x * d2z
    nz = d1x * d2y - d1y * d2x
    nn = math.sqrt(nx * nx + ny * ny + nz * nz)
    l1 = math.sqrt(d1x * d1x + d1y * d1y + d1z * d1z)
    l2 = math.sqrt(d2x * d2x + d2y * d2y + d2z * d2z)
    if nn > eps_par * l1 * l2 and nn > 0.0:
        nx /= nn
        ny /= nn
        nz /= nn
    elif l1 > eps_len:
        nx, ny, nz = perpendicular_unit(d1x, d1y, d1z)
    else:
        nx, ny, nz = perpendicular_unit(d2x, d2y, d2z)
    return write_rounded(ax, ay, az, ra, bx, by, bz, rb, nx, ny, nz, 0.0, out, base)


@njit(cache=True)
def capsule_capsule(p0, p1, ra, q0, q1, rb, out, eps_len, eps_par):  # pragma: no cover - compiled
    """Signed distance between capsules ``(p0, p1, ra)`` and ``(q0, q1, rb)`` (Ranger link-link).

    ``p0, p1, q0, q1 : (3,) float64, m``; ``ra, rb`` m.  Writes ``out[0:9]`` =
    ``[p_WA, p_WB, nhat_AB_W]``; returns the signed distance (m).  A zero radius is a segment, a
    zero length a sphere.  Allocation-free; callable from njit code.
    """
    return capsule_capsule_scalar(
        p0[0], p0[1], p0[2], p1[0], p1[1], p1[2], ra, q0[0], q0[1], q0[2], q1[0], q1[1], q1[2], rb,
        out, 0, eps_len, eps_par,
    )


@njit(cache=True)
def capsule_capsule_packed(a, b, out, eps_len, eps_par):  # pragma: no cover - compiled
    """Capsule-capsule on packed buffers ``[p0, p1, r]`` (7,) -- the single-call fast path."""
    return capsule_capsule_scalar(
        a[0], a[1], a[2], a[3], a[4], a[5], a[6], b[0], b[1], b[2], b[3], b[4], b[5], b[6],
        out, 0, eps_len, eps_par,
    )
