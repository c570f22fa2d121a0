"""The support face of a hull found over its vertex graph: :func:`face_span` without the scan.

:func:`armguard.backends._jacobian.face_span` decides a witness's uniqueness from the support
face of a shape in a direction ``u``: the vertices within ``tol_face`` of the highest one.  It
scans every vertex twice, and on mesh hulls of thousands of vertices that scan is most of a
distance Jacobian's cost (so101's 4,880-vertex gripper, z1's 6,877).

On a convex polytope the same set is found from the edges alone:

* a vertex with no higher neighbour is a highest vertex (a linear function has no local maximum
  on a polytope's vertex graph that is not global: the simplex method's argument), so a climb
  from any vertex ends at the top;
* the vertices at most ``tol_face`` below the top induce a connected subgraph (from any of them a
  climb to the top goes through higher vertices only, and the top face's own vertices are
  connected), so a breadth-first search from the top over vertices above ``top - tol_face``
  reaches each of them and no other.

:func:`face_span_graph` climbs (from the best of six precomputed extreme vertices), searches,
then takes the highest vertex of smallest index and the farthest face vertex of smallest index,
as the scan's strict comparisons in index order do: its answer is the scan's, bit for bit
(``tests/test_face_graph.py``).  Shapes with at most ``MIN_GRAPH`` vertices, shapes whose points
are not all hull vertices, flat ones, and shapes armguard cannot describe keep the scan.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["MIN_GRAPH", "face_span", "vertex_graph", "face_span_graph", "face_scratch"]

MIN_GRAPH = 64  # vertices: below this the scan is as quick as the climb


@njit(cache=True, nogil=True, inline="always")
def _dimension(R, V, fbuf, nf, k0, k1, far, tol_face, dir_out):  # pragma: no cover - numba
    """The dimension of the face ``fbuf[:nf]`` (vertices of ``V``) from its highest vertex ``k0`` and the
    farthest ``k1`` (``far``: their squared distance); a 1-D face's direction in W to ``dir_out``."""
    if far <= tol_face * tol_face:
        return 0
    inv = 1.0 / np.sqrt(far)
    a0, a1, a2 = (V[k1, 0] - V[k0, 0]) * inv, (V[k1, 1] - V[k0, 1]) * inv, (V[k1, 2] - V[k0, 2]) * inv
    for f in range(nf):  # a face vertex off the line k0-k1: a 2-D face
        k = fbuf[f]
        w0, w1, w2 = V[k, 0] - V[k0, 0], V[k, 1] - V[k0, 1], V[k, 2] - V[k0, 2]
        t = w0 * a0 + w1 * a1 + w2 * a2
        off = w0 * w0 + w1 * w1 + w2 * w2 - t * t
        if off > tol_face * tol_face:
            return 2
    for r in range(3):
        dir_out[r] = R[r, 0] * a0 + R[r, 1] * a1 + R[r, 2] * a2
    return 1


@njit(cache=True, nogil=True, inline="always")
def face_span(R, u, s, e, V, disk_axis, disk_r, tol_face, tol_par, dir_out, hbuf, fbuf):  # pragma: no cover - numba
    """The dimension (0, 1, 2) of the support face, in the world direction ``u`` ``(3,)``, of the
    shape whose rotation in W is ``R`` ``(3, 3)`` and whose vertices in its own frame are
    ``V[s:e]`` (a disk of radius ``disk_r > 0`` about ``disk_axis``: a cylinder's end); for a 1-D
    face its direction in W goes to ``dir_out`` ``(3,)``.  ``hbuf`` (float) and ``fbuf`` (int),
    ``(>= e - s,)``: scratch (each vertex's height along ``u``, the face's vertices)."""
    u0, u1, u2 = u[0], u[1], u[2]
    uL0 = R[0, 0] * u0 + R[1, 0] * u1 + R[2, 0] * u2
    uL1 = R[0, 1] * u0 + R[1, 1] * u1 + R[2, 1] * u2
    uL2 = R[0, 2] * u0 + R[1, 2] * u1 + R[2, 2] * u2
    if disk_r > 0.0:
        c = abs(uL0 * disk_axis[0] + uL1 * disk_axis[1] + uL2 * disk_axis[2])
        if 1.0 - c <= tol_par:  # the disk faces u: a flat face
            return 2
    hmax, k0 = -np.inf, s
    for k in range(s, e):
        h = uL0 * V[k, 0] + uL1 * V[k, 1] + uL2 * V[k, 2]
        hbuf[k - s] = h
        if h > hmax:
            hmax, k0 = h, k
    # the face: vertices within tol_face of the support plane; its extent from the highest one (k0)
    low = hmax - tol_face
    far, k1, nf = 0.0, -1, 0
    for k in range(s, e):
        if hbuf[k - s] >= low:
            fbuf[nf] = k
            nf += 1
            dd = (V[k, 0] - V[k0, 0]) ** 2 + (V[k, 1] - V[k0, 1]) ** 2 + (V[k, 2] - V[k0, 2]) ** 2
            if dd > far:
                far, k1 = dd, k
    return _dimension(R, V, fbuf, nf, k0, k1, far, tol_face, dir_out)



