"""Verifier.check_edges: a planner's straight edges, certified (CLEAR / COLLISION / INCOMPLETE per edge).

Against the certified trajectory verifier (same verdicts), against coal sampled densely along the edge
(a CLEAR edge has no sample in contact; a COLLISION's configuration is in contact for coal too), on thin
obstacles a 0.05 rad sampled check steps over, and for its invariants (hypothesis)."""

from __future__ import annotations

import math
import threading

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import armguard
from armguard import DEFAULT_TOLERANCES, VerificationError
from armguard.kinematics import Trajectory
from armguard.verify import EdgeResults, EdgeStatus, VerificationStatus, Verifier, verify

from _verify_fixtures import thin_suite

CONTACT = DEFAULT_TOLERANCES.verify_contact


def _edges(model, n, seed, max_step=0.5):
    """``n`` random in-limit edges of the model's first robot, no joint moving more than ``max_step`` rad."""
    Q0, Q1 = [], []
    for i in range(n):
        Q = model.scene_q(model.random_q(2, seed + i))
        d = Q[1] - Q[0]
        Q[1] = Q[0] + d * min(1.0, max_step / float(np.max(np.abs(d))))
        Q0.append(Q[0])
        Q1.append(Q[1])
    return np.array(Q0), np.array(Q1)


@pytest.fixture(scope="module")
def ur5():
    m = armguard.load_model("ur5")
    return m, Verifier(m.scene)


@pytest.mark.parametrize("name", ["ur5", "panda", "z1"])
def test_same_verdicts_as_the_certified_verifier(name):
    m = armguard.load_model(name)
    v = Verifier(m.scene)
    robot = next(iter(m.scene.robots))
    names = m.scene.robots[robot].joint_names
    Q0, Q1 = _edges(m, 40, 300)
    res = v.check_edges(Q0, Q1)
    assert isinstance(res, EdgeResults) and len(res) == 40 and res.robot == robot
    assert res.counts()["incomplete"] == 0
    for i in range(40):
        rep = v.verify(Trajectory(robot, names, [0.0, 1.0], np.stack([Q0[i], Q1[i]])))
        assert (rep.status is VerificationStatus.SAFE) == bool(res.clear[i]), (i, rep.status, res.status[i])
    assert 0 < int(np.sum(res.clear)) < 40  # both verdicts occur
    assert np.all(res.evaluations[res.clear] >= 2) and np.all(res.evaluations >= 1)  # both ends; a collision at q0 ends at once


def test_clear_edges_have_no_colliding_sample_and_collisions_are_real_for_coal(ur5):
    """Differential against coal: 300 samples along every CLEAR edge are apart for coal; every
    COLLISION configuration is in contact for coal (within the contact tolerance and coal's accuracy)."""
    m, v = ur5
    coal = armguard.checker(m, "coal")
    Q0, Q1 = _edges(m, 60, 900, max_step=0.8)
    res = v.check_edges(Q0, Q1)
    s = np.linspace(0.0, 1.0, 301)
    n_clear = n_coll = 0
    for i in range(len(res)):
        if res.code[i] == EdgeStatus.CLEAR:
            n_clear += 1
            Q = m.pin_q(Q0[i] + s[:, None] * (Q1[i] - Q0[i]))
            assert not np.any(coal.collides(Q)), i
        elif res.code[i] == EdgeStatus.COLLISION:
            n_coll += 1
            assert 0.0 <= res.s[i] <= 1.0 and res.distance[i] <= CONTACT
            np.testing.assert_allclose(res.q[i], Q0[i] + res.s[i] * (Q1[i] - Q0[i]), atol=1e-12)
            d = coal.pair_distances(m.pin_q(res.q[i])).distance
            assert float(np.min(d)) <= CONTACT + 1e-6, (i, float(np.min(d)))
            assert res.pair[i] is not None and all(isinstance(x, str) for x in res.pair[i])
        else:
            pytest.fail(f"edge {i}: INCOMPLETE within the default budget")
    assert n_clear >= 10 and n_coll >= 5


