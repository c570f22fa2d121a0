"""Trajectories: trapezoidal profiles (closed forms), joint interpolation, Cartesian lines through IK,
poses relative to a base frame, sampling, YAML round trip and located errors."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from armguard import SceneFileError, TrajectoryError
from armguard.kinematics import PUMA560_DH, PUMA560_LOWER, PUMA560_UPPER, Robot, Trajectory, pose_from_xyz_rpy
from armguard.kinematics._frames import trans

SETTINGS = settings(max_examples=40, deadline=None, derandomize=True)
VMAX = np.array([1.0, 0.8, 1.2, 2.0, 2.0, 3.0])
AMAX = np.array([2.0, 1.5, 3.0, 4.0, 4.0, 6.0])


@pytest.fixture(scope="module")
def puma() -> Robot:
    return Robot.from_dh("puma560", PUMA560_DH, lower=PUMA560_LOWER, upper=PUMA560_UPPER,
                         max_velocity=VMAX, max_acceleration=AMAX)


def _q(u):
    lo, hi = np.asarray(PUMA560_LOWER), np.asarray(PUMA560_UPPER)
    return lo + np.asarray(u) * (hi - lo)


unit6 = st.lists(st.floats(0.0, 1.0), min_size=6, max_size=6)


@SETTINGS
@given(unit6, unit6)
def test_trapezoid_respects_limits_and_ends_exactly_at_goal(puma, u0, u1):
    q0, q1 = _q(u0), _q(u1)
    if np.allclose(q0, q1):
        return
    tr = Trajectory.trapezoidal(puma, q0, q1)
    assert np.array_equal(tr.at(tr.times[-1]), q1) and np.array_equal(tr.at(tr.times[0]), q0)
    t = np.linspace(0, tr.duration, 401)
    v = tr.velocity(t)
    assert np.all(np.abs(v) <= VMAX * (1 + 1e-9))
    # acceleration by differences of the exact velocity (piecewise linear in t)
    a = np.diff(v, axis=0) / np.diff(t)[:, None]
    assert np.all(np.abs(a) <= AMAX * (1 + 1e-6))
    # time optimal: some joint reaches its velocity or acceleration limit
    assert np.any(np.isclose(tr.peak_velocity(), VMAX)) or np.any(np.isclose(tr.peak_acceleration(), AMAX))
    tr.check(puma)


@pytest.mark.parametrize(
    "D, expected",
    [
        (1.0, (1.0 / 1.0 + 1.0 / 2.0, 0.5)),                 # joint 1: D/v + v/a, blend v/a
        (0.2, (2.0 * math.sqrt(0.2 / 2.0), math.sqrt(0.1))),  # triangular: 2 sqrt(D/a)
    ],
    ids=["trapezoid", "triangle"],
)
def test_single_joint_closed_form_duration(puma, D, expected):
    q1 = np.zeros(6)
    q1[0] = D
    tr = Trajectory.trapezoidal(puma, np.zeros(6), q1)
    assert tr.duration == pytest.approx(expected[0], rel=1e-12)
    assert tr.blend_times[0] == pytest.approx(expected[1], rel=1e-12)
    # closed form s(t) at the end of the blend: a tb^2 / 2 = D tb / (2 (T - tb))
    T, tb = expected
    assert tr.at(tb)[0] == pytest.approx(D * tb / (2 * (T - tb)), rel=1e-12)


def test_every_segment_is_a_straight_joint_space_line(puma):
    W = np.array([[0, 0, 0, 0, 0, 0], [0.5, -0.2, 0.3, 0.1, 0, 0.4], [0.1, 0.3, -0.4, 0.0, 0.5, -0.2]])
    for profile in ("trapezoidal", "linear"):
        tr = Trajectory.joint_interpolated(puma, W, profile=profile)
        t, q = tr.sample(frequency=200)
        for t0, t1, q0, q1 in tr.segments():
            m = (t >= t0) & (t <= t1)
            s = (q[m] - q0) @ (q1 - q0) / ((q1 - q0) @ (q1 - q0))
            np.testing.assert_allclose(q[m], q0 + s[:, None] * (q1 - q0), atol=1e-12)
            assert np.all(np.diff(s) >= -1e-15) and s.min() >= -1e-15 and s.max() <= 1 + 1e-15


def test_velocity_is_the_derivative_of_position(puma):
    tr = Trajectory.joint_interpolated(puma, [[0] * 6, [0.5, -0.2, 0.3, 0.1, 0, 0.4], [0] * 6])
    t = np.linspace(0.01, tr.duration - 0.01, 57)
    h = 1e-6
    np.testing.assert_allclose(tr.velocity(t), (tr.at(t + h) - tr.at(t - h)) / (2 * h), atol=1e-6)


def test_linear_profile_and_given_times(puma):
    W = [[0] * 6, [0.4, 0, 0, 0, 0, 0]]
    lin = Trajectory.joint_interpolated(puma, W, profile="linear")
    assert lin.duration == pytest.approx(0.4 / VMAX[0]) and lin.blend_times[0] == 0.0
    slow = Trajectory.joint_interpolated(puma, W, times=[1.0, 3.0])
    assert slow.duration == 2.0 and slow.at(2.0)[0] == pytest.approx(0.2)
    with pytest.raises(TrajectoryError, match="segment 0: duration 0.1 s is shorter"):
        Trajectory.joint_interpolated(puma, W, times=[0.0, 0.1])


def test_sampling_by_frequency_and_dt(puma):
    tr = Trajectory.joint_interpolated(puma, [[0] * 6, [0.3] * 6], times=[0.0, 1.05])
    t, q = tr.sample(frequency=10.0)
    assert t[0] == 0.0 and t[-1] == 1.05 and len(t) == 12 and q.shape == (12, 6)
    t2, _ = tr.sample(dt=0.35)
    np.testing.assert_allclose(t2, [0, 0.35, 0.7, 1.05], atol=1e-15)
    with pytest.raises(TrajectoryError, match="exactly one"):
        tr.sample()
    with pytest.raises(TrajectoryError, match="> 0"):
        tr.sample(dt=-1.0)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(times=[0, 1, 1], waypoints=np.zeros((3, 2))), "strictly increasing"),
        (dict(times=[0, 1], waypoints=np.zeros((3, 2))), "expected shape"),
        (dict(times=[0, float("nan")], waypoints=np.zeros((2, 2))), "NaN"),
        (dict(times=[0, 1], waypoints=np.zeros((2, 2)), blend_times=[0.7]), "blend_times"),
        (dict(times=[0], waypoints=np.zeros((1, 2))), "at least 2"),
    ],
    ids=["times-not-increasing", "shape", "nan", "blend-too-long", "one-knot"],
)
def test_invalid_trajectory_raises(kwargs, match):
    with pytest.raises(TrajectoryError, match=match):
        Trajectory("r", ["a", "b"], **kwargs)


def test_query_outside_span_or_nan_raises(puma):
    tr = Trajectory.trapezoidal(puma, np.zeros(6), np.full(6, 0.1))
    with pytest.raises(TrajectoryError, match="outside"):
        tr.at(tr.duration + 1.0)
    with pytest.raises(TrajectoryError, match="NaN"):
        tr.at(float("nan"))


def test_waypoint_outside_limits_names_it(puma):
    with pytest.raises(TrajectoryError, match=r"waypoints\[1\].*joint 'joint2'"):
        Trajectory.joint_interpolated(puma, [[0] * 6, [0, 5.0, 0, 0, 0, 0]])


def test_cartesian_line_is_straight_and_reaches_goal(puma):
    q0 = np.array([0.2, 0.5, -0.6, 0.3, 0.6, 0.1])
    X0 = puma.forward_kinematics(q0)[-1]
    goal = puma.forward_kinematics(q0 + [0.15, -0.1, 0.1, 0.1, 0.1, 0.1])[-1]
    tr = Trajectory.cartesian_line(puma, q0, goal, speed=0.1, frequency=100.0)
    np.testing.assert_allclose(puma.forward_kinematics(tr.waypoints[-1])[-1], goal, atol=1e-9)
    P = puma.forward_kinematics(tr.waypoints)[:, -1, :3, 3]
    d = (goal[:3, 3] - X0[:3, 3]) / np.linalg.norm(goal[:3, 3] - X0[:3, 3])
    off_line = np.linalg.norm(np.cross(P - X0[:3, 3], d), axis=1)
    assert off_line.max() < 1e-9  # at the knots (IK-exact); between knots joint-space lines
    speed = np.linalg.norm(np.diff(P, axis=0), axis=1) / np.diff(tr.times)
    assert speed.max() <= 0.1 * (1 + 1e-6)


def test_cartesian_line_with_trapezoidal_speed(puma):
    """Ranger's canned tests: a trapezoidal motion of the end effector along a line."""
    q0 = np.array([0.2, 0.5, -0.6, 0.3, 0.6, 0.1])
    X0 = puma.forward_kinematics(q0)[-1]
    goal = X0.copy()
    goal[:3, 3] += [0.1, 0.0, -0.05]  # a pure translation of 0.1118 m
    L = float(np.hypot(0.1, 0.05))
    tr = Trajectory.cartesian_line(puma, q0, goal, speed=0.1, acceleration=0.2, frequency=200.0)
    assert tr.duration == pytest.approx(L / 0.1 + 0.1 / 0.2, rel=1e-12)  # D/v + v/a
    P = puma.forward_kinematics(tr.waypoints)[:, -1, :3, 3]
    along = (P - X0[:3, 3]) @ (goal[:3, 3] - X0[:3, 3]) / L
    v = np.diff(along) / np.diff(tr.times)
    assert v.max() <= 0.1 * (1 + 1e-6) and v.max() > 0.099
    assert v[0] < 0.01 and v[-1] < 0.01  # starts and ends (nearly) at rest
    tr.check(puma)  # sampled (constant-speed) segments: joint speeds within limits


