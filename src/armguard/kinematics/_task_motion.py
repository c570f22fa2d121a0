"""Ranger's canned-test motions: trapezoids in the end-effector coordinates or the arm angle.

Seed ``000`` (Bon & Seraji), section 6: "Each Test or Demo button commands the active arm to
execute a trapezoidal trajectory in one or more of the six end-effector coordinates or the arm
angle", and the motion control panel "provides operator control of the position and
orientation of the end-effector of the currently active arm, as well as the arm angle".

The task coordinates of an arm are ``x = (x, y, z, roll, pitch, yaw, psi)``: the tool position
(m) and roll-pitch-yaw (rad, :func:`~._frames.pose_from_xyz_rpy`) in W and, for a 7-joint arm,
the arm angle ``psi`` (rad, :func:`arm_angle`).  A canned motion changes them by ``delta``
along the common path parameter ``s(t)`` of :mod:`._profile` — ``x(t) = x0 + s(t) delta`` —, so
every moving coordinate follows the same trapezoid, synchronised, and the tool position moves
on a straight line with a trapezoidal speed.  The coordinates a motion does not change are
held: an arm-angle motion keeps the tool pose; an end-effector motion of a 7-joint arm keeps
its arm angle (the redundancy is resolved by ``psi``, as on Ranger's 7-DOF arms).

The motion is sampled at ``frequency`` Hz; each sample's joints solve the 7 (6 without an arm
angle) task equations by bounded least squares (``scipy.optimize.least_squares`` within the
joint limits, seeded by the previous sample); between samples the arm moves on joint-space
lines (the verifier's segments).

The seed names the arm angle without defining it.  Here it is the angle, about the
shoulder-to-wrist line, from the vertical plane through that line (``reference`` = W's z axis)
to the plane of shoulder, elbow and wrist — the usual redundancy parameter of a
shoulder-elbow-wrist 7-DOF arm.  It is undefined when the elbow is on the shoulder-wrist line
(arm stretched) or that line is vertical; such a configuration raises.
"""

from __future__ import annotations

import math

import numpy as np

from .._errors import KinematicsError, TrajectoryError
from ._frames import pose_from_xyz_rpy, rotation_vector_from_matrix, xyz_rpy_from_pose
from ._profile import min_time_trapezoid, path_s, pose_samples

__all__ = ["arm_angle", "arm_points", "task_coordinates", "task_trapezoid", "CANNED_LIMITS"]

CANNED_LIMITS = {"speed": 0.1, "angular_speed": math.radians(15.0),
                 "acceleration": 0.1, "angular_acceleration": math.radians(30.0)}
"""Default task-space limits of a canned motion: m/s, rad/s, m/s^2, rad/s^2 (assumed: the seed
gives none; slow enough that the Ranger model's joints stay within their speed limits)."""

_DEGENERATE = 1e-6
"""Smallest distance (m) of the elbow from the shoulder-wrist line, and smallest horizontal part
of that line's unit direction, for which the arm angle is defined."""

_SOLVE_TOL = 1e-10
"""Largest task residual (m or rad) accepted at a sample."""


def arm_points(robot) -> tuple[str, str, str]:
    """The links whose origins are the shoulder, elbow and wrist of a 7-joint arm.

    The shoulder-elbow-wrist arm in standard DH (Ranger's dexterous arms in armguard's model):
    frame 1 at the shoulder (joints 1-3 meet), frame 3 at the elbow (joint 4), frame 5 at the
    wrist (joints 5-7 meet) — ``link_names[1], [3], [5]``.  Raises KinematicsError for other arms.
    """
    if robot.n_joints != 7:
        raise KinematicsError(f"robot {robot.name!r}: {robot.n_joints} joints; only 7-joint arms have an arm angle")
    names = robot.link_names
    return names[1], names[3], names[5]


