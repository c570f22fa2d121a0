"""Distance Jacobians inside the kernel: ``d(distance)/dq`` of every checked pair from the
detector's own forward kinematics, right after :func:`._pair_rows.pair_rows`.

Equation (1) of :mod:`armguard.backends._jacobian` (Faverjon & Tournassoud, ICRA 1987; the
envelope theorem on the closest-point problem),

    d(distance)/dq = nhat_AB_W^T (J_WB(p_WB) - J_WA(p_WA)),   nhat_AB_W = (p_WB - p_WA) / distance,

with the point Jacobians written joint by joint instead of through Pinocchio's ``(6, nv)``
joint Jacobians: a point ``p_W`` on a link moves with every joint on the link's path to the root;
a revolute joint with world axis ``z_W`` through ``o_W`` moves it at ``z_W x (p_W - o_W)`` per
unit of its value, a prismatic one at ``z_W`` (Siciliano et al., *Robotics: Modelling, Planning
and Control*, 2009, eq. (3.30)), so that joint adds

    nhat^T (z_W x (p_W - o_W)) = z_W . ((p_W - o_W) x nhat)      (revolute)
    nhat^T z_W                                                   (prismatic)

to the row.  A joint's value is ``offset + sum(coeff * q[term_joint])`` (the flattened tree of
:mod:`armguard.kinematics._fk`: mimic joints and drive couplings are terms), so the term's scene
joint ``k`` receives ``coeff`` times it, in Pinocchio's velocity column ``vcol[k]`` (a continuous
joint's angle has one column).  ``z_W`` and ``o_W`` come from the link poses ``Xs`` the kernel has
just computed: the joint frame is ``X_WJ = X_WL[parent] @ X_pre`` and its axis is fixed in it.

``smooth`` is the reference's test (:func:`armguard.backends._jacobian.face_span` on the Model's
``collision_model`` shapes, placed by the same link poses); touching pairs get a zero row and
``smooth = False`` here, and the caller refines them (forward differences), as the reference does.
"""

from __future__ import annotations

import numpy as np
from numba import carray, njit

from armguard.backends._face_graph import face_span_graph
from armguard.backends._jacobian import unique_witness
# segment numbers compiled in as constants (see ._layout: a change there comes with an edit here)
from ._layout import K, SC, at, seg1, seg2, seg3

__all__ = ["jacobian_rows", "ROW_LINK_A", "ROW_LINK_B", "ROW_GEOM_A", "ROW_GEOM_B"]

ROW_LINK_A, ROW_LINK_B, ROW_GEOM_A, ROW_GEOM_B = 0, 1, 2, 3
# geometry float rows: R (9; in its link's frame, or in W for a static shape), disk axis (3), disk radius
G_R, G_AXIS, G_RADIUS, G_WIDTH = 0, 9, 12, 13
# geometry int rows: first vertex, end vertex, described (0: a shape armguard cannot describe)
G_VS, G_VE, G_DESCRIBED = 0, 1, 2

_K_Xs = K["Xs"]
_K_parent = K["parent"]
_K_X_pre = K["X_pre"]
_K_axis = K["axis"]
_K_jtype = K["jtype"]
_K_term_start = K["term_start"]
_K_term_joint = K["term_joint"]
_K_term_coeff = K["term_coeff"]
_SC_n_links = SC["n_links"]


@njit(cache=True, nogil=True, inline="always")
def _link_term(row, sign, lk, p0, p1, p2, nh, jtype, term_start, term_joint, term_coeff, zo, vcol):  # pragma: no cover
    """Add ``sign * nhat^T`` (the motion of the point ``p`` due to link ``lk``'s joint) to ``row``."""
    jt = jtype[lk]
    if jt != 0 and term_start[lk + 1] > term_start[lk]:
        z0, z1, z2 = zo[lk, 0], zo[lk, 1], zo[lk, 2]
        if jt == 1:
            r0, r1, r2 = p0 - zo[lk, 3], p1 - zo[lk, 4], p2 - zo[lk, 5]
            c = z0 * (r1 * nh[2] - r2 * nh[1]) + z1 * (r2 * nh[0] - r0 * nh[2]) + z2 * (r0 * nh[1] - r1 * nh[0])
        else:
            c = z0 * nh[0] + z1 * nh[1] + z2 * nh[2]
        for t in range(term_start[lk], term_start[lk + 1]):
            col = vcol[term_joint[t]]
            if col >= 0:
                row[col] += sign * term_coeff[t] * c


