"""The detector on mesh-hull links (ConvexPolyhedron of 60-100 points: vertex graphs, EPA depth).

Oracles: the brute-force reference (``check_reference``: the scene's own geometry and
``armguard.geometry.distance``, whose polytope depth is the exhaustive SAT), the all-pairs batch
(``check_many_bruteforce``), and the exact batch for the yes/no verdicts (``collides_many``
stops at GJK's overlap verdict without a depth).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from armguard.detect import Detector
from armguard.detect._reference import check_reference
from armguard.geometry import Box, ConvexPolyhedron
from armguard.scene import Scene

sys.path.insert(0, str(Path(__file__).parent))
from _verify_fixtures import spatial_arm  # noqa: E402


def _blob(rng, p0, p1, r, n):
    """A hull of ``n`` points near the ellipsoid around the segment ``p0 p1`` (semi-axes ``|p1 - p0| / 2
    + r`` along it, ``r`` across): nearly all of them hull vertices."""
    p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
    ax = p1 - p0
    L = np.linalg.norm(ax)
    e0 = ax / L
    e1 = np.cross(e0, [1.0, 0.0, 0.0] if abs(e0[0]) < 0.9 else [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(e0, e1)
    d = rng.normal(size=(n, 3))
    d *= rng.uniform(0.97, 1.0, (n, 1)) / np.linalg.norm(d, axis=1)[:, None]
    pts = 0.5 * (p0 + p1) + d[:, :1] * (0.5 * L + r) * e0 + d[:, 1:2] * r * e1 + d[:, 2:3] * r * e2
    return ConvexPolyhedron(pts)


@pytest.fixture(scope="module")
def hull_scene():
    rng = np.random.default_rng(3)
    arm = spatial_arm()
    segs = {"link1": ([0, 0, 0], [0, 0, -0.2], 0.06), "link2": ([-0.4, 0, 0], [0, 0, 0], 0.05),
            "link3": ([0, 0, 0], [0, 0, 0.15], 0.06), "link4": ([0, 0, -0.2], [0, 0, 0], 0.04),
            "link6": ([0, 0, 0], [0.1, 0.05, 0.08], 0.05)}
    shapes = {ln: (_blob(rng, a, b, r, int(rng.integers(60, 100))),) for ln, (a, b, r) in segs.items()}
    shapes["link5"] = ()
    sc = Scene("hulls")
    sc.add_robot(arm.with_link_shapes(shapes))
    for k in range(6):
        c = rng.uniform([-0.7, -0.7, -0.3], [0.7, 0.7, 0.7])
        a = rng.uniform(-np.pi, np.pi)
        R = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
        sc.add_body(f"box{k}", [Box(c, rng.uniform(0.03, 0.15, 3), R)])
    sc.add_body("rock", [_blob(rng, [0.35, -0.35, 0.2], [0.45, -0.3, 0.35], 0.12, 80)])
    return sc


def _limits(scene):
    lo = np.concatenate([scene.robots[r].lower for r in scene.robots])
    hi = np.concatenate([scene.robots[r].upper for r in scene.robots])
    return np.where(np.isfinite(lo), lo, -np.pi), np.where(np.isfinite(hi), hi, np.pi)


def test_hull_elements_get_vertex_graphs(hull_scene):
    """Every hull of >= 48 vertices carries a graph (the fast path is the one under test) and no
    face normals or edge directions (the kernel does not move them)."""
    det = Detector(hull_scene, threshold=0.05)
    cs = det._model.compiled
    gadjs = det._layout.view(det._MI, "gadjs")
    pstart = det._layout.view(det._MI, "pstart")
    n_graph = 0
    for g in range(cs.n_elements):
        nv = cs.elem_vert_start[g + 1] - cs.elem_vert_start[g]
        if cs.elem_core[g] == 3 and nv >= 48:
            assert gadjs[g + 1] > gadjs[g] and pstart[g + 1] == pstart[g]
            n_graph += 1
    assert n_graph >= 5


def test_exact_batch_matches_brute_force_reference(hull_scene):
    det = Detector(hull_scene, threshold=0.05)
    lo, hi = _limits(hull_scene)
    Q = np.random.default_rng(1).uniform(lo, hi, size=(12, len(lo)))
    got = det.check_many(Q)
    n_pen = 0
    for k, q in enumerate(Q):
        ref = check_reference(hull_scene, q, 0.05)
        fin = np.isfinite(ref.min_distance)
        assert np.array_equal(np.isfinite(got.min_distance[k]), fin)
        assert np.max(np.abs(got.min_distance[k][fin] - ref.min_distance[fin])) <= 1e-9
        assert got.status[k] == ref.status
        n_pen += int(ref.min_distance[fin].min() < 0.0)
    assert n_pen >= 2  # penetrating configurations (EPA depths) are among them


def test_yes_no_and_pruned_batch_agree_with_all_pairs(hull_scene):
    det = Detector(hull_scene, threshold=0.05)
    lo, hi = _limits(hull_scene)
    Q = np.random.default_rng(2).uniform(lo, hi, size=(2000, len(lo)))
    brute = det.check_many_bruteforce(Q)
    exact = det.check_many(Q)
    fin = np.isfinite(brute.min_distance)
    assert np.array_equal(np.isfinite(exact.min_distance), fin)
    assert np.max(np.abs(exact.min_distance[fin] - brute.min_distance[fin])) <= 1e-12
    assert 0.05 < brute.collision.mean() < 0.95  # both verdicts occur
    np.testing.assert_array_equal(exact.collision, brute.collision)
    np.testing.assert_array_equal(det.collides_many(Q), brute.collision)


def test_link_boxes_contain_their_hulls(hull_scene):
    """The yes/no cull's oriented boxes (``_hulls.link_obbs``) contain every core point of their
    element, grown by its core radius, so a pair whose boxes are apart is apart."""
    det = Detector(hull_scene, threshold=0.05)
    cs = det._model.compiled
    obb = det._layout.view(det._MF, "obb_L").reshape(-1, 16)
    n = 0
    for g in range(cs.n_elements):
        if obb[g, 15] == 0.0:
            continue
        c, h, R = obb[g, 0:3], obb[g, 3:6], obb[g, 6:15].reshape(3, 3)
        assert np.allclose(R.T @ R, np.eye(3), atol=1e-12) and np.linalg.det(R) > 0.0
        p = np.asarray(cs.verts[cs.elem_vert_start[g]:cs.elem_vert_start[g + 1]])
        assert np.all(np.abs((p - c) @ R) <= h - float(cs.elem_radius[g]))
        n += 1
    assert n == 5  # every moving hull has one


def test_box_cull_never_drops_a_pair_within_the_level():
    """``obb_apart_static`` says apart only when the element's true distance to the box exceeds the
    level (oracle: ``armguard.geometry.distance`` on the moved hull), and it does cull."""
    from armguard_analytic._engine._cull import obb_apart_static
    from armguard_analytic._engine._hulls import link_obbs
    from armguard.geometry import distance
    from armguard.scene import compile_scene

    rng = np.random.default_rng(11)
    hull = _blob(rng, [0, 0, -0.25], [0, 0, 0.25], 0.06, 70)
    sc = Scene("one")
    sc.add_body("h", [hull])
    cs = compile_scene(sc)
    row = link_obbs(cs, np.zeros(cs.n_elements, np.int64), 1e-9)[0]
    assert row[15] == 1.0
    culled = 0
    for _ in range(400):
        X = np.eye(4)
        a, b = rng.uniform(-np.pi, np.pi, 2)
        ca, sa, cb, sb = np.cos(a), np.sin(a), np.cos(b), np.sin(b)
        X[:3, :3] = np.array([[ca, -sa, 0], [sa, ca, 0], [0, 0, 1]]) @ np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
        X[:3, 3] = rng.uniform(-0.5, 0.5, 3)
        yaw = rng.uniform(-np.pi, np.pi)
        R_WB = np.array([[np.cos(yaw), -np.sin(yaw), 0.0], [np.sin(yaw), np.cos(yaw), 0.0], [0.0, 0.0, 1.0]])
        box = Box(rng.uniform(-0.3, 0.3, 3), rng.uniform(0.02, 0.2, 3), R_WB)
        level = float(rng.choice([0.0, 0.02]))
        SF = np.concatenate([X.reshape(-1), box.center, box.half_extents, box.rotation.reshape(-1)])
        apart = obb_apart_static(row, 0, 0, SF, 16, level, 1e-9)
        d = distance(ConvexPolyhedron(hull.vertices @ X[:3, :3].T + X[:3, 3]), box).distance
        if apart:
            culled += 1
            assert d > level
    assert 50 < culled < 390


def test_yes_no_with_a_stopping_distance_agrees_with_all_pairs(hull_scene):
    det = Detector(hull_scene, threshold=0.05, stopping_distance=0.03)
    lo, hi = _limits(hull_scene)
    Q = np.random.default_rng(4).uniform(lo, hi, size=(1500, len(lo)))
    brute = det.check_many_bruteforce(Q)
    assert 0.05 < brute.collision.mean() < 0.95
    np.testing.assert_array_equal(det.collides_many(Q), brute.collision)
