"""Messages for the mistakes people make in scene files and on the command line.

A joint value outside its limits in a scene file or on ``--q`` names the value, the limits in the
units it was given in, and, where a radian or metre value that large looks like degrees or
millimetres, says how the file or command reads it (before: "home is outside the limits of joint
'shoulder_lift_joint'", at the robot's line, with neither)."""

from __future__ import annotations

import warnings

import pytest
import yaml
from click.testing import CliRunner

import armguard
from armguard.cli import main
from armguard.model._public import public_robot_files


def _scene(tmp_path, robot: dict, **top):
    p = tmp_path / "cell.yaml"
    p.write_text(yaml.safe_dump({"armguard_scene": 1, "name": "cell", "robots": [robot], **top}))
    return p


def _error(path) -> armguard.SceneFileError:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(armguard.SceneFileError) as err:
            armguard.load_model(path)
    return err.value


def test_a_home_in_degrees_read_as_radians_names_value_limits_and_units(tmp_path):
    urdf, _ = public_robot_files("ur5")
    err = _error(_scene(tmp_path, {"name": "ur5", "urdf": str(urdf), "home": [0, -90, 90, 0, 0, 0]}))
    assert err.where == "robots[0].home"
    assert "'shoulder_lift_joint' = -90 rad is outside its limits [-6.28319, 6.28319] rad" in err.message
    assert "units: {angle: deg}" in err.message
    ok = _scene(tmp_path, {"name": "ur5", "urdf": str(urdf), "home": [0, -90, 90, 0, 0, 0]}, units={"angle": "deg"})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert armguard.load_model(ok).scene.home("ur5")[1] == pytest.approx(-1.5707963267948966)


def test_a_waypoint_outside_the_limits_in_degrees_says_so_in_degrees(tmp_path):
    urdf, _ = public_robot_files("ur5")
    err = _error(_scene(tmp_path, {"name": "ur5", "urdf": str(urdf)}, units={"angle": "deg"},
                        trajectories=[{"name": "t", "robot": "ur5", "waypoints": [[0] * 6, [0, 400, 0, 0, 0, 0]]}]))
    assert err.where == "trajectories[0].waypoints[1]"
    assert "'shoulder_lift_joint' = 400 deg is outside its limits [-360, 360] deg" in err.message
    assert "read as radians" not in err.message


def test_q_in_degrees_without_deg_is_told_to_add_it():
    r = CliRunner().invoke(main, ["-q", "check", "ur5", "--q=-90,0,0,0,0,0"])
    assert r.exit_code == 2 and "-90 rad is outside its limits" in r.output and "add --deg" in r.output
    r = CliRunner().invoke(main, ["-q", "check", "ur5", "--q=-7,0,0,0,0,0"])  # 7 rad: beyond a turn, also a hint
    assert "add --deg" in r.output


def test_a_misspelt_optional_key_is_told_the_key_it_looks_like(tmp_path):
    """``catgory:`` and ``trajectory:`` were "unknown key ... check the spelling"; the nearest key of
    the format is named (the misspelling of a required key already was)."""
    p = tmp_path / "typo.yaml"
    p.write_text("armguard_scene: 1\nname: c\nbodies:\n  - name: b\n    shapes: [{type: box, size: [1, 1, 1]}]\n"
                 "    catgory: vehicle\ntrajectory: []\nzzzz: 1\n")
    with pytest.raises(armguard.SceneFileError) as err:
        armguard.load_scene(p)
    text = str(err.value)
    assert "bodies[0].catgory (line 6): unknown key (not part of the armguard_scene format; did you mean 'category'?)" in text
    assert "trajectory (line 7): unknown key (not part of the armguard_scene format; did you mean 'trajectories'?)" in text
    assert "zzzz (line 8): unknown key (not part of the armguard_scene format; check the spelling)" in text
    p.write_text("armguard_scene: 1\nname: c\nrobot: []\n")  # a payload's key elsewhere: not 'did you mean robot'
    with pytest.raises(armguard.SceneFileError, match=r"robot \(line 3\): unknown key \(.*did you mean 'robots'\?\)"):
        armguard.load_scene(p)


def test_a_trajectory_file_in_degrees_lists_the_values_outside_and_says_degrees(tmp_path):
    """puma560 waypoints written in degrees: one value was named (waypoint 1's before waypoint 0's, joint by
    joint), with no word of degrees, as ``check --q`` and scene files give."""
    p = tmp_path / "deg.yaml"
    p.write_text(yaml.safe_dump({"format": "armguard.trajectory", "version": 1, "robot": "puma560",
                                 "joint_names": ["j1", "j2", "j3", "j4", "j5", "j6"], "times": [0, 2],
                                 "waypoints": [[0, 45, -135, 0, -45, 0], [30, 70, -170, 0, -75, -150]]},
                                default_flow_style=None))
    r = CliRunner().invoke(main, ["-q", "verify", "puma560", str(p)])
    assert r.exit_code == 3, r.output
    text = " ".join(r.output.split())
    assert "waypoints[0][1]" in text and "'j2' = 45 is outside its limits" in text
    assert "7 more outside: waypoints[0][2] 'j3' = -135; waypoints[0][4] 'j5' = -45; waypoints[1][0] 'j1' = 30" in text
    assert "these look like degrees" in text


def test_a_trajectory_value_just_outside_in_radians_gets_no_degrees_hint(tmp_path):
    p = tmp_path / "rad.yaml"
    p.write_text(yaml.safe_dump({"format": "armguard.trajectory", "version": 1, "robot": "puma560",
                                 "joint_names": ["j1", "j2", "j3", "j4", "j5", "j6"], "times": [0, 2],
                                 "waypoints": [[0, 0, 0, 0, 0, 0], [0, -1.0, 0, 0, 0, 0]]}, default_flow_style=None))
    r = CliRunner().invoke(main, ["-q", "verify", "puma560", str(p)])
    text = " ".join(r.output.split())
    assert r.exit_code == 3 and "waypoints[1][1]" in text and "more outside" not in text and "degrees" not in text, text
