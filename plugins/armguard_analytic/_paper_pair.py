"""The papers' checkers for one pair of shapes given in W (Ranger §2/§4 link–polytope, Hermes's four
modules): the kernels of :mod:`._paper` and :mod:`._paper_hermes` on a one-body scene, for tests and
examples."""

from __future__ import annotations

import numpy as np

from armguard._tolerance import DEFAULT_TOLERANCES

from ._paper import _face_edge, _hermes_hit, _paper_face, _unit_rows
from ._paper_hermes import B_HIT, _hermes_payload_link, _hermes_payload_obstacle, _hermes_segments

__all__ = ["paper_capsule_polytope", "hermes_link_obstacle", "hermes_link_link", "hermes_payload_link",
           "hermes_payload_obstacle", "payload_sphere_radius"]


def _one_body(polytope):
    from armguard.scene import Scene, compile_scene

    scene = Scene("paper")
    scene.add_body("obstacle", polytope)
    cs = compile_scene(scene)
    F = len(cs.face_vert_start) - 1
    fn, fd = np.zeros((F, 3)), np.zeros(F)
    for f in range(F):
        fn[f], fd[f] = _paper_face(cs.verts[cs.face_verts[cs.face_vert_start[f]:cs.face_vert_start[f + 1]]])
    c = cs.verts.mean(axis=0)
    sph = np.array([[*c, np.linalg.norm(cs.verts - c, axis=1).max()]])
    return cs, fn, fd, sph


def paper_capsule_polytope(capsule, polytope, tol=DEFAULT_TOLERANCES):
    """Ranger §2/§4 for one link ``capsule`` (``p1`` its distal end) against one polytope (W):
    ``(distance (m), p_WA (3,), p_WB (3,))``."""
    cs, fn, fd, _ = _one_body(polytope)
    out = np.zeros(9)
    ev = cs.verts[cs.edges[:, 1]] - cs.verts[cs.edges[:, 0]]
    eW, _ = _unit_rows(ev, tol.length)
    d = _face_edge(tuple(capsule.p0), tuple(capsule.p1), float(capsule.radius), 0, np.ascontiguousarray(cs.verts),
                   cs.elem_face_start, cs.face_vert_start, cs.face_verts, fn, fd, cs.elem_edge_start,
                   np.ascontiguousarray(cs.edges.reshape(-1, 2)), np.ascontiguousarray(eW),
                   np.linalg.norm(ev, axis=1), out, float(tol.length), float(tol.parallel))
    return float(d), out[0:3].copy(), out[3:6].copy()


def hermes_link_obstacle(capsule, polytope, margin: float = 0.0, tol=DEFAULT_TOLERANCES) -> bool:
    """Hermes's link–obstacle module for one link ``capsule`` against one closed convex polytope (W)."""
    cs, _, _, sph = _one_body(polytope)
    return _hermes_hit(tuple(capsule.p0), tuple(capsule.p1), float(capsule.radius) + float(margin), 0,
                       np.ascontiguousarray(cs.planes.reshape(-1, 4)), cs.elem_plane_start, sph,
                       float(tol.parallel)) == B_HIT


def _t(p):
    return tuple(float(x) for x in p)


def hermes_link_link(link_a, link_b, margin: float = 0.0, tol=DEFAULT_TOLERANCES):
    """Hermes's link–link module for two capsules (W): ``(hit, distance of the axes (m), M_a, M_b, branch)``
    (``branch`` indexes :data:`._paper_hermes.BRANCHES` ``["link-link"]``)."""
    d, M1, M2, br = _hermes_segments(_t(link_a.p0), _t(link_a.p1), _t(link_b.p0), _t(link_b.p1), float(tol.length),
                                     float(tol.parallel))
    return bool(d <= link_a.radius + link_b.radius + margin), float(d), np.array(M1), np.array(M2), int(br)


def payload_sphere_radius(payload) -> float:
    """The radius of the sphere circumscribing the payload's cylinder (axis ``p0-p1``, radius ``radius``)."""
    h = 0.5 * float(np.linalg.norm(np.subtract(payload.p1, payload.p0)))
    return float(np.sqrt(h * h + payload.radius ** 2))


def hermes_payload_link(payload, link, margin: float = 0.0, tol=DEFAULT_TOLERANCES):
    """Hermes's payload–link module for a capsule ``payload`` and a capsule ``link`` (W):
    ``(hit, distance of the axes or inf, branch)`` (``BRANCHES["payload-link"]``)."""
    hit, d, br = _hermes_payload_link(_t(link.p0), _t(link.p1), float(link.radius) + margin, _t(payload.p0),
                                      _t(payload.p1), payload_sphere_radius(payload),
                                      float(link.radius + payload.radius) + margin, float(tol.length),
                                      float(tol.parallel))
    return bool(hit), float(d), int(br)


def hermes_payload_obstacle(payload, polytope, margin: float = 0.0, tol=DEFAULT_TOLERANCES):
    """Hermes's payload–obstacle module for a capsule ``payload`` and a closed convex polytope (W):
    ``(hit, branch)`` (``BRANCHES["payload-obstacle"]``)."""
    cs, _, _, sph = _one_body(polytope)
    hit, _, br = _hermes_payload_obstacle(_t(payload.p0), _t(payload.p1), float(payload.radius) + margin,
                                          payload_sphere_radius(payload) + margin, 0, np.ascontiguousarray(cs.verts),
                                          sph, np.ascontiguousarray(cs.planes.reshape(-1, 4)), cs.elem_plane_start,
                                          cs.elem_face_start, cs.face_vert_start, cs.face_verts, float(tol.length),
                                          float(tol.parallel))
    return bool(hit), int(br)
