"""The joint values of a YAML scene file (:mod:`._scenefile`): a robot's in file units, checked against its limits,
and the canned tests and trajectories made from them; each failure at its place (``ctx.error``)."""

from __future__ import annotations

import math

import numpy as np

from .._errors import ArmguardError
from ._scene import CannedTest, Scene


def _q_scale(robot, ctx) -> np.ndarray:
    """Per-joint factor from file units to SI: angle for revolute joints, length for prismatic."""
    return np.array([ctx.L if jt.value == "prismatic" else ctx.A for jt in robot.joint_types])


def _canned_test(scene: Scene, c, ctx, w: str) -> None:
    if c.robot not in scene.robots:
        raise ctx.error(f"{w}.robot", f"unknown robot {c.robot!r}; robots are {list(scene.robots)}")
    setup = {}
    for rname, q in c.setup.items():
        if rname not in scene.robots:
            raise ctx.error(f"{w}.setup.{rname}", f"unknown robot {rname!r}")
        setup[rname] = _joint_values(scene.robots[rname], q, ctx, f"{w}.setup.{rname}")
    m = c.motion
    goal = None if m.goal is None else _joint_values(scene.robots[c.robot], m.goal, ctx, f"{w}.motion.goal")
    ee = None if m.end_effector is None else np.asarray(m.end_effector, dtype=np.float64) * ([ctx.L] * 3 + [ctx.A] * 3)
    psi = None if m.arm_angle is None else m.arm_angle * ctx.A
    try:
        scene.add_canned_test(CannedTest(c.name, c.description, c.robot, c.threshold * ctx.L, setup, goal, ee, psi))
    except ArmguardError as exc:
        raise ctx.error(w, str(exc)) from None


def _joint_values(robot, q, ctx, where: str) -> np.ndarray:
    if len(q) != robot.n_joints:
        raise ctx.error(where, f"expected {robot.n_joints} joint values {list(robot.joint_names)}, got {len(q)}")
    return np.asarray(q, dtype=np.float64) * _q_scale(robot, ctx)


def _in_limits(robot, q, ctx, where: str) -> None:
    """Refuse ``q`` (SI) with a joint outside its limits at ``where``: value and limits in the file's units,
    and a word on them where a radian or metre value that large looks like degrees or millimetres."""
    bad = np.flatnonzero((q < robot.lower) | (q > robot.upper))
    if bad.size:
        j = int(bad[0])
        s = _q_scale(robot, ctx)[j]
        rev = robot.joint_types[j].value != "prismatic"
        unit = ("deg" if ctx.A != 1.0 else "rad") if rev else ("mm" if ctx.L != 1.0 else "m")
        hint = ""
        if rev and ctx.A == 1.0 and abs(q[j]) > 2.0 * math.pi:
            hint = " (read as radians: a file in degrees says units: {angle: deg})"
        elif not rev and ctx.L == 1.0 and abs(q[j]) > 10.0:
            hint = " (read as metres: a file in millimetres says units: {length: mm})"
        raise ctx.error(where, f"joint {robot.joint_names[j]!r} = {q[j] / s:.6g} {unit} is outside its limits "
                               f"[{robot.lower[j] / s:.6g}, {robot.upper[j] / s:.6g}] {unit}{hint}")


def _trajectory(scene: Scene, t, ctx, where: str) -> None:
    from ..kinematics import Trajectory

    if t.robot not in scene.robots:
        raise ctx.error(f"{where}.robot", f"unknown robot {t.robot!r}; robots are {list(scene.robots)}")
    robot = scene.robots[t.robot]
    wps = np.stack([_joint_values(robot, q, ctx, f"{where}.waypoints[{k}]") for k, q in enumerate(t.waypoints)])
    for k, q in enumerate(wps):
        _in_limits(robot, q, ctx, f"{where}.waypoints[{k}]")
    try:
        traj = Trajectory.joint_interpolated(robot, wps, times=t.times, profile=t.profile)
        scene.add_trajectory(t.name, traj)
    except ArmguardError as exc:
        raise ctx.error(where, str(exc)) from None
    scene._trajectory_specs[t.name] = {"robot": t.robot, "waypoints": wps, "times": t.times,
                                       "profile": t.profile, "description": t.description}
