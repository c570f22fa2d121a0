"""Kinematics: DH and URDF joint trees, coupled/mimic joints, batched FK, Jacobians, IK, trajectories."""

from ._frames import invert_pose, pose_from_xyz_rpy, xyz_rpy_from_pose
from ._robot import Coupling, DHRow, JointSpec, JointType, Robot

__all__ = [
    "Robot",
    "DHRow",
    "Coupling",
    "JointType",
    "JointSpec",
    "pose_from_xyz_rpy",
    "xyz_rpy_from_pose",
    "invert_pose",
]