def test_thin_obstacles_a_sampled_check_steps_over_are_found():
    """The planar arm among 2 mm plates and rods: every edge the dense reference finds colliding is a
    COLLISION, and some of them pass a 0.05 rad sampled check."""
    rng = np.random.default_rng(77)
    missed_by_sampling = found = 0
    for sc, traj in thin_suite(rng, 30, n_obstacles=6):
        v = Verifier(sc, source="reference")
        q0, q1 = np.asarray(traj.waypoints[0]), np.asarray(traj.waypoints[-1])
        res = v.check_edges(q0, q1)
        cert = verify(sc, traj, method="certified")
        assert (cert.status is VerificationStatus.SAFE) == bool(res.clear[0])
        model = v.model
        dense = [model.reference_distances(q0 + s * (q1 - q0))[0].min() for s in np.linspace(0.0, 1.0, 801)]
        if min(dense) <= 0.0:
            found += 1
            assert res.code[0] == EdgeStatus.COLLISION
            if verify(sc, traj, method="sampled", joint_step=0.05).safe:
                missed_by_sampling += 1
    assert found >= 5 and missed_by_sampling >= 1


def test_budget_spent_is_incomplete_never_clear(ur5):
    m, v = ur5
    Q0, Q1 = _edges(m, 30, 500, max_step=1.5)
    full = v.check_edges(Q0, Q1)
    short = v.check_edges(Q0, Q1, max_evaluations=2)
    needs_more = full.evaluations > 2
    assert needs_more.any()
    assert np.all(short.code[needs_more & full.clear] == EdgeStatus.INCOMPLETE)
    assert not np.any(short.clear & ~full.clear)
    assert np.all(short.evaluations <= 2)
    assert "incomplete" in short.summary()
    from dataclasses import replace

    by_tol = Verifier(m.scene, tol=replace(DEFAULT_TOLERANCES, edge_max_evaluations=2)).check_edges(Q0, Q1)
    np.testing.assert_array_equal(by_tol.code, short.code)  # the default budget is the tolerance's


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(seed=st.integers(0, 10_000), a=st.floats(0.0, 0.45), b=st.floats(0.55, 1.0), m1=st.floats(0.0, 0.02))
def test_invariants_sub_edges_margins_and_reversal(ur5, seed, a, b, m1):
    """A CLEAR edge: its reverse and every sub-edge are CLEAR; CLEAR at a margin is CLEAR at a smaller one."""
    m, v = ur5
    Q0, Q1 = _edges(m, 1, seed)
    q0, q1 = Q0[0], Q1[0]
    res = v.check_edges(q0, q1, margin=m1)
    rev = v.check_edges(q1, q0, margin=m1)
    assert rev.clear[0] == res.clear[0]
    if res.clear[0]:
        sub = v.check_edges(q0 + a * (q1 - q0), q0 + b * (q1 - q0), margin=m1)
        assert sub.clear[0]
        assert v.check_edges(q0, q1, margin=0.5 * m1).clear[0]
    else:
        assert res.code[0] == EdgeStatus.COLLISION and res.distance[0] <= m1 + CONTACT


def test_a_still_edge_is_one_configuration(ur5):
    m, v = ur5
    Q = m.scene_q(m.random_q(20, 3))
    res = v.check_edges(Q, Q)
    assert np.all(res.evaluations == 1)
    hits = armguard.checker(m, "coal").collides(m.pin_q(Q))
    np.testing.assert_array_equal(res.code == EdgeStatus.COLLISION, hits)
    assert np.all(res.s_free[res.clear] == 1.0) and np.all(res.s_free[~res.clear] == -np.inf)


def test_the_free_prefix_is_clear_and_ends_before_the_first_contact(ur5):
    """``s_free`` (OMPL's last valid fraction): dense coal samples on [0, s_free] are apart, and it is no
    later than the first contact the certified trajectory verifier finds."""
    m, v = ur5
    coal = armguard.checker(m, "coal")
    robot = "ur5"
    names = m.scene.robots[robot].joint_names
    Q = m.scene_q(m.random_q(400, 21))
    Q = Q[~coal.collides(m.pin_q(Q))]
    Q0, Q1 = Q[:60], Q[60:120]
    res = v.check_edges(Q0, Q1)
    hit = np.flatnonzero(res.code == EdgeStatus.COLLISION)
    assert len(hit) >= 5
    for i in hit:
        sf = res.s_free[i]
        assert 0.0 < sf <= res.s[i] <= 1.0
        s = np.linspace(0.0, sf, 200)[:, None]
        assert not coal.collides(m.pin_q(Q0[i] + s * (Q1[i] - Q0[i]))).any(), i
        first = v.verify(Trajectory(robot, names, [0.0, 1.0], np.stack([Q0[i], Q1[i]]))).first_collision.time
        assert sf <= first + 1e-9, (i, sf, first)


