"""Polytope pairs checked in their link frames (``_narrow.narrow_rel``), against the same pairs moved to W.

The analytic engine checks two polytope cores (boxes, mesh hulls), or a cylinder and a polytope,
without moving their points to W: GJK runs in A's frame on hull(A) and ``X_AB hull(B)``
(:func:`armguard.geometry._pair_gjk.gjk_dir_rel`), cold climbs start from each hull's support table
(:func:`armguard.geometry._pack.support_table`), a cylinder's buffer is mapped into the hull's frame.
Oracles: the W path (every point moved, :func:`_pair_epa.convex_convex_fast` /
``_narrow.pair_distance``), brute-force supports, and coal's verdicts on public robots.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numba import njit

import armguard
from armguard.geometry._pack import hull_graph, support_table
from armguard.geometry._pair_gjk import (GJK_NOT_CONVERGED, _support, gjk_dir_adj2, gjk_dir_rel, table_size, table_start,
                                         warm_start)
from armguard.model import known_models


sys.path.insert(0, str(Path(__file__).parent))
from _engine_world import random_cloud as _cloud, random_rotation as _rotation  # noqa: E402


@njit(cache=False)
def _climb_from(p, adj, start, d):
    return _support(p, adj, start, d[0], d[1], d[2])


@njit(cache=False)
def _start(tab, d):
    return table_start(tab, d[0], d[1], d[2])


@njit(cache=False)
def _warm(p, tab, i, d):
    return warm_start(p, tab, table_size(tab), i, d[0], d[1], d[2])


@settings(max_examples=30, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**31), n=st.integers(60, 600))
def test_climbs_from_the_support_table_reach_the_true_support(seed, n):
    """The table's start is a vertex; a climb from it maximises ``p . d`` (brute force), every direction."""
    rng = np.random.default_rng(seed)
    p = _cloud(rng, n)
    adj, _ = hull_graph(p)
    tab = support_table(p)
    assert tab.shape == (6 * 16 * 16,) and tab.min() >= 0 and tab.max() < n
    for d in rng.normal(size=(40, 3)):
        s = _start(tab, d)
        assert 0 <= s < n
        i = _climb_from(p, adj, s, d)
        assert p[i] @ d >= np.max(p @ d) - 1e-12
    assert _start(tab, np.zeros(3)) == -1  # the zero vector: the stored extremes
    assert _start(np.zeros(0, np.int64), np.ones(3)) == -1  # no table
    # a warm start (the better of a previous support and the table's entry) from any vertex: a
    # vertex at least as far along d as the previous one, from which the climb is exact
    for d in rng.normal(size=(40, 3)):
        prev = int(rng.integers(0, n))
        s = _warm(p, tab, prev, d)
        assert 0 <= s < n and p[s] @ d >= p[prev] @ d
        assert s == prev or s == _start(tab, d)
        assert p[_climb_from(p, adj, s, d)] @ d >= np.max(p @ d) - 1e-12
    assert _warm(p, tab, 3, np.zeros(3)) == 3 and _warm(p, np.zeros(0, np.int64), 3, np.ones(3)) == 3


@settings(max_examples=40, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**31), gap=st.floats(-0.2, 1.0))
def test_gjk_in_a_frame_of_its_own_equals_gjk_on_moved_points(seed, gap):
    """hull(A) against ``R_AB hull(B) + t_AB`` in A's frame (B's points as stored) equals GJK on
    both point sets moved to W: same distance, witnesses the same points of W."""
    rng = np.random.default_rng(seed)
    pa, pb = _cloud(rng, int(rng.integers(60, 400))), _cloud(rng, int(rng.integers(60, 400)))
    ga, gb = hull_graph(pa)[0], hull_graph(pb)[0]
    ta, tb = support_table(pa), support_table(pb)
    R_WA, R_WB = _rotation(rng), _rotation(rng)
    t_WA = rng.normal(size=3)
    t_WB = t_WA + (0.8 + gap) * rng.normal(size=3) / np.sqrt(3)
    pa_W, pb_W = pa @ R_WA.T + t_WA, pb @ R_WB.T + t_WB
    R_AB, t_AB = R_WA.T @ R_WB, R_WA.T @ (t_WB - t_WA)
    simp = np.zeros(9)
    d0 = pa_W.mean(axis=0) - pb_W.mean(axis=0)
    ref = gjk_dir_adj2(np.ascontiguousarray(pa_W), ga, np.ascontiguousarray(pb_W), gb, 0.0, 0.0, 0.0, *d0,
                       1e-12, 1e-12, 128, simp, np.inf)
    d0_A = R_WA.T @ d0
    got = gjk_dir_rel(pa, ga, ta, pb, gb, tb, np.ascontiguousarray(R_AB.ravel()), *t_AB, *d0_A,
                      1e-12, 1e-12, 128, simp, np.inf, np.zeros(0, np.int64))
    assert ref[0] != GJK_NOT_CONVERGED and got[0] != GJK_NOT_CONVERGED
    assert got[0] == ref[0]
    assert abs(got[1] - ref[1]) <= 1e-9
    if got[0] == 1 and simp[0] == 1.0:  # overlapping: EPA in A's frame equals EPA on the moved points
        from armguard.geometry._pair_epa import EPA_WORK_SIZE, epa_depth

        w_rel = np.zeros(EPA_WORK_SIZE)
        gjk_dir_rel(pa, ga, ta, pb, gb, tb, np.ascontiguousarray(R_AB.ravel()), *t_AB, *d0_A, 1e-12, 1e-12, 128,
                    w_rel[0:9], np.inf, np.zeros(0, np.int64))
        w_W = np.zeros(EPA_WORK_SIZE)
        gjk_dir_adj2(np.ascontiguousarray(pa_W), ga, np.ascontiguousarray(pb_W), gb, 0.0, 0.0, 0.0, *d0,
                     1e-12, 1e-12, 128, w_W[0:9], np.inf)
        e_rel = epa_depth(pa, ga, pb, gb, w_rel, 1e-12, np.ascontiguousarray(R_AB.ravel()), *t_AB)
        e_W = epa_depth(np.ascontiguousarray(pa_W), ga, np.ascontiguousarray(pb_W), gb, w_W, 1e-12)
        w_tab = np.zeros(EPA_WORK_SIZE)  # the link-frame path's call: climbs warm-started from the tables
        gjk_dir_rel(pa, ga, ta, pb, gb, tb, np.ascontiguousarray(R_AB.ravel()), *t_AB, *d0_A, 1e-12, 1e-12, 128,
                    w_tab[0:9], np.inf, np.zeros(0, np.int64))
        e_tab = epa_depth(pa, ga, pb, gb, w_tab, 1e-12, np.ascontiguousarray(R_AB.ravel()), *t_AB, ta, tb)
        for e in (e_rel, e_tab):
            if e[0] and e_W[0]:
                assert abs(e[1] - e_W[1]) <= 1e-9  # the depth
                n_W = R_WA @ np.array(e[2:5])
                assert np.linalg.norm(n_W - np.array(e_W[2:5])) <= 1e-6
    if ref[0] == 0:  # separated: the witnesses, mapped to W, are the reference's nearest points
        a_W = R_WA @ np.array(got[2:5]) + t_WA
        b_W = R_WA @ np.array(got[5:8]) + t_WA
        assert abs(np.linalg.norm(b_W - a_W) - ref[1]) <= 1e-9
        assert np.max(np.abs(a_W - np.array(ref[2:5]))) <= 1e-6  # unique nearest points up to ties on a face
        assert np.max(np.abs(b_W - np.array(ref[5:8]))) <= 1e-6


