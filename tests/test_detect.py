"""The Detector against brute force, its status logic, the anytime bounds and the obstacle lists.

Oracles: the brute-force reference (``check_reference``: the scene's own world geometry,
every allowed pair, the geometry core's public ``distance``), the all-pairs numba path
(``check_many_bruteforce``), and sampling of the kinematic chain for the reach / lever bounds.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from armguard import DetectionError
from armguard.detect import CATEGORIES, Detector, Status, check_reference
from armguard.scene import load_scene

SCENES = ["puma560", "hermes", "ranger", "gmf_s480", "rover"]
STATUS_OF = {0: Status.CLEAR, 1: Status.WARNING, 2: Status.COLLISION}


def _limits(scene):
    lo = np.concatenate([scene.robots[r].lower for r in scene.robots])
    hi = np.concatenate([scene.robots[r].upper for r in scene.robots])
    return np.where(np.isfinite(lo), lo, -math.pi), np.where(np.isfinite(hi), hi, math.pi)


def _sample(scene, rng, n):
    lo, hi = _limits(scene)
    return rng.uniform(lo, hi, size=(n, len(lo)))


@pytest.fixture(scope="module", params=SCENES, ids=SCENES)
def scene(request):
    return load_scene(request.param)


def _by_cat(report):
    return np.array([report.by_category[c].distance if c in report.by_category else np.inf for c in CATEGORIES])


def test_check_matches_brute_force_reference(scene):
    rng = np.random.default_rng(1)
    det = Detector(scene, threshold=0.05)
    for q in _sample(scene, rng, 25):
        rep = det.check(q)
        ref = check_reference(scene, q, 0.05)
        got = _by_cat(rep)
        assert np.array_equal(np.isfinite(got), np.isfinite(ref.min_distance))
        fin = np.isfinite(got)
        assert np.max(np.abs(got[fin] - ref.min_distance[fin]), initial=0.0) <= 1e-9
        assert rep.status is STATUS_OF[ref.status]
        within = sorted(d for *_, d in ref.pairs if d <= 0.05)
        assert np.allclose(sorted(r.distance for r in rep.within_threshold), within, atol=1e-9)


def test_pruned_batch_equals_all_pairs_over_many_configurations(scene):
    """>= 10^5 configurations over the five scenes: zero status disagreements, distance error <= 1e-9 m."""
    rng = np.random.default_rng(2)
    det = Detector(scene, threshold=0.05)
    Q = _sample(scene, rng, 20_000)
    fast = det.check_many(Q)
    brute = det.check_many_bruteforce(Q)
    assert np.array_equal(fast.status, brute.status)
    assert np.array_equal(fast.collision, brute.collision)
    assert np.array_equal(np.isfinite(fast.min_distance), np.isfinite(brute.min_distance))
    fin = np.isfinite(fast.min_distance)
    assert np.max(np.abs(fast.min_distance[fin] - brute.min_distance[fin]), initial=0.0) <= 1e-9
    assert np.array_equal(det.collides_many(Q), brute.collision)


def test_check_many_agrees_with_check(scene):
    rng = np.random.default_rng(3)
    det = Detector(scene, threshold=0.05)
    Q = _sample(scene, rng, 40)
    batch = det.check_many(Q)
    for m, q in enumerate(Q):
        rep = det.check(q)
        assert np.allclose(_by_cat(rep), batch.min_distance[m], atol=0, rtol=0, equal_nan=False) or np.array_equal(
            _by_cat(rep), batch.min_distance[m]
        )
        assert rep.status is batch.statuses()[m]


def test_lazy_mode_keeps_status_and_within_threshold(scene):
    rng = np.random.default_rng(4)
    det = Detector(scene, threshold=0.1)
    for q in _sample(scene, rng, 40):
        exact = det.check(q)
        lazy = det.check(q, lazy=True)
        assert lazy.status is exact.status
        assert [r.distance for r in lazy.within_threshold] == [r.distance for r in exact.within_threshold]
        # (no n_evaluated comparison: an exact check proves pairs beyond its cut-off with GJK's bound,
        # counted as culled, where the lazy mode computes the distances of every pair it visits)
        for ne in lazy.not_evaluated:
            assert ne.lower_bound >= 0.1


@pytest.mark.parametrize("stop", [0.0, 0.03], ids=["no-stop", "stop-3cm"])
def test_status_levels(stop):
    scene = load_scene("puma560")
    det = Detector(scene, threshold=0.08, stopping_distance=stop)
    rng = np.random.default_rng(5)
    seen = set()
    for q in _sample(scene, rng, 200):
        rep = det.check(q)
        d = rep.nearest.distance
        expect = Status.COLLISION if d <= stop else (Status.WARNING if d <= 0.08 else Status.CLEAR)
        assert rep.status is expect
        seen.add(rep.status)
    assert Status.COLLISION in seen and len(seen) >= 2


def test_anytime_bounds_are_lower_bounds_and_never_clear_by_omission():
    scene = load_scene("ranger")
    det = Detector(scene, threshold=0.05, active="left_arm")
    rng = np.random.default_rng(6)
    Q = _sample(scene, rng, 60)
    lo = np.concatenate([r.lower for r in scene.robots.values()])
    hi = np.concatenate([r.upper for r in scene.robots.values()])
    first = Detector(scene, threshold=0.05, active="left_arm").check(Q[0], budget_us=0.0)
    assert first.n_evaluated == 0
    assert first.status in (Status.INCOMPLETE, Status.CLEAR)
    if first.status is Status.CLEAR:  # only when every bound already proves the threshold
        assert all(n.lower_bound > 0.05 for n in first.not_evaluated)
    for k in range(len(Q) - 1):
        det.check(Q[k])  # full check: every pair's distance is remembered
        q1 = np.clip(Q[k] + rng.normal(0.0, 0.02, Q.shape[1]), lo, hi)  # configurations outside the limits are refused
        rep = det.check(q1, budget_us=0.0)
        truth = det.pair_distances(q1)
        for ne in rep.not_evaluated:
            assert ne.lower_bound <= truth.distance[ne.pair_index] + 1e-12
        if rep.status is not Status.INCOMPLETE:
            ref = check_reference(scene, q1, 0.05, active="left_arm")
            assert rep.status is STATUS_OF[ref.status]


def test_anytime_with_budget_evaluates_nearest_first():
    scene = load_scene("ranger")
    det = Detector(scene, threshold=0.05, active="left_arm")
    q = scene.flat_q(scene.default_q())
    det.check(q)
    rep = det.check(q, budget_us=1e6)
    assert not rep.not_evaluated and rep.status is not Status.INCOMPLETE
    assert rep.status is det.check(q).status


def test_lever_bound_covers_sampled_motion(scene):
    det = Detector(scene, threshold=0.05)
    m = det._model
    cs = m.compiled
    rng = np.random.default_rng(7)
    Q = _sample(scene, rng, 60)
    for k in range(0, len(Q) - 1, 2):
        q0, q1 = Q[k], Q[k + 1]
        X0 = np.concatenate([scene.robots[r].forward_kinematics(q) for r, q in scene.split_q(q0).items()])
        X1 = np.concatenate([scene.robots[r].forward_kinematics(q) for r, q in scene.split_q(q1).items()])
        for i, g in enumerate(m.mov_ids):
            L = m.elem_glink[g]
            V = cs.verts[cs.elem_vert_start[g]:cs.elem_vert_start[g + 1]]
            moved = np.linalg.norm((V @ X1[L, :3, :3].T + X1[L, :3, 3]) - (V @ X0[L, :3, :3].T + X0[L, :3, 3]), axis=1)
            bound = float(np.abs(q1 - q0) @ m.lever[i])
            assert moved.max() <= bound + 1e-9
            # the reach sphere holds every core point (plus radius) at every configuration
            P1 = V @ X1[L, :3, :3].T + X1[L, :3, 3]
            assert np.all(np.linalg.norm(P1 - m.reach_center[i], axis=1) + cs.elem_radius[g] <= m.reach_radius[i] + 1e-9)


@pytest.mark.parametrize("margin", [0.05, 0.3], ids=["5cm", "30cm"])
def test_obstacle_lists_are_conservative(margin):
    """A pair dropped from the obstacle lists is farther than the margin at every sampled configuration."""
    scene = load_scene("puma560")
    full = Detector(scene, threshold=0.0, reach_margin=math.inf)
    listed = Detector(scene, threshold=0.0, reach_margin=margin)
    kept = set(zip(listed._names_a, listed._names_b, listed._model.pair_a.tolist(), listed._model.pair_b.tolist()))
    dropped = [p for p, key in enumerate(zip(full._names_a, full._names_b, full._model.pair_a.tolist(),
                                             full._model.pair_b.tolist())) if key not in kept]
    rng = np.random.default_rng(8)
    for q in _sample(scene, rng, 3000 if dropped else 10):
        d = full.pair_distances(q).distance
        if dropped:
            assert d[dropped].min() > margin
    a = listed.check_many(_sample(scene, np.random.default_rng(9), 500))
    b = full.check_many(_sample(scene, np.random.default_rng(9), 500))
    assert np.array_equal(a.collision, b.collision)


def test_active_arm_checks_only_its_pairs():
    scene = load_scene("ranger")
    det = Detector(scene, threshold=0.05, active="left_arm")
    assert all(a.startswith("left_arm/") or b.startswith("left_arm/") for a, b in zip(det._names_a, det._names_b))
    every = Detector(scene, threshold=0.05)
    assert every.n_pairs > det.n_pairs
    with pytest.raises(DetectionError):
        det.set_active("no_such_arm")


def test_bad_input_raises():
    scene = load_scene("puma560")
    det = Detector(scene, threshold=0.05)
    q = scene.flat_q(scene.default_q())
    bad = q.copy()
    bad[2] = np.nan
    with pytest.raises(DetectionError):
        det.check(bad)
    with pytest.raises(DetectionError):
        det.check(q[:3])
    with pytest.raises(DetectionError):
        det.check_many(np.full((3, len(q)), np.inf))
    with pytest.raises(DetectionError):
        Detector(scene, threshold=-1.0)
    with pytest.raises(DetectionError):
        det.check(q, budget_us=float("nan"))


def test_report_contents_and_mapping_input():
    scene = load_scene("ranger")
    det = Detector(scene, threshold=0.3)
    rep = det.check(scene.default_q())
    assert set(rep.by_category) <= set(CATEGORIES)
    n = rep.nearest
    assert n is not None and n.distance == min(r.distance for r in rep.by_category.values())
    for r in rep.by_category.values():
        assert abs(np.linalg.norm(r.p_WA - r.p_WB) - abs(r.distance)) <= 1e-9
    env = rep.by_category["environment"]
    assert env.feature is not None
    assert rep.to_dict()["status"] == rep.status.value
    with pytest.raises(Exception):
        rep.status = Status.CLEAR  # frozen


def test_pair_distances_of_one_robot_are_rows_of_all_pairs():
    scene = load_scene("ranger")
    det = Detector(scene, threshold=0.0)
    rng = np.random.default_rng(10)
    for q in _sample(scene, rng, 5):
        full = det.pair_distances(q)
        arm = det.pair_distances(q, robot="left_arm")
        assert 0 < len(arm.distance) < len(full.distance)
        assert np.array_equal(arm.distance, full.distance[arm.pair_index])
        assert np.array_equal(arm.p_WA, full.p_WA[arm.pair_index])
        assert all(a.startswith("left_arm/") or b.startswith("left_arm/") for a, b in zip(arm.owner_a, arm.owner_b))
        kept = arm.distance.copy()
        det.pair_distances(_sample(scene, rng, 1)[0], robot="left_arm")
        assert np.array_equal(arm.distance, kept)  # results are copies, not views of the kernel's buffers
    with pytest.raises(DetectionError):
        det.pair_distances(q, robot="no_such_arm")


@pytest.mark.parametrize("name", ["ranger", "hermes", "rover"], ids=["ranger", "hermes", "rover"])
def test_fast_narrow_phase_matches_generic_pair_kernel(name):
    """The scalar / capsule-polytope / link-frame dispatch of the kernel against the generic per-pair
    kernel (GJK + EPA / SAT) on the same poses, every element moved to W."""
    from _engine_world import move_all, world_pair_distance

    scene = load_scene(name)
    det = Detector(scene, threshold=0.0)
    m = det._model
    for q in _sample(scene, np.random.default_rng(11), 20):
        res = det.pair_distances(q)  # leaves the link poses; polytope pairs are checked in their link frames
        move_all(det)
        for k, p in enumerate(res.pair_index):
            a, b = int(m.pair_a[p]), int(m.pair_b[p])
            if b < 0:
                continue
            d, err = world_pair_distance(det, a, b)
            assert err == 0
            assert abs(d - res.distance[k]) <= 1e-9


def test_report_survives_later_checks():
    """Reports keep copies of the evaluated rows: building them after further checks gives the same pairs."""
    scene = load_scene("ranger")
    det = Detector(scene, threshold=0.3, active="left_arm")
    Q = _sample(scene, np.random.default_rng(12), 3)
    first = det.check(Q[0])
    det.check(Q[1])
    det.check(Q[2])
    again = Detector(scene, threshold=0.3, active="left_arm").check(Q[0])
    assert {k: v.distance for k, v in first.by_category.items()} == {k: v.distance for k, v in again.by_category.items()}
    assert [r.distance for r in first.within_threshold] == [r.distance for r in again.within_threshold]


def test_batch_minimum_with_deep_penetration():
    """Regression: a BVH node overlapping a link's sphere has a negative gap that bounds nothing; the
    batch path once pruned such a node against a negative category minimum (hermes, rng 3, row 5679:
    environment -0.822 m instead of -0.852 m)."""
    scene = load_scene("hermes")
    det = Detector(scene, threshold=0.05)
    Q = _sample(scene, np.random.default_rng(3), 6000)
    fast = det.check_many(Q)
    brute = det.check_many_bruteforce(Q)
    assert brute.min_distance[5679, 1] < -0.85
    fin = np.isfinite(fast.min_distance)
    assert np.array_equal(fin, np.isfinite(brute.min_distance))
    assert np.max(np.abs(fast.min_distance[fin] - brute.min_distance[fin])) <= 1e-9


@pytest.mark.parametrize("backend", [None, "coal"])
def test_detector_accepts_a_model(backend):
    """``armguard.Detector(model)`` (the contract's ``scene_or_model``) is the Detector of the Model's
    scene: same class, same distances per category (it failed on ``Model.robots`` before)."""
    import armguard

    model = armguard.load_model("panda")
    a = armguard.Detector(model, threshold=0.05, backend=backend)
    b = armguard.Detector(model.scene, threshold=0.05, backend=backend)
    assert type(a) is type(b) and a.scene is model.scene_for()  # the Model's own copy of its system
    for q in model.random_q(5, 3):
        qs = model.scene_q(q)
        ra, rb = a.check(qs), b.check(qs)
        assert ra.status == rb.status
        assert {k: v.distance for k, v in ra.by_category.items()} == {k: v.distance for k, v in rb.by_category.items()}


@pytest.mark.parametrize("backend", [None, "coal"])
def test_a_nan_is_placed_by_joint_for_one_q_and_by_row_for_a_batch(backend):
    """One q named the NaN's place as a 2-D index ("first at (0, 2)"); both Detectors word it alike."""
    import armguard

    model = armguard.load_model("puma560")
    det = armguard.Detector(model, backend=backend)
    q = model.scene_q(model.neutral())
    q[2] = np.nan
    with pytest.raises(DetectionError, match=r"first(?: at joint 2: |: joint 'j3', )nan\)"):  # by number or by name
        det.check(q)
    with pytest.raises(DetectionError, match=r"first at row 1, joint 2: nan\)"):
        det.check_many(np.vstack([model.scene_q(model.neutral()), q]))
