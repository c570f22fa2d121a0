"""Hermes's four collision modules as the paper writes them (Sciomachen & Magnani, seed ``001``, §3
"Link–Obstacle", "Link–Link", "Payload–Obstacle" and "Payload–Link Module", flow charts Figs. 5, 7,
9 and 11), compiled for ``fidelity = "paper"`` with ``verdicts = "hermes"``.

Each module answers yes/no ("there is a collision") for one pair, with the stopping distance
``margin`` added to the radii (the seed's §3: "two objects are defined to be in collision if and
only if their relative distance is less than the stopping distance"; armguard counts a distance
equal to it as a collision, as ``collides`` does everywhere).  The seed numbers no equations in
§3; the docstrings cite the module and the figure.  Each kernel returns ``(hit, d, branch)``: ``d``
the distance the module computes (``inf`` where it computes none) and ``branch`` the flow-chart
exit it took (``B_*``), so the benches can count them.

* :func:`_hermes_segments` -- **link–link** (Fig. 7): the distance of the two link axes "through
  the derivatives, with respect to the two links equations parameters, of the distance equation":
  ``X1 = P1 + s u``, ``X2 = P2 + t v``, ``w = P1 - P2``, ``a = u.u``, ``b = u.v``, ``c = v.v``,
  ``d = u.w``, ``e = v.w``; the system ``a s - b t = -d``, ``b s - c t = -e`` has determinant
  ``a c - b^2`` (up to sign; near parallel, below ``1e-4 a c`` (angle below 0.01 rad), where it and ``b e - c d``
  cancel, armguard computes the same numbers without cancellation: ``det = |n|^2``, ``s = -((w x
  v) . n) / det``, ``t = -((w x u) . n) / det`` with ``n = u x v``, so that parallel axes are not
  taken for skew ones, nor near-parallel ones solved with rounding noise; there ``t`` is then
  re-solved for ``s``, the foot of ``M1`` on link 2).  Not zero (``> Tolerances.parallel^2 a c``): ``s = (b e - c d) /
  det``, ``t = (a e - b d) / det``; both in [0, 1] is the answer, else "eight different cases":
  each end-point against the point of the other link at its foot (when the foot is inside that
  link) and each end-point against each end-point of the other link; the least distance wins
  (exact).  Zero (parallel): the foot ``F`` of ``P2`` on link 1's line; ``|P2 - F| <=
  Tolerances.length`` is the *coincident* branch (0 when the segments overlap, else the distance
  of the nearest end-points: exact); otherwise the *parallel* branch returns ``|P2 - F|``, "the
  distance between one extreme and the normal projection of the extreme of the other link" --
  the distance of the two *lines*, below the segments' distance when their projections do not
  overlap (a false alarm, never a miss).  A link shorter than ``Tolerances.length`` is a point
  (armguard's guard; the paper's links have length).
* :func:`_hermes_payload_link` -- **payload–link** (Fig. 11): the link's line against the
  sphere circumscribing the payload *cylinder* (centre the axis midpoint, radius
  ``sqrt(h^2 + R^2)`` for half-length ``h``), grown by the link radius and the margin "as in the
  link–obstacle module": the discriminant of ``|L0 + t v - c|^2 = rho^2``; ``>= 0`` gives the
  two roots and the link meets the sphere when ``[t1, t2]`` meets [0, 1]; then the link-link
  distance of the two axes against ``r + R + margin``.  (The OCR reads "the straight line
  connecting the extreme of the link with the medium point of the payload axis"; a line through
  the sphere's centre always meets it, so we read "the link's line" and "the sphere about the
  medium point".)  armguard's payloads are capsules: their hemispherical ends reach
  ``h + R > sqrt(h^2 + R^2)`` from the centre, so the pre-test can miss a contact at a payload
  end (never one on the cylindrical part, since ``sqrt(h^2 + (R + r)^2) <= sqrt(h^2 + R^2) + r``).
* :func:`_hermes_payload_obstacle` -- **payload–obstacle** (Figs. 8-9): the spheres about the
  payload (as above, grown by the margin) and the obstacle (vertex barycentre, farthest vertex)
  must meet; then per face, with ``D1``, ``D2`` the end-points' distances to the face plane and
  ``R`` the payload radius plus the margin: ``D1 > R`` and ``D2 > R`` on the same side: next face
  (Fig. 8a); else both projections are computed and tested against the face (inside every other
  face plane of the closed polytope), and ``D1 <= R`` with ``P1`` in the face, ``D2 <= R`` with
  ``P2`` in the face, or the end-points on opposite sides with both projections in the face is a
  collision (Fig. 8b); else every edge of the face against the payload axis (the link-link
  distance) within ``R`` is a collision.  Every hit is a true contact of the capsule payload (but
  for an edge exactly parallel to the axis, where the link-link distance is the lines'); it
  misses a payload crossing a face whose projections are not both in it and far from its edges,
  a payload wholly inside an obstacle, and (the pre-test) contacts at a payload end.
* :func:`_hermes_hit` -- **link–obstacle** (Fig. 5; :mod:`._paper` states it).
"""

