"""Out-of-limit configurations: every detector and guard entry point refuses them (JointLimitError).

The obstacle lists and the lever-arm bounds hold only within the joint limits; a configuration
beyond them once came back CLEAR while the link was inside a wall.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import armguard
from armguard.detect import JointLimitError
from armguard.geometry import Box, Sphere, distance
from armguard.kinematics import JointSpec, JointType, Robot
from armguard.scene import Scene
from armguard.verify import Guard


def _trans(x=0.0, y=0.0, z=0.0):
    X = np.eye(4)
    X[:3, 3] = (x, y, z)
    return X


def _slider_scene():
    """A sphere (r 0.05) on a prismatic joint along x, limits [0, 0.1]; a wall from x = 0.8 to 1.2."""
    rob = Robot("slider", "base", [JointSpec("x", JointType.PRISMATIC, "base", "carriage", _trans(), np.array([1.0, 0, 0]),
                                             lower=0.0, upper=0.1)],
                link_shapes={"carriage": (Sphere([0.0, 0.0, 0.0], 0.05),)})
    sc = Scene("slider")
    sc.add_robot(rob, self_pairs=[])
    sc.add_body("wall", [Box([1.0, 0.0, 0.0], [0.2, 0.5, 0.5])])
    return sc


def _arm_scene():
    """A revolute joint about z then a prismatic joint along the link (limits [0, 0.3]); a wall from y = 4.5 to 5.5."""
    rob = Robot("arm", "base", [
        JointSpec("turn", JointType.REVOLUTE, "base", "l1", _trans(), np.array([0.0, 0, 1]), lower=-math.pi, upper=math.pi),
        JointSpec("reach", JointType.PRISMATIC, "l1", "l2", _trans(0.2), np.array([1.0, 0, 0]), lower=0.0, upper=0.3),
    ], link_shapes={"l2": (Sphere([0.0, 0.0, 0.0], 0.05),)})
    sc = Scene("arm")
    sc.add_robot(rob, self_pairs=[])
    sc.add_body("wall", [Box([0.0, 5.0, 0.0], [2.0, 0.5, 0.5])])
    return sc


def _true_clearance(sc, q):
    return min(distance(it.shape, sc.bodies["wall"].shapes[0]).distance
               for it in sc.shapes_at(np.asarray(q, float)) if it.kind == "link")


def test_the_out_of_limit_configuration_is_really_in_the_wall():
    """The premise: at x = 0.95 (limits [0, 0.1]) the sphere is inside the wall."""
    assert _true_clearance(_slider_scene(), [0.95]) < -0.09


@pytest.mark.parametrize("call", ["check", "lazy", "budget", "budget0", "pair_distances", "check_many", "collides_many",
                                  "check_many_bruteforce"])
@pytest.mark.parametrize("margin", [0.1, math.inf], ids=["margin0.1", "margin_inf"])
def test_every_detector_entry_point_refuses_a_joint_outside_its_limits(call, margin):
    sc = _slider_scene()
    det = armguard.Detector(sc, threshold=0.05, reach_margin=margin)
    q = np.array([0.95])
    calls = {
        "check": lambda: det.check(q),
        "lazy": lambda: det.check(q, lazy=True),
        "budget": lambda: det.check(q, budget_us=1e6),
        "budget0": lambda: det.check(q, budget_us=0.0),
        "pair_distances": lambda: det.pair_distances(q),
        "check_many": lambda: det.check_many(np.array([[0.05], [0.95]])),
        "collides_many": lambda: det.collides_many(np.array([[0.05], [0.95]])),
        "check_many_bruteforce": lambda: det.check_many_bruteforce(np.array([[0.05], [0.95]])),
    }
    with pytest.raises(JointLimitError) as info:
        calls[call]()
    e = info.value
    assert e.joint == "slider/x" and e.value == 0.95 and (e.lower, e.upper) == (0.0, 0.1)
    msg = str(e)
    assert "'slider/x'" in msg and "0.95" in msg and "[0, 0.1]" in msg and "joint_limit" in msg
    if call in ("check_many", "collides_many", "check_many_bruteforce"):
        assert "row 1" in msg
    assert isinstance(e, armguard.ArmguardError) and isinstance(e, armguard.KinematicsError)


def test_within_limits_and_the_allowance_still_answer():
    sc = _slider_scene()
    det = armguard.Detector(sc, threshold=0.05)
    tol = armguard.DEFAULT_TOLERANCES.joint_limit
    for x in (0.0, 0.1, 0.1 + 0.5 * tol, -0.5 * tol):
        assert det.check(np.array([x])).status.value == "clear"
    assert not det.collides_many(np.array([[0.0], [0.1 + 0.5 * tol]])).any()
    with pytest.raises(JointLimitError):
        det.check(np.array([0.1 + 2 * tol]))
    with pytest.raises(JointLimitError):
        det.check(np.array([-2 * tol]))
    # a mapping goes through the same rule
    with pytest.raises(JointLimitError):
        det.check({"slider": np.array([0.95])})


def test_the_budget_sequence_of_the_report_is_refused_not_proven_clear():
    """check([0, 5], budget) then check([pi/2, 5], budget 0) once gave CLEAR with a 'proven' bound of 6 m
    while the sphere was 0.25 m inside the wall: the first call is refused, the second is honest."""
    sc = _arm_scene()
    det = armguard.Detector(sc, threshold=0.05)
    with pytest.raises(JointLimitError) as info:
        det.check(np.array([0.0, 5.0]), budget_us=1e6)
    assert info.value.joint == "arm/reach"
    assert _true_clearance(sc, [math.pi / 2, 5.0]) < 0.0
    with pytest.raises(JointLimitError):
        det.check(np.array([math.pi / 2, 5.0]), budget_us=0.0)
    # within the limits the anytime mode is never more optimistic than the exact one
    q = np.array([math.pi / 2, 0.3])
    exact = det.check(q).status.value
    assert det.check(q, budget_us=0.0).status.value in ("incomplete", exact)


def test_a_refused_row_leaves_the_detector_usable():
    sc = _slider_scene()
    det = armguard.Detector(sc, threshold=0.05)
    r0 = det.check(np.array([0.05]))
    with pytest.raises(JointLimitError):
        det.check(np.array([0.95]))
    r1 = det.check(np.array([0.05]))
    assert r1.status == r0.status and r1.nearest.distance == pytest.approx(r0.nearest.distance, abs=1e-12)


def test_the_guard_refuses_an_out_of_limit_configuration_or_command():
    sc = _arm_scene()
    guard = Guard(sc, stopping_distance=0.01, horizon_s=0.5, period_s=0.01)
    with pytest.raises(JointLimitError) as info:
        guard.step([0.0, 5.0], target=[math.pi, 5.0])  # once OK on a path through the wall
    assert info.value.joint == "arm/reach" and "Guard.step: q" in str(info.value)
    with pytest.raises(JointLimitError) as info:
        guard.step([0.0, 0.1], target=[0.0, 5.0])
    assert "Guard.step: target" in str(info.value)
    with pytest.raises(JointLimitError) as info:
        guard.step([0.0, 0.1], [0.0, 0.4])
    assert "Guard.step: q_cmd_next" in str(info.value)


def test_the_guard_predicts_a_motion_that_stops_at_the_limits():
    """A jog toward the limit whose extrapolation leaves the limits: the prediction saturates at the
    limit (the arm cannot go past it) and is still certified; a wall just beyond the limit is not hit."""
    sc = _arm_scene()
    guard = Guard(sc, stopping_distance=0.01, horizon_s=0.5, period_s=0.01)
    # at turn = pi/2 the slider points along +y: the link centre at 0.2 + 0.3 = 0.5 at the limit
    dec = guard.step([math.pi / 2, 0.25], qdot=[0.0, 10.0])
    assert _true_clearance(sc, [math.pi / 2, 0.25 + 10.0 * 0.5]) < 0.0  # the unsaturated extrapolation
    assert dec.ok, dec.reason
    assert 0.0 < dec.predicted_clearance <= _true_clearance(sc, [math.pi / 2, 0.3]) + 1e-9
