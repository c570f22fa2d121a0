"""URDF robots: real files nobody here wrote (pybullet's KUKA iiwa, example-robot-data's Panda) and a
synthetic tree with every supported joint kind.  Oracles: pybullet's and yourdfpy's link frames."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from armguard import KinematicsError, SceneFileError
from armguard.geometry import Box, ConvexPolyhedron, Cylinder, Sphere
from armguard.kinematics import Robot, pose_from_xyz_rpy

yourdfpy = pytest.importorskip("yourdfpy")
pybullet_data = pytest.importorskip("pybullet_data")

KUKA = Path(pybullet_data.getDataPath()) / "kuka_iiwa" / "model.urdf"
_ERD = Path(yourdfpy.__file__).parent.parent / "cmeel.prefix" / "share" / "example-robot-data" / "robots"
PANDA = _ERD / "panda_description" / "urdf" / "panda.urdf"


@pytest.fixture(scope="module")
def kuka() -> Robot:
    return Robot.from_urdf(KUKA)


def _yourdfpy_frames(path, robot: Robot, q: np.ndarray) -> np.ndarray:
    u = yourdfpy.URDF.load(str(path), build_scene_graph=True, load_meshes=False)
    out = []
    for qi in q:
        u.update_cfg(dict(zip(robot.joint_names, qi)))
        out.append([u.get_transform(ln) for ln in robot.link_names])
    return np.array(out)


def test_kuka_loads_with_limits_and_collision_hulls(kuka):
    assert kuka.n_joints == 7 and len(kuka.link_names) == 8
    assert kuka.link_names[0] == "lbr_iiwa_link_0" and kuka.tool_link == "lbr_iiwa_link_7"
    np.testing.assert_allclose(kuka.upper[:2], [2.96705972839, 2.09439510239])  # from the file
    np.testing.assert_allclose(kuka.max_velocity, 10.0)
    assert all(len(kuka.link_shapes[ln]) == 1 and isinstance(kuka.link_shapes[ln][0], ConvexPolyhedron)
               for ln in kuka.link_names)


def test_kuka_fk_matches_pybullet(kuka):
    """pybullet's link frames at random configurations.  pybullet reports worldLinkFramePosition
    (getLinkState[4:6]) rounded through float32 (0.1575 comes back as 0.1574999988), so the exact
    comparison composes its double-precision inertial frame [0:2] with the inverse of the
    link-local inertial frame [2:4]; the float32 entries are checked to 1e-6."""
    p = pytest.importorskip("pybullet")
    cid = p.connect(p.DIRECT)
    try:
        body = p.loadURDF(str(KUKA), useFixedBase=True, physicsClientId=cid)
        rng = np.random.default_rng(11)
        q = rng.uniform(kuka.lower, kuka.upper, (25, 7))
        X = kuka.forward_kinematics(q)

        def pose(pos, quat):
            T = np.eye(4)
            T[:3, :3] = np.reshape(p.getMatrixFromQuaternion(quat, physicsClientId=cid), (3, 3))
            T[:3, 3] = pos
            return T

        for qi, Xi in zip(q, X):
            for k in range(7):
                p.resetJointState(body, k, qi[k], physicsClientId=cid)
            for k in range(7):
                s = p.getLinkState(body, k, computeForwardKinematics=True, physicsClientId=cid)
                X_pb = pose(s[0], s[1]) @ np.linalg.inv(pose(s[2], s[3]))
                np.testing.assert_allclose(Xi[k + 1], X_pb, atol=1e-9)
                np.testing.assert_allclose(Xi[k + 1, :3, 3], s[4], atol=1e-6)
                np.testing.assert_allclose(Xi[k + 1], pose(s[4], s[5]), atol=1e-6)
    finally:
        p.disconnect(cid)


def test_kuka_fk_matches_yourdfpy(kuka):
    q = np.random.default_rng(5).uniform(kuka.lower, kuka.upper, (20, 7))
    np.testing.assert_allclose(kuka.forward_kinematics(q), _yourdfpy_frames(KUKA, kuka, q), atol=1e-9)


@pytest.mark.skipif(not PANDA.exists(), reason="example-robot-data is not installed")
def test_panda_loads_package_meshes_and_matches_yourdfpy():
    robot = Robot.from_urdf(PANDA)
    assert robot.n_joints == 8  # 7 arm joints + finger 1; finger 2 mimics finger 1
    assert len(robot.couplings) == 1 and robot.couplings[0].joint == "panda_finger_joint2"
    assert sum(len(v) for v in robot.link_shapes.values()) >= 9  # package:// collision meshes found
    lo = np.where(np.isfinite(robot.lower), robot.lower, -1)
    hi = np.where(np.isfinite(robot.upper), robot.upper, 1)
    q = np.random.default_rng(2).uniform(lo, hi, (10, robot.n_joints))
    np.testing.assert_allclose(robot.forward_kinematics(q), _yourdfpy_frames(PANDA, robot, q), atol=1e-9)


_SYNTHETIC = """<?xml version="1.0"?>
<robot name="synthetic">
  <link name="base">
    <collision><origin xyz="0 0 0.05" rpy="0 0 0"/><geometry><box size="0.4 0.3 0.1"/></geometry></collision>
  </link>
  <link name="turret">
    <collision><origin xyz="0 0 0.2" rpy="0.3 0 0"/><geometry><cylinder radius="0.05" length="0.4"/></geometry></collision>
  </link>
  <link name="slider"/>
  <link name="arm_a"><collision><geometry><sphere radius="0.07"/></geometry></collision></link>
  <link name="arm_b"/>
  <link name="flange"/>
  <joint name="spin" type="continuous">
    <parent link="base"/><child link="turret"/><origin xyz="0 0 0.1" rpy="0 0 0.2"/><axis xyz="0 0 1"/>
  </joint>
  <joint name="lift" type="prismatic">
    <parent link="turret"/><child link="slider"/><origin xyz="0.1 0 0.3" rpy="0.1 0.2 0.3"/><axis xyz="0 0.6 0.8"/>
    <limit lower="-0.2" upper="0.5" effort="10" velocity="0.3"/>
  </joint>
  <joint name="elbow_a" type="revolute">
    <parent link="slider"/><child link="arm_a"/><origin xyz="0 0.2 0" rpy="1.0 0 0"/><axis xyz="1 0 0"/>
    <limit lower="-1.5" upper="1.5" effort="10" velocity="2"/>
  </joint>
  <joint name="elbow_b" type="revolute">
    <parent link="slider"/><child link="arm_b"/><origin xyz="0 -0.2 0" rpy="0 0.5 0"/><axis xyz="0 0 1"/>
    <limit lower="-1.5" upper="1.5" effort="10" velocity="2"/>
    <mimic joint="elbow_a" multiplier="-0.5" offset="0.1"/>
  </joint>
  <joint name="flange_fix" type="fixed">
    <parent link="arm_b"/><child link="flange"/><origin xyz="0 0 0.3" rpy="0 0 1.0"/>
  </joint>
