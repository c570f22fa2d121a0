"""Trajectories over a subset of a robot's joints: the others are held at the model's home."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

import armguard
from armguard import SceneError, TrajectoryError, VerificationError
from armguard.cli import main
from armguard.kinematics import Trajectory
from armguard.verify import Subdivided, VerificationStatus

from test_backends import ROBOTS
from test_srdf import package, srdf_text

HOME = ('<group_state name="home" group="arm"><joint name="j2" value="0.4"/><joint name="j3" value="-0.8"/></group_state>'
        '<group name="upper"><joint name="j2"/><joint name="j1"/><joint name="fix"/></group>'
        '<group name="both"><group name="upper"/><joint name="j3"/></group>')


@pytest.fixture()
def arm(tmp_path):
    urdf = package(tmp_path)
    urdf.with_suffix(".srdf").write_text(srdf_text(HOME))
    return armguard.load_model(urdf)


def test_over_joints_holds_the_others_and_keeps_the_motion():
    t = Trajectory("arm", ["j3", "j1"], [0.0, 1.0, 2.5], [[0.1, 0.2], [0.3, -0.4], [0.5, 0.6]], blend_times=[0.2, 0.5])
    full, held = t.over_joints(["j1", "j2", "j3"], [9.0, 0.4, 9.0])
    assert held == {"j2": 0.4} and full.joint_names == ("j1", "j2", "j3")
    for s in np.linspace(0.0, 2.5, 11):  # the same path and time law, joint by joint
        np.testing.assert_array_equal(full.at(s), [t.at(s)[1], 0.4, t.at(s)[0]])
    same, none = full.over_joints(["j1", "j2", "j3"], [0.0, 0.0, 0.0])
    assert same is full and none == {}
    with pytest.raises(TrajectoryError, match="'j7' is not a joint"):
        Trajectory("arm", ["j1", "j7"], [0, 1], [[0, 0], [1, 1]]).over_joints(["j1", "j2", "j3"], [0, 0, 0])
    with pytest.raises(TrajectoryError, match="named twice"):
        Trajectory("arm", ["j1", "j1"], [0, 1], [[0, 0], [1, 1]]).over_joints(["j1", "j2", "j3"], [0, 0, 0])


@pytest.mark.parametrize("method", ["certified", "sampled"])
def test_verify_a_subset_equals_verifying_the_held_trajectory(arm, method):
    sub = Trajectory("arm", ["j1", "j2"], [0.0, 1.0, 2.0], [[-1.0, 0.0], [0.0, 0.5], [1.0, -0.3]], blend_times=[0.3, 0.3])
    rep = armguard.verify(arm.scene, sub, method=method)
    by_hand = Trajectory("arm", ["j1", "j2", "j3"], sub.times, np.c_[sub.waypoints, np.full(3, -0.8)], sub.blend_times)
    ref = armguard.verify(arm.scene, by_hand, method=method)
    assert rep.held_joints == {"j3": -0.8} and ref.held_joints == {}
    assert rep.status == ref.status and rep.min_clearance == ref.min_clearance
    assert "held still, not in the trajectory (the Verifier's home, or its q_others): j3 = -0.8" in rep.summary()
    assert rep.to_dict()["held_joints"] == {"j3": -0.8}
    piecewise = armguard.verify(arm.scene, Subdivided(sub, 4), method=method)
    assert piecewise.held_joints == {"j3": -0.8} and piecewise.status == rep.status
    with pytest.raises(VerificationError, match="'j9' is not a joint"):
        armguard.verify(arm.scene, Trajectory("arm", ["j9"], [0, 1], [[0], [1]]))


def test_a_held_joint_can_make_the_collision(arm):
    """The held value is used: j3 held at home (-0.8) leaves l3 in the post's way as j1 turns; the
    same motion with l3 folded up (j3 = 1.5) clears it."""
    sub = Trajectory("arm", ["j1"], [0.0, 2.0], [[-3.0], [3.0]])
    a = armguard.verify(arm.scene, sub)
    b = armguard.verify(arm.scene, Trajectory("arm", ["j1", "j2", "j3"], [0.0, 2.0], [[-3.0, 0.4, 1.5], [3.0, 0.4, 1.5]]))
    assert a.held_joints == {"j2": 0.4, "j3": -0.8}
    assert a.status is VerificationStatus.COLLISION and {a.first_collision.a, a.first_collision.b} == {"arm/l3", "post"}
    assert b.status is VerificationStatus.SAFE


def test_srdf_groups_name_joint_subsets(arm, tmp_path):
    assert arm.group_joints("upper") == ("j1", "j2")  # the robot's order; fixed joints are not moved
    assert arm.group_joints("both") == ("j1", "j2", "j3")
    with pytest.raises(SceneError, match="unknown SRDF group 'legs'"):
        arm.group_joints("legs")
    urdf = package(tmp_path / "chain")
    urdf.with_suffix(".srdf").write_text(srdf_text('<group name="reach"><chain base_link="base" tip_link="l2"/></group>'))
    chained = armguard.load_model(urdf)
    assert list(chained.scene.robots) == ["reach"] and chained.group_joints("reach") == ("j1", "j2")


def test_cli_verifies_a_file_over_a_subset(arm, tmp_path):
    traj = tmp_path / "sub.yaml"
    traj.write_text("format: armguard.trajectory\nversion: 1\nrobot: arm\njoint_names: [j2, j1]\n"
                    "times: [0.0, 1.0]\nwaypoints:\n  - [0.0, -1.0]\n  - [0.5, 1.0]\n")
    urdf = arm.files[0]
    out = CliRunner().invoke(main, ["verify", str(urdf), str(traj)])
    assert out.exit_code in (0, 1) and "held still, not in the trajectory (the Verifier's home, or its q_others): j3 = -0.8" in out.output, out.output
    traj.write_text(traj.read_text().replace("[j2, j1]", "upper"))  # an SRDF group: its joints j1, j2 in that order
    out = CliRunner().invoke(main, ["verify", str(urdf), str(traj)])
    assert out.exit_code in (0, 1) and "held still, not in the trajectory (the Verifier's home, or its q_others): j3 = -0.8" in out.output, out.output
    traj.write_text(traj.read_text().replace("upper", "legs"))
    bad = CliRunner().invoke(main, ["verify", str(urdf), str(traj)])
    assert bad.exit_code == 3 and "joint_names" in bad.output and "unknown SRDF group 'legs'" in bad.output, bad.output
    traj.write_text(traj.read_text().replace("legs", "[j2, j7]"))
    bad = CliRunner().invoke(main, ["verify", str(urdf), str(traj)])
    assert bad.exit_code == 3 and "joint_names" in bad.output and "'j7'" in bad.output, bad.output


def test_panda_trajectory_over_its_seven_arm_joints():
    """A planner's Panda trajectory names the 7 arm joints; the finger is held at the SRDF's default."""
    m = armguard.load_model(ROBOTS / "panda_description/urdf/panda_collision.urdf")  # the Panda in capsules: fast
    arm = [f"panda_joint{k}" for k in range(1, 8)]
    assert m.group_joints("arm") == tuple(arm) and m.group_joints("arm_and_hand") == (*arm, "panda_finger_joint1")
    home = m.scene.home("panda")
    q0 = home[:7]
    traj = Trajectory("panda", arm, [0.0, 2.0], [q0, q0 + np.r_[0.3, 0.2, 0.0, 0.2, 0.0, -0.2, 0.0]])
    rep = armguard.verify(m.scene, traj)
    assert rep.held_joints == {"panda_finger_joint1": pytest.approx(0.001)}
    assert rep.status.value in ("safe", "collision")