def arm_angle(robot, q, *, points=None, reference=(0.0, 0.0, 1.0)) -> float:
    """The arm angle (rad, in (-pi, pi]) of a 7-joint arm at ``q``.

    With shoulder S, elbow E and wrist W (origins of the ``points`` links, default
    :func:`arm_points`) in W, ``u = (W - S) / |W - S|``, ``e`` and ``r`` the parts of ``E - S`` and
    ``reference`` normal to ``u``: ``psi = atan2(u . (r x e), r . e)``.  Raises KinematicsError
    where it is undefined (elbow on the shoulder-wrist line; that line along ``reference``).
    """
    s_link, e_link, w_link = arm_points(robot) if points is None else points
    p_S, p_E, p_W = (robot.link_pose(q, ln)[:3, 3] for ln in (s_link, e_link, w_link))
    return _psi_of_points(p_S, p_E, p_W, reference)


def task_coordinates(robot, q, *, with_arm_angle: bool | None = None) -> np.ndarray:
    """``(7,)`` ``(x, y, z, roll, pitch, yaw, psi)`` of the tool at ``q`` (``(6,)`` without the arm angle).

    ``with_arm_angle`` defaults to ``robot.n_joints == 7``.
    """
    xyz, rpy = xyz_rpy_from_pose(robot.link_pose(q))
    if with_arm_angle is None:
        with_arm_angle = robot.n_joints == 7
    if not with_arm_angle:
        return np.concatenate([xyz, rpy])
    return np.concatenate([xyz, rpy, [arm_angle(robot, q)]])


def _wrap(a: float) -> float:
    return math.remainder(a, 2.0 * math.pi)


def task_trapezoid(robot, q_start, delta, *, speed: float | None = None, angular_speed: float | None = None,
                   acceleration: float | None = None, angular_acceleration: float | None = None,
                   frequency: float = 50.0):
    """A canned motion: the task coordinates change by ``delta`` along one synchronised trapezoid.

    ``delta`` (6,) ``(dx, dy, dz, droll, dpitch, dyaw)`` (m, rad) or (7,) with ``dpsi`` (rad) last
    (7-joint arms: a 6-vector holds the arm angle).  Position coordinates are limited by ``speed``
    (m/s) / ``acceleration`` (m/s^2), angles by ``angular_speed`` (rad/s) /
    ``angular_acceleration`` (rad/s^2) (defaults :data:`CANNED_LIMITS`), each coordinate on its
    own: the slowest sets the time (:func:`~._profile.min_time_trapezoid`); where a joint would
    then pass its speed limit the motion is stretched in time until none does (the same path and
    trapezoid, slower).  Returns a ``Trajectory`` of ``ceil(duration * frequency)`` samples (at
    ``frequency`` Hz before any stretch).  Raises TrajectoryError naming the sample where no joint
    values within the limits reach the task coordinates.
    """
    from ._trajectory import Trajectory

    lim = dict(CANNED_LIMITS)
    for name, val in (("speed", speed), ("angular_speed", angular_speed), ("acceleration", acceleration),
                      ("angular_acceleration", angular_acceleration), ("frequency", frequency)):
        if val is None:
            continue
        if isinstance(val, bool) or not isinstance(val, (int, float)) or not (0.0 < val < math.inf):
            raise TrajectoryError(f"{name}: expected a finite number > 0, got {val!r}")
        lim[name] = float(val)
    d = np.asarray(delta, dtype=np.float64).reshape(-1)
    redundant = robot.n_joints == 7
    if d.shape[0] not in (6, 7) or not np.all(np.isfinite(d)):
        raise TrajectoryError(f"delta: expected 6 or 7 finite task-coordinate changes, got {delta!r}")
    if d.shape[0] == 7 and not redundant:
        raise TrajectoryError(f"delta: robot {robot.name!r} has {robot.n_joints} joints; only 7-joint arms "
                              "have an arm angle")
    if redundant and d.shape[0] == 6:
        d = np.append(d, 0.0)
    try:
        q0 = robot.check_limits(q_start).reshape(robot.n_joints)
        x0 = task_coordinates(robot, q0)
    except KinematicsError as exc:
        raise TrajectoryError(f"canned motion from the start configuration: {exc}") from None
    n_x = x0.shape[0]
    vmax = np.array([lim["speed"]] * 3 + [lim["angular_speed"]] * (n_x - 3))
    amax = np.array([lim["acceleration"]] * 3 + [lim["angular_acceleration"]] * (n_x - 3))
    D = np.abs(d)
    D[:3] = 0.0  # the position moves along its line: its limit applies to the distance, not per axis
    D_line = float(np.linalg.norm(d[:3]))
    duration, blend = min_time_trapezoid(np.append(D, D_line), np.append(vmax, lim["speed"]),
                                         np.append(amax, lim["acceleration"]))
    if duration == 0.0:
        raise TrajectoryError("canned motion: delta is zero (no motion)")
    n = pose_samples(duration, lim["frequency"], "canned motion", TrajectoryError)
    times = np.linspace(0.0, duration, n + 1)
    s_path = path_s(times, duration, blend)

    solver = _Solver(robot, n_x == 7)
    qs = [q0]
    for k in range(1, n + 1):
        x_t = x0 + float(s_path[k]) * d
        try:
            q, err = solver.solve(x_t, qs[-1])
        except KinematicsError as exc:
            raise TrajectoryError(f"canned motion: sample {k} of {n} (t = {times[k]:.4g} s): {exc}") from None
        if err > _SOLVE_TOL:
            raise TrajectoryError(f"canned motion: no joint values within the limits reach the task coordinates "
                                  f"at sample {k} of {n} (t = {times[k]:.4g} s; residual {err:.3g})")
        qs.append(q)
    traj = Trajectory(robot.name, robot.joint_names, times, np.stack(qs))
    # The joint path q(s) does not depend on the timing: where a joint would pass its speed limit
    # the whole trapezoid is stretched in time by the excess (the same trapezoid, slower).
    excess = float(np.max(traj.peak_velocity() / robot.max_velocity))
    if excess > 1.0:
        traj = Trajectory(robot.name, robot.joint_names, times * excess * (1.0 + 1e-9), traj.waypoints)
    over = traj.peak_velocity() > robot.max_velocity
    if np.any(over):
        j = int(np.argmax(over))
        raise TrajectoryError(f"canned motion: joint {robot.joint_names[j]!r} would move at "
                              f"{traj.peak_velocity()[j]:.4g} > max_velocity {robot.max_velocity[j]:.4g} "
                              "after stretching (round-off)")
    return traj


