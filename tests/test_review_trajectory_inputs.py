"""Trajectory builders and files turn bad input into a TrajectoryError / SceneFileError, never a bare numpy error.

Found in review: ``Trajectory.joint_interpolated(robot, W, max_velocity=[1, 2])`` on a 3-joint
arm (and ``max_velocity="fast"``) raised numpy's ValueError about broadcasting.
"""

from __future__ import annotations

import pytest

from armguard import TrajectoryError
from armguard.kinematics import Trajectory

from _verify_fixtures import planar_arm

W = [[1.0, 0.0, 0.0], [2.0, 0.5, 0.0]]


@pytest.mark.parametrize(
    "kwargs",
    [{"max_velocity": [1.0, 2.0]}, {"max_velocity": "fast"}, {"max_acceleration": [[1.0, 2.0, 3.0]] * 2},
     {"max_acceleration": {"j1": 1.0}}],
    ids=["velocity-count", "velocity-text", "acceleration-2d", "acceleration-mapping"],
)
def test_bad_limits_raise_trajectory_error(kwargs):
    with pytest.raises(TrajectoryError, match="max_"):
        Trajectory.joint_interpolated(planar_arm(), W, **kwargs)


def test_scalar_and_per_joint_limits_still_work():
    arm = planar_arm()  # max_velocity 1 rad/s, max_acceleration 2 rad/s^2 per joint
    slow = Trajectory.joint_interpolated(arm, W, max_velocity=0.5)
    same = Trajectory.joint_interpolated(arm, W, max_velocity=[0.5, 0.5, 0.5])
    assert slow.duration == same.duration > Trajectory.joint_interpolated(arm, W).duration


def test_trajectory_file_with_an_integer_beyond_float_range_names_the_key(tmp_path):
    # found in review: ``times: [0, 1000...0]`` (an integer YAML reads exactly, too big for a
    # float) escaped as a bare OverflowError
    path = tmp_path / "big.yaml"
    path.write_text(
        "format: armguard.trajectory\nversion: 1\nrobot: arm\njoint_names: [joint1, joint2, joint3]\n"
        f"times: [0, 1{'0' * 400}]\nwaypoints: [[0, 0, 0], [1, 0, 0]]\n",
        encoding="utf-8",
    )
    from armguard import SceneFileError

    with pytest.raises(SceneFileError) as err:
        Trajectory.load_yaml(path)
    assert err.value.file == str(path) and err.value.where == "times"


def test_a_trajectory_naming_no_robot_is_verified_on_the_scenes_only_one():
    """``Trajectory(None, ...)`` named the robot 'None', and the verifier refused it ("robot 'None' is not in the
    scene") where a trajectory naming no robot is meant for the scene's only robot."""
    import numpy as np

    import armguard
    from armguard.kinematics import Trajectory

    m = armguard.load_model("ur5")
    names = list(m.scene.robots["ur5"].joint_names)
    q0 = m.scene_q(m.neutral())  # the one robot's joints, in its order
    t = Trajectory(None, names, [0.0, 1.0], np.vstack([q0, q0]))
    assert t.robot_name == ""
    assert armguard.verify(m, t).status is not None


@pytest.mark.parametrize("times, waypoints, blends, said", [
    ([0.0, 1e-310], [[0.0], [1e-300]], None, "are so close that the speed"),  # 1 / dt overflows: at() was NaN
    ([0.0, 1.0], [[0.0], [1.0]], [5e-311], "blend_times[0]: 5e-311 s is too short to divide by"),
])
def test_a_subnormal_segment_or_blend_is_refused_never_nan(times, waypoints, blends, said):
    with pytest.raises(TrajectoryError) as err:
        Trajectory("r", ["a"], times, waypoints, blends)
    assert said in str(err.value)