def test_cartesian_line_relative_to_a_moving_base_frame(puma):
    """WORKMATE: the same relative motion, with the part frame F located at run time."""
    q0 = np.array([0.0, 0.6, -0.7, 0.0, 0.5, 0.0])
    X_FE = pose_from_xyz_rpy([0.0, 0.0, 0.05], [math.pi, 0.0, 0.0])
    for q_part in (q0 + [0.2, 0.1, 0.1, 0.1, -0.1, 0.2], q0 + [-0.2, -0.1, -0.1, -0.1, 0.1, -0.3]):
        X_WF = puma.forward_kinematics(q_part)[-1] @ np.linalg.inv(X_FE)  # the part where q_part reaches it
        tr = Trajectory.cartesian_line(puma, q0, X_FE, X_WF=X_WF, speed=0.2, angular_speed=2.0)
        np.testing.assert_allclose(puma.forward_kinematics(tr.waypoints[-1])[-1], X_WF @ X_FE, atol=1e-9)


def test_cartesian_line_unreachable_goal_names_the_sample(puma):
    q0 = np.array([0.0, 0.6, -0.7, 0.0, 0.5, 0.0])
    with pytest.raises(TrajectoryError, match=r"inverse kinematics failed at sample \d+ of \d+"):
        Trajectory.cartesian_line(puma, q0, trans(2.0, 0.0, 0.0), speed=1.0, frequency=20.0)


