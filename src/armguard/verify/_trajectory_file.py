"""What a verification is given, checked against its scene: a trajectory file (its errors located in the
file), the trajectory argument itself, and the other robots' configurations (``q_others``)."""

from __future__ import annotations

import os

import numpy as np

__all__ = ["load_trajectory", "trajectory_of", "within_limits"]


def load_trajectory(scene, path):
    """The :class:`armguard.kinematics.Trajectory` in the YAML file ``path`` (``docs/trajectory-format.md``),
    checked against ``scene`` (a Scene or Model): its robot is one of the scene's, its joints are
    joints of that robot (a subset is fine: the others are held at home), each named once, and every
    waypoint is within the joint's limits.  ``joint_names`` may name an SRDF group of the Model.

    Any problem raises :class:`armguard.SceneFileError` naming the file, the key, its line and what
    was expected, e.g. ``traj.yaml: waypoints[1][1] (line 8): joint 'j2' = 9 is outside its limits
    [-0.785398, 3.92699]``.  :func:`armguard.verify` calls this for a path; ``armguard verify`` for
    each ``.yaml`` argument."""
    from .._errors import SceneFileError, TrajectoryError
    from .._lines import lines_for
    from .._tolerance import DEFAULT_TOLERANCES
    from ..kinematics import Trajectory
    from ..model import scene_of

    scene = scene_of(scene)  # a Model: its scene
    file = os.fspath(path)
    grouped: dict = {}  # the SRDF group the file names -> the robot it moves

    def groups(name: str):  # an SRDF group of the scene's Model (made only for a file that names one)
        from ..model import model_of

        model = model_of(scene, geometry=False)
        if model.srdf is None:
            raise TrajectoryError("no model with SRDF groups to resolve it")
        grouped[name], joints = model.group_robot_joints(name)
        return joints

    traj = Trajectory.load_yaml(file, groups=groups)
    with lines_for(file):
        for name, robot_of_group in grouped.items():  # arms may share joint names (ranger's j1 ...)
            if robot_of_group != traj.robot_name:
                raise SceneFileError(file, "joint_names", f"SRDF group {name!r} moves robot {robot_of_group!r}, "
                                     f"not the file's robot {traj.robot_name!r}")
        if traj.robot_name not in scene.robots:
            raise SceneFileError(file, "robot", f"robot {traj.robot_name!r} is not in scene {scene.name!r} "
                                 f"(its robots: {', '.join(scene.robots)})")
        robot = scene.robots[traj.robot_name]
        want = list(robot.joint_names)
        names = list(traj.joint_names)
        unknown = [j for j in names if j not in want]
        twice = [j for k, j in enumerate(names) if j in names[:k]]
        if unknown or twice:
            import difflib

            near = difflib.get_close_matches(unknown[0], want, n=1) if unknown else []
            what = (f"{unknown[0]!r} is not a joint of robot {traj.robot_name!r}" + (f" (did you mean {near[0]!r}?)" if near else "")
                    if unknown else f"{twice[0]!r} is named twice")
            raise SceneFileError(file, "joint_names", f"{what}; expected some of its joints {want}")
        slack = DEFAULT_TOLERANCES.joint_limit
        idx = [want.index(n) for n in names]
        lo, hi = np.asarray(robot.lower, dtype=float)[idx], np.asarray(robot.upper, dtype=float)[idx]
        W = np.asarray(traj.waypoints, dtype=float)
        bad = np.argwhere((W < lo - slack) | (W > hi + slack))  # every value outside, waypoint by waypoint
        if len(bad):
            k, j = (int(x) for x in bad[0])
            more = "; ".join(f"waypoints[{a}][{b}] {names[b]!r} = {W[a, b]:.6g}" for a, b in bad[1:6])
            more = (f"; {len(bad) - 1} more outside: {more}" + ("; ..." if len(bad) > 6 else "")) if len(bad) > 1 else ""
            rev = [robot.joint_types[i].value != "prismatic" for i in idx]
            looks_deg = any(rev[b] and abs(W[a, b]) > 2.0 * np.pi for a, b in bad)
            hint = " (a trajectory file's angles are radians: these look like degrees)" if looks_deg else ""
            raise SceneFileError(file, f"waypoints[{k}][{j}]", f"joint {names[j]!r} = {W[k, j]:.10g} is outside its "
                                 f"limits [{lo[j]:.10g}, {hi[j]:.10g}]{more}{hint}")
    return traj


def trajectory_of(scene, trajectory, name: str | None):
    """``(Trajectory, name)``: a path is read and checked against the scene (:func:`load_trajectory`:
    an error names the file, the key and its line; the name defaults to the file's stem); anything
    but a Trajectory is refused saying what was expected."""
    from .._errors import VerificationError
    from ..kinematics import Trajectory
    from ._subdivide import Subdivided

    if isinstance(trajectory, (str, os.PathLike)):
        path = os.fspath(trajectory)
        return load_trajectory(scene, path), name or os.path.splitext(os.path.basename(path))[0]
    if not isinstance(trajectory, (Trajectory, Subdivided)):
        raise VerificationError(f"trajectory: expected an armguard.kinematics.Trajectory or the path of a "
                                f"trajectory YAML file, got {type(trajectory).__name__}")
    return trajectory, name


def within_limits(robot, q, where: str):
    """``q`` (a robot's joint values) when it has one value per joint, each within the joint's limits (to
    ``Tolerances.joint_limit``); else a VerificationError naming ``where`` and the joint."""
    from .._errors import VerificationError
    from .._tolerance import DEFAULT_TOLERANCES

    names = list(robot.joint_names)
    if q.shape != (len(names),):
        raise VerificationError(f"{where}: expected {len(names)} values (one per joint {names}), got shape {q.shape}")
    slack = DEFAULT_TOLERANCES.joint_limit
    for i, name in enumerate(names):
        lo, hi = float(robot.lower[i]), float(robot.upper[i])
        if not lo - slack <= q[i] <= hi + slack:
            raise VerificationError(f"{where}: joint {name!r} = {q[i]:.10g} is outside its limits [{lo:.10g}, {hi:.10g}]")
    return q
