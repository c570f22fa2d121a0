"""Outputs into a folder that does not exist yet: every writer of a user's file makes it, as
``verify --report``, ``edges --out`` and ``srdf --out`` do (``save_scene``, ``Trajectory.save_yaml``
and ``cspace plot --out`` refused with "nodir is not a folder"); a writer that does not make it says
the folder does not exist."""

from __future__ import annotations

import numpy as np
import pytest

import armguard
from armguard._errors import OutputError
from armguard._io import atomic_write
from armguard.kinematics import Trajectory
from armguard.scene import load_scene, save_scene


def test_save_scene_and_a_trajectory_make_their_folder(tmp_path):
    m = armguard.load_model("puma560")
    out = save_scene(m.scene, tmp_path / "a" / "b" / "cell.yaml")
    assert load_scene(out).joint_names == m.scene.joint_names
    r = m.scene.robots["puma560"]
    q0 = m.scene.home("puma560")
    traj = Trajectory.joint_interpolated(r, np.array([q0, q0 + 0.1]))
    traj.save_yaml(tmp_path / "c" / "t.yaml")
    assert Trajectory.load_yaml(tmp_path / "c" / "t.yaml").duration == pytest.approx(traj.duration)


def test_a_missing_folder_is_said_to_be_missing(tmp_path):
    with pytest.raises(OutputError, match=r"the folder .*nodir does not exist"):
        atomic_write(tmp_path / "nodir" / "x.txt", "x")
    (tmp_path / "file").write_text("x")
    with pytest.raises(OutputError, match="is not a folder"):
        atomic_write(tmp_path / "file" / "x.txt", "x")
