"""The compiled kernels of ``fidelity = "paper"`` (:mod:`armguard_analytic._paper` states the methods):
Ranger's §3 segment-segment closest points (Bon & Seraji 1997, eqs. 1-6 and §3.2's correction), its
§2/§4 distal end-point face test (eqs. 7-10) with the link-edge terms, its §2 bounding-box
subtractions; ``_paper_rows`` runs them, and Hermes's four modules (:mod:`._paper_hermes`), over
configurations.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from armguard.geometry._pair_segment_segment import perpendicular_unit
from armguard.geometry.kernels import GJK_NOT_CONVERGED, GJK_WORK_SIZE, convex_convex
from armguard.kinematics._fk import _fk_kernel

from ._paper_hermes import H_NONE, _hermes_hit, _hermes_pair  # noqa: F401  (_hermes_hit is read from here)
from ._paper_vec import _axpy, _cross, _dist, _dot, _on_segment, _sub, _v  # noqa: F401

M_SEGSEG, M_FACE_EDGE, M_BOX, M_EXACT, M_EXACT_BOX = 0, 1, 2, 3, 4


# ---------------------------------------------------------------- Ranger §3
@njit(cache=True)
def ranger_segment_segment(P1, P1p, P2, P2p, eps_len, eps_par):  # pragma: no cover - compiled
    """Ranger §3: nearest points ``(M_1, M_2)`` of segments ``P1-P1p`` and ``P2-P2p`` (3-tuples, m, W)."""
    A1, l1 = _direction(P1, P1p)
    A2, l2 = _direction(P2, P2p)
    return _ranger(P1, A1, l1, P2, A2, l2, eps_len, eps_par)


@njit(cache=True, inline="always")
def _direction(P, Pp):  # pragma: no cover - compiled
    """Direction cosines and length of segment ``P-Pp`` (eq. 1); ``(0, 0, 0), 0`` for a point."""
    v = _sub(Pp, P)
    l = math.sqrt(_dot(v, v))
    if l == 0.0:
        return (0.0, 0.0, 0.0), 0.0
    return (v[0] / l, v[1] / l, v[2] / l), l


@njit(cache=True, inline="always")
def _ranger(P1, A1, l1, P2, A2, l2, eps_len, eps_par):  # pragma: no cover - compiled
    """:func:`ranger_segment_segment` from start points, unit directions and lengths (§2: the
    "redundant data, computed at initialization time" of the static edges)."""
    if l1 <= eps_len:
        if l2 <= eps_len:
            return P1, P2
        return P1, _on_segment(P2, A2, l2, P1)
    if l2 <= eps_len:
        return _on_segment(P1, A1, l1, P2), P2
    P1p = _axpy(P1, l1, A1)
    P2p = _axpy(P2, l2, A2)
    D12 = _sub(P2, P1)
    a = _dot(D12, A1)
    b = _dot(A1, A2)
    c = _dot(D12, A2)
    s2 = 1.0 - b * b  # sin^2 of the angle between the lines
    if s2 <= eps_par * eps_par:
        # parallel (b = +-1): least of the four end-point-to-segment distances
        M1, M2 = P1, _on_segment(P2, A2, l2, P1)
        best = _dist(M1, M2)
        X = _on_segment(P2, A2, l2, P1p)
        d = _dist(P1p, X)
        if d < best:
            best, M1, M2 = d, P1p, X
        X = _on_segment(P1, A1, l1, P2)
        d = _dist(X, P2)
        if d < best:
            best, M1, M2 = d, X, P2
        X = _on_segment(P1, A1, l1, P2p)
        d = _dist(X, P2p)
        if d < best:
            best, M1, M2 = d, X, P2p
        return M1, M2
    t2 = (a * b - c) / s2  # eq. 6
    t1 = a + t2 * b  # eq. 5
    in1 = 0.0 <= t1 <= l1
    in2 = 0.0 <= t2 <= l2
    if in1 and in2:  # §3.2: the infinite-line points are the answer
        return _axpy(P1, t1, A1), _axpy(P2, t2, A2)
    if in1:  # §3.2, one in: the other's end-point nearest its line point, re-projected
        M2 = _axpy(P2, min(max(t2, 0.0), l2), A2)
        return _on_segment(P1, A1, l1, M2), M2
    if in2:
        M1 = _axpy(P1, min(max(t1, 0.0), l1), A1)
        return M1, _on_segment(P2, A2, l2, M1)
    # §3.2, neither in: two-stage correction
    E1 = _axpy(P1, min(max(t1, 0.0), l1), A1)
    E2 = _axpy(P2, min(max(t2, 0.0), l2), A2)
    F2 = _on_segment(P2, A2, l2, E1)
    F1 = _on_segment(P1, A1, l1, E2)
    if _dist(E1, F2) <= _dist(F1, E2):
        return E1, F2
    return F1, E2


@njit(cache=True, inline="always")
def _rounded(M1, M2, ra, rb, ux, uy, uz, out):  # pragma: no cover - compiled
    """Witnesses on the surfaces from axis points ``M1``, ``M2``: ``out[0:6]``; returns the distance."""
    d = _dist(M1, M2)
    if d > 0.0:
        ux, uy, uz = (M2[0] - M1[0]) / d, (M2[1] - M1[1]) / d, (M2[2] - M1[2]) / d
    out[0] = M1[0] + ra * ux
    out[1] = M1[1] + ra * uy
    out[2] = M1[2] + ra * uz
    out[3] = M2[0] - rb * ux
    out[4] = M2[1] - rb * uy
    out[5] = M2[2] - rb * uz
    return d - ra - rb


# ---------------------------------------------------------------- per pair
@njit(cache=True)
def _face_edge(P0, P1, r, g, vW, fstart, fvs, fverts, fn, fd, estart, edges, eW, elen, out, eps_len, eps_par):  # pragma: no cover
    """Ranger §2/§4: link axis ``P0``-``P1`` (``P1`` distal), radius ``r``, against static polytope ``g``.

    ``eW`` ``(E, 3)``, ``elen`` ``(E,)``: unit direction and length of every edge (W, m).
    """
    best = math.inf
    M1 = P1
    M2 = P1
    ux, uy, uz = 0.0, 0.0, 0.0  # set by a face term; an edge term at distance 0 takes a perpendicular
    for f in range(fstart[g], fstart[g + 1]):
        n = _v(fn, f)
        d_f = _dot(n, P1) - fd[f]  # eq. 8 (fd is d_of, eq. 7)
        Q = _axpy(P1, -d_f, n)  # eq. 9
        inside = True
        k0 = fvs[f]
        k1 = fvs[f + 1]
        for k in range(k0, k1):
            vi = _v(vW, fverts[k])
            vj = _v(vW, fverts[k + 1 if k + 1 < k1 else k0])
            if not _dot(n, _cross(_sub(vj, vi), _sub(Q, vi))) > 0.0:  # eq. 10
                inside = False
                break
        if inside and abs(d_f) - r < best:
            best = abs(d_f) - r
            M1, M2 = P1, Q
            s = 1.0 if d_f < 0.0 else -1.0  # towards the plane when P is on it
            ux, uy, uz = s * n[0], s * n[1], s * n[2]
    A1, l1 = _direction(P0, P1)
    for e in range(estart[g], estart[g + 1]):
        A, B = _ranger(P0, A1, l1, _v(vW, edges[e, 0]), _v(eW, e), elen[e], eps_len, eps_par)
        d = _dist(A, B) - r
        if d < best:
            best, M1, M2 = d, A, B
            ux, uy, uz = 0.0, 0.0, 0.0
    if ux == 0.0 and uy == 0.0 and uz == 0.0:
        ux, uy, uz = perpendicular_unit(A1[0], A1[1], A1[2])
    return _rounded(M1, M2, r, 0.0, ux, uy, uz, out)


@njit(cache=True)
def _box_gap(vW, v0, v1, r, lo, hi, out):  # pragma: no cover - compiled
    """Least end-point-to-limit subtraction over vertices ``v0:v1`` (Ranger §2), less ``r``; witnesses in ``out``."""
    best = math.inf
    bi, bax, blim = v0, 0, 0.0
    for k in range(v0, v1):
        for ax in range(3):
            gap = hi[ax] - vW[k, ax] - r
            if gap < best:
                best, bi, bax, blim = gap, k, ax, hi[ax]
            gap = vW[k, ax] - lo[ax] - r
            if gap < best:
                best, bi, bax, blim = gap, k, ax, lo[ax]
    for ax in range(3):
        out[ax] = vW[bi, ax]
        out[3 + ax] = vW[bi, ax]
    if r > 0.0:
        out[bax] += r if blim == hi[bax] else -r
    out[3 + bax] = blim
    return best


@njit(cache=True, nogil=True)
def _paper_rows(Q, T, E, R, mode, margin, H, want, out_d, out_p, out_hit, out_mod, eps, work):  # pragma: no cover
    """Every pair of every configuration ``Q`` (M, n) (see :class:`PaperChecker` for the packed tuples).

    ``mode`` 0 distances (``out_d`` (M, P), ``out_p`` (M, P, 6) when ``want``), 1 verdicts
    (``out_hit`` (M,): a pair within ``margin``, Hermes's module ``H[0][p]`` (``H_*``) on the pairs
    that have one, stopping at the first), 2 every pair's verdict (``out_mod`` (M, P, 2): hit, the
    module's exit ``B_*`` or -1 for a distance rule; ``out_d`` the module's distance, ``inf`` where
    it computes none).  Returns -1, or the first (config, pair) whose fallback GJK failed as
    ``m * P + k``.
    """
    parent, X_pre, axis, jtype, X_post, has_post, offset, tstart, tjoint, tcoeff = T
    glink, vstart, vL, vW, pstart, nL, nW, estart, edges, eL, eW, elen, e_ok, rad, fstart, fvs, fverts, fn, fd, planes, sph, lo, hi = E
    ra, rb, meth, distal, swap = R
    hcode, ha, hb, prho = H
    eps_len, eps_par, gjk_eps, max_iter, off = eps
    Xs = np.empty((1, parent.shape[0], 4, 4))
    out9 = np.empty(9)
    P = ra.shape[0]
    for m in range(Q.shape[0]):
        _fk_kernel(Q[m:m + 1], parent, X_pre, axis, jtype, X_post, has_post, offset, tstart, tjoint, tcoeff, Xs)
        for g in range(glink.shape[0]):  # move the moving elements into W
            lk = glink[g]
            if lk < 0:
                continue
            X = Xs[0, lk]
            for k in range(vstart[g], vstart[g + 1]):
                for i in range(3):
                    vW[k, i] = X[i, 0] * vL[k, 0] + X[i, 1] * vL[k, 1] + X[i, 2] * vL[k, 2] + X[i, 3]
            for k in range(pstart[g], pstart[g + 1]):
                for i in range(3):
                    nW[k, i] = X[i, 0] * nL[k, 0] + X[i, 1] * nL[k, 1] + X[i, 2] * nL[k, 2]
            for k in range(estart[g], estart[g + 1]):
                for i in range(3):
                    eW[k, i] = X[i, 0] * eL[k, 0] + X[i, 1] * eL[k, 1] + X[i, 2] * eL[k, 2]
        if mode == 1:
            out_hit[m] = False
        for p in range(P):
            if mode >= 1 and hcode[p] != H_NONE:
                hit, dh, br = _hermes_pair(hcode[p], ha[p], hb[p], margin, vW, vstart, rad, prho, planes, pstart,
                                           fstart, fvs, fverts, sph, eps_len, eps_par)
                if mode == 1:
                    if hit:
                        out_hit[m] = True
                        break
                    continue
                out_d[m, p] = dh
                out_mod[m, p, 0] = 1 if hit else 0
                out_mod[m, p, 1] = br
                continue
            a = ra[p]
            b = rb[p]
            mt = meth[p]
            if mt == M_SEGSEG:
                ka = estart[a]
                kb = estart[b]
                A, B = _ranger(_v(vW, edges[ka, 0]), _v(eW, ka), elen[ka], _v(vW, edges[kb, 0]), _v(eW, kb), elen[kb],
                               eps_len, eps_par)
                ux, uy, uz = 0.0, 0.0, 0.0
                if _dist(A, B) == 0.0:
                    ux, uy, uz = perpendicular_unit(eW[ka, 0], eW[ka, 1], eW[ka, 2])
                d = _rounded(A, B, rad[a], rad[b], ux, uy, uz, out9)
            elif mt == M_FACE_EDGE:
                P0 = _v(vW, vstart[a] + 1 - distal[p])
                P1 = _v(vW, vstart[a] + distal[p])
                d = _face_edge(P0, P1, rad[a], b, vW, fstart, fvs, fverts, fn, fd, estart, edges, eW, elen, out9, eps_len,
                               eps_par)
            elif mt == M_BOX:
                d = _box_gap(vW, vstart[a], vstart[a] + 2, 0.0, lo, hi, out9)
            elif mt == M_EXACT_BOX:
                d = _box_gap(vW, vstart[a], vstart[a + 1], rad[a], lo, hi, out9)
            else:
                ea = eW[estart[a]:estart[a + 1]] if e_ok[a] else eW[0:0]
                eb = eW[estart[b]:estart[b + 1]] if e_ok[b] else eW[0:0]
                d, st = convex_convex(vW[vstart[a]:vstart[a + 1]], nW[pstart[a]:pstart[a + 1]], ea, rad[a],
                                      vW[vstart[b]:vstart[b + 1]], nW[pstart[b]:pstart[b + 1]], eb, rad[b],
                                      out9, work, eps_len, eps_par, gjk_eps, max_iter, off)
                if st == GJK_NOT_CONVERGED:
                    return m * P + p
            if mode == 1:
                if d <= margin:
                    out_hit[m] = True
                    break
                continue
            out_d[m, p] = d
            if mode == 2:
                out_mod[m, p, 0] = 1 if d <= margin else 0
                out_mod[m, p, 1] = -1
                continue
            if want:
                s = 3 if swap[p] else 0
                for i in range(3):
                    out_p[m, p, i] = out9[s + i]
                    out_p[m, p, 3 + i] = out9[3 - s + i]
    return -1
