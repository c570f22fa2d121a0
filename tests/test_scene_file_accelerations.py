"""Joint accelerations of URDF robots: a sidecar's ``joints: {R/joint: {max_acceleration}}`` reaches
a public URDF's joint (it was keyed ``R_joint``, which only armguard's own exported URDFs name, and
silently set nothing), a scene file's ``robots[i].max_acceleration`` sets them, and a plain scene
file's top-level ``joints:`` (which would set nothing) is refused at its place."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
import yaml

import armguard
from armguard.model._public import public_robot_files
from armguard.scene import load_scene


def _load(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return armguard.load_model(path)


def test_a_sidecar_sets_a_public_urdfs_joint_acceleration_by_its_scene_name(tmp_path):
    urdf, _ = public_robot_files("ur5")
    p = tmp_path / "cell.yaml"
    p.write_text(yaml.safe_dump({"armguard_scene": 1, "name": "cell", "units": {"angle": "deg"}, "model": {"urdf": str(urdf)},
                                 "joints": {"ur5/shoulder_pan_joint": {"max_acceleration": 180}}}))
    robot = _load(p).scene.robots["ur5"]
    assert robot.max_acceleration[0] == pytest.approx(math.pi) and np.all(np.isinf(robot.max_acceleration[1:]))
    p.write_text(yaml.safe_dump({"armguard_scene": 1, "name": "cell", "model": {"urdf": str(urdf)},
                                 "joints": {"ur5/shoulder_pan_jiont": {"max_acceleration": 3}}}))
    with pytest.raises(armguard.SceneFileError) as err:
        _load(p)
    assert err.value.where.startswith("joints.ur5/shoulder_pan_jiont") and "unknown joint" in err.value.message


def test_a_scene_files_urdf_robot_takes_accelerations_and_a_top_level_joints_map_is_refused(tmp_path):
    urdf, _ = public_robot_files("ur5")
    p = tmp_path / "cell.yaml"
    p.write_text(yaml.safe_dump({"armguard_scene": 1, "name": "cell",
                                 "robots": [{"name": "ur5", "urdf": str(urdf), "max_acceleration": [2, 2, 3, 4, 4, 4]}]}))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert list(load_scene(p).robots["ur5"].max_acceleration) == [2, 2, 3, 4, 4, 4]
        p.write_text(yaml.safe_dump({"armguard_scene": 1, "name": "cell", "robots": [{"name": "ur5", "urdf": str(urdf)}],
                                     "joints": {"ur5/shoulder_pan_joint": {"max_acceleration": 3}}}))
        for load in (load_scene, armguard.load_model):
            with pytest.raises(armguard.SceneFileError) as err:
                load(p)
            assert err.value.where.startswith("joints.ur5/shoulder_pan_joint")
            assert "robots[i].max_acceleration" in err.value.message and err.value.line is not None