def _robots() -> list[str]:
    names = {m.name for m in known_models() if m.available}
    # hull-hull (kinova, iiwa), cylinder-hull and cylinder-cylinder (z1), box-hull (ur5), built-in hulls (panda)
    # ur3: half its random configurations collide (EPA depths in the link frames); rover: boxes and
    # prisms without vertex graphs, penetrating in most configurations (the link-frame SAT for box-box,
    # EPA on scanned supports for the others); puma560: built-in boxes and prisms
    return [n for n in ("z1", "kinova", "ur5", "ur3", "kuka_iiwa", "panda", "rover", "puma560") if n in names]


@pytest.mark.parametrize("name", _robots())
def test_link_frame_pairs_equal_the_world_frame_kernel(name):
    """Every pair of a robot's check against the W path on the same poses (every element moved, the
    generic per-pair kernel) to 1e-9 m, over in-limit random configurations; verdicts equal coal's."""
    from _engine_world import move_all, world_pair_distance

    model = armguard.load_model(name)
    det = armguard.Detector(model, threshold=0.0)
    m = det._model
    coal = armguard.checker(model, "coal")
    cores = m.compiled.elem_core
    n_rel = 0
    for q in model.random_q(12, 5):
        res = det.pair_distances(model.scene_q(q))
        move_all(det)
        for k, p in enumerate(res.pair_index):
            a, b = int(m.pair_a[p]), int(m.pair_b[p])
            if b < 0:
                continue
            n_rel += int(cores[a] in (2, 3, 4) and cores[b] in (2, 3, 4) and not cores[a] == cores[b] == 4)
            d, err = world_pair_distance(det, a, b)
            assert err == 0
            assert abs(d - res.distance[k]) <= 1e-9, (name, k)
            if d > 1e-6:  # apart: the nearest points are the W kernel's (ties aside, to GJK's accuracy)
                assert abs(np.linalg.norm(res.p_WB[k] - res.p_WA[k]) - d) <= 1e-9
        ref = coal.pair_distances(q)
        assert ((ref.distance <= 0).any()) == ((res.distance <= 0).any())
    assert n_rel > 0  # the link-frame path was exercised


@pytest.mark.parametrize("threshold", [0.0, 0.05, 0.3])
def test_exact_checks_with_gjk_cut_offs_match_the_brute_force_reference(threshold):
    """The exact mode stops GJK on a link-frame pair once it is proved beyond the category's cut-off
    (``_step.pair_step``'s ``beyond``): the per-category nearest distances and the pairs within the
    threshold still equal the brute-force reference's (the built-in panda: mesh hulls and boxes,
    with an obstacle box added so every category has pairs)."""
    from armguard.detect import CATEGORIES, Detector, Status, check_reference

    STATUS_OF_CODE = {0: Status.CLEAR, 1: Status.WARNING, 2: Status.COLLISION}
    from armguard.geometry import Box
    from armguard.scene import load_scene

    scene = load_scene("panda")
    scene.add_body("crate", [Box([0.55, 0.0, 0.35], [0.12, 0.2, 0.1])])
    det = Detector(scene, threshold=threshold)
    robot = next(iter(scene.robots.values()))
    rng = np.random.default_rng(8)
    lo, hi = robot.lower, robot.upper
    for q in rng.uniform(lo, hi, size=(30, len(lo))):
        rep = det.check(q)
        ref = check_reference(scene, q, threshold)
        got = np.array([rep.by_category[c].distance if c in rep.by_category else np.inf for c in CATEGORIES])
        assert np.array_equal(np.isfinite(got), np.isfinite(ref.min_distance))
        fin = np.isfinite(got)
        assert np.allclose(got[fin], ref.min_distance[fin], atol=1e-9)
        all_d = det.pair_distances(q).distance
        assert len(rep.within_threshold) == int(np.sum(all_d <= threshold))
        assert STATUS_OF_CODE[ref.status] is rep.status
