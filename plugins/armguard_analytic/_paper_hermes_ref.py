"""Slow, obviously-correct references for Hermes's modules (:mod:`._paper_hermes`), in numpy.

Each states the paper's rule (seed ``001`` §3) by the most direct geometry rather than the
kernels' arithmetic: the segments' distance by enumerating every candidate of the parameter
square (its interior stationary point from ``numpy.linalg.solve``, the four sides' clamped
projections), parallelism from the cross product, a segment meeting a sphere from the distance of
the sphere's centre to the segment, a point in a face from the signs of the edge cross products
around the face's vertex loop, and an edge's distance to the payload axis from the same
enumeration.  The tests hold the kernels to these.
"""

from __future__ import annotations

import numpy as np

__all__ = ["ref_segments", "ref_link_link", "ref_link_obstacle", "ref_payload_link", "ref_payload_obstacle"]


def _point_segment(x, p, q):
    d = q - p
    t = np.clip(np.dot(x - p, d) / np.dot(d, d), 0.0, 1.0) if np.dot(d, d) > 0 else 0.0
    return float(np.linalg.norm(x - (p + t * d)))


def ref_segments(p0, p1, q0, q1) -> float:
    """The exact distance of segments ``p0-p1`` and ``q0-q1``: the least over the parameter square's
    candidates (interior stationary point when there is one, each end-point against the other segment)."""
    p0, p1, q0, q1 = (np.asarray(x, dtype=np.float64) for x in (p0, p1, q0, q1))
    u, v = p1 - p0, q1 - q0
    cands = [_point_segment(p0, q0, q1), _point_segment(p1, q0, q1), _point_segment(q0, p0, p1),
             _point_segment(q1, p0, p1)]
    M = np.array([[u @ u, -(u @ v)], [u @ v, -(v @ v)]])
    if abs(np.linalg.det(M)) > 1e-300:
        s, t = np.linalg.solve(M, [-(u @ (p0 - q0)), -(v @ (p0 - q0))])
        if 0 <= s <= 1 and 0 <= t <= 1:
            cands.append(float(np.linalg.norm(p0 + s * u - q0 - t * v)))
            # near parallel the solve is ill-conditioned: the foot of each solved point on the other
            # segment too (every candidate is a distance between points of the segments)
            t2 = min(max(float(v @ (p0 + s * u - q0)) / float(v @ v), 0.0), 1.0)
            s2 = min(max(float(u @ (q0 + t * v - p0)) / float(u @ u), 0.0), 1.0)
            cands += [float(np.linalg.norm(p0 + s * u - q0 - t2 * v)), float(np.linalg.norm(p0 + s2 * u - q0 - t * v))]
    return min(cands)


def ref_link_link(p0, p1, q0, q1, eps_len=1e-12, eps_par=1e-12) -> float:
    """Hermes's link–link distance: exact, except parallel axes that are not coincident, where it is
    the distance of the two lines."""
    p0, p1, q0, q1 = (np.asarray(x, dtype=np.float64) for x in (p0, p1, q0, q1))
    u, v = p1 - p0, q1 - q0
    cr = np.cross(u, v)
    if cr @ cr <= eps_par ** 2 * (u @ u) * (v @ v) and u @ u > eps_len ** 2 and v @ v > eps_len ** 2:
        h = float(np.linalg.norm(np.cross(q0 - p0, u)) / np.linalg.norm(u))
        if h > eps_len:
            return h
    return ref_segments(p0, p1, q0, q1)


def ref_payload_link(payload, link, margin: float = 0.0) -> bool:
    """Hermes's payload–link verdict: the link segment meets the sphere about the payload axis's
    midpoint circumscribing its cylinder, grown by the link radius and the margin, and the axes'
    link–link distance is within both radii plus the margin."""
    c = 0.5 * (np.asarray(payload.p0, float) + np.asarray(payload.p1, float))
    h = 0.5 * np.linalg.norm(np.subtract(payload.p1, payload.p0))
    rho = np.hypot(h, payload.radius)
    if _point_segment(c, np.asarray(link.p0, float), np.asarray(link.p1, float)) > rho + link.radius + margin:
        return False
    return ref_link_link(link.p0, link.p1, payload.p0, payload.p1) <= link.radius + payload.radius + margin