@pytest.mark.parametrize("speed", [1e-300, 1e-6])
def test_a_line_too_slow_to_sample_is_refused_before_solving(puma, speed):
    """1e-300 m/s was numpy's raw ValueError from linspace; 1e-6 m/s solved 5 million poses (minutes)."""
    q0 = np.array([0.0, 0.6, -0.7, 0.0, 0.5, 0.0])
    goal = puma.forward_kinematics(q0 + [0.05, -0.05, 0.05, 0.0, 0.05, 0.0])[-1]
    with pytest.raises(TrajectoryError, match=r"cartesian_line: .* poses to solve, more than 100000: raise the speed"):
        Trajectory.cartesian_line(puma, q0, goal, speed=speed, frequency=50.0)
    with pytest.raises(TrajectoryError, match="poses to solve"):
        Trajectory.through_poses(puma, q0, goal[None], mode="line", speed=speed)
    slow = Trajectory.cartesian_line(puma, q0, goal, speed=1e-3, frequency=50.0)  # under the cap: sampled
    assert slow.n_segments == math.ceil(slow.duration * 50.0) and slow.duration > 10.0


def test_through_poses_joint_mode(puma):
    q0 = np.array([0.0, 0.6, -0.7, 0.0, 0.5, 0.0])
    X_WF = trans(0.1, 0.0, -0.05)
    targets = [q0 + d for d in (np.full(6, 0.05), np.full(6, -0.05), np.full(6, 0.1))]
    poses = [np.linalg.inv(X_WF) @ puma.forward_kinematics(q)[-1] for q in targets]
    tr = Trajectory.through_poses(puma, q0, poses, X_WF=X_WF)
    assert tr.waypoints.shape == (4, 6)
    for k, X in enumerate(poses):
        np.testing.assert_allclose(puma.forward_kinematics(tr.waypoints[k + 1])[-1], X_WF @ X, atol=1e-9)
    line = Trajectory.through_poses(puma, q0, poses, X_WF=X_WF, mode="line", speed=0.2, angular_speed=2.0)
    np.testing.assert_allclose(puma.forward_kinematics(line.waypoints[-1])[-1], X_WF @ poses[-1], atol=1e-9)