def _psi_of_points(p_S, p_E, p_W, reference=(0.0, 0.0, 1.0)) -> float:
    """:func:`arm_angle` from the three points (m, W); plain float arithmetic (3-vectors)."""
    sx, sy, sz = (float(v) for v in p_S)
    wx, wy, wz = float(p_W[0]) - sx, float(p_W[1]) - sy, float(p_W[2]) - sz
    n = math.sqrt(wx * wx + wy * wy + wz * wz)
    if n < _DEGENERATE:
        raise KinematicsError("arm angle: the wrist is at the shoulder")
    ux, uy, uz = wx / n, wy / n, wz / n
    ex, ey, ez = float(p_E[0]) - sx, float(p_E[1]) - sy, float(p_E[2]) - sz
    t = ex * ux + ey * uy + ez * uz
    ex, ey, ez = ex - t * ux, ey - t * uy, ez - t * uz
    rx, ry, rz = (float(v) for v in reference)
    t = rx * ux + ry * uy + rz * uz
    rx, ry, rz = rx - t * ux, ry - t * uy, rz - t * uz
    if math.sqrt(ex * ex + ey * ey + ez * ez) < _DEGENERATE:
        raise KinematicsError("arm angle: undefined with the elbow on the shoulder-wrist line (arm stretched)")
    if math.sqrt(rx * rx + ry * ry + rz * rz) < _DEGENERATE:
        raise KinematicsError("arm angle: undefined with the shoulder-wrist line along the reference (vertical)")
    cx, cy, cz = ry * ez - rz * ey, rz * ex - rx * ez, rx * ey - ry * ex  # r x e
    return math.atan2(ux * cx + uy * cy + uz * cz, rx * ex + ry * ey + rz * ez)