from __future__ import annotations

import math

from numba import njit

from ._paper_vec import _axpy, _cross, _dist, _dot, _sub, _v

H_NONE, H_LINK_OBSTACLE, H_LINK_LINK, H_PAYLOAD_LINK, H_PAYLOAD_OBSTACLE = 0, 1, 2, 3, 4
MODULES = ("", "link-obstacle", "link-link", "payload-link", "payload-obstacle")
# flow-chart exits
B_INTERIOR, B_EIGHT, B_PARALLEL, B_COINCIDENT, B_POINT = 0, 1, 2, 3, 4  # link-link (Fig. 7)
B_NO_ROOT, B_ROOTS_OUTSIDE, B_DISTANCE = 0, 1, 2  # payload-link (Fig. 11)
B_SPHERES, B_NO_FACE, B_END_POINT, B_CROSSING, B_EDGE = 0, 1, 2, 3, 4  # payload-obstacle (Fig. 9)
B_PRETEST, B_FACE, B_HIT = 0, 1, 2  # link-obstacle (Fig. 5): rejected by the sphere, faces examined, a face met
BRANCHES = {
    "link-link": ("interior", "eight cases", "parallel", "coincident", "point"),
    "payload-link": ("no root", "roots outside the link", "distance"),
    "payload-obstacle": ("spheres apart", "no face", "end-point over a face", "crossing, projections in", "edge"),
    "link-obstacle": ("sphere pre-test", "no face met", "a face met"),
}


# ---------------------------------------------------------------- link-link (Fig. 7)
@njit(cache=True, inline="always")
def _foot(X, P, u, uu):  # pragma: no cover - compiled
    """End-point ``X`` against the point of link ``P + s u`` at its foot: ``(distance, foot)``,
    ``(inf, X)`` when the foot is outside the link (one of the eight cases)."""
    s = _dot(_sub(X, P), u) / uu
    if s < 0.0 or s > 1.0:
        return math.inf, X
    F = _axpy(P, s, u)
    return _dist(X, F), F


@njit(cache=True)
def _hermes_segments(P1, P1p, P2, P2p, eps_len, eps_par):  # pragma: no cover - compiled
    """Hermes link–link module (seed 001 §3, Fig. 7): ``(d, M1, M2, branch)`` for axes ``P1-P1p``, ``P2-P2p``."""
    u = _sub(P1p, P1)
    v = _sub(P2p, P2)
    w = _sub(P1, P2)
    a = _dot(u, u)
    c = _dot(v, v)
    ll = eps_len * eps_len
    if a <= ll or c <= ll:  # armguard's guard: a point against a link
        if a <= ll and c <= ll:
            return _dist(P1, P2), P1, P2, B_POINT
        if a <= ll:
            t = min(max(_dot(v, w) / c, 0.0), 1.0)
            M2 = _axpy(P2, t, v)
            return _dist(P1, M2), P1, M2, B_POINT
        s = min(max(-_dot(u, w) / a, 0.0), 1.0)
        M1 = _axpy(P1, s, u)
        return _dist(M1, P2), M1, P2, B_POINT
    b = _dot(u, v)
    d = _dot(u, w)
    e = _dot(v, w)
    ac = a * c
    det = ac - b * b
    ill = det <= 1e-4 * ac  # near parallel (sin <= 0.01): a c - b^2 and b e - c d cancel
    n = u
    if ill:  # Lagrange's identity |u x v|^2, and s, t from cross products (the same numbers, exactly)
        n = _cross(u, v)
        det = _dot(n, n)
    if det > eps_par * eps_par * ac:
        if ill:
            s = -_dot(_cross(w, v), n) / det
            t = -_dot(_cross(w, u), n) / det
        else:
            s = (b * e - c * d) / det
            t = (a * e - b * d) / det
        if 0.0 <= s <= 1.0 and 0.0 <= t <= 1.0:
            if ill:  # near parallel, s is known to ~1e-16 / sin: t re-solved for it (M1's foot on link 2)
                t = min(max((b * s + e) / c, 0.0), 1.0)
            M1 = _axpy(P1, s, u)
            M2 = _axpy(P2, t, v)
            return _dist(M1, M2), M1, M2, B_INTERIOR
        # the eight cases: end-point against the other link's interior, end-point against end-point
        best, M2 = _foot(P1, P2, v, c)
        M1 = P1
        x, F = _foot(P1p, P2, v, c)
        if x < best:
            best, M1, M2 = x, P1p, F
        x, F = _foot(P2, P1, u, a)
        if x < best:
            best, M1, M2 = x, F, P2
        x, F = _foot(P2p, P1, u, a)
        if x < best:
            best, M1, M2 = x, F, P2p
        x = _dist(P1, P2)
        if x < best:
            best, M1, M2 = x, P1, P2
        x = _dist(P1, P2p)
        if x < best:
            best, M1, M2 = x, P1, P2p
        x = _dist(P1p, P2)
        if x < best:
            best, M1, M2 = x, P1p, P2
        x = _dist(P1p, P2p)
        if x < best:
            best, M1, M2 = x, P1p, P2p
        return best, M1, M2, B_EIGHT
    # determinant zero: parallel axes; the foot of P2 on link 1's line
    s0 = -d / a
    F = _axpy(P1, s0, u)
    h = _dist(F, P2)
    if h > eps_len:  # parallel: one extreme against its normal projection on the other axis
        return h, F, P2, B_PARALLEL
    s1 = _dot(u, _sub(P2p, P1)) / a  # coincident: the overlap of the two parameter ranges
    lo = min(s0, s1)
    hi = max(s0, s1)
    if hi >= 0.0 and lo <= 1.0:
        M = _axpy(P1, max(lo, 0.0), u)
        return 0.0, M, M, B_COINCIDENT
    if hi < 0.0:  # link 2 behind P1: its extreme nearest P1
        M2 = P2 if s0 == hi else P2p
        return _dist(P1, M2), P1, M2, B_COINCIDENT
    M2 = P2 if s0 == lo else P2p
    return _dist(P1p, M2), P1p, M2, B_COINCIDENT