def test_first_contact_is_the_certified_verifiers_first_collision(ur5):
    """``first_contact=True``: a COLLISION's ``s`` is where the two-knot trajectory's certified verification
    first meets contact (both approach it by conservative advancement, to within the contact tolerance);
    ``s_free`` reaches it, and coal finds no contact before it."""
    m, v = ur5
    coal = armguard.checker(m, "coal")
    names = m.scene.robots["ur5"].joint_names
    Q = m.scene_q(m.random_q(400, 21))
    Q = Q[~coal.collides(m.pin_q(Q))]
    Q0, Q1 = Q[:60], Q[60:120]
    plain = v.check_edges(Q0, Q1)
    first = v.check_edges(Q0, Q1, first_contact=True)
    np.testing.assert_array_equal(first.code, plain.code)
    hit = np.flatnonzero(first.code == EdgeStatus.COLLISION)
    assert len(hit) >= 5
    moved = 0
    for i in hit:
        t = v.verify(Trajectory("ur5", names, [0.0, 1.0], np.stack([Q0[i], Q1[i]]))).first_collision.time
        assert first.s[i] <= plain.s[i] and first.s_free[i] <= first.s[i]
        assert abs(first.s[i] - t) < 1e-4, (i, first.s[i], t)
        assert first.s[i] - first.s_free[i] < 1e-4  # the prefix proven clear reaches the contact
        s = np.linspace(0.0, first.s_free[i], 200)[:, None]
        assert not coal.collides(m.pin_q(Q0[i] + s * (Q1[i] - Q0[i]))).any()
        moved += first.s[i] < plain.s[i] - 1e-3
    assert moved >= 1  # the covering's contact was not the first one somewhere


def test_a_shared_end_is_evaluated_once_a_call(ur5):
    """One start against 40 goals: the start's clearances come from its first evaluation (the same bits: the
    same configuration), so the verdicts are those of 40 separate calls with 39 evaluations fewer."""
    m, v = ur5
    Q = m.scene_q(m.random_q(200, 17))
    Q = Q[~armguard.checker(m).collides(m.pin_q(Q))]
    q0, goals = Q[0], Q[1:41]
    together = v.check_edges(q0, goals)
    alone = [v.check_edges(q0, g) for g in goals]
    np.testing.assert_array_equal(together.code, [r.code[0] for r in alone])
    np.testing.assert_array_equal(together.s_free, [r.s_free[0] for r in alone])
    np.testing.assert_array_equal(together.s, [r.s[0] for r in alone])
    assert int(together.evaluations.sum()) == sum(int(r.evaluations[0]) for r in alone) - 39


def test_a_joint_subset_holds_the_others_and_one_side_broadcasts():
    """Panda's 7 arm joints (MoveIt's group ``arm``), its finger held at home; one start to many goals."""
    m = armguard.load_model("panda")
    v = Verifier(m.scene)
    robot = next(iter(m.scene.robots))
    arm = m.group_joints("arm")
    full = m.scene.robots[robot].joint_names
    assert len(arm) == 7 and len(full) == 8
    Q = m.scene_q(m.random_q(6, 8))
    idx = [full.index(j) for j in arm]
    home = m.scene.default_q()[robot]
    res = v.check_edges(Q[0, idx], Q[1:, idx], joints=arm)
    assert res.joint_names == tuple(arm) and len(res) == 5
    (held_name,) = set(full) - set(arm)
    assert res.held == {held_name: float(home[full.index(held_name)])}
    Q0 = np.tile(home, (5, 1))
    Q1 = Q0.copy()
    Q0[:, idx], Q1[:, idx] = Q[0, idx], Q[1:, idx]
    ref = v.check_edges(Q0, Q1)  # the same edges, every joint given
    np.testing.assert_array_equal(res.code, ref.code)
    np.testing.assert_array_equal(res.evaluations, ref.evaluations)
    with pytest.raises(VerificationError, match="is not a joint of robot"):
        v.check_edges(Q[0, idx], Q[1, idx], joints=list(arm[:-1]) + ["nope"])
    with pytest.raises(VerificationError, match="named twice"):
        v.check_edges(Q[0, idx], Q[1, idx], joints=list(arm[:-1]) + [arm[0]])
    by_group = v.check_edges(Q[0, idx], Q[1:, idx], joints="arm")  # an SRDF group's name, as the files take it
    np.testing.assert_array_equal(by_group.code, res.code)
    assert by_group.joint_names == res.joint_names
    with pytest.raises(VerificationError, match="unknown SRDF group .no_such_group."):
        v.check_edges(Q[0, idx], Q[1, idx], joints="no_such_group")
    with pytest.raises(VerificationError, match="a subset of the joints"):
        v.check_edges(Q[0, idx], Q[1, idx])  # 7 values, no joints=: the hint says how
    with pytest.raises(VerificationError, match="an empty list"):
        v.check_edges(Q[0, idx], Q[1, idx], joints=[])