def _psi_gradient(p_S, p_E, p_W, h: float = 1e-7) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(dpsi/dp_S, dpsi/dp_E, dpsi/dp_W)`` (1/m, each (3,)).

    E: analytic, ``(u x e) / |e|^2`` (E turning about the shoulder-wrist line by dpsi moves
    ``|e| dpsi`` along ``u x e / |e|``; along ``u`` or ``e`` it does not change psi).  W: central
    differences of step ``h`` m.  S: ``-(dE + dW)``, psi being unchanged when all three points move
    together."""
    p_S, p_E, p_W = (np.asarray(p, dtype=np.float64) for p in (p_S, p_E, p_W))
    u = (p_W - p_S) / np.linalg.norm(p_W - p_S)
    e = (p_E - p_S) - float((p_E - p_S) @ u) * u
    g_E = np.cross(u, e) / float(e @ e)
    g_W = np.empty(3)
    for a in range(3):
        dp = np.zeros(3)
        dp[a] = h
        g_W[a] = _wrap(_psi_of_points(p_S, p_E, p_W + dp) - _psi_of_points(p_S, p_E, p_W - dp)) / (2.0 * h)
    return -(g_E + g_W), g_E, g_W


class _Solver:
    """Joints for task coordinates: Newton's method on the square (or 6 x n) task equations with
    the geometric Jacobian, seeded by the previous sample; bounded least squares
    (``scipy.optimize.least_squares``, joint limits as bounds) where Newton leaves the limits or
    does not converge."""

    def __init__(self, robot, with_psi: bool) -> None:
        self.robot, self.with_psi = robot, with_psi
        self.idx = [robot.link_names.index(ln) for ln in arm_points(robot)] if with_psi else []
        self.tool = robot.link_names.index(robot.tool_link)
        self.n_x = 7 if with_psi else 6

    def residual(self, q, x_t) -> np.ndarray:
        X_all = self.robot.forward_kinematics(q)
        X = X_all[self.tool]
        X_t = pose_from_xyz_rpy(x_t[:3], x_t[3:6])
        r = np.empty(self.n_x)
        r[:3] = X[:3, 3] - X_t[:3, 3]
        r[3:6] = rotation_vector_from_matrix(X[:3, :3] @ X_t[:3, :3].T)  # about W: R = exp(r) R_t
        if self.with_psi:
            pts = [X_all[i][:3, 3] for i in self.idx]
            r[6] = _wrap(_psi_of_points(*pts) - x_t[6])
        return r

    def jacobian(self, q) -> np.ndarray:
        J = np.empty((self.n_x, self.robot.n_joints))
        J[:6] = self.robot.jacobian(q)  # [v; w]: d(position)/dq, and d(r[3:6])/dq to first order
        if self.with_psi:
            X_all = self.robot.forward_kinematics(q)
            grads = _psi_gradient(*(X_all[i][:3, 3] for i in self.idx))
            J[6] = sum(g @ self.robot.jacobian(q, ln)[:3] for g, ln in zip(grads, arm_points(self.robot)))
        return J

    def solve(self, x_t, q_seed) -> tuple[np.ndarray, float]:
        lo, hi = self.robot.lower, self.robot.upper
        q = np.clip(np.asarray(q_seed, dtype=np.float64), lo, hi)
        r = self.residual(q, x_t)
        for _ in range(20):
            if float(np.max(np.abs(r))) <= 0.01 * _SOLVE_TOL:
                return q, float(np.max(np.abs(r)))
            step = np.linalg.lstsq(self.jacobian(q), -r, rcond=None)[0]
            q_new = q + step
            if np.any(q_new < lo) or np.any(q_new > hi):
                break
            r_new = self.residual(q_new, x_t)
            if np.linalg.norm(r_new) >= np.linalg.norm(r):
                break
            q, r = q_new, r_new
        if float(np.max(np.abs(r))) <= _SOLVE_TOL:
            return q, float(np.max(np.abs(r)))
        from scipy.optimize import least_squares

        free = hi > lo  # a frozen joint (lower == upper) held where it is: scipy's bounds must be strictly increasing
        q = np.clip(np.asarray(q_seed, dtype=np.float64), lo, hi)
        if np.any(free):
            def residual(x, x_t):
                full = q.copy()
                full[free] = x
                return self.residual(full, x_t)

            sol = least_squares(residual, q[free], bounds=(lo[free], hi[free]), args=(x_t,), method="trf",
                                xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=200)
            q = q.copy()
            q[free] = sol.x
        return q, float(np.max(np.abs(self.residual(q, x_t))))
