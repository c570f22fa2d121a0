"""Ranger's canned-test motions (Bon & Seraji, seed 000 section 6): "a trapezoidal trajectory in
one or more of the six end-effector coordinates or the arm angle".

The references here are written independently of ``armguard.kinematics._task_motion``: the
trapezoid as its textbook piecewise law (distance ``L``, cruise speed ``v``, acceleration ``a``),
the arm angle by turning the elbow about the shoulder-wrist line with Rodrigues' formula, its
gradient by central differences.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from armguard import SceneFileError
from armguard.kinematics import CANNED_LIMITS, arm_angle, task_coordinates, task_trapezoid
from armguard.kinematics._task_motion import _psi_gradient, _psi_of_points
from armguard.models import builtin_path
from armguard.scene import load_scene, save_scene

V, A = CANNED_LIMITS["speed"], CANNED_LIMITS["acceleration"]
W_V, W_A = CANNED_LIMITS["angular_speed"], CANNED_LIMITS["angular_acceleration"]


@pytest.fixture(scope="module")
def ranger():
    return load_scene("ranger")


def _trapezoid(t, T, tb):
    """Fraction of the way (0..1) at times ``t`` of a rest-to-rest trapezoid of duration ``T``, blend ``tb``."""
    v = 1.0 / (T - tb)  # peak speed (fraction / s)
    a = v / tb
    out = []
    for x in np.asarray(t, dtype=float):
        if x <= tb:
            out.append(0.5 * a * x * x)
        elif x <= T - tb:
            out.append(0.5 * a * tb * tb + v * (x - tb))
        else:
            out.append(1.0 - 0.5 * a * (T - x) ** 2)
    return np.array(out)


def _angle(X, Y) -> float:
    """The rotation angle (rad) between the orientations of poses X and Y."""
    R = X[:3, :3].T @ Y[:3, :3]
    return math.acos(max(-1.0, min(1.0, 0.5 * (np.trace(R) - 1.0))))


def _pose_error(X, Y) -> float:
    """Largest of the position error (m) and the rotation angle between X and Y (rad)."""
    return max(float(np.linalg.norm(X[:3, 3] - Y[:3, 3])), _angle(X, Y))


@pytest.mark.parametrize("name", ["test1_left_inward", "test3_left_forward_up", "test7_right_inward"])
def test_cartesian_canned_test_is_a_straight_line_with_a_trapezoidal_speed(ranger, name):
    ct = ranger.canned_tests[name]
    assert ct.mode == "end_effector" and np.all(ct.end_effector[3:] == 0.0)
    robot = ranger.robots[ct.robot]
    tr = ct.trajectory(ranger)
    dp = ct.end_effector[:3]
    L = float(np.linalg.norm(dp))
    assert L >= V * V / A  # long enough to cruise: T = L / v + v / a, blend v / a
    T, tb = L / V + V / A, V / A
    assert tr.duration == pytest.approx(T, rel=1e-12)  # no joint near its speed limit: not stretched
    X = robot.forward_kinematics(tr.waypoints)[:, -1]
    p = X[:, :3, 3]
    expected = p[0] + np.outer(_trapezoid(tr.times, T, tb), dp)
    assert np.max(np.linalg.norm(p - expected, axis=1)) < 1e-6  # on the line, at the trapezoid's place
    assert max(_angle(X[0], Xk) for Xk in X) < 1e-6  # the orientation held
    psi = [arm_angle(robot, q) for q in tr.waypoints]
    assert np.max(np.abs(np.asarray(psi) - psi[0])) < 1e-6  # the redundancy held
    speed = np.linalg.norm(np.diff(p, axis=0), axis=1) / np.diff(tr.times)
    assert speed.max() <= V * (1 + 1e-6) and speed.max() > 0.99 * V
    dt = float(tr.times[1])
    assert speed[0] == pytest.approx(0.5 * A * dt, rel=1e-6) == speed[-1]  # from rest, to rest


@pytest.mark.parametrize("name", ["test5_left_arm_angle_up", "test6_left_arm_angle_down", "test9_right_arm_angle"])
def test_arm_angle_canned_test_keeps_the_tool_pose(ranger, name):
    ct = ranger.canned_tests[name]
    assert ct.mode == "arm_angle"
    robot = ranger.robots[ct.robot]
    tr = ct.trajectory(ranger)
    X = robot.forward_kinematics(tr.waypoints)[:, -1]
    assert max(_pose_error(X[0], Xk) for Xk in X) < 1e-6
    psi = np.array([arm_angle(robot, q) for q in tr.waypoints])
    d = abs(ct.arm_angle)
    T0 = d / W_V + W_V / W_A  # the trapezoid the angular limits give; stretched if a joint is too fast
    k = tr.duration / T0
    assert k >= 1.0 and np.all(tr.peak_velocity() <= robot.max_velocity)
    expected = psi[0] + ct.arm_angle * _trapezoid(tr.times, tr.duration, k * W_V / W_A)
    assert np.max(np.abs(psi - expected)) < 1e-6
    assert abs(psi[-1] - psi[0] - ct.arm_angle) < 1e-9


def test_an_orientation_motion_turns_about_the_held_position(ranger):
    ct = ranger.canned_tests["test8_left_wrist_pitch"]
    robot = ranger.robots[ct.robot]
    tr = ct.trajectory(ranger)
    x = np.array([task_coordinates(robot, q) for q in tr.waypoints])
    assert np.max(np.abs(x[:, :3] - x[0, :3])) < 1e-9
    T = tr.duration
    expected = x[0] + np.outer(_trapezoid(tr.times, T, T * (W_V / W_A) / (ct.end_effector[4] / W_V + W_V / W_A)),
                               np.append(ct.end_effector, 0.0))
    assert np.max(np.abs(x - expected)) < 1e-6


_coord = st.floats(-1.0, 1.0, allow_nan=False)
_point = st.tuples(_coord, _coord, _coord).map(np.array)


def _rodrigues(v, axis, angle):
    k = axis / np.linalg.norm(axis)
    return v * math.cos(angle) + np.cross(k, v) * math.sin(angle) + k * float(k @ v) * (1 - math.cos(angle))


@settings(max_examples=200, deadline=None)
@given(_point, _point, _point, st.floats(-3.0, 3.0))
def test_turning_the_elbow_about_the_shoulder_wrist_line_turns_the_arm_angle(S, E, W, alpha):
    u = W - S
    if np.linalg.norm(u) < 0.05 or np.linalg.norm(np.cross(u, E - S)) < 0.05 * np.linalg.norm(u) \
            or np.linalg.norm(np.cross(u, [0, 0, 1])) < 0.05 * np.linalg.norm(u):
        return  # degenerate: the arm angle is undefined there
    E2 = S + _rodrigues(E - S, u, alpha)
    turned = _psi_of_points(S, E2, W) - _psi_of_points(S, E, W)
    assert math.remainder(turned - alpha, 2 * math.pi) == pytest.approx(0.0, abs=1e-9)
    # psi = 0 with the elbow in the vertical plane through S-W, above the line
    up = np.array([0.0, 0.0, 1.0]) - (u @ [0, 0, 1]) / (u @ u) * u
    assert _psi_of_points(S, S + 0.3 * u + up, W) == pytest.approx(0.0, abs=1e-9)


@settings(max_examples=100, deadline=None)
@given(_point, _point, _point)
def test_arm_angle_gradient_matches_central_differences(S, E, W):
    u = W - S
    if np.linalg.norm(u) < 0.1 or np.linalg.norm(np.cross(u, E - S)) < 0.1 * np.linalg.norm(u) \
            or np.linalg.norm(np.cross(u, [0, 0, 1])) < 0.1 * np.linalg.norm(u):
        return
    grads = _psi_gradient(S, E, W)
    h = 1e-6
    for i, g in enumerate(grads):
        num = np.empty(3)
        for a in range(3):
            P_hi, P_lo = [S.copy(), E.copy(), W.copy()], [S.copy(), E.copy(), W.copy()]
            P_hi[i][a] += h
            P_lo[i][a] -= h
            num[a] = math.remainder(_psi_of_points(*P_hi) - _psi_of_points(*P_lo), 2 * math.pi) / (2 * h)
        np.testing.assert_allclose(g, num, atol=1e-5 * max(1.0, float(np.abs(num).max())))


def test_arm_angle_motion_needs_a_bent_elbow(ranger):
    from armguard import TrajectoryError

    robot = ranger.robots["left_arm"]
    with pytest.raises(TrajectoryError, match="arm stretched"):
        task_trapezoid(robot, np.zeros(7), [0, 0, 0, 0, 0, 0, 0.5])
    with pytest.raises(TrajectoryError, match="only 7-joint arms"):
        task_trapezoid(ranger.robots["grapple_arm"], np.zeros(6), [0, 0, 0, 0, 0, 0, 0.5])
    with pytest.raises(TrajectoryError, match="no motion"):
        task_trapezoid(robot, np.radians([0, 30, 0, 60, 0, 30, 0]), np.zeros(6))


def test_a_canned_motion_too_slow_to_sample_is_refused(ranger):
    from armguard import TrajectoryError

    robot = ranger.robots["left_arm"]
    q0 = np.radians([0, 30, 0, 60, 0, 30, 0])
    with pytest.raises(TrajectoryError, match=r"canned motion: .* poses to solve"):
        task_trapezoid(robot, q0, [0.05, 0, 0, 0, 0, 0], speed=1e-300)


def test_unreachable_end_effector_motion_names_the_sample(ranger):
    from armguard import TrajectoryError

    robot = ranger.robots["left_arm"]
    with pytest.raises(TrajectoryError, match=r"sample \d+ of \d+"):
        task_trapezoid(robot, np.radians([0, 30, 0, 60, 0, 30, 0]), [2.0, 0, 0, 0, 0, 0])


def test_canned_motions_survive_save_and_load(tmp_path):
    scene = load_scene(builtin_path("ranger"))  # the scene file (DH arms): save_scene writes it back whole
    back = load_scene(save_scene(scene, tmp_path / "ranger.yaml"))
    for name, ct in scene.canned_tests.items():
        b = back.canned_tests[name]
        assert b.mode == ct.mode, name
        if ct.mode == "end_effector":
            np.testing.assert_allclose(b.end_effector, ct.end_effector, rtol=0, atol=1e-12)
        else:
            assert b.arm_angle == pytest.approx(ct.arm_angle, abs=1e-12)


@pytest.mark.parametrize("motion, message", [
    ("{goal: [0, 0, 0, 0, 0, 0, 0], arm_angle: 10}", "exactly one of"),
    ("{}", "exactly one of"),
    ("{end_effector: [0, 0, 0.1]}", "at least 6"),
])
def test_a_bad_canned_motion_names_its_place(tmp_path, motion, message):
    text = builtin_path("ranger").read_text()
    text = text.replace("motion: {end_effector: [0, -1.0, 0, 0, 0, 0]}", f"motion: {motion}", 1)
    p = tmp_path / "ranger.yaml"
    p.write_text(text)
    with pytest.raises(SceneFileError) as err:
        load_scene(p)
    assert "canned_tests[0].motion" in str(err.value) and message in str(err.value)


def test_arm_angle_motion_of_a_six_joint_arm_is_refused(tmp_path):
    text = builtin_path("ranger").read_text()
    i = text.index("  - name: test9_right_arm_angle")
    block = text[i:].split("  - name: test10", 1)[0]
    bad = block.replace("robot: right_arm", "robot: grapple_arm")
    p = tmp_path / "ranger.yaml"
    p.write_text(text.replace(block, bad))
    with pytest.raises(SceneFileError) as err:
        load_scene(p)
    assert "canned_tests[8]" in str(err.value) and "7-joint arm" in str(err.value)


_small = st.floats(-0.15, 0.15, allow_nan=False)


@functools.lru_cache(maxsize=1)
def _ranger_left_arm():
    return load_scene("ranger").robots["left_arm"]


@settings(max_examples=6, deadline=None)
@given(st.tuples(_small, _small, _small), st.floats(-0.3, 0.3, allow_nan=False))
def test_any_small_task_motion_follows_its_trapezoid(dp, dpsi):
    """Invariant: from a pose with the elbow at 90 deg (the shoulder-wrist line 0.74 m of the arm's
    1.05 m, so 0.26 m of motion cannot stretch it), every sample of a motion in the position and the
    arm angle is at ``x0 + s(t) delta`` (one shared trapezoid), orientation held, within the limits."""
    robot = _ranger_left_arm()
    q0 = np.radians([0, 30, 0, 90, 0, 40, 0])
    delta = np.array([*dp, 0.0, 0.0, 0.0, dpsi])
    if np.linalg.norm(delta) < 1e-3:
        return
    tr = task_trapezoid(robot, q0, delta)
    x = np.array([task_coordinates(robot, q) for q in tr.waypoints])
    k = int(np.argmax(np.abs(delta)))
    s = (x[:, k] - x[0, k]) / delta[k]  # the shared path parameter, read off the largest coordinate
    assert s[0] == 0.0 and s[-1] == pytest.approx(1.0, abs=1e-9) and np.all(np.diff(s) >= -1e-9)
    np.testing.assert_allclose(x - x[0], np.outer(s, delta), atol=1e-9)
    assert np.all(tr.waypoints >= robot.lower) and np.all(tr.waypoints <= robot.upper)
    assert np.all(tr.peak_velocity() <= robot.max_velocity)


def test_a_frozen_joint_stays_put_in_a_task_motion():
    """A joint with lower == upper (a URDF <limit> without bounds) made scipy's bounded solve raise a raw ValueError
    ("Each lower bound must be strictly less than each upper bound") when Newton's method stopped short."""
    import warnings

    import armguard
    from armguard.kinematics import Robot, task_trapezoid
    from armguard.models import builtin_path

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sc = armguard.load_scene(str(builtin_path("ranger")))
    arm = sc.robots["left_arm"]
    conv, rows = arm.dh
    lo, hi = np.array(arm.lower), np.array(arm.upper)
    lo[6] = hi[6] = 0.0
    r = Robot.from_dh("left_arm", rows, convention=conv, lower=lo, upper=hi, max_velocity=arm.max_velocity,
                      max_acceleration=arm.max_acceleration, X_WB=arm.X_WB)
    tr = task_trapezoid(r, np.radians([0, 30, 0, 90, 0, 40, 0]), [0, -0.1, 0, 0, 0, 0])
    assert np.all(tr.waypoints[:, 6] == 0.0) and all(r.within_limits(w) for w in tr.waypoints)
