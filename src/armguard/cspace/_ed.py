"""Hermes's discretisation error of a joint-space map, eq. (4-5), from the model's own link lengths.

Hermes (``001_…``, §4, "Forbidden Values Method") bounds the error of discretising joints 1 and 2
at ``n`` degrees by

    ``Ed = n π/180 · (L2² + L3²)^½ = 11.4 n`` cm                                      (4-5)

with ``L2``, ``L3`` the lengths of links 2 and 3 of *its* arm.  The paper prints only the constant
(11.4 cm/deg, i.e. ``(L2² + L3²)^½ ≈ 6.53 m``), not the lengths.  :func:`ed_constant` derives the
constant of a loaded model instead: ``L2`` is the distance from joint 2 to joint 3 and ``L3`` the
distance from joint 3 to joint 4 (the wrist; the tool frame when the robot has only three joints),
both at the zero configuration.  armguard's HERA (``urdf/hermes``, lengths assumed: the seed gives
none) has ``L2 = L3 = 4.2`` m, hence 10.4 cm/deg, not the paper's 11.4.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..model import kinematics_of, scene_of
from .._errors import ForbiddenMapError
from ._clearance import pick_robot

__all__ = ["EdConstant", "ed_constant", "PAPER_CM_PER_DEGREE"]

#: Hermes eq. (4-5): ``Ed = 11.4 n`` (cm, n in degrees), for the paper's arm.
PAPER_CM_PER_DEGREE = 11.4


@dataclass(frozen=True)
class EdConstant:
    """The constant of Hermes eq. (4-5) for one robot.

    Attributes
    ----------
    robot : str
    l2, l3 : float, m
        Joint 2 to joint 3 and joint 3 to joint 4 (at the zero configuration).
    m_per_rad : float
        ``(l2² + l3²)^½``: the discretisation error per radian of ``n``.
    """

    robot: str
    l2: float
    l3: float
    m_per_rad: float

    @property
    def cm_per_degree(self) -> float:
        """``Ed / n`` in cm per degree (the paper's 11.4 for its arm)."""
        return self.m_per_rad * math.pi / 180.0 * 100.0

    def resolution_deg(self, ed_cm: float) -> float:
        """The resolution ``n`` (degrees) whose discretisation error is ``ed_cm`` (cm)."""
        return float(ed_cm) / self.cm_per_degree


def ed_constant(scene, robot: str | None = None) -> EdConstant:
    """Hermes eq. (4-5)'s constant for ``robot`` of ``scene`` (see the module docstring)."""
    scene = scene_of(scene, "map")  # a Model: its scene
    robot = pick_robot(scene, robot)
    rob = scene.robots[robot]
    moving = [j for j in rob.joints if j.joint_type.value != "fixed"]
    if len(moving) < 3:
        raise ForbiddenMapError(f"robot {robot!r} has {len(moving)} moving joints; eq. (4-5) needs three")
    X_WL = kinematics_of(scene).robot_link_poses(robot, np.zeros(rob.n_joints))  # the Model's kinematics
    p = {ln: X_WL[i, :3, 3] for i, ln in enumerate(rob.link_names)}
    wrist = moving[3].child if len(moving) > 3 else rob.tool_link
    l2 = float(np.linalg.norm(p[moving[2].child] - p[moving[1].child]))
    l3 = float(np.linalg.norm(p[wrist] - p[moving[2].child]))
    return EdConstant(robot, l2, l3, math.hypot(l2, l3))
