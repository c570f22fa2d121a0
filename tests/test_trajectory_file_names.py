"""A trajectory file's joint_names: an unknown joint (with the nearest real name) and a joint named
twice are told apart (the message said "is not a joint ... or is named twice" for both)."""

from __future__ import annotations

import pytest
import yaml

import armguard
from armguard.verify._trajectory_file import load_trajectory


def _file(tmp_path, names):
    p = tmp_path / "t.yaml"
    p.write_text(yaml.safe_dump({"format": "armguard.trajectory", "version": 1, "robot": "ur5", "joint_names": names,
                                 "times": [0.0, 1.0], "waypoints": [[0.0] * len(names), [0.1] * len(names)]}))
    return p


@pytest.mark.parametrize("names, expect", [
    (["shoulder_pan_joint", "wrist1_joint"], "'wrist1_joint' is not a joint of robot 'ur5' (did you mean 'wrist_1_joint'?)"),
    (["shoulder_pan_joint", "shoulder_pan_joint"], "'shoulder_pan_joint' is named twice"),
])
def test_unknown_and_repeated_joint_names_are_told_apart(tmp_path, names, expect):
    scene = armguard.load_model("ur5").scene
    with pytest.raises(armguard.SceneFileError) as err:
        load_trajectory(scene, _file(tmp_path, names))
    assert err.value.where.startswith("joint_names") and expect in err.value.message


@pytest.mark.parametrize("text, expect", [
    ("", "got an empty file (no YAML document)"),
    ('<robot name="r"><link name="base"/></robot>\n', "got XML text (a URDF or SRDF?"),
    ("[1, 2]\n", "got a list"),
])
def test_a_file_that_is_no_trajectory_says_what_it_is(tmp_path, text, expect):
    """An empty file said "got NoneType", a URDF given as the trajectory "got str"."""
    p = tmp_path / "t.yaml"
    p.write_text(text)
    with pytest.raises(armguard.SceneFileError) as err:
        load_trajectory(armguard.load_model("ur5").scene, p)
    assert "expected a trajectory: a YAML mapping" in err.value.message and expect in err.value.message, err.value.message


def test_a_trajectory_or_program_given_as_a_scene_says_what_it_is(tmp_path):
    """``check traj.yaml`` listed eight scene-schema errors (one per key) and never said it was a trajectory."""
    p = tmp_path / "t.yaml"
    p.write_text(yaml.safe_dump({"format": "armguard.trajectory", "version": 1, "robot": "ur5",
                                 "joint_names": ["shoulder_pan_joint"], "times": [0.0, 1.0], "waypoints": [[0.0], [0.1]]}))
    with pytest.raises(armguard.SceneFileError, match=r"this file is a trajectory, not a scene or model file .*armguard verify"):
        armguard.load_model(p)
    p.write_text("armguard_program: 1\nname: x\ncell: cell.yaml\ntasks: []\n")
    with pytest.raises(armguard.SceneFileError, match=r"this file is a task program, not a scene .*armguard program run"):
        armguard.load_model(p)
