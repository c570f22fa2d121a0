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