def test_every_joint_named_in_another_order(ur5):
    """``joints=`` naming all the robot's joints, reordered: the columns are read in that order."""
    m, v = ur5
    Q0, Q1 = _edges(m, 60, 4321)
    names = list(m.scene.robots["ur5"].joint_names)
    order = [1, 0, 5, 2, 4, 3]
    res = v.check_edges(Q0[:, order], Q1[:, order], joints=[names[k] for k in order])
    ref = v.check_edges(Q0, Q1)
    assert res.joint_names == tuple(names[k] for k in order) and res.held == {}
    np.testing.assert_array_equal(res.code, ref.code)
    np.testing.assert_array_equal(res.evaluations, ref.evaluations)
    np.testing.assert_array_equal(res.q[~res.clear], ref.q[~ref.clear])  # q: all joints, the robot's order


def test_every_robot_at_once_on_ranger():
    """``robot="*"``: Ranger's two manipulators moving together (the scene's flat joint order); a CLEAR edge has
    no contact in 300 coal samples, a COLLISION is in contact for coal; with one arm moving alone the verdicts are
    ``robot="left_arm"``'s."""
    m = armguard.load_model("ranger")
    v = Verifier(m.scene)
    coal = armguard.checker(m, "coal")
    sc = m.scene
    home = sc.flat_q(sc.default_q())
    names = list(sc.joint_names)
    arms = [k for k, j in enumerate(names) if j.split("/")[0] in ("left_arm", "right_arm")]
    rng = np.random.default_rng(9)
    lo, hi = np.concatenate([r.lower for r in sc.robots.values()]), np.concatenate([r.upper for r in sc.robots.values()])
    Q0, Q1 = np.tile(home, (80, 1)), np.tile(home, (80, 1))
    for Q in (Q0, Q1):
        Q[:, arms] = np.clip(home[arms] + rng.uniform(-2.0, 2.0, (80, len(arms))), lo[arms], hi[arms])
    res = v.check_edges(Q0, Q1, robot="*")
    assert res.robot == "*" and res.joint_names == tuple(names)
    s = np.linspace(0.0, 1.0, 301)[:, None]
    for i in range(80):
        hits = coal.collides(m.pin_q(Q0[i] + s * (Q1[i] - Q0[i])))
        if res.clear[i]:
            assert not hits.any(), i
        else:
            assert res.code[i] == EdgeStatus.COLLISION
            assert float(np.min(coal.pair_distances(m.pin_q(res.q[i])).distance)) <= CONTACT + 1e-6
    assert 0 < int(res.clear.sum()) < 80
    left = [k for k, j in enumerate(names) if j.startswith("left_arm/")]
    L0, L1 = np.tile(home, (30, 1)), np.tile(home, (30, 1))
    L0[:, left], L1[:, left] = Q0[:30, left], Q1[:30, left]
    alone = v.check_edges(L0[:, left], L1[:, left], robot="left_arm")
    together = v.check_edges(L0, L1, robot="*")
    np.testing.assert_array_equal(alone.code, together.code)
    with pytest.raises(VerificationError, match=r"got \(1, 7\); one robot's joints\? pass robot='left_arm'"):
        v.check_edges(np.zeros(7), np.zeros(7), robot="*")


def test_continuous_joints_the_short_way_on_request():
    """kinova's continuous joint 1 from 3.0 to -3.0 rad: along the angle's line by default (6 rad through 0),
    the short way (0.28 rad through pi) with ``continuous="shortest"``: the edge to 3.0 + (2 pi - 6)."""
    m = armguard.load_model("kinova")
    v = Verifier(m.scene)
    home = m.scene.default_q()[next(iter(m.scene.robots))]
    q0, q1 = home.copy(), home.copy()
    q0[0], q1[0] = 3.0, -3.0
    short = v.check_edges(q0, q1, continuous="shortest")
    q1s = q1.copy()
    q1s[0] = 3.0 + (2.0 * np.pi - 6.0)
    same = v.check_edges(q0, q1s)
    long = v.check_edges(q0, q1)
    assert short.code[0] == same.code[0] and short.evaluations[0] == same.evaluations[0]
    assert long.evaluations[0] > short.evaluations[0]
    with pytest.raises(VerificationError, match="continuous: expected 'line'"):
        v.check_edges(q0, q1, continuous="wrap")