def vertex_graph(V: np.ndarray, vstart: np.ndarray, disk_r: np.ndarray | None = None) -> tuple:
    """The hull graphs of the shapes, for :func:`face_span_graph`.

    ``V`` ``(N, 3)``: every shape's vertices, shape ``g``'s at ``V[vstart[g]:vstart[g + 1]]``;
    ``disk_r`` ``(G,)``: a cylinder's disk radius (such shapes keep the scan).  Returns
    ``(adj (.,) int64, adj_start (G + 1,) int64)``: shape ``g``'s graph is
    ``adj[adj_start[g]:adj_start[g + 1]]`` in the format of :func:`armguard.geometry._pack.hull_graph`
    (six extreme vertices, then CSR offsets, then neighbours; indices local to the shape), empty
    where the shape keeps the scan."""
    from ..geometry._pack import hull_graph

    V = np.asarray(V, dtype=np.float64)
    vstart = np.asarray(vstart, dtype=np.int64)
    parts, starts = [], [0]
    for g in range(len(vstart) - 1):
        s, e = int(vstart[g]), int(vstart[g + 1])
        a = np.zeros(0, np.int64)
        if e - s > MIN_GRAPH and (disk_r is None or not disk_r[g] > 0.0):
            try:
                a, tri = hull_graph(V[s:e])
            except Exception:  # noqa: BLE001 - flat or degenerate: the scan
                a, tri = np.zeros(0, np.int64), np.zeros((0, 3), np.int64)
            if len(np.unique(tri)) != e - s:  # a point that is no hull vertex: the scan sees it, a climb would not
                a = np.zeros(0, np.int64)
        parts.append(a)
        starts.append(starts[-1] + len(a))
    adj = np.concatenate(parts + [np.zeros(1, np.int64)])  # one unused entry past the end: never empty
    return np.ascontiguousarray(adj, dtype=np.int64), np.array(starts, np.int64)


@njit(cache=True, nogil=True)
def face_scratch(n):  # pragma: no cover - numba
    """``(hbuf, fbuf, mark, qbuf)`` for :func:`face_span_graph` over ``n`` vertices (``mark`` all False)."""
    n = max(n, 1)
    return np.empty(n), np.empty(n, np.int64), np.zeros(n, np.bool_), np.empty(n, np.int64)


@njit(cache=True, nogil=True, inline="always")
def face_span_graph(R, u, s, e, V, disk_axis, disk_r, tol_face, tol_par, dir_out, hbuf, fbuf, A, mark,
                    qbuf):  # pragma: no cover - numba
    """:func:`face_span` over the vertex graph (see the module docstring); ``A`` this shape's graph
    from :func:`vertex_graph` (empty: the scan).  ``mark`` ``(N,) bool``, all False (left so), and
    ``qbuf`` ``(N,) int64``: scratch; ``hbuf``, ``fbuf`` as :func:`face_span`'s."""
    if A.shape[0] == 0 or disk_r > 0.0:  # no graph, or a cylinder's disk: the scan
        return face_span(R, u, s, e, V, disk_axis, disk_r, tol_face, tol_par, dir_out, hbuf, fbuf)
    u0, u1, u2 = u[0], u[1], u[2]
    uL0 = R[0, 0] * u0 + R[1, 0] * u1 + R[2, 0] * u2
    uL1 = R[0, 1] * u0 + R[1, 1] * u1 + R[2, 1] * u2
    uL2 = R[0, 2] * u0 + R[1, 2] * u1 + R[2, 2] * u2
    # climb from the best seed to a highest vertex
    # (vertex indices local to the shape in A, global in V, mark and qbuf: k + s)
    k = s + A[0]
    h = uL0 * V[k, 0] + uL1 * V[k, 1] + uL2 * V[k, 2]
    for i in range(1, 6):
        kk = s + A[i]
        hh = uL0 * V[kk, 0] + uL1 * V[kk, 1] + uL2 * V[kk, 2]
        if hh > h:
            k, h = kk, hh
    moved = True
    while moved:
        moved = False
        for t in range(A[6 + k - s], A[7 + k - s]):
            nb = s + A[t]
            hh = uL0 * V[nb, 0] + uL1 * V[nb, 1] + uL2 * V[nb, 2]
            if hh > h:
                k, h = nb, hh
                moved = True
    # breadth first over the vertices within tol_face of the top (searched to twice that: rounding at the
    # boundary never cuts a path; the set is filtered below); their heights in hbuf by queue place
    low = h - 2.0 * tol_face
    mark[k] = True
    qbuf[0] = k
    nq, head, nf = 1, 0, 0
    while head < nq:
        kk = qbuf[head]
        hh = uL0 * V[kk, 0] + uL1 * V[kk, 1] + uL2 * V[kk, 2]
        hbuf[head] = hh
        head += 1
        if hh < low:
            continue
        for t in range(A[6 + kk - s], A[7 + kk - s]):
            nb = s + A[t]
            if not mark[nb]:
                mark[nb] = True
                qbuf[nq] = nb
                nq += 1
    # the scan's highest vertex: the largest height, the smallest index among equals
    hmax, k0 = -np.inf, -1
    for i in range(nq):
        if hbuf[i] > hmax or (hbuf[i] == hmax and qbuf[i] < k0):
            hmax, k0 = hbuf[i], qbuf[i]
    low = hmax - tol_face
    far, k1 = 0.0, -1
    for i in range(nq):
        kk = qbuf[i]
        mark[kk] = False
        if hbuf[i] >= low:
            fbuf[nf] = kk
            nf += 1
            dd = (V[kk, 0] - V[k0, 0]) ** 2 + (V[kk, 1] - V[k0, 1]) ** 2 + (V[kk, 2] - V[k0, 2]) ** 2
            if dd > far or (dd == far and dd > 0.0 and kk < k1):
                far, k1 = dd, kk
    return _dimension(R, V, fbuf, nf, k0, k1, far, tol_face, dir_out)