# ---------------------------------------------------------------- payload-link (Fig. 11)
@njit(cache=True)
def _hermes_payload_link(L0, L1, grow, Pa, Pb, rho, reach, eps_len, eps_par):  # pragma: no cover - compiled
    """Hermes payload–link module (seed 001 §3, Fig. 11): link axis ``L0-L1`` against the payload axis
    ``Pa-Pb`` whose cylinder's circumscribing sphere has radius ``rho``; ``grow`` the link radius plus
    the margin, ``reach`` both radii plus the margin.  ``(hit, d, branch)``."""
    c = ((Pa[0] + Pb[0]) * 0.5, (Pa[1] + Pb[1]) * 0.5, (Pa[2] + Pb[2]) * 0.5)  # the medium point
    v = _sub(L1, L0)
    w = _sub(L0, c)
    r = rho + grow
    A = _dot(v, v)
    B = _dot(v, w)
    C = _dot(w, w) - r * r
    disc = B * B - A * C  # the second-order equation's determinant (quarter discriminant)
    if disc < 0.0 or A <= eps_len * eps_len:
        if not (A <= eps_len * eps_len and C <= 0.0):  # a point link: inside the sphere or not
            return False, math.inf, B_NO_ROOT
    else:
        sq = math.sqrt(disc)
        t1 = (-B - sq) / A
        t2 = (-B + sq) / A
        if t1 > 1.0 or t2 < 0.0:
            return False, math.inf, B_ROOTS_OUTSIDE
    d = _hermes_segments(L0, L1, Pa, Pb, eps_len, eps_par)[0]
    return d <= reach, d, B_DISTANCE


# ---------------------------------------------------------------- payload-obstacle (Figs. 8-9)
@njit(cache=True, inline="always")
def _in_face(X, k, g, planes, pstart):  # pragma: no cover - compiled
    """A point ``X`` of the plane of face ``k`` lies in the face: inside every other plane of polytope ``g``."""
    for h in range(pstart[g], pstart[g + 1]):
        if h != k and _dot(_v(planes, h), X) > planes[h, 3]:
            return False
    return True


