"""The on-line Guard with collision avoidance (``Guard(..., avoidance=Damper(...))``).

Closed loop on Ranger's left arm, the other arms at home: the command drives the arm straight at a
configuration in contact.  Without avoidance the Guard stops the arm; with it the arm keeps moving
(the command unchanged while free, filtered near the scene), every left-arm pair stays at least
the stand-off less 1 mm away, and the arm gets at least as far as where the plain Guard stopped.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

import armguard
from armguard import VerificationError
from armguard.avoidance import AvoidanceStatus, Damper
from armguard.verify import Guard, GuardVerdict

ROBOT = "left_arm"
DAMPER = Damper(stand_off=0.03, influence=0.15, approach_speed=0.3, period=0.01, velocity_limit=1.0)
PERIOD = 0.01


@pytest.fixture(scope="module")
def ranger():
    m = armguard.load_model("ranger")
    s = m.scene
    c = armguard.checker(m, "analytic")
    P = m.pairs
    left = np.array([a.startswith(ROBOT + "/") or b.startswith(ROBOT + "/") for a, b in zip(P.owner_a, P.owner_b)])
    names = s.joint_names
    k = np.array([n.startswith(ROBOT + "/") for n in names])
    q0 = s.flat_q(s.default_q())
    lo, hi = np.asarray(s.robots[ROBOT].lower), np.asarray(s.robots[ROBOT].upper)

    def left_min(q_robot):
        full = q0.copy()
        full[k] = q_robot
        return float(c.pair_distances(m.pin_q(full)).distance[left].min())

    # a target in contact, the first of a seeded search (the command drives straight at it)
    rng = np.random.default_rng(0)
    while True:
        qt = lo + (hi - lo) * rng.random(int(k.sum()))
        if left_min(qt) <= 0.0:
            break
    v = qt - q0[k]
    v /= np.abs(v).max()  # 1 rad/s on the fastest joint
    return m, s, q0[k], lo, hi, v, left_min


def test_plain_guard_stops_but_avoidance_keeps_stand_off_and_moves(ranger):
    m, s, q_start, lo, hi, v, left_min = ranger
    plain = Guard(s, stopping_distance=0.01, horizon_s=0.2, period_s=PERIOD, robot=ROBOT)
    q, stop_at = q_start.copy(), None
    for i in range(300):
        d = plain.step(q, qdot=v)
        assert d.velocity is None and d.motion is None  # no avoidance fields without avoidance
        if not d.ok:
            stop_at = i
            break
        q = np.clip(q + v * PERIOD, lo, hi)
    assert stop_at is not None  # the command does drive into the scene
    plain_reach = float(np.abs(q - q_start).max())

    guard = Guard(s, stopping_distance=0.01, horizon_s=0.2, period_s=PERIOD, robot=ROBOT, avoidance=DAMPER)
    q, seen, d_least = q_start.copy(), [], left_min(q_start)
    for _ in range(300):
        d = guard.step(q, qdot=v)
        seen.append(d.motion)
        assert d.velocity.shape == v.shape and np.all(np.abs(d.velocity) <= 1.0 + 1e-9)
        if d.motion == "free":
            np.testing.assert_allclose(d.velocity, v, atol=1e-12)  # free: the command passes unchanged
        if d.motion == "stopped":
            assert d.verdict is GuardVerdict.STOP and not np.any(d.velocity)
        q = np.clip(q + d.velocity * PERIOD, lo, hi)
        d_least = min(d_least, left_min(q))
    assert d_least >= DAMPER.stand_off - 1e-3, d_least
    assert seen.count("free") > 0 and seen.count("slowed") > 0
    assert float(np.abs(q - q_start).max()) >= plain_reach  # got at least as far as the plain Guard


def test_avoidance_decision_reports_the_filter(ranger):
    m, s, q_start, lo, hi, v, _ = ranger
    per_joint = Damper(stand_off=0.03, influence=0.15, approach_speed=0.3, period=0.01,
                       velocity_limit=tuple([0.5] * len(v)))
    g = Guard(s, stopping_distance=0.01, period_s=PERIOD, robot=ROBOT, avoidance=per_joint)
    d = g.step(q_start, qdot=v)
    assert d.avoidance is not None and d.avoidance.velocity.shape == (m.pin_model.nv,)
    assert d.motion == d.avoidance.status.value == "slowed"  # clipped to 0.5 rad/s
    assert np.all(np.abs(d.velocity) <= 0.5 + 1e-12)
    other = np.setdiff1d(np.arange(m.pin_model.nv), g._st.v_index)
    assert not np.any(d.avoidance.velocity[other])  # only the guarded robot moves
    same = g.step(q_start, q_cmd_next=np.clip(q_start + v * PERIOD, lo, hi))
    assert same.avoidance.status in (AvoidanceStatus.FREE, AvoidanceStatus.SLOWED)


def test_avoidance_needs_a_velocity_and_a_damper(ranger):
    m, s, q_start, lo, hi, v, _ = ranger
    g = Guard(s, robot=ROBOT, avoidance=DAMPER)
    with pytest.raises(VerificationError, match="a target is not filtered"):
        g.step(q_start, target=q_start)
    with pytest.raises(VerificationError, match="one of q_cmd_next or qdot, not both"):  # it said "(no target)"
        g.step(q_start, q_cmd_next=q_start, qdot=np.zeros_like(q_start))
    with pytest.raises(VerificationError, match="got neither"):
        g.step(q_start)
    with pytest.raises(VerificationError, match="Damper"):
        Guard(s, robot=ROBOT, avoidance=0.03)
    with pytest.raises(VerificationError, match="velocity_limit"):
        Guard(s, robot=ROBOT, avoidance=Damper(stand_off=0.03, influence=0.15, approach_speed=0.3, period=0.01,
                                                velocity_limit=(1.0, 1.0)))


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(seed=st.integers(0, 2**31 - 1), speed=st.floats(0.05, 3.0))
@example(seed=39872002, speed=1.0)  # DAQP left 1.9e-34 rad/s on a column whose limit is 0 (another robot's)
def test_filtered_velocity_keeps_every_damper_and_moves_only_the_robot(ranger, seed, speed):
    """Any command at any in-limit configuration: the Guard's velocity is within the limits, leaves
    the other robots' columns at zero and holds every constrained pair's damper (d' >= bound)."""
    m, s, q_start, lo, hi, v, _ = ranger
    rng = np.random.default_rng(seed)
    q = lo + (hi - lo) * rng.random(len(lo))
    cmd = speed * rng.normal(size=len(lo))
    g = _GUARDS.setdefault("g", Guard(s, stopping_distance=0.0, period_s=PERIOD, robot=ROBOT, avoidance=DAMPER))
    d = g.step(q, qdot=cmd)
    av = d.avoidance
    assert np.all(np.abs(av.velocity) <= 1.0 + 1e-9)
    other = np.setdiff1d(np.arange(m.pin_model.nv), g._st.v_index)
    assert not np.any(av.velocity[other])
    assert np.all(av.closing >= av.rate - 1e-9)
    if d.ok:
        np.testing.assert_array_equal(d.velocity, av.velocity[g._st.v_index])
    else:
        assert not np.any(d.velocity)


_GUARDS: dict = {}


def test_single_joint_mode_with_avoidance_slows_that_joint_and_moves_no_other():
    """The filter deflected a one-joint jog into a slide of several joints, and single-joint mode then stopped it
    (naming every joint, DAQP's round-off moving the others by 1e-17)."""
    from collections import Counter

    from armguard.verify import GuardMode

    m = armguard.load_model("ranger")
    s = m.scene
    dmp = Damper(stand_off=0.03, influence=0.15, approach_speed=0.3, period=0.01, velocity_limit=1.0)
    g = Guard(s, stopping_distance=0.01, horizon_s=0.2, period_s=0.01, robot="left_arm", avoidance=dmp,
              mode=GuardMode.SINGLE_JOINT)
    q = s.flat_q(s.default_q())[:7]
    lo, hi = s.robots["left_arm"].lower, s.robots["left_arm"].upper
    v = np.array([0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    seen = Counter()
    for _ in range(200):
        d = g.step(q, qdot=v)
        seen[d.motion] += 1
        assert "single-joint mode" not in d.reason, d.reason
        assert np.all(d.velocity[[0, 2, 3, 4, 5, 6]] == 0.0)
        if d.ok:
            assert d.clearance >= dmp.stand_off - 1e-3
        q = np.clip(q + d.velocity * 0.01, lo, hi)
    assert seen["slowed"] > 0


def test_a_stop_at_a_joint_limit_says_the_limits_stopped_it():
    """It said "avoidance stopped the arm (none: 1 pair within influence, moved by no joint)"."""
    m = armguard.load_model("ranger")
    s = m.scene
    dmp = Damper(stand_off=0.03, influence=0.15, approach_speed=0.3, period=0.01, velocity_limit=1.0)
    g = Guard(s, stopping_distance=0.01, period_s=0.01, robot="left_arm", avoidance=dmp)
    q = s.flat_q(s.default_q())[:7].copy()
    q[0] = s.robots["left_arm"].upper[0]
    v = np.zeros(7)
    v[0] = 1.0
    d = g.step(q, qdot=v)
    assert d.verdict is GuardVerdict.STOP and "joint or velocity limits: the command clipped to 0" in d.reason


def test_a_solver_failure_is_a_stop_marked_unfinished(monkeypatch):
    """DAQP reporting no optimum stopped the arm like a true zero optimum, the decision marked finished."""
    import daqp

    m = armguard.load_model("ranger")
    s = m.scene
    dmp = Damper(stand_off=0.03, influence=0.15, approach_speed=0.3, period=0.01, velocity_limit=1.0)
    g = Guard(s, stopping_distance=0.01, horizon_s=0.2, period_s=0.01, robot="left_arm", avoidance=dmp)
    q = s.flat_q(s.default_q())[:7]
    lo, hi = s.robots["left_arm"].lower, s.robots["left_arm"].upper
    v = np.array([0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    for _ in range(200):  # to where a damper binds (the QP is solved)
        d = g.step(q, qdot=v)
        if d.avoidance.solver == "daqp: optimal":
            break
        q = np.clip(q + d.velocity * 0.01, lo, hi)
    assert d.avoidance.solver == "daqp: optimal" and not d.avoidance.solver_failed
    real = daqp.solve
    monkeypatch.setattr(daqp, "solve", lambda *a: (real(*a)[0], 0.0, -1, {}))  # exit flag -1: infeasible
    d = g.step(q, qdot=v)
    assert d.avoidance.status is AvoidanceStatus.STOPPED and d.avoidance.solver_failed
    assert d.verdict is GuardVerdict.STOP and not d.finished and "exit flag -1" in d.reason
