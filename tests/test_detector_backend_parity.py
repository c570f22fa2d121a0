"""The Detector over any backend keeps the analytic Detector's rules (a review's findings, each
reproduced before the fix): lower bounds that hold, no verdict without a pair, the Detector's own
tolerances, a refused setting that changes nothing, every skipped pair listed, a cost model that does
not run away, payload pairs named alike, strict JSON."""

from __future__ import annotations

import dataclasses
import json
import warnings

import numpy as np
import pytest

import armguard
from armguard import DetectionError
from armguard.geometry import Sphere

BACKENDS = ["analytic", "coal"]


@pytest.fixture(autouse=True)
def _quiet():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_lazy_reports_bounds_are_the_checks_not_a_later_thresholds(backend):
    """coal: a lazy report read after ``set_threshold(1.0)`` gave 46 of 62 bounds of 1.0 where the pairs
    were 0.06 m, 0.43 m ... away (the bound was taken from the detector's threshold at reading time)."""
    m = armguard.load_model("puma560")
    det = armguard.Detector(m, threshold=0.05, backend=backend)
    q = m.scene_q(m.random_q(1, 3)[0])
    det.check(q)
    r = det.check(q, lazy=True)
    det.set_threshold(1.0)
    d = armguard.Detector(m, threshold=0.05, backend=backend).pair_distances(q).distance
    assert r.not_evaluated
    assert all(n.lower_bound <= d[n.pair_index] + 1e-12 for n in r.not_evaluated)


def _left_arm_alone():
    sc = armguard.load_scene("ranger")
    for other in list(sc.bodies) + [r for r in sc.robots if r != "left_arm"]:
        sc.disable_pair("left_arm", other)
    sc.set_self_pairs("left_arm", [])
    sc.clear_workspace()
    return sc


@pytest.mark.parametrize("backend", BACKENDS)
def test_an_active_arm_without_a_pair_is_refused_and_a_refused_arm_changes_nothing(backend):
    """coal said CLEAR at every configuration for an arm with no pair left; the analytic Detector, refusing
    ``set_active``, kept ``active`` naming the refused arm (checks ran on the old build, a later edit raised)."""
    sc = _left_arm_alone()
    q = sc.flat_q(sc.default_q())
    with pytest.raises(DetectionError, match="no pair to check on arm 'left_arm'"):
        armguard.Detector(sc, threshold=0.15, backend=backend, active="left_arm")
    det = armguard.Detector(sc, threshold=0.15, backend=backend)
    before = det.check(q)
    with pytest.raises(DetectionError, match="no pair to check on arm 'left_arm'"):
        det.set_active("left_arm")
    assert det.active is None
    after = det.check(q)
    assert (after.status, after.nearest.a, after.nearest.b) == (before.status, before.nearest.a, before.nearest.b)
    sc.disable_pair("right_arm", list(sc.bodies)[0])  # an edit: the next call builds again, for all arms
    assert det.check(q).status is not None and det.active is None


@pytest.mark.parametrize("backend", BACKENDS)
def test_collides_many_uses_the_detectors_contact_tolerance(backend):
    """coal's ``collides_many`` asked the Checker at margin 0 while ``check`` uses the Detector's contact
    tolerance: a sphere 0.5 mm away with ``tol.length = 1 mm`` was a COLLISION to check, not to collides_many."""
    tol = dataclasses.replace(armguard.DEFAULT_TOLERANCES, length=1e-3)
    sc = armguard.load_scene("puma560")
    for b in list(sc.bodies):
        sc.remove_body(b)
    q = sc.flat_q(sc.default_q())
    sc.add_body("probe", [Sphere(np.array([2.0, 2.0, 2.0]), 0.1)])
    det = armguard.Detector(sc, threshold=0.01, backend=backend, tol=tol)
    pd = det.pair_distances(q)
    i = min((i for i in range(len(pd.distance)) if pd.owner_b[i] == "probe"), key=lambda i: pd.distance[i])
    n = (pd.p_WB[i] - pd.p_WA[i]) / np.linalg.norm(pd.p_WB[i] - pd.p_WA[i])
    sc.remove_body("probe")
    sc.add_body("probe", [Sphere(pd.p_WA[i] + n * (0.1 + 5e-4), 0.1)])
    assert 4e-4 < det.pair_distances(q).distance.min() < 6e-4
    assert det.check(q).status.value == "collision"
    assert det.check_many(q[None]).collision[0]
    assert det.collides_many(q[None])[0]