@njit(cache=True)
def _hermes_payload_obstacle(Pa, Pb, R, rho, g, vW, sphere, planes, pstart, fstart, fvs, fverts, eps_len,
                             eps_par):  # pragma: no cover - compiled
    """Hermes payload–obstacle module (seed 001 §3, Figs. 8-9): payload axis ``Pa-Pb``, ``R`` its radius
    plus the margin, ``rho`` its cylinder's circumscribing radius plus the margin, against closed convex
    polytope ``g`` (``planes`` ``[n, d]`` outward, face ``f`` on plane ``pstart[g] + f - fstart[g]``).
    ``(hit, inf, branch)``."""
    c = ((Pa[0] + Pb[0]) * 0.5, (Pa[1] + Pb[1]) * 0.5, (Pa[2] + Pb[2]) * 0.5)
    if _dist(c, _v(sphere, g)) > rho + sphere[g, 3]:  # the two spheres apart
        return False, math.inf, B_SPHERES
    for f in range(fstart[g], fstart[g + 1]):
        k = pstart[g] + f - fstart[g]
        n = _v(planes, k)
        D1 = _dot(n, Pa) - planes[k, 3]
        D2 = _dot(n, Pb) - planes[k, 3]
        opposite = (D1 < 0.0 < D2) or (D2 < 0.0 < D1)
        if abs(D1) > R and abs(D2) > R and not opposite:  # Fig. 8a: this face cannot be touched
            continue
        in1 = _in_face(_axpy(Pa, -D1, n), k, g, planes, pstart)  # the projections P1, P2
        in2 = _in_face(_axpy(Pb, -D2, n), k, g, planes, pstart)
        if (abs(D1) <= R and in1) or (abs(D2) <= R and in2):  # Fig. 8b
            return True, math.inf, B_END_POINT
        if opposite and in1 and in2:
            return True, math.inf, B_CROSSING
        k0 = fvs[f]
        k1 = fvs[f + 1]
        for i in range(k0, k1):  # each edge of the face against the payload axis
            j = i + 1 if i + 1 < k1 else k0
            if _hermes_segments(Pa, Pb, _v(vW, fverts[i]), _v(vW, fverts[j]), eps_len, eps_par)[0] <= R:
                return True, math.inf, B_EDGE
    return False, math.inf, B_NO_FACE


# ---------------------------------------------------------------- link-obstacle (Fig. 5)
@njit(cache=True)
def _hermes_hit(P0, P1, grow, g, planes, pstart, sphere, eps_par):  # pragma: no cover - compiled
    """Hermes link–obstacle module: does segment ``P0``-``P1`` meet a face of polytope ``g`` grown by ``grow``?
    ``B_HIT`` (yes), ``B_FACE`` (no, after the faces) or ``B_PRETEST`` (no: the sphere pre-test)."""
    c = _v(sphere, g)
    v = _sub(P1, P0)
    ll = _dot(v, v)
    t = min(max(_dot(_sub(c, P0), v) / ll, 0.0), 1.0) if ll > 0.0 else 0.0
    if _dist(_axpy(P0, t, v), c) > sphere[g, 3] + grow:  # sphere pre-test
        return B_PRETEST
    lv = math.sqrt(ll)
    for f in range(pstart[g], pstart[g + 1]):
        n = _v(planes, f)
        nd = _dot(n, v)
        if not abs(nd) > eps_par * lv:  # parallel to the face plane: not considered
            continue
        t = (planes[f, 3] + grow - _dot(n, P0)) / nd
        if t < 0.0 or t > 1.0:
            continue
        x = _axpy(P0, t, v)
        on_face = True
        for h in range(pstart[g], pstart[g + 1]):
            if h != f and _dot(_v(planes, h), x) > planes[h, 3] + grow:
                on_face = False
                break
        if on_face:
            return B_HIT
    return B_FACE


# ---------------------------------------------------------------- one pair of the model
@njit(cache=True)
def _hermes_pair(code, a, b, margin, vW, vstart, rad, prho, planes, pstart, fstart, fvs, fverts, sphere, eps_len,
                 eps_par):  # pragma: no cover - compiled
    """Pair ``(a, b)`` (elements; for payload–link ``a`` the link, ``b`` the payload; for the obstacle
    modules ``b`` the polytope) through Hermes module ``code`` (``H_*``): ``(hit, d, branch)``."""
    A0 = _v(vW, vstart[a])
    A1 = _v(vW, vstart[a] + 1)
    if code == H_LINK_OBSTACLE:
        br = _hermes_hit(A0, A1, rad[a] + margin, b, planes, pstart, sphere, eps_par)
        return br == B_HIT, math.inf, br
    if code == H_LINK_LINK:
        d, _, _, br = _hermes_segments(A0, A1, _v(vW, vstart[b]), _v(vW, vstart[b] + 1), eps_len, eps_par)
        return d <= rad[a] + rad[b] + margin, d, br
    if code == H_PAYLOAD_LINK:
        return _hermes_payload_link(A0, A1, rad[a] + margin, _v(vW, vstart[b]), _v(vW, vstart[b] + 1), prho[b],
                                    rad[a] + rad[b] + margin, eps_len, eps_par)
    return _hermes_payload_obstacle(A0, A1, rad[a] + margin, prho[a] + margin, b, vW, sphere, planes, pstart, fstart,
                                    fvs, fverts, eps_len, eps_par)