def test_the_short_way_from_a_huge_continuous_angle_is_the_angle_pinocchio_places():
    """kinova, joint 4 (continuous) to 1e17 rad: the difference of the raw values rounded to whole turns,
    the edge came out still (CLEAR after one evaluation) where the goal Pinocchio places (-2.658 rad) collides."""
    m = armguard.load_model("kinova")
    v = Verifier(m.scene)
    q0 = np.array([-2.0280442, 2.62193397, 0.68508276, 1.41925132, 0.98315036, -0.65915824])
    q1 = q0.copy()
    q1[3] = 1e17
    q1p = q0.copy()
    q1p[3] = math.atan2(math.sin(1e17), math.cos(1e17))  # where Pinocchio's (cos, sin) puts it
    huge = v.check_edges(q0, q1, continuous="shortest")
    placed = v.check_edges(q0, q1p, continuous="shortest")
    assert placed.code[0] == EdgeStatus.COLLISION
    assert huge.code[0] == placed.code[0] and huge.s[0] == pytest.approx(placed.s[0], abs=1e-9)
    np.testing.assert_allclose(huge.q[0], placed.q[0], atol=1e-9)


def test_results_are_read_only_and_masks_select_pairs(ur5):
    m, v = ur5
    Q0, Q1 = _edges(m, 30, 40)
    res = v.check_edges(Q0, Q1, margin=0.01)
    hit = res.code != EdgeStatus.CLEAR
    assert hit.any() and all(isinstance(p, tuple) for p in res.pair[hit]) and all(p is None for p in res.pair[~hit])
    with pytest.raises(ValueError):
        res.code[0] = 0
    assert "within the margin (10 mm)" in res.summary()
    inc = v.check_edges(Q0, Q1, max_evaluations=2)
    k = np.flatnonzero(inc.code == EdgeStatus.INCOMPLETE)
    assert len(k) and all(inc.pair[i] is not None and np.isfinite(inc.distance[i]) for i in k)  # where it stood
    assert np.all((inc.s_free[k] >= 0.0) & (inc.s_free[k] < 1.0))


def test_threads_share_one_verifier(ur5):
    m, v = ur5
    Q0, Q1 = _edges(m, 40, 1200)
    ref = v.check_edges(Q0, Q1)
    out = [None] * 4

    def work(k):
        out[k] = v.check_edges(Q0, Q1)

    ts = [threading.Thread(target=work, args=(k,)) for k in range(4)]
    for t in ts:
        t.start()
    for t in ts:
        t.join()
    for r in out:
        np.testing.assert_array_equal(r.code, ref.code)
        np.testing.assert_array_equal(r.s, ref.s)
        np.testing.assert_array_equal(r.evaluations, ref.evaluations)


def test_bad_inputs_are_named(ur5):
    m, v = ur5
    q = m.scene_q(m.random_q(1, 0))[0]
    with pytest.raises(VerificationError, match=r"Q0: expected shape \(M, 6\) or \(6,\), one value per joint \['shoulder_pan_joint'"):
        v.check_edges(q[:5], q)
    with pytest.raises(VerificationError, match="same number of edges"):
        v.check_edges(np.stack([q, q]), np.stack([q, q, q]))
    with pytest.raises(VerificationError, match=r"got \(1, 7\); a Pinocchio configuration converts with model.scene_q"):
        v.check_edges(np.r_[q, 0.0], q)
    for bad_input in (None, "abc", [["a"] * 6]):
        with pytest.raises(VerificationError, match="Q0: expected"):
            v.check_edges(bad_input, q)
    assert v.check_edges(q, q, margin=np.array(0.001)).margin == 0.001  # a 0-d array is a number
    bad = q.copy()
    bad[1] = 99.0
    with pytest.raises(VerificationError, match=r"Q1\[1\]: .*shoulder_lift_joint"):
        v.check_edges(np.stack([q, q]), np.stack([q, bad]))
    nan = q.copy()
    nan[2] = np.nan
    with pytest.raises(VerificationError, match=r"Q0\[2\]: NaN or infinite \(1 such values\)"):
        v.check_edges(nan, q)
    for margin in (-0.01, float("nan"), "1 cm", True):
        with pytest.raises(VerificationError, match="margin"):
            v.check_edges(q, q, margin=margin)
    for budget in (1, 2.5, True):
        with pytest.raises(VerificationError, match="max_evaluations"):
            v.check_edges(q, q, max_evaluations=budget)
    with pytest.raises(VerificationError, match="robot 'arm' is not in the scene"):
        v.check_edges(q, q, robot="arm")
    ranger = Verifier(armguard.load_model("ranger").scene)
    with pytest.raises(VerificationError, match=r"this scene has several robots .*: pass robot= .* '\*' for all"):
        ranger.check_edges(np.zeros(7), np.zeros(7))