# ------------------------------------------------------------------ YAML
@SETTINGS
@given(st.integers(2, 6), st.integers(0, 2**31))
def test_yaml_round_trip_is_exact(tmp_path_factory, n, seed):
    rng = np.random.default_rng(seed)
    times = np.cumsum(rng.uniform(0.01, 2.0, n)) - 0.5
    tr = Trajectory("arm", [f"j{i}" for i in range(3)], times, rng.normal(size=(n, 3)),
                    rng.uniform(0, 0.5, n - 1) * np.diff(times))
    path = tmp_path_factory.mktemp("yaml") / "t.yaml"
    tr.save_yaml(path)
    back = Trajectory.load_yaml(path)
    assert back.robot_name == "arm" and back.joint_names == tr.joint_names
    for name in ("times", "waypoints", "blend_times"):
        assert np.array_equal(getattr(back, name), getattr(tr, name))
    assert Trajectory.from_dict(tr.to_dict()).duration == tr.duration


@pytest.mark.parametrize(
    "text, where",
    [
        ("format: armguard.trajectory\nversion: 1\nrobot: r\njoint_names: [a]\ntimes: [0, 1]\n", "waypoints"),
        ("format: armguard.trajectory\nversion: 2\nrobot: r\njoint_names: [a]\ntimes: [0, 1]\nwaypoints: [[0], [1]]\n", "version"),
        ("format: armguard.trajectory\nversion: 1\nrobot: r\njoint_names: [a]\ntimes: [0, 1]\nwaypoints: [[0], [.nan]]\n", "waypoints[1][0]"),
        ("format: armguard.trajectory\nversion: 1\nrobot: r\njoint_names: [a]\ntimes: [0, 1]\nwaypoints: [[0], [1]]\nspeed: 3\n", "speed"),
        ("format: armguard.trajectory\nversion: 1\nrobot: r\njoint_names: [a]\ntimes: [1, 0]\nwaypoints: [[0], [1]]\n", "times"),
        ("times: [0, 1\n", "line 2, column 1"),
    ],
    ids=["missing-key", "version", "nan", "unknown-key", "decreasing-times", "bad-yaml"],
)
def test_bad_yaml_names_file_and_key(tmp_path, text, where):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(SceneFileError) as info:
        Trajectory.load_yaml(path)
    assert info.value.file == str(path) and info.value.where == where


def test_a_trajectory_of_no_joint_is_refused():
    """It moved nothing: verify gave SAFE with the robot held at home, for whatever motion was meant."""
    with pytest.raises(TrajectoryError, match="at least one joint"):
        Trajectory("ur5", [], [0.0, 1.0], np.zeros((2, 0)))
