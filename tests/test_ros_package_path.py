"""``package://`` meshes of a URDF copied out of its package: found through ``$ROS_PACKAGE_PATH`` or
``$AMENT_PREFIX_PATH`` as Pinocchio finds them (the command line had no way to give
``package_dirs``), and the error for a missing one says so."""

from __future__ import annotations

import shutil
import warnings

import pytest

import armguard
from armguard.model._public import public_robot_files


def _copied_ur5(tmp_path):
    urdf, _ = public_robot_files("ur5")
    share = next(p for p in urdf.parents if p.name == "example-robot-data").parent  # .../cmeel.prefix/share
    copy = tmp_path / "ur5.urdf"
    shutil.copy(urdf, copy)
    return copy, share


def _load(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return armguard.load_model(path, srdf=False)


def test_a_copied_urdf_finds_its_package_meshes_by_ros_package_path(tmp_path, monkeypatch):
    copy, share = _copied_ur5(tmp_path)
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    monkeypatch.delenv("AMENT_PREFIX_PATH", raising=False)
    with pytest.raises(armguard.SceneFileError) as err:
        _load(copy)
    assert "mesh file not found: 'package://example-robot-data/" in err.value.message
    assert "set ROS_PACKAGE_PATH" in err.value.message
    monkeypatch.setenv("ROS_PACKAGE_PATH", f"{tmp_path / 'elsewhere'}:{share}")
    m = _load(copy)
    assert len(m.pairs) == len(_load(public_robot_files("ur5")[0]).pairs)
    monkeypatch.delenv("ROS_PACKAGE_PATH")
    monkeypatch.setenv("AMENT_PREFIX_PATH", str(share.parent))  # a ROS 2 prefix: prefix/share/pkg
    assert len(_load(copy).pairs) == len(m.pairs)
