"""Cartesian control and the arm angle of :class:`~._state.ConsoleState` (Ranger's motion control panel)."""

from __future__ import annotations

import math

import numpy as np

from ._parse import ConsoleInputError, parse_number, parse_numbers

__all__ = ["MotionMixin", "ARM_ANGLE_STEP"]


class MotionMixin:
    """Commands of the Cartesian panel; mixed into ConsoleState (uses its lock, arms and checks)."""

    # ------------------------------------------------------------------ Cartesian control
    def move_ee(self, p_WE, rpy_WE=None) -> np.ndarray:
        """Cartesian control: put the active arm's tool at ``p_WE`` (3, m) with roll-pitch-yaw ``rpy_WE`` (3, rad).

        Solved by the arm's inverse kinematics seeded at the current configuration; no solution
        raises ConsoleInputError and leaves the arm where it was.  Returns the new joints.
        """
        from ..kinematics._frames import pose_from_xyz_rpy, xyz_rpy_from_pose

        p = parse_numbers(p_WE, "end-effector position", 3, unit="m")
        with self._lock:
            name = self._active
            robot = self._robot(name)
            if rpy_WE is None:
                rpy = np.asarray(xyz_rpy_from_pose(robot.link_pose(self._q[name]))[1], dtype=np.float64)
            else:
                rpy = parse_numbers(rpy_WE, "end-effector orientation", 3, unit="rad")
            X = pose_from_xyz_rpy(p, rpy)
            q = self._solve_ik(robot, X, self._q[name])
            self._q[name] = q
            self._changed(self._arm_moved(name))
            return q.copy()

    def _solve_ik(self, robot, X_WE, q_seed) -> np.ndarray:
        from .._errors import KinematicsError

        try:
            res = robot.inverse_kinematics(X_WE, q_seed=q_seed, rng=np.random.default_rng(0), tol=self._tol)
        except KinematicsError as exc:
            raise ConsoleInputError(f"Cartesian move: {exc}; arm kept where it was") from None
        q = getattr(res, "q", None)
        status = getattr(getattr(res, "status", None), "name", "")
        if q is None or (status and status != "SUCCESS"):
            raise ConsoleInputError(
                f"Cartesian move: no inverse-kinematics solution within the joint limits ({status.lower() or 'failed'}); "
                "arm kept where it was"
            )
        return self._checked_q(robot.name, q)

    def set_arm_angle(self, value) -> float:
        """Move the active 7-DOF arm's elbow by the self-motion ("arm angle", rad) keeping the tool pose.

        The arm angle of Ranger's 7-DOF arms parametrises the self-motion that leaves the
        end-effector pose fixed.  Here it is followed as a null-space motion: from the current
        value to the new one in steps of at most ``ARM_ANGLE_STEP`` rad along the unit null-space
        direction of the 6xN tool Jacobian (sign kept continuous between steps), each step
        corrected back onto the tool pose by inverse kinematics.  For arms with other than seven
        joints (none, or more than one self-motion) this raises.
        """
        psi = parse_number(value, "arm angle", lo=-math.pi, hi=math.pi, unit="rad")
        with self._lock:
            name = self._active
            robot = self._robot(name)
            if robot.n_joints != 7:
                raise ConsoleInputError(f"arm angle: {name} has {robot.n_joints} joints; only 7-DOF arms have one "
                                        "(one self-motion)")
            q = self._q[name].copy()
            X_target = robot.link_pose(q)
            delta = psi - self._arm_angle
            n_steps = max(1, int(math.ceil(abs(delta) / ARM_ANGLE_STEP)))
            step = delta / n_steps
            prev = None
            for _ in range(n_steps):
                J = np.asarray(robot.jacobian(q))
                _, _, Vt = np.linalg.svd(J)
                v = Vt[-1]
                if prev is not None and float(v @ prev) < 0.0:
                    v = -v
                prev = v
                q = q + step * v
                q = self._solve_ik(robot, X_target, q)
            self._q[name] = q
            self._arm_angle = psi
            self._changed(self._taken_over(name))
            return psi


ARM_ANGLE_STEP = 0.05
"""Largest arm-angle increment (rad) of one null-space step in :meth:`ConsoleState.set_arm_angle`."""