def _poison_evaluations(monkeypatch) -> None:
    """Every evaluation of the verifier's record gives its first moving pair a NaN clearance."""
    from armguard.verify import _record

    real = _record._Run.eval

    def poisoned(self, si, s, q, t=None):
        row = real(self, si, s, q, t)
        self.D[row, np.flatnonzero(self.moving)[0]] = np.nan
        return row

    monkeypatch.setattr(_record._Run, "eval", poisoned)


def test_a_nan_clearance_is_an_error_not_a_verdict(ur5, monkeypatch):
    m, v = ur5
    Q0, Q1 = _edges(m, 1, 4)
    _poison_evaluations(monkeypatch)
    with pytest.raises(VerificationError, match="NaN at s = 0.0"):
        v.check_edges(Q0, Q1)


def test_a_nan_clearance_gives_no_sampled_verdict_and_stops_the_guard(ur5, monkeypatch):
    """A shape pair's NaN makes its pair of parts NaN (``owner_rows``: never hidden by a finite sibling);
    sampled verification then raises (it had said SAFE: ``nan <= 0`` is False) and the Guard stops (it had
    said OK, "predicted path clear")."""
    from armguard.verify import Guard, GuardVerdict
    from armguard.verify import _oracle

    m, v = ur5
    robot = next(iter(m.scene.robots))
    names = m.scene.robots[robot].joint_names
    Q0, Q1 = _edges(m, 1, 4)
    traj = Trajectory(robot, names, [0.0, 1.0], np.stack([Q0[0], Q1[0]]))
    _poison_evaluations(monkeypatch)
    with pytest.raises(VerificationError, match="NaN: no verdict"):
        v.verify(traj, method="sampled")
    monkeypatch.undo()
    real_d = _oracle.ClearanceModel._distances

    def nan_distances(self, q, robot=None):
        d, a, b = real_d(self, q, robot)
        d = d.copy()
        d[0] = np.nan
        return d, a, b

    g = Guard(m.scene)
    monkeypatch.setattr(_oracle.ClearanceModel, "_distances", nan_distances)
    dec = g.step(Q0[0], Q0[0] + 0.01)
    assert dec.verdict is GuardVerdict.STOP and "NaN" in dec.reason, dec


def test_a_group_name_is_of_the_robot_the_edges_move():
    """Ranger's arms all call their joints j1 ...: another arm's SRDF group is refused, never read as this
    arm's joints."""
    m = armguard.load_model("ranger")
    v = Verifier(m)
    q = m.scene.home("left_arm")
    assert v.check_edges(q, q, robot="left_arm", joints="left_arm").counts()["clear"] == 1
    with pytest.raises(VerificationError, match="moves robot 'right_arm', not 'left_arm'"):
        v.check_edges(q, q, robot="left_arm", joints="right_arm")


def test_the_short_way_keeps_the_users_start():
    """kinova joint 4 from 7.70 to 3.625 rad the short way: the hit's q lies on the user's segment (from 7.70), not at
    the reduced start's angle; a start beyond 1e6 rad is taken at its angle (a short turn added to it rounds away)."""
    m = armguard.load_model("kinova")
    rob = m.scene.robots[next(iter(m.scene.robots))]
    from armguard.verify._edges import _shortest

    q0 = np.zeros((1, len(rob.joint_names)))
    q1 = q0.copy()
    q0[0, 3], q1[0, 3] = 7.70, 3.625
    s0, s1 = _shortest(rob, q0, q1)
    assert s0[0, 3] == 7.70 and abs(s1[0, 3] - s0[0, 3]) <= math.pi
    assert math.isclose(math.remainder(s1[0, 3] - 3.625, 2 * math.pi), 0.0, abs_tol=1e-12)
    q0[0, 3] = 1e17
    s0, s1 = _shortest(rob, q0, q1)
    assert abs(s0[0, 3]) <= math.pi and abs(s1[0, 3] - s0[0, 3]) <= math.pi