@njit(cache=True, nogil=True)
def jacobian_rows(H, MF, MI, SF, rows, vcol, gF, gI, V, adj, adj_start, tol, d, p_WA, p_WB, jac,
                  smooth):  # pragma: no cover - compiled
    """Equation (1) and the smoothness test for the ``n`` pairs of ``d`` ``(n,)``, ``p_WA``,
    ``p_WB`` ``(n, 3)``, with the link poses left in the scratch ``SF`` by the last check (at the
    same configuration).  ``rows`` ``(n, 4)``: per pair the global link of A and of B (-1: fixed
    in W) and their geometry rows of ``gF`` / ``gI`` (-1: a workspace wall, a plane); ``vcol``
    ``(n_q,)``: Pinocchio's velocity column of each scene joint (-1: none); ``V`` ``(., 3)``: the
    shapes' vertices in their frames, ``adj``, ``adj_start``: their hulls' vertex graphs
    (:func:`armguard.backends._face_graph.vertex_graph`: the support faces are found by a climb, not
    a scan); ``tol`` = ``[length, jacobian_face, jacobian_parallel]``.
    Writes ``jac`` ``(n, nv)`` and ``smooth`` ``(n,) bool``; returns the number of touching pairs
    (``|distance| <= length``: zero rows, ``smooth`` False, for the caller to refine)."""
    # every array as a view without a reference count (numba.carray, as the distance kernel does):
    # each helper call would otherwise increment and decrement each array's count atomically
    H = carray(at(H, 0), H.shape)
    MF = carray(at(MF, 0), MF.shape)
    MI = carray(at(MI, 0), MI.shape)
    SF = carray(at(SF, 0), SF.shape)
    rows = carray(at(rows, 0), rows.shape)
    vcol = carray(at(vcol, 0), vcol.shape)
    gF = carray(at(gF, 0), gF.shape)
    gI = carray(at(gI, 0), gI.shape)
    V = carray(at(V, 0), V.shape)
    adj = carray(at(adj, 0), adj.shape)
    adj_start = carray(at(adj_start, 0), adj_start.shape)
    d = carray(at(d, 0), d.shape)
    p_WA = carray(at(p_WA, 0), p_WA.shape)
    p_WB = carray(at(p_WB, 0), p_WB.shape)
    jac = carray(at(jac, 0), jac.shape)
    smooth = carray(at(smooth, 0), smooth.shape)
    n_links = H[_SC_n_links]
    Xs = seg3(SF, H, _K_Xs, 4, 4)
    parent = seg1(MI, H, _K_parent)
    X_pre = seg3(MF, H, _K_X_pre, 4, 4)
    axis = seg2(MF, H, _K_axis, 3)
    jtype = seg1(MI, H, _K_jtype)
    term_start = seg1(MI, H, _K_term_start)
    term_joint = seg1(MI, H, _K_term_joint)
    term_coeff = seg1(MF, H, _K_term_coeff)
    eps_len, tol_face, tol_par = tol[0], tol[1], tol[2]
    # each moving joint's axis z_W and origin o_W: X_WJ = X_WL[parent] @ X_pre (X_pre alone at a root)
    zo_ = np.empty((max(n_links, 1), 6))
    zo = carray(at(zo_.reshape(-1), 0), zo_.shape)
    for i in range(n_links):
        if jtype[i] == 0:
            continue
        B = X_pre[i]
        p = parent[i]
        a0, a1, a2 = axis[i, 0], axis[i, 1], axis[i, 2]
        # the axis and origin in the parent's frame, then in W
        x0 = B[0, 0] * a0 + B[0, 1] * a1 + B[0, 2] * a2
        x1 = B[1, 0] * a0 + B[1, 1] * a1 + B[1, 2] * a2
        x2 = B[2, 0] * a0 + B[2, 1] * a1 + B[2, 2] * a2
        if p < 0:
            zo[i, 0], zo[i, 1], zo[i, 2] = x0, x1, x2
            zo[i, 3], zo[i, 4], zo[i, 5] = B[0, 3], B[1, 3], B[2, 3]
        else:
            P = Xs[p]
            for r in range(3):
                zo[i, r] = P[r, 0] * x0 + P[r, 1] * x1 + P[r, 2] * x2
                zo[i, 3 + r] = P[r, 0] * B[0, 3] + P[r, 1] * B[1, 3] + P[r, 2] * B[2, 3] + P[r, 3]
    n, nv = jac.shape
    small = np.zeros(24)  # nhat (3), u (3), R (9), dirs (2 x 3)
    nh = carray(at(small, 0), (3,))
    u = carray(at(small, 3), (3,))
    R = carray(at(small, 6), (3, 3))
    dirs = carray(at(small, 15), (2, 3))
    dims_ = np.zeros(2, np.int64)
    dims = carray(at(dims_, 0), (2,))
    hb_ = np.empty(max(V.shape[0], 1))  # face_span's scratch
    hbuf = carray(at(hb_, 0), hb_.shape)
    fb_ = np.empty(max(V.shape[0], 1), np.int64)
    fbuf = carray(at(fb_, 0), fb_.shape)
    mk_ = np.zeros(max(V.shape[0], 1), np.bool_)  # face_span_graph's scratch (left all False)
    mark = carray(at(mk_, 0), mk_.shape)
    qb_ = np.empty(max(V.shape[0], 1), np.int64)
    qbuf = carray(at(qb_, 0), qb_.shape)
    n_touch = 0
    for i in range(n):
        row = jac[i]
        for k in range(nv):
            row[k] = 0.0
        di = d[i]
        if abs(di) <= eps_len:  # touching: no normal; the caller refines the row
            smooth[i] = False
            n_touch += 1
            continue
        pa0, pa1, pa2 = p_WA[i, 0], p_WA[i, 1], p_WA[i, 2]
        pb0, pb1, pb2 = p_WB[i, 0], p_WB[i, 1], p_WB[i, 2]
        inv = 1.0 / di
        nh[0], nh[1], nh[2] = (pb0 - pa0) * inv, (pb1 - pa1) * inv, (pb2 - pa2) * inv
        # up both paths to the root until they meet: a joint both links hang from moves both points
        # alike and adds n^T (J(p_B) - J(p_A)) = z . ((p_B - p_A) x n) = 0 (prismatic: n.z - n.z),
        # so the walk stops at the common ancestor (links are numbered parents first; -1 is W)
        la, lb = rows[i, ROW_LINK_A], rows[i, ROW_LINK_B]
        while la != lb:
            if la > lb:
                _link_term(row, -1.0, la, pa0, pa1, pa2, nh, jtype, term_start, term_joint, term_coeff, zo, vcol)
                la = parent[la]
            else:
                _link_term(row, 1.0, lb, pb0, pb1, pb2, nh, jtype, term_start, term_joint, term_coeff, zo, vcol)
                lb = parent[lb]
        # smoothness: the support faces of A along nhat and of B along -nhat
        ok = True
        dirs[:] = 0.0
        for side in range(2):
            g = rows[i, ROW_GEOM_A + side]
            if g < 0:
                dims[side] = 2
                continue
            ok = ok and gI[g, G_DESCRIBED] != 0
            lk = rows[i, ROW_LINK_A + side]
            if lk >= 0:
                X = Xs[lk]
                for r in range(3):
                    for c in range(3):
                        R[r, c] = X[r, 0] * gF[g, 3 * 0 + c] + X[r, 1] * gF[g, 3 * 1 + c] + X[r, 2] * gF[g, 3 * 2 + c]
            else:
                for r in range(3):
                    for c in range(3):
                        R[r, c] = gF[g, 3 * r + c]
            s = 1.0 if side == 0 else -1.0
            u[0], u[1], u[2] = s * nh[0], s * nh[1], s * nh[2]
            dims[side] = face_span_graph(R, u, gI[g, G_VS], gI[g, G_VE], V, gF[g, G_AXIS:G_AXIS + 3], gF[g, G_RADIUS],
                                         tol_face, tol_par, dirs[side], hbuf, fbuf, adj[adj_start[g]:adj_start[g + 1]], mark,
                                         qbuf)
        smooth[i] = ok and unique_witness(dims, dirs, tol_par)
    # the local buffers are used here last: numba frees an array after its last use, and the
    # views above do not hold it
    return n_touch + 0 * (zo_.shape[0] + small.shape[0] + dims_.shape[0] + hb_.shape[0] + fb_.shape[0] + mk_.shape[0]
                          + qb_.shape[0])
