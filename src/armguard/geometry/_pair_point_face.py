"""Ranger's point-to-polygonal-face test (seed ``000`` §4, eqs. 7-10).

For a planar convex face with vertices ``v_i`` counter-clockwise seen from outside, unit edge
directions ``A_i = (v_(i+1) - v_i) / |.|`` and outward normal ``n`` (the average of
``A_i x A_(i+1)``), the plane offset is ``d_of = n . p_f`` with ``p_f`` the vertex centroid
(eq. 7), the signed point-plane distance ``d_f = n . p - d_of`` (eq. 8), the projection
``Q = p - d_f n`` (eq. 9), and ``Q`` is inside the face iff ``n . (A_i x B_i) > 0`` for every
edge, ``B_i = Q - v_i`` (eq. 10).  Eq. 10 is a sign test, so ``A_i`` need not be normalised;
we accept ``>= 0`` so that points on the boundary count as inside (the nearest point is then
the projection, which equals the edge point).
"""

from __future__ import annotations

from numba import njit

__all__ = ["point_face"]


@njit(cache=True)
def point_face(p, verts, normal, offset, out):  # pragma: no cover - compiled
    """Project ``p`` onto a face and test whether the projection lies inside it.

    ``p : (3,) float64, m``; ``verts : (n, 3) float64, m`` counter-clockwise about ``normal``
    (``(3,)`` unit, outward); ``offset = normal . centroid`` (m, eq. 7).  Writes ``Q`` into
    ``out[0:3]``; returns ``(inside, d_f)``: whether ``Q`` is in the face (eq. 10) and the
    signed distance of ``p`` above the face plane (m, eq. 8).  Allocation-free.
    """
    nx = normal[0]
    ny = normal[1]
    nz = normal[2]
    px = p[0]
    py = p[1]
    pz = p[2]
    d_f = nx * px + ny * py + nz * pz - offset
    qx = px - d_f * nx
    qy = py - d_f * ny
    qz = pz - d_f * nz
    out[0] = qx
    out[1] = qy
    out[2] = qz
    n = verts.shape[0]
    inside = True
    for i in range(n):
        j = i + 1 if i + 1 < n else 0
        ax = verts[j, 0] - verts[i, 0]
        ay = verts[j, 1] - verts[i, 1]
        az = verts[j, 2] - verts[i, 2]
        bx = qx - verts[i, 0]
        by = qy - verts[i, 1]
        bz = qz - verts[i, 2]
        cx = ay * bz - az * by
        cy = az * bx - ax * bz
        cz = ax * by - ay * bx
        if nx * cx + ny * cy + nz * cz < 0.0:
            inside = False
            break
    return inside, d_f
