"""A pair no joint of the moving robot moves (a base link on its table) fails every margin at once:
the verification report and the Guard say so, and how to disable the pair, instead of leaving the
user to find why every trajectory of the robot is UNSAFE."""

from __future__ import annotations

import numpy as np
import pytest

import armguard
from armguard.geometry import Box
from armguard.kinematics import Trajectory
from armguard.verify import Guard, GuardVerdict


@pytest.fixture(scope="module")
def floored():
    """puma560 with a floor plate 1 mm under its base link (the base box spans z 0.002 .. 0.522 m)."""
    m = armguard.load_model("puma560")
    return m.with_body("floor", [Box(np.array([0.0, 0.0, -0.001]), np.array([0.15, 0.15, 0.002]))])


def _move(model):
    r = model.scene.robots["puma560"]
    q0 = model.scene.home("puma560")
    return q0, Trajectory.joint_interpolated(r, np.array([q0, q0 + 0.1]))


def test_a_fixed_pair_within_the_stopping_distance_is_named_fixed_with_the_way_out(floored):
    _, tr = _move(floored)
    rep = armguard.verify(floored, tr, stopping_distance=0.005)
    c = rep.first_collision
    assert rep.status.value == "collision" and c is not None and c.time == 0.0
    assert {c.a, c.b} == {"puma560/base", "floor"} and c.fixed
    assert "no joint moves puma560/base or floor" in rep.summary()
    assert "with_pair_disabled('puma560/base', 'floor')" in rep.summary()
    clear = armguard.verify(floored.with_pair_disabled("puma560/base", "floor"), tr, stopping_distance=0.005)
    assert clear.first_collision is None or {clear.first_collision.a, clear.first_collision.b} != {"puma560/base", "floor"}


def test_a_moving_pair_within_the_stopping_distance_has_no_such_hint(floored):
    m = armguard.load_model("puma560")  # no floor: the table is 0.237 m from link1 at home
    _, tr = _move(m)
    rep = armguard.verify(m, tr, stopping_distance=0.245)
    c = rep.first_collision
    assert c is not None and not c.fixed  # link2 against the base: link2 moves
    assert "moves either" not in rep.summary() and "no joint moves" not in rep.summary()


def test_the_guard_says_no_motion_clears_a_fixed_pair(floored):
    q0, _ = _move(floored)
    dec = Guard(floored, stopping_distance=0.005).step(q0, qdot=np.full(6, 0.1))
    assert dec.verdict is GuardVerdict.STOP and set(dec.pair) == {"puma560/base", "floor"}
    assert "no joint moves either side" in dec.reason
    m = armguard.load_model("puma560")
    dec = Guard(m, stopping_distance=0.245).step(q0, qdot=np.full(6, 0.1))
    assert dec.verdict is GuardVerdict.STOP and "moves either side" not in dec.reason


def _two_arms(tmp_path):
    """Two one-joint arms 3 m apart; B's forearm (at home) touches a post; A's base box sits at the origin."""
    import math

    import yaml

    from armguard.scene import load_scene

    def arm(name, x, home):
        return {"name": name, "mount": {"xyz": [x, 0, 0]}, "convention": "standard",
                "joints": [{"name": "j1", "a": 0.4, "alpha": 0, "d": 0.1, "limits": [-4, 4], "max_velocity": 1,
                            "max_acceleration": 2}],
                "links": ["link0", "link1"],
                "link_shapes": {"link0": [{"type": "box", "size": [0.2, 0.2, 0.2], "xyz": [0, 0, 0.1]}],
                                "link1": [{"type": "capsule", "radius": 0.03, "p0": [-0.4, 0, 0], "p1": [0, 0, 0]}]},
                "home": [home]}
    f = tmp_path / "two.yaml"
    f.write_text(yaml.safe_dump({"armguard_scene": 1, "name": "two",
                                 "bodies": [{"name": "post", "shapes": [{"type": "box", "size": [0.1, 0.1, 0.4],
                                                                         "xyz": [3.0, 0.3, 0.1]}]}],
                                 "robots": [arm("A", 0.0, 0.0), arm("B", 3.0, math.pi / 2)]}))
    return load_scene(f)


