"""Clipping kernels (numba): Cyrus–Beck for segments, Sutherland–Hodgman for polygons, and the
paper's ``COLLIDE`` over an obstacle's primitives.

Conventions, shared with :mod:`armguard.geometry`:

* a clipping volume is a ``planes (K, 4) float64`` array, row ``[n, d]`` with unit *outward*
  ``n`` (m⁻⁰) and offset ``d`` (m); the volume is ``{x : n . x <= d for every row}``.  Smith's
  paper loads the clippers with *inward* normals; ours are their negatives, the kept side is
  the same.
* every point is ``(3,) float64`` in metres, in the clipping volume's frame (``F(CLIPVOL)``);
  obstacle vertices arrive in their own frame ``F(OB)`` with the 4x4 rigid transform ``REL``
  mapping ``F(OB)`` to ``F(CLIPVOL)`` (the paper's ``REL = IVOLLOC * OBLOC``).
* ``eps`` (m) is ``Tolerances.clip_plane``: a point with ``n . x - d <= eps`` is kept, so
  touching counts as intersecting (as ``armguard.geometry.intersects`` does).

An obstacle's geometry travels as a tuple ``geom = (verts, segs, poly_off, poly_idx, solid)``:
``verts (V, 3)`` m in ``F(OB)``; ``segs (S, 2) int64`` vertex pairs; polygon ``p`` is
``verts[poly_idx[poly_off[p]:poly_off[p + 1]]]`` (a convex planar loop); ``solid (F, 4)`` the
outward planes of the closed convex solid the faces bound, in ``F(OB)`` (0 rows when the obstacle
is not a solid).  An undefined volume (the paper's "not defined") has ``V == 0``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["cyrus_beck", "sutherland_hodgman", "collide", "transform_points"]


@njit(cache=True)
def cyrus_beck(planes, p0, p1, eps):
    """Cyrus–Beck parametric clipping of the segment ``p0 -> p1`` against ``planes``.

    ``planes (K, 4)``, ``p0``, ``p1`` ``(3,)`` m, all in one frame.  Each plane bounds the kept
    parameter interval of ``p(t) = p0 + t (p1 - p0)``, ``t`` in [0, 1]: entering planes raise
    ``t_in``, leaving planes lower ``t_out``.  Returns ``(hit, t_in, t_out)``; ``hit`` is True
    when ``t_in <= t_out`` (something survives every clipper: the paper's ``HIT``).
    """
    t_in = 0.0
    t_out = 1.0
    for k in range(planes.shape[0]):
        nx, ny, nz, d = planes[k, 0], planes[k, 1], planes[k, 2], planes[k, 3]
        num = d + eps - (nx * p0[0] + ny * p0[1] + nz * p0[2])
        den = nx * (p1[0] - p0[0]) + ny * (p1[1] - p0[1]) + nz * (p1[2] - p0[2])
        if den == 0.0:
            if num < 0.0:
                return False, t_in, t_out  # parallel and outside this plane
            continue
        t = num / den
        if den > 0.0:
            if t < t_out:
                t_out = t  # leaving the half-space
        elif t > t_in:
            t_in = t  # entering the half-space
        if t_in > t_out:
            return False, t_in, t_out
    return True, t_in, t_out


@njit(cache=True)
def sutherland_hodgman(planes, poly, n, buf_a, buf_b, eps):
    """Sutherland–Hodgman re-entrant clipping of the polygon ``poly[:n]`` against ``planes``.

    ``poly (>= n, 3)`` m: the loop's vertices in order (it is read, not written); ``buf_a``,
    ``buf_b`` ``(>= n + K, 3)`` scratch (a convex polygon gains at most one vertex per plane).
    Each clipper keeps the part of the polygon inside its plane and passes it on, as the
    paper's pipeline does.  Returns ``(count, which)``: the clipped loop is ``buf_a[:count]``
    when ``which == 0`` else ``buf_b[:count]``; ``count == 0`` means nothing survived.
    """
    for i in range(n):
        buf_a[i, 0] = poly[i, 0]
        buf_a[i, 1] = poly[i, 1]
        buf_a[i, 2] = poly[i, 2]
    cur, nxt = buf_a, buf_b
    m = n
    which = 0
    for k in range(planes.shape[0]):
        nx, ny, nz, d = planes[k, 0], planes[k, 1], planes[k, 2], planes[k, 3]
        out = 0
        sx, sy, sz = cur[m - 1, 0], cur[m - 1, 1], cur[m - 1, 2]
        fs = nx * sx + ny * sy + nz * sz - d - eps
        for i in range(m):
            px, py, pz = cur[i, 0], cur[i, 1], cur[i, 2]
            fp = nx * px + ny * py + nz * pz - d - eps
            if fp <= 0.0:
                if fs > 0.0:  # S outside, P inside: emit the crossing, then P
                    t = fs / (fs - fp)
                    nxt[out, 0] = sx + t * (px - sx)
                    nxt[out, 1] = sy + t * (py - sy)
                    nxt[out, 2] = sz + t * (pz - sz)
                    out += 1
                nxt[out, 0] = px
                nxt[out, 1] = py
                nxt[out, 2] = pz
                out += 1
            elif fs <= 0.0:  # S inside, P outside: emit the crossing only
                t = fs / (fs - fp)
                nxt[out, 0] = sx + t * (px - sx)
                nxt[out, 1] = sy + t * (py - sy)
                nxt[out, 2] = sz + t * (pz - sz)
                out += 1
            sx, sy, sz, fs = px, py, pz, fp
        m = out
        if m == 0:
            return 0, which
        cur, nxt = nxt, cur
        which = 1 - which
    return m, which


@njit(cache=True)
def transform_points(X, P, out):
    """``out[i] = X[:3, :3] @ P[i] + X[:3, 3]``: ``X (4, 4)`` rigid, ``P``, ``out`` ``(V, 3)`` m."""
    for i in range(P.shape[0]):
        x, y, z = P[i, 0], P[i, 1], P[i, 2]
        for r in range(3):
            out[i, r] = X[r, 0] * x + X[r, 1] * y + X[r, 2] * z + X[r, 3]


@njit(cache=True)
def _inside(planes, p, eps):
    for k in range(planes.shape[0]):
        if planes[k, 0] * p[0] + planes[k, 1] * p[1] + planes[k, 2] * p[2] - planes[k, 3] > eps:
            return False
    return True


@njit(cache=True)
def collide(planes, probe, REL, REL_inv, geom, work, buf_a, buf_b, buf_c, eps):
    """The paper's ``COLLIDE(OBJ, CLIPVOL, RELATION)``: does ``OBJ`` meet the clipping volume?

    ``planes (K, 4)`` the clipping volume in ``F(CLIPVOL)``; ``probe (3,)`` m a point of it in
    ``F(CLIPVOL)``; ``REL`` / ``REL_inv`` ``(4, 4)`` map ``F(OBJ)`` to ``F(CLIPVOL)`` and back;
    ``geom`` the obstacle tuple (module docstring); ``work (>= V, 3)`` receives the transformed
    vertices; ``buf_a``, ``buf_b``, ``buf_c`` ``(>= max loop + K, 3)`` scratch.

    Each vertex is converted by ``V = RELATION * V`` and each primitive clipped; the answer is
    *yes* as soon as anything survives the pipeline (the OCR reads "If any HIT[k] are ON"; a
    plane flag alone would also be set by a primitive crossing one plane outside the volume, so
    we take the pipeline's output, "any data left at the end of the pipeline lies in the
    interior", as the hit — derived).  One addition the paper's loop needs for solids: a
    clipping volume wholly inside a solid obstacle meets none of its faces, so for a solid the
    probe point is also tested against the solid's planes (the volume is connected, so if it
    meets the solid and no face, it lies inside).  Returns a bool.
    """
    verts, segs, poly_off, poly_idx, solid = geom
    nv = verts.shape[0]
    if nv == 0:
        return False
    transform_points(REL, verts, work)
    for s in range(segs.shape[0]):
        hit, _, _ = cyrus_beck(planes, work[segs[s, 0]], work[segs[s, 1]], eps)
        if hit:
            return True
    for p in range(poly_off.shape[0] - 1):
        a, b = poly_off[p], poly_off[p + 1]
        for j in range(a, b):
            i = poly_idx[j]
            buf_c[j - a, 0] = work[i, 0]
            buf_c[j - a, 1] = work[i, 1]
            buf_c[j - a, 2] = work[i, 2]
        count, _ = sutherland_hodgman(planes, buf_c, b - a, buf_a, buf_b, eps)
        if count > 0:
            return True
    if solid.shape[0] > 0:
        q = np.empty(3)
        for r in range(3):
            q[r] = REL_inv[r, 0] * probe[0] + REL_inv[r, 1] * probe[1] + REL_inv[r, 2] * probe[2] + REL_inv[r, 3]
        if _inside(solid, q, eps):
            return True
    return False


# status codes shared with _procedure.ClipStatus
CLEAR = 0
INTERSECTED = 1
MAYBE = 2
# the step that decided: 3..8 are Appendix A's numbered steps, 9 the second-level tests
STEP_SECOND_LEVEL = 9


@njit(cache=True)
def rigid_inverse(X):
    """``(4, 4)`` inverse of a rigid transform (``R^T``, ``-R^T t``)."""
    Y = np.zeros((4, 4))
    for i in range(3):
        for j in range(3):
            Y[i, j] = X[j, i]
    for i in range(3):
        Y[i, 3] = -(Y[i, 0] * X[0, 3] + Y[i, 1] * X[1, 3] + Y[i, 2] * X[2, 3])
    Y[3, 3] = 1.0
    return Y


@njit(cache=True)
def _matmul4(A, B):
    C = np.zeros((4, 4))
    for i in range(4):
        for j in range(4):
            s = 0.0
            for k in range(4):
                s += A[i, k] * B[k, j]
            C[i, j] = s
    return C


@njit(cache=True)
def _max_loop(off):
    m = 0
    for p in range(off.shape[0] - 1):
        m = max(m, off[p + 1] - off[p])
    return m


@njit(cache=True)
def _scratch(ob, guard):
    geom, po, pi = ob[0], ob[1], ob[2]
    nv = max(geom[0].shape[0], po[0].shape[0], pi[0].shape[0], 1)
    loop = max(3, _max_loop(geom[2]), _max_loop(po[2]), _max_loop(pi[2]))
    k = max(guard[0].shape[0], guard[1].shape[0], 1)
    cell_off = guard[6]
    for c in range(cell_off.shape[0] - 1):
        k = max(k, cell_off[c + 1] - cell_off[c])
    m = loop + k + 1
    return np.empty((nv, 3)), np.empty((m, 3)), np.empty((m, 3)), np.empty((m, 3))


@njit(cache=True)
def second_level(guard, REL, REL_inv, geom, work, ba, bb, bc, eps):
    """The second-level tests SRI left undone: clip ``OB`` against the shell's convex cells.

    ``guard`` is the guard tuple (``Guard.pack``); the cells tile the volume between ``PO(VOL)``
    and ``PI(VOL)`` and each is labelled, when the guard is built, INSIDE the test object (0),
    OUTSIDE it (1) or MIXED (2), a MIXED cell carrying the children it was split into.  A hit
    on an INSIDE cell proves an intersection; a MIXED cell is opened only when hit; a hit MIXED
    leaf (the depth limit) leaves the answer MAYBE — never a guess.  Returns a status code.
    """
    cell_planes, cell_off, cell_probe, cell_kind = guard[5], guard[6], guard[7], guard[8]
    child_off, child_idx, roots = guard[9], guard[10], guard[11]
    n_cells = cell_kind.shape[0]
    if n_cells == 0:
        return MAYBE
    stack = np.empty(n_cells, dtype=np.int64)
    top = 0
    for r in range(roots.shape[0]):
        stack[top] = roots[r]
        top += 1
    maybe = False
    while top > 0:
        top -= 1
        c = stack[top]
        if cell_kind[c] == 1:
            continue  # OUTSIDE: a hit there touches nothing of the test object
        planes = cell_planes[cell_off[c]:cell_off[c + 1]]
        if not collide(planes, cell_probe[c], REL, REL_inv, geom, work, ba, bb, bc, eps):
            continue
        if cell_kind[c] == 0:
            return INTERSECTED
        if child_off[c + 1] > child_off[c]:
            for j in range(child_off[c], child_off[c + 1]):
                stack[top] = child_idx[j]
                top += 1
        else:
            maybe = True
    return MAYBE if maybe else CLEAR


@njit(cache=True)
def procedure(guard, X_W_VOL, ob, X_W_OB, eps, subdivide):
    """Appendix A of Smith's paper for one guard ``VOL`` and one obstacle ``OB``.

    ``guard`` the guard tuple (``Guard.pack``), ``X_W_VOL`` ``(4, 4)`` the pose of ``F(VOL)`` in W
    (``IVOLLOC`` is its inverse), ``ob`` the obstacle tuple (``Obstacle.pack``), ``X_W_OB``
    ``(4, 4)`` ``OBLOC``.  Returns ``(status, step)``.
    """
    outer, inner, cs, ro, ri = guard[0], guard[1], guard[2], guard[3], guard[4]
    geom, po_ob, pi_ob, cs_ob, ro_ob, ri_ob = ob
    # 1. [Compute the relation of F(OB) to F(VOL)]  REL = IVOLLOC * OBLOC
    REL = _matmul4(rigid_inverse(X_W_VOL), X_W_OB)
    REL_inv = rigid_inverse(REL)
    # 2. [Distance between the bounding spheres' centres]  D = dist(CS(VOL), REL * CS(OB))
    d2 = 0.0
    for r in range(3):
        x = REL[r, 0] * cs_ob[0] + REL[r, 1] * cs_ob[1] + REL[r, 2] * cs_ob[2] + REL[r, 3] - cs[r]
        d2 += x * x
    D = np.sqrt(d2)
    # 3. If the outer spheres don't overlap: no intersection with this OB.
    if D > ro + ro_ob + eps:
        return CLEAR, 3
    # 4. If both inner spheres are defined and overlap, VOL and OB must intersect.
    if ri >= 0.0 and ri_ob >= 0.0 and D < ri + ri_ob:
        return INTERSECTED, 4
    work, ba, bb, bc = _scratch(ob, guard)
    probe = cs  # CS(VOL) lies in PO(VOL) and in PI(VOL) (both are homothetic about it)
    # 5. COLLIDE(PO(OB), PO(VOL), REL) = no: no intersection.
    if po_ob[0].shape[0] > 0:
        if not collide(outer, probe, REL, REL_inv, po_ob, work, ba, bb, bc, eps):
            return CLEAR, 5
    # 6. COLLIDE(PI(OB), PI(VOL), REL) = yes: intersected.
    if pi_ob[0].shape[0] > 0 and inner.shape[0] > 0:
        if collide(inner, probe, REL, REL_inv, pi_ob, work, ba, bb, bc, eps):
            return INTERSECTED, 6
    # 7. COLLIDE(OB, PI(VOL), REL) = yes: intersected.
    if inner.shape[0] > 0:
        if collide(inner, probe, REL, REL_inv, geom, work, ba, bb, bc, eps):
            return INTERSECTED, 7
    # 8. COLLIDE(OB, PO(VOL), REL) = no: no intersection; else MAYBE.
    if not collide(outer, probe, REL, REL_inv, geom, work, ba, bb, bc, eps):
        return CLEAR, 8
    if not subdivide:
        return MAYBE, 8
    status = second_level(guard, REL, REL_inv, geom, work, ba, bb, bc, eps)
    return status, STEP_SECOND_LEVEL


@njit(cache=True, nogil=True)
def procedure_many(guard, X_W_VOL, ob, X_W_OB, eps, subdivide, status, step):
    """:func:`procedure` for ``M`` guard poses ``X_W_VOL (M, 4, 4)`` against one posed obstacle;
    writes ``status (M,) int8`` and ``step (M,) int8``."""
    for m in range(X_W_VOL.shape[0]):
        s, k = procedure(guard, X_W_VOL[m], ob, X_W_OB, eps, subdivide)
        status[m] = s
        step[m] = k