def _faces(polytope):
    """``[(unit outward normal, offset, vertices (k, 3) counter-clockwise from outside)]`` and the
    vertices of a closed polytope given in W."""
    from armguard.scene import Scene, compile_scene

    scene = Scene("ref")
    scene.add_body("obstacle", polytope)
    cs = compile_scene(scene)
    out = []
    for f in range(len(cs.face_vert_start) - 1):
        V = cs.verts[cs.face_verts[cs.face_vert_start[f]:cs.face_vert_start[f + 1]]]
        out.append((cs.planes[f, :3], float(cs.planes[f, 3]), V))
    return out, cs.verts


def ref_link_obstacle(link, polytope, margin: float = 0.0) -> bool:
    """Hermes's link–obstacle verdict (Fig. 5): the link's axis, not rejected by the sphere pre-test
    (its distance from the vertices' barycentre within the farthest vertex's distance plus the
    link radius and the margin), crosses the boundary of the obstacle whose face planes are moved out
    by the link radius and the margin: the axis clipped to that grown polytope (Cyrus–Beck, one
    half-space at a time) leaves a piece that does not hold the whole axis.  A link wholly inside
    crosses no face (the miss the paper admits)."""
    faces, verts = _faces(polytope)
    p0, p1 = np.asarray(link.p0, float), np.asarray(link.p1, float)
    grow = float(link.radius) + margin
    centre = verts.mean(axis=0)
    if _point_segment(centre, p0, p1) > np.linalg.norm(verts - centre, axis=1).max() + grow:
        return False
    t0, t1 = 0.0, 1.0
    for n, off, _ in faces:  # n . (p0 + t (p1 - p0)) <= off + grow
        a, b = n @ (p1 - p0), off + grow - n @ p0
        if a == 0.0:
            if b < 0.0:
                return False  # parallel and outside this half-space
            continue
        if a > 0.0:
            t1 = min(t1, b / a)
        else:
            t0 = max(t0, b / a)
    return t0 <= t1 and (t0 > 0.0 or t1 < 1.0)


def _in_polygon(x, n, V) -> bool:
    """``x`` (on the plane of the convex polygon ``V`` with normal ``n``) lies in it: on the inner
    side of every edge of the counter-clockwise loop."""
    return all(n @ np.cross(V[(i + 1) % len(V)] - V[i], x - V[i]) >= -1e-12 for i in range(len(V)))


def ref_payload_obstacle(payload, polytope, margin: float = 0.0) -> bool:
    """Hermes's payload–obstacle verdict for a capsule payload and a closed convex polytope (W)."""
    faces, verts = _faces(polytope)
    p0, p1 = np.asarray(payload.p0, float), np.asarray(payload.p1, float)
    c = 0.5 * (p0 + p1)
    rho = np.hypot(0.5 * np.linalg.norm(p1 - p0), payload.radius) + margin
    centre = verts.mean(axis=0)
    if np.linalg.norm(c - centre) > rho + np.linalg.norm(verts - centre, axis=1).max():
        return False
    R = payload.radius + margin
    for n, off, V in faces:
        D1, D2 = n @ p0 - off, n @ p1 - off
        opposite = D1 * D2 < 0
        if abs(D1) > R and abs(D2) > R and not opposite:
            continue
        in1, in2 = _in_polygon(p0 - D1 * n, n, V), _in_polygon(p1 - D2 * n, n, V)
        if (abs(D1) <= R and in1) or (abs(D2) <= R and in2) or (opposite and in1 and in2):
            return True
        if any(ref_link_link(p0, p1, V[i], V[(i + 1) % len(V)]) <= R for i in range(len(V))):
            return True
    return False