def test_the_guard_of_one_robot_answers_for_its_own_pairs_only(tmp_path):
    """B's forearm touching a post is no reason to stop A (a verification of A does not check it
    either); before, A's Guard stopped on it and advised disabling B's pair with the post."""
    s = _two_arms(tmp_path)
    assert Guard(s, robot="B").step(s.home("B"), qdot=np.array([0.1])).verdict is GuardVerdict.STOP
    dec = Guard(s, robot="A").step(s.home("A"), qdot=np.array([0.1]))
    assert dec.verdict is GuardVerdict.OK, dec.reason
    traj = Trajectory.joint_interpolated(s.robots["A"], np.array([[0.0], [0.3]]))
    assert armguard.verify(s, traj).status.value == "safe"


def test_a_pair_another_robots_joint_moves_is_not_called_fixed(tmp_path):
    """B's long forearm (at home) reaches over A's base box: verifying A, that pair fails, and A's
    joints move neither side, but B's do: no "disable the pair" advice (it would hide B's own
    collisions with A's base)."""
    import math

    import yaml

    from armguard.scene import load_scene

    def arm(name, x, a, dz, r, home):
        return {"name": name, "mount": {"xyz": [x, 0, 0]}, "convention": "standard",
                "joints": [{"name": "j1", "a": a, "alpha": 0, "d": dz, "limits": [-4, 4], "max_velocity": 1,
                            "max_acceleration": 2}],
                "links": ["link0", "link1"],
                "link_shapes": {"link0": [{"type": "box", "size": [0.2, 0.2, 0.2], "xyz": [0, 0, 0.1]}],
                                "link1": [{"type": "capsule", "radius": r, "p0": [-a, 0, 0], "p1": [0, 0, 0]}]},
                "home": [home]}
    f = tmp_path / "over.yaml"
    f.write_text(yaml.safe_dump({"armguard_scene": 1, "name": "over", "robots": [
        arm("A", 0.0, 0.4, 0.1, 0.03, math.pi / 2), arm("B", 1.0, 0.95, 0.18, 0.015, math.pi)]}))
    s = load_scene(f)
    rep = armguard.verify(s, Trajectory.joint_interpolated(s.robots["A"], np.array([[math.pi / 2], [2.0]])))
    c = rep.first_collision
    assert c is not None and {c.a, c.b} == {"A/link0", "B/link1"} and not c.fixed
    assert "no joint moves" not in rep.summary()
    dec = Guard(s, robot="A").step(s.home("A"), qdot=np.array([0.5]))
    assert dec.verdict is GuardVerdict.STOP and "no joint moves" not in dec.reason


def test_a_base_outside_the_workspace_is_told_to_enlarge_the_box_not_to_disable_a_pair():
    m = armguard.load_model("puma560").with_workspace([-2, -2, 0.01], [2, 2, 2])  # the base's bottom is at z 0.002
    q0, tr = _move(m)
    rep = armguard.verify(m, tr)
    c = rep.first_collision
    assert c is not None and c.check == "link-workspace" and c.fixed
    assert "enlarge the workspace box" in rep.summary() and "with_pair_disabled" not in rep.summary()
    dec = Guard(m).step(q0, qdot=np.full(6, 0.1))
    assert dec.verdict is GuardVerdict.STOP and "enlarge the workspace box" in dec.reason


def test_a_guard_of_a_robot_without_a_pair_of_its_own_refuses_as_verify_does(tmp_path):
    """Every pair of A disabled, B's still checked: the Guard gave OK with an infinite clearance."""
    s = _two_arms(tmp_path)
    s.disable_pair("A", "B")
    s.disable_pair("A", "post")
    with pytest.raises(armguard.VerificationError, match="robot 'A' has no pair to check"):
        Guard(s, robot="A").step(s.home("A"), qdot=np.array([0.1]))
    with pytest.raises(armguard.VerificationError, match="robot 'A' has no pair to check"):
        armguard.verify(s, Trajectory.joint_interpolated(s.robots["A"], np.array([[0.0], [0.3]])))
