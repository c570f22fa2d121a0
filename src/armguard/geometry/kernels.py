"""The per-pair compiled kernels, callable from other numba ``@njit`` code (stable signatures).

All are ``@njit(cache=True)``, allocation-free, and trust their inputs (validate at the
public boundary).  Arrays are float64, m; ``out`` has at least 9 entries and receives
``[p_WA (3), p_WB (3), nhat_AB_W (3)]`` with ``p_WB - p_WA == distance * nhat_AB_W``.
Tolerances are passed as floats from :class:`armguard.Tolerances` (``eps_len = tol.length``,
``eps_par = tol.parallel``, ``gjk_eps = tol.gjk_epsilon``, ``max_iter = tol.gjk_max_iterations``,
``offset = tol.penetration_witness_offset``).

* ``segment_segment(p0, p1, q0, q1, out, eps_len, eps_par) -> float``: closest points of two
  segments (``out[0:6]``), unsigned distance (Ranger §3, Hermes's cases; Ericson's clamped form).
* ``capsule_capsule(p0, p1, ra, q0, q1, rb, out, eps_len, eps_par) -> float``: signed distance.
* ``capsule_box(p0, p1, r, center, half_extents, R_WB, out, eps_len, eps_par, offset) -> float``.
* ``capsule_polytope(p0, p1, r, verts, faces, edges, out, work, eps_len, eps_par, gjk_eps,
  max_iter, offset) -> (float, int)``: capsule against a polytope given by its vertices
  ``(V, 3)``, unit face normals ``(F, 3)`` and unit edge directions ``(E, 3)`` (one per
  parallel class; a shape's ``_sat`` tuple holds them); ``work`` has ``GJK_WORK_SIZE`` floats.
* ``convex_convex(pa, fa, ea, ra, pb, fb, eb, rb, out, work, eps_len, eps_par, gjk_eps,
  max_iter, offset) -> (float, int)``: any two sphere-swept polytopes (GJK; SAT depth).
* ``gjk_distance(pa, ra, pb, rb, out, work, eps_len, gjk_eps, max_iter) -> (float, int)``: GJK
  on core points plus radii (exact when the cores are disjoint; see its docstring).
* ``point_face(p, verts, normal, offset, out) -> (bool, float)``: Ranger §4 eqs. 7-10.
* ``box_box_overlap(ca, ha, R_WA, cb, hb, R_WB, eps_par) -> bool``: JPL division-free SAT.

The int returned by the GJK-based kernels is ``GJK_SEPARATED``, ``GJK_INTERSECTING`` or
``GJK_NOT_CONVERGED`` (the caller must treat the last as an error, never as a verdict).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._pair_box_box import box_box_overlap
from ._pair_gjk import GJK_INTERSECTING, GJK_NOT_CONVERGED, GJK_SEPARATED, GJK_WORK_SIZE
from ._pair_point_face import point_face
from ._pair_sat import convex_convex, gjk_distance, sat_depth
from ._pair_segment_box import capsule_box
from ._pair_segment_segment import capsule_capsule, segment_segment

__all__ = [
    "segment_segment",
    "capsule_capsule",
    "capsule_box",
    "capsule_polytope",
    "convex_convex",
    "gjk_distance",
    "sat_depth",
    "point_face",
    "box_box_overlap",
    "GJK_WORK_SIZE",
    "GJK_SEPARATED",
    "GJK_INTERSECTING",
    "GJK_NOT_CONVERGED",
]


@njit(cache=True)
def capsule_polytope(
    p0, p1, r, verts, faces, edges, out, work, eps_len, eps_par, gjk_eps, max_iter, offset
):  # pragma: no cover - compiled
    """Capsule ``(p0, p1, r)`` (A) against a polytope (B): see the module docstring."""
    seg = work[48:54].reshape((2, 3))  # scratch inside ``work``: no allocation
    edge = work[54:57].reshape((1, 3))
    for q in range(3):
        seg[0, q] = p0[q]
        seg[1, q] = p1[q]
    ex = p1[0] - p0[0]
    ey = p1[1] - p0[1]
    ez = p1[2] - p0[2]
    le = np.sqrt(ex * ex + ey * ey + ez * ez)
    if le > eps_len:
        edge[0, 0] = ex / le
        edge[0, 1] = ey / le
        edge[0, 2] = ez / le
        return convex_convex(seg, faces[0:0], edge, r, verts, faces, edges, 0.0, out, work, eps_len, eps_par, gjk_eps, max_iter, offset)
    return convex_convex(seg[0:1], faces[0:0], edge[0:0], r, verts, faces, edges, 0.0, out, work, eps_len, eps_par, gjk_eps, max_iter, offset)