@pytest.mark.parametrize("backend", BACKENDS)
def test_the_detectors_joint_limit_slack_holds_for_every_entry_point(backend):
    """docs/detector.md's measured-state recipe (``tol.joint_limit = 1e-3``) worked for coal's ``check``
    only: ``check_many``, ``collides_many`` and the budgeted ``check`` refused 0.5 mrad past a limit."""
    tol = dataclasses.replace(armguard.DEFAULT_TOLERANCES, joint_limit=1e-3)
    m = armguard.load_model("puma560")
    robot = next(iter(m.scene.robots.values()))
    q = m.scene_q(m.neutral())
    q[0] = robot.upper[0] + 5e-4
    det = armguard.Detector(m, threshold=0.05, backend=backend, tol=tol)
    exact = det.check(q)
    assert det.check(q, budget_us=1e6).status == exact.status
    assert det.check_many(q[None]).status[0] == {"clear": 0, "warning": 1, "collision": 2}[exact.status.value]
    assert bool(det.collides_many(q[None])[0]) == (exact.status.value == "collision")
    assert det.pair_distances(q).distance.min() == pytest.approx(exact.nearest.distance, abs=1e-12)
    q[0] = robot.upper[0] + 2e-3  # beyond the slack: refused, naming the joint
    with pytest.raises(armguard.JointLimitError, match="j1"):
        det.check_many(q[None])


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_budgeted_lazy_check_lists_every_pair_it_did_not_evaluate(backend):
    """analytic: ``check(q, budget_us=1e9, lazy=True)`` on ranger evaluated 2 pairs and listed 0 of the
    other 198 (the pairs its bounds proved beyond the threshold went unlisted)."""
    m = armguard.load_model("ranger")
    q = m.scene_q(m.random_q(1, 0)[0])
    det = armguard.Detector(m, threshold=0.08, backend=backend)
    det.check(q)
    for kw in ({"lazy": True}, {"budget_us": 1e9}, {"budget_us": 1e9, "lazy": True}):
        r = det.check(q, **kw)
        listed = {n.pair_index for n in r.not_evaluated}
        assert r.n_evaluated + len(listed) == det.n_pairs, kw


def test_budgets_that_fit_no_pair_do_not_run_the_cost_model_down():
    """300 checks at a 1e-3 µs budget took the analytic cost model from ~5,000 to 0.85 ns a pair: the next
    5 µs budget then evaluated all 74 pairs.  It now stops at half the least a pair has taken."""
    m = armguard.load_model("ranger")
    Q = np.array([m.scene_q(x) for x in m.random_q(260, 1)])
    det = armguard.Detector(m, threshold=0.15, active="left_arm")
    for q in Q[:30]:
        det.check(q, budget_us=5.0)
    learnt = det._ns_per_pair
    for q in Q[:300]:
        det.check(q, budget_us=1e-3)
    est = det._ns_per_pair
    assert est >= 0.5 * min(det._ns_min, learnt) - 1e-9
    first = det.check(Q[250], budget_us=5.0)
    assert first.n_evaluated <= int(5.0e3 / est) + 1 < det.n_pairs / 4, (first.n_evaluated, est)


def test_a_payload_pair_names_its_carrier_link_with_every_backend():
    """coal's Detector named the payload itself as ``link`` where the analytic one names the link carrying it."""
    m = armguard.load_model("hermes")
    q = m.scene_q(m.random_q(1, 8)[0])
    links = {}
    for backend in BACKENDS:
        r = armguard.Detector(m, threshold=10.0, backend=backend).check(q)
        p = next(p for p in r.within_threshold if p.a == "payload" and p.b == "cockpit")
        links[backend] = p.link
    assert links == {"analytic": "hera/link6", "coal": "hera/link6"}


@pytest.mark.parametrize("backend", BACKENDS)
def test_to_dict_is_strict_json_and_a_bound_decided_clear_may_have_no_nearest(backend):
    """A budgeted report's ``lower_bound`` of ``-inf`` was written as ``-Infinity`` (not JSON); a check whose
    remembered bounds prove CLEAR with no pair evaluated has ``nearest`` None (now documented)."""
    m = armguard.load_model("puma560")
    det = armguard.Detector(m, threshold=0.05, backend=backend)
    q = m.scene_q(m.random_q(1, 3)[0])
    r = det.check(q, budget_us=0.0)  # nothing evaluated yet: every bound -inf, INCOMPLETE
    out = json.loads(json.dumps(r.to_dict(), allow_nan=False))
    assert r.status.value == "incomplete"
    assert [n["lower_bound"] for n in out["not_evaluated"]] == \
        [b.lower_bound if np.isfinite(b.lower_bound) else None for b in r.not_evaluated]
    assert any(not np.isfinite(b.lower_bound) for b in r.not_evaluated) or backend == "analytic"  # coal: no bound yet
    full = det.check(q)
    again = det.check(q, budget_us=0.0)
    if full.status.value == "clear" and min(n.lower_bound for n in again.not_evaluated) > 0.05:
        assert again.status.value == "clear" and again.nearest is None and again.by_category == {}
    json.dumps(again.to_dict(), allow_nan=False)


@pytest.mark.parametrize("name", ["hermes", "rover"])
def test_the_obstacles_feature_is_named_over_every_backend(name):
    """The nearest pair's obstacle feature (face / edge / vertex of a static polytope): the analytic
    Detector named it, the Detector over coal said None.  Now both name the same one, and None where
    the obstacle is no polytope."""
    m = armguard.load_model(name)
    det = {b: armguard.Detector(m, threshold=0.5, backend=b) for b in BACKENDS}
    named = 0
    for q in m.random_q(30, 4):
        q = m.scene_q(q)
        r = {b: d.check(q).by_category for b, d in det.items()}
        for cat, pa in r["analytic"].items():
            pc = r["coal"][cat]
            if pa.obstacle == pc.obstacle and abs(pa.distance - pc.distance) < 1e-9:
                assert pa.feature == pc.feature, (cat, pa.feature, pc.feature)
                named += pc.feature is not None
    assert named >= 20