</robot>
"""


@pytest.fixture()
def synthetic(tmp_path) -> Path:
    path = tmp_path / "synthetic.urdf"
    path.write_text(_SYNTHETIC)
    return path


def test_synthetic_tree_joint_kinds_and_shapes(synthetic):
    robot = Robot.from_urdf(synthetic, X_WB=pose_from_xyz_rpy([1, 0, 0], [0, 0, 0.5]))
    assert robot.joint_names == ("spin", "lift", "elbow_a")  # elbow_b mimics elbow_a
    assert math.isinf(robot.lower[0]) and math.isinf(robot.upper[0])  # continuous
    assert robot.max_velocity[1] == 0.3
    (box,), (cyl,), (sphere,) = robot.link_shapes["base"], robot.link_shapes["turret"], robot.link_shapes["arm_a"]
    assert isinstance(box, Box) and np.allclose(box.half_extents, [0.2, 0.15, 0.05])
    # a URDF cylinder is an exact cylinder (as coal holds it), its axis the cylinder's (rot x 0.3 of z)
    assert isinstance(cyl, Cylinder) and cyl.radius == 0.05 and cyl.half_length == 0.2
    assert isinstance(sphere, Sphere) and sphere.radius == 0.07
    np.testing.assert_allclose(cyl.rotation[:, 2], pose_from_xyz_rpy([0, 0, 0], [0.3, 0, 0])[:3, 2], atol=1e-15)
    q = np.random.default_rng(0).uniform([-3, -0.2, -1.5], [3, 0.5, 1.5], (15, 3))
    expected = _yourdfpy_frames(synthetic, robot, q)
    np.testing.assert_allclose(robot.forward_kinematics(q), robot.X_WB @ expected, atol=1e-12)


@pytest.mark.parametrize(
    "edit, where",
    [
        (lambda s: s.replace('type="continuous"', 'type="floating"'), "joint[spin]"),
        (lambda s: s.replace('<sphere radius="0.07"/>', '<mesh filename="nowhere/missing.stl"/>'), "link[arm_a].collision[0]"),
        (lambda s: "not a robot", "line 1, column 1"),
    ],
    ids=["floating-joint", "missing-mesh", "broken-xml"],
)
def test_bad_urdf_raises_scene_file_error(tmp_path, edit, where):
    path = tmp_path / "bad.urdf"
    path.write_text(edit(_SYNTHETIC))
    with pytest.raises(SceneFileError) as info:
        Robot.from_urdf(path)
    assert info.value.file == str(path) and info.value.where == where


def test_missing_urdf_file_raises(tmp_path):
    with pytest.raises(SceneFileError, match="file not found"):
        Robot.from_urdf(tmp_path / "nope.urdf")


def test_load_without_collision_has_no_shapes(synthetic):
    robot = Robot.from_urdf(synthetic, load_collision=False, name="bare")
    assert robot.name == "bare" and all(v == () for v in robot.link_shapes.values())
    with pytest.raises(KinematicsError):
        robot.forward_kinematics([0.0, 0.0])
