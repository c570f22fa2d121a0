"""Kinematics: DH and URDF joint trees, coupled/mimic joints, batched FK, Jacobians, IK, trajectories,
Ranger's canned motions in the end-effector coordinates and the arm angle.

The closed-form PUMA 560 inverse (:func:`puma560_ik`) is registered for robots named ``"puma560"``.
"""

from ._frames import dh_modified, dh_standard, invert_pose, pose_from_xyz_rpy, xyz_rpy_from_pose
from ._ik import IKPlugin, IKResult, IKStatus, ik_plugin, register_ik, unregister_ik
from ._puma import PUMA560_DH, PUMA560_LOWER, PUMA560_UPPER, puma560_ik
from ._robot import Coupling, DHRow, JointSpec, JointType, Robot
from ._task_motion import CANNED_LIMITS, arm_angle, arm_points, task_coordinates, task_trapezoid
from ._trajectory import PROFILES, Trajectory

register_ik("puma560", puma560_ik)

__all__ = [
    "Robot",
    "DHRow",
    "Coupling",
    "JointType",
    "JointSpec",
    "Trajectory",
    "PROFILES",
    "task_trapezoid",
    "task_coordinates",
    "arm_angle",
    "arm_points",
    "CANNED_LIMITS",
    "IKResult",
    "IKStatus",
    "IKPlugin",
    "register_ik",
    "unregister_ik",
    "ik_plugin",
    "puma560_ik",
    "PUMA560_DH",
    "PUMA560_LOWER",
    "PUMA560_UPPER",
    "pose_from_xyz_rpy",
    "xyz_rpy_from_pose",
    "invert_pose",
    "dh_standard",
    "dh_modified",
]
