"""The check fast path: FK per robot block, reports copied out only when still held, heapsort order.

Oracles: the robot's own forward kinematics (``Robot.forward_kinematics``), the slow path of the
same detector (a report built from copies taken right after the check), ``numpy.argsort``.
"""

from __future__ import annotations

import numpy as np
import pytest

from armguard.detect import Detector
from armguard_analytic._engine._cull import _argsort_heap
from armguard.scene import load_scene


@pytest.fixture(scope="module")
def ranger():
    return load_scene("ranger")


def _limits(scene):
    lo = np.concatenate([scene.robots[r].lower for r in scene.robots])
    hi = np.concatenate([scene.robots[r].upper for r in scene.robots])
    return np.where(np.isfinite(lo), lo, -np.pi), np.where(np.isfinite(hi), hi, np.pi)


def test_block_fk_matches_robot_fk_when_only_one_arm_moves(ranger):
    det = Detector(ranger, threshold=0.05, active="left_arm")
    lo, hi = _limits(ranger)
    rng = np.random.default_rng(7)
    q = rng.uniform(lo, hi)
    names = list(ranger.robots)
    j0 = sum(ranger.robots[r].n_joints for r in names[:names.index("left_arm")])
    n = ranger.robots["left_arm"].n_joints
    Xs = det._layout.view(det._SF, "Xs")
    for _ in range(5):  # only the left arm moves: the other blocks keep their cached poses
        q[j0:j0 + n] = rng.uniform(lo[j0:j0 + n], hi[j0:j0 + n])
        det.check(q)
        want = np.concatenate([ranger.robots[r].forward_kinematics(qq) for r, qq in ranger.split_q(q).items()])
        np.testing.assert_allclose(Xs, want, atol=1e-12)
    q2 = rng.uniform(lo, hi)  # every arm moves
    det.check(q2)
    want = np.concatenate([ranger.robots[r].forward_kinematics(qq) for r, qq in ranger.split_q(q2).items()])
    np.testing.assert_allclose(Xs, want, atol=1e-12)


def test_held_report_survives_later_checks(ranger):
    det = Detector(ranger, threshold=0.05, active="left_arm")
    lo, hi = _limits(ranger)
    Q = np.random.default_rng(3).uniform(lo, hi, size=(6, len(lo)))
    held = det.check(Q[0])  # not read before the next checks
    want = Detector(ranger, threshold=0.05, active="left_arm").check(Q[0])
    for q in Q[1:]:
        det.check(q)
        det.pair_distances(q)
    assert held.status == want.status
    assert held.n_evaluated == want.n_evaluated
    got = {k: (v.distance, v.a, v.b) for k, v in held.by_category.items()}
    exp = {k: (v.distance, v.a, v.b) for k, v in want.by_category.items()}
    assert got == exp


def test_dropped_reports_cost_no_copy_and_stay_right(ranger):
    det = Detector(ranger, threshold=0.05, active="left_arm")
    lo, hi = _limits(ranger)
    Q = np.random.default_rng(5).uniform(lo, hi, size=(4, len(lo)))
    for q in Q:
        det.check(q)
    raw = det._last_raw
    assert raw is not None and raw._f is None  # nothing held the earlier reports: never copied
    last = det.check(Q[-1])
    ref = Detector(ranger, threshold=0.05, active="left_arm").check(Q[-1])
    assert [r.distance for r in last.within_threshold] == [r.distance for r in ref.within_threshold]


@pytest.mark.parametrize("n", [0, 1, 2, 7, 74, 155], ids=lambda n: f"n{n}")
def test_heapsort_order_matches_stable_argsort(n):
    rng = np.random.default_rng(n)
    key = np.round(rng.normal(size=n), 1)  # ties on purpose
    key[: n // 4] = -np.inf
    order = np.full(n, -1, dtype=np.int64)
    _argsort_heap(key, order, n)
    np.testing.assert_array_equal(order, np.argsort(key, kind="stable"))


def test_yesno_box_cull_agrees_with_all_pairs_on_capsules_among_boxes():
    """collides_many (sphere + segment-box culls, early exit) == the all-pairs brute force."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parent))
    from _verify_fixtures import spatial_arm

    from armguard.geometry import Box, Sphere
    from armguard.scene import Scene

    rng = np.random.default_rng(11)
    sc = Scene("cull")
    sc.add_robot(spatial_arm())
    for k in range(12):
        c = rng.uniform([-0.8, -0.8, -0.5], [0.8, 0.8, 0.8])
        a = rng.uniform(-np.pi, np.pi)
        R = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
        sc.add_body(f"box{k}", [Box(c, rng.uniform(0.02, 0.15, 3), R)])
    sc.add_body("ball", [Sphere([0.3, 0.3, 0.3], 0.1)])
    det = Detector(sc, threshold=0.05)
    lo, hi = _limits(sc)
    Q = rng.uniform(lo, hi, size=(3000, len(lo)))
    got = det.collides_many(Q)
    want = det.check_many_bruteforce(Q).collision
    assert 0.05 < want.mean() < 0.95  # both verdicts occur
    np.testing.assert_array_equal(got, want)


def test_the_fused_detector_refuses_an_unknown_option():
    """Detector(scene, backend_options={"warm_strat": True}) was accepted and left warm start off (coal's
    Detector and the analytic Checker refused it)."""
    from armguard._errors import BackendError

    scene = load_scene("ranger")
    with pytest.raises(BackendError, match=r"analytic: unknown options \['warm_strat'\]"):
        Detector(scene, threshold=0.02, backend_options={"warm_strat": True})


def test_a_detector_of_a_name_or_nothing_is_refused_by_name():
    """Detector("ranger") and Detector(None) were AttributeErrors ('str' object has no attribute 'robots')."""
    from armguard._errors import DetectionError

    with pytest.raises(DetectionError, match=r"expected a Scene or a Model \(armguard.load_model\('ranger'\)\), got str"):
        Detector("ranger", threshold=0.1)
    with pytest.raises(DetectionError, match="expected a Scene or a Model, got NoneType"):
        Detector(None, threshold=0.1)


@pytest.mark.parametrize("name", ["ranger", "hermes", "puma560"])
def test_the_all_pairs_capsule_rows_are_the_pair_steps_bits(name):
    """``pair_distances`` writes a capsule-capsule pair's row in place (``_step.capsule_step``); the exact
    mode's ``pair_step`` (a threshold past every pair: each pair's row in ``within_threshold``) computes it
    through the narrow phase.  Every row of one is a row of the other, to the bit (witnesses either way
    round); ranger has 94 capsule-capsule pairs, puma560 capsule-sphere ones (a sphere: a 1-vertex core)."""
    import armguard

    model = armguard.load_model(name)
    det = Detector(model, threshold=100.0)
    checker = armguard.checker(model, "analytic")
    kinds = {go.name: type(go.geometry).__name__ for go in model.collision_model.geometryObjects}
    capsules = sum(kinds.get(a) == kinds.get(b) == "Capsule" for a, b in zip(model.pairs.a, model.pairs.b))
    assert capsules > 0
    for q in model.random_q(30, 5):
        rows = checker.pair_distances(q)
        rows = {(float(d),) + tuple(a) + tuple(b) for d, a, b in zip(rows.distance, rows.p_WA, rows.p_WB)} | {
            (float(d),) + tuple(b) + tuple(a) for d, a, b in zip(rows.distance, rows.p_WA, rows.p_WB)}
        report = det.check(model.scene_q(q))
        assert len(report.within_threshold) == len(model.pairs)
        assert all((float(p.distance),) + tuple(p.p_WA) + tuple(p.p_WB) in rows for p in report.within_threshold)
