"""A scene file's URDF robots keep their SRDF's groups: ``joints="arm"``, a trajectory file's
``joint_names: arm`` and ``armguard edges`` with a group, as on the robot loaded alone (the Model of a
scene file had no SRDF: "no model with SRDF groups"); two robots whose SRDFs name a group alike get
``robot/group``."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import yaml

import armguard
from armguard.model._public import public_robot_files
from armguard.verify import Verifier


def _load(tmp_path, robots):
    p = tmp_path / "cell.yaml"
    p.write_text(yaml.safe_dump({"armguard_scene": 1, "name": "cell", "robots": robots}))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return p, armguard.load_model(p)


def test_one_robot_keeps_its_groups_and_two_are_told_apart(tmp_path):
    urdf, _ = public_robot_files("panda")
    arm = ("panda_joint1", "panda_joint2", "panda_joint3", "panda_joint4", "panda_joint5", "panda_joint6", "panda_joint7")
    _, one = _load(tmp_path, [{"name": "cobot", "urdf": str(urdf)}])
    assert one.group_robot_joints("arm") == ("cobot", arm)
    _, two = _load(tmp_path, [{"name": "left", "urdf": str(urdf)},
                              {"name": "right", "urdf": str(urdf), "mount": {"xyz": [1.0, 0, 0]}}])
    assert two.group_robot_joints("left/arm") == ("left", arm) and two.group_robot_joints("right/arm") == ("right", arm)
    with pytest.raises(armguard.SceneError, match="unknown SRDF group 'arm'"):
        two.group_robot_joints("arm")


def test_a_trajectory_file_and_check_edges_name_the_group(tmp_path):
    urdf, _ = public_robot_files("panda")
    path, m = _load(tmp_path, [{"name": "panda", "urdf": str(urdf)}])
    q0 = m.scene.home("panda")[:7]
    t = tmp_path / "t.yaml"
    t.write_text(yaml.safe_dump({"format": "armguard.trajectory", "version": 1, "robot": "panda", "joint_names": "arm",
                                 "times": [0.0, 2.0], "waypoints": [q0.tolist(), (q0 + 0.1).tolist()]}))
    scene = armguard.load_scene(path)  # a plain Scene, no Model made yet: the group is resolved all the same
    assert armguard.verify(scene, t).status.value == "safe"
    res = Verifier(m).check_edges(q0, q0 + 0.1, joints="arm")
    assert res.status[0].name == "CLEAR"


def test_another_arms_group_is_refused_where_the_arms_share_joint_names(tmp_path):
    """Ranger's arms call their joints alike (j1 ...): an edges file or a trajectory file naming the grapple
    arm's group was certified on the left arm (the group's joint names matched), exit 0 on an edge that
    collides on the grapple arm."""
    from click.testing import CliRunner

    from armguard.cli import ExitCode, main

    m = armguard.load_model("ranger")
    robot, joints = m.group_robot_joints("grapple_arm")
    assert robot == "grapple_arm" and set(joints) <= set(m.scene.robots["left_arm"].joint_names)
    q0 = np.zeros(len(joints))
    np.savez(tmp_path / "e.npz", Q0=q0, Q1=q0 + 0.1, joint_names=np.array("grapple_arm"))
    res = CliRunner().invoke(main, ["edges", "ranger", str(tmp_path / "e.npz"), "--robot", "left_arm"])
    assert res.exit_code == ExitCode.INPUT and "moves robot 'grapple_arm', not 'left_arm'" in res.output, res.output
    res = CliRunner().invoke(main, ["edges", "ranger", str(tmp_path / "e.npz")])  # the group names its robot
    assert res.exit_code in (ExitCode.OK, ExitCode.UNSAFE) and "edges of 'grapple_arm'" in res.output, res.output
    t = tmp_path / "t.yaml"
    t.write_text(yaml.safe_dump({"format": "armguard.trajectory", "version": 1, "robot": "left_arm",
                                 "joint_names": "grapple_arm", "times": [0.0, 2.0],
                                 "waypoints": [q0.tolist(), (q0 + 0.1).tolist()]}))
    with pytest.raises(armguard.SceneFileError, match="joint_names.*moves robot 'grapple_arm', not the file's robot"):
        armguard.verify(m.scene, t)
    t.write_text(t.read_text().replace("robot: left_arm", "robot: grapple_arm"))
    assert armguard.verify(m.scene, t).status is not None
