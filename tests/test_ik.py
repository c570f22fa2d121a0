"""Inverse kinematics: the closed-form PUMA 560 plug-in, the damped-least-squares default, the registry.

Oracle: forward kinematics (a round trip FK(IK(X)) == X), and the independent count of PUMA
solutions (8 for a generic reachable pose, all distinct)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from armguard import IKError, KinematicsError, Tolerances
from armguard.kinematics import (
    PUMA560_DH,
    PUMA560_LOWER,
    PUMA560_UPPER,
    DHRow,
    IKStatus,
    Robot,
    ik_plugin,
    pose_from_xyz_rpy,
    puma560_ik,
    register_ik,
    unregister_ik,
)
from armguard.kinematics._frames import trans

SETTINGS = settings(max_examples=60, deadline=None, derandomize=True)


def _puma(**kw) -> Robot:
    return Robot.from_dh("puma560", PUMA560_DH, lower=PUMA560_LOWER, upper=PUMA560_UPPER, **kw)


def _assert_reaches(robot, res, X, link=None, tol=Tolerances()):
    assert res.status is IKStatus.SUCCESS and res.q is not None
    X_got = robot.forward_kinematics(res.q)[robot.link_index(link or robot.tool_link)]
    np.testing.assert_allclose(X_got[:3, 3], X[:3, 3], atol=tol.ik_position * 10)
    np.testing.assert_allclose(X_got[:3, :3], X[:3, :3], atol=tol.ik_orientation * 10)
    assert res.position_error <= tol.ik_position and res.orientation_error <= tol.ik_orientation
    assert robot.within_limits(res.q)


def test_puma_plugin_is_registered():
    assert ik_plugin("puma560") is puma560_ik


@SETTINGS
@given(st.lists(st.floats(0.0, 1.0), min_size=6, max_size=6))
def test_puma_round_trip_recovers_the_seeded_configuration(u):
    robot = _puma()
    q = np.asarray(PUMA560_LOWER) + np.asarray(u) * (np.asarray(PUMA560_UPPER) - np.asarray(PUMA560_LOWER))
    X = robot.forward_kinematics(q)[-1]
    res = robot.inverse_kinematics(X, q_seed=q)
    _assert_reaches(robot, res, X)
    assert res.iterations <= 20  # a closed form: at most a short polish near a singularity


@pytest.mark.parametrize("eps", [0.0, 1e-12, -1e-12, 1e-10, -1e-10, 1e-9, -1e-9])
def test_puma_reaches_poses_with_the_elbow_stretched(eps):
    """With the elbow stretched, the elbow's cosine rounded past 1 and the closed form called 7 of 20 reachable
    poses "outside the workspace"."""
    robot = _puma()
    rng = np.random.default_rng(0)
    stretched = -math.atan2(0.4318, 0.0203)
    for _ in range(20):
        q = rng.uniform(PUMA560_LOWER, PUMA560_UPPER)
        q[2] = stretched + eps
        X = robot.forward_kinematics(q)[-1]
        _assert_reaches(robot, robot.inverse_kinematics(X, q_seed=q), X)


def test_puma_plugin_gives_eight_distinct_verified_solutions():
    robot = _puma()
    q = np.array([0.3, 0.4, -0.9, 0.5, 0.7, -0.2])
    X_BE = robot.forward_kinematics(q)[-1]
    sols = puma560_ik(robot, X_BE, None)
    assert len(sols) == 8
    wrapped = {tuple(np.round(np.mod(s + math.pi, 2 * math.pi) - math.pi, 6)) for s in sols}
    assert len(wrapped) == 8
    for s in sols:
        np.testing.assert_allclose(robot.forward_kinematics(s)[-1], X_BE, atol=1e-12)


def test_puma_with_base_tool_and_offsets():
    """The plug-in works in the base frame, removes a fixed tool and honours DH angle offsets."""
    rows = [DHRow(r.a, r.alpha, r.d, 0.1 * (i + 1)) for i, r in enumerate(PUMA560_DH)]
    robot = Robot.from_dh("puma560", rows, X_LT=trans(0.0, 0.05, 0.12),
                          X_WB=pose_from_xyz_rpy([0.4, -0.3, 0.8], [0.0, 0.1, 2.0]))
    rng = np.random.default_rng(4)
    for _ in range(10):
        q = rng.uniform(-1.2, 1.2, 6)
        X = robot.forward_kinematics(q)[-1]
        _assert_reaches(robot, robot.inverse_kinematics(X, q_seed=q + 0.05), X)


def test_puma_unreachable_and_out_of_limits():
    robot = _puma()
    far = trans(3.0, 0.0, 0.0)
    res = robot.inverse_kinematics(far)
    assert res.status is IKStatus.UNREACHABLE and res.q is None and not res.ok
    tight = _puma().__class__.from_dh("puma560", PUMA560_DH, lower=[-0.1] * 6, upper=[0.1] * 6)
    X = tight.forward_kinematics(np.array([1.5, 0.2, -0.5, 0.3, 0.4, 0.5]))[-1]
    res = tight.inverse_kinematics(X)
    assert res.status is IKStatus.OUT_OF_LIMITS and res.q is None and "limit" in res.message


def test_puma_plugin_rejects_a_robot_of_another_structure():
    rows = list(PUMA560_DH)
    rows[1] = DHRow(0.4318, 0.3, 0.0)  # alpha_2 must be 0
    robot = Robot.from_dh("puma560", rows)
    with pytest.raises(IKError, match="PUMA 560 structure"):
        robot.inverse_kinematics(np.eye(4))


@pytest.fixture(scope="module")
def seven_dof() -> Robot:
    """A KUKA-iiwa-like 7-DOF chain (standard DH, its published link lengths), finite limits."""
    rows = [DHRow(0, -math.pi / 2, 0.36), DHRow(0, math.pi / 2, 0), DHRow(0, math.pi / 2, 0.42),
            DHRow(0, -math.pi / 2, 0), DHRow(0, -math.pi / 2, 0.4), DHRow(0, math.pi / 2, 0), DHRow(0, 0, 0.126)]
    lim = np.radians([170, 120, 170, 120, 170, 120, 175])
    return Robot.from_dh("iiwa-dh", rows, lower=-lim, upper=lim)


def test_numerical_ik_round_trips_on_a_redundant_arm(seven_dof):
    rng = np.random.default_rng(0)
    ok = 0
    for _ in range(12):
        q = rng.uniform(seven_dof.lower, seven_dof.upper) * 0.8
        X = seven_dof.forward_kinematics(q)[-1]
        res = seven_dof.inverse_kinematics(X, rng=rng)
        if res.ok:
            ok += 1
            _assert_reaches(seven_dof, res, X)
        else:
            assert res.q is None and res.message
    assert ok >= 11  # DLS with restarts; never a wrong pose when it fails


def test_numerical_ik_for_an_intermediate_link(seven_dof):
    q = np.array([0.2, 0.5, -0.3, -1.0, 0.4, 0.8, 0.1])
    X = seven_dof.forward_kinematics(q)[4]
    res = seven_dof.inverse_kinematics(X, link="link4", q_seed=np.zeros(7))
    _assert_reaches(seven_dof, res, X, link="link4")


def test_numerical_ik_reports_no_convergence_for_unreachable_pose(seven_dof):
    res = seven_dof.inverse_kinematics(trans(5.0, 0.0, 0.0), rng=np.random.default_rng(1),
                                       tol=Tolerances(ik_restarts=2, ik_max_iterations=50))
    assert res.status is IKStatus.NO_CONVERGENCE and res.q is None
    assert res.position_error > 3.0 and "best" in res.message


def test_position_only_ik_for_a_five_joint_arm():
    """A 5-DOF arm (the rover's instrument arm kind) reaches points, not arbitrary poses."""
    rows = [DHRow(0.05, math.pi / 2, 0.2), DHRow(0.4, 0, 0), DHRow(0.35, 0, 0), DHRow(0, math.pi / 2, 0),
            DHRow(0, 0, 0.1)]
    arm = Robot.from_dh("arm5", rows, lower=[-3] * 5, upper=[3] * 5)
    q = np.array([0.4, 0.6, -1.1, 0.7, 0.2])
    target = arm.forward_kinematics(q)[-1] @ pose_from_xyz_rpy([0, 0, 0], [0.4, 0.3, 0.0])  # orientation off
    full = arm.inverse_kinematics(target, tol=Tolerances(ik_restarts=2, ik_max_iterations=60))
    assert full.status is IKStatus.NO_CONVERGENCE and full.q is None
    pos = arm.inverse_kinematics(target, position_only=True)
    assert pos.ok and pos.position_error <= 1e-9
    np.testing.assert_allclose(arm.forward_kinematics(pos.q)[-1, :3, 3], target[:3, 3], atol=1e-9)


def test_wrong_plugin_never_yields_a_wrong_pose():
    robot = Robot.from_dh("liar", PUMA560_DH)
    register_ik("liar", lambda robot, X_BE, q_seed: [np.full(6, 0.3)])
    try:
        res = robot.inverse_kinematics(robot.forward_kinematics(np.full(6, 1.0))[-1])
        assert res.status is IKStatus.NO_CONVERGENCE and res.q is None
        register_ik("liar", lambda robot, X_BE, q_seed: [np.zeros(5)])
        with pytest.raises(IKError, match="expected 6 finite joint values"):
            robot.inverse_kinematics(np.eye(4))
    finally:
        unregister_ik("liar")
    assert ik_plugin("liar") is None


def test_ik_rejects_nan_target():
    with pytest.raises(KinematicsError, match="X_WE"):
        _puma().inverse_kinematics(np.full((4, 4), np.nan))


def test_plugin_solution_wrapped_into_limits():
    """Joint 6 of the PUMA turns +-266 deg: a seed beyond pi gets the 2 pi-shifted solution."""
    robot = _puma()
    q = np.array([0.1, 0.2, -0.3, 0.4, 0.5, 4.0])
    X = robot.forward_kinematics(q)[-1]
    res = robot.inverse_kinematics(X, q_seed=q)
    _assert_reaches(robot, res, X)
    assert abs(res.q[5] - 4.0) < 1e-6


def test_the_builtin_puma560_from_urdf_uses_the_closed_form():
    """The built-in puma560 comes from URDF (no DH table): the plug-in identifies its kinematics
    with PUMA560_DH and solves in closed form; a Cartesian line works on it."""
    import armguard
    from armguard.kinematics import Trajectory, ik_plugin

    robot = next(iter(armguard.load_model("puma560").scene.robots.values()))
    assert robot.dh is None and ik_plugin(robot.name) is not None
    rng = np.random.default_rng(5)
    for q in rng.uniform(-0.8, 0.8, size=(10, 6)):
        X_WE = robot.link_pose(q, robot.tool_link)
        cands = ik_plugin(robot.name)(robot, np.linalg.inv(robot.link_pose(q, robot.link_names[0])) @ X_WE, None)
        assert cands, q
        assert min(np.abs(robot.link_pose(c, robot.tool_link) - X_WE).max() for c in cands) < 1e-9
        res = robot.inverse_kinematics(X_WE)
        assert res.status.value == "success" and np.abs(robot.link_pose(res.q, robot.tool_link) - X_WE).max() < 1e-9
    q0 = np.array([0.1, -0.3, 0.2, 0.1, 0.4, 0.0])
    goal = robot.link_pose(q0, robot.tool_link).copy()
    goal[:3, 3] += [0.05, 0.0, -0.05]
    traj = Trajectory.cartesian_line(robot, q0, goal, speed=0.2)
    assert np.abs(robot.link_pose(traj.waypoints[-1], robot.tool_link) - goal).max() < 1e-6


def test_the_puma_plugin_refuses_a_robot_that_is_not_a_puma():
    import armguard
    from armguard._errors import IKError
    from armguard.kinematics._puma import puma560_ik

    robot = next(iter(armguard.load_model("ur5").scene.robots.values()))
    with pytest.raises(IKError, match="does not move its link 6 as the PUMA 560"):
        puma560_ik(robot, np.eye(4), None)


# ---------------------------------------------------------------- the routine the model file names (ik:)
def _closed_form_calls(monkeypatch):
    """Count calls of the registered PUMA 560 routine."""
    from armguard.kinematics import _ik

    calls = []
    original = _ik._PLUGINS["puma560"]

    def counted(robot, X_BE, q_seed):
        calls.append(robot.name)
        return original(robot, X_BE, q_seed)

    monkeypatch.setitem(_ik._PLUGINS, "puma560", counted)
    return calls


def test_the_builtin_puma560_names_its_closed_form_in_the_model_file(monkeypatch):
    import armguard

    robot = armguard.load_model("puma560").scene.robots["puma560"]
    assert robot.ik == "puma560"
    calls = _closed_form_calls(monkeypatch)
    res = robot.inverse_kinematics(robot.link_pose(np.array([0.1, 0.5, -1.0, 0.2, -0.5, 0.3]), robot.tool_link))
    assert res.status.value == "success" and calls == ["puma560"]
    # the routine follows the file, not the name: a robot renamed still uses it
    renamed = robot.with_name("arm_a")
    assert renamed.ik == "puma560"
    renamed.inverse_kinematics(renamed.link_pose(np.zeros(6), renamed.tool_link))
    assert calls == ["puma560", "arm_a"]


def _scene_with_ik(tmp_path, ik_line: str):
    import armguard
    from armguard.model import models_dir

    text = (models_dir() / "puma560" / "puma560.yaml").read_text().replace("ik: {puma560: puma560}", ik_line)
    (tmp_path / "puma560").mkdir(exist_ok=True)
    for f in (models_dir() / "puma560").iterdir():
        if f.suffix != ".yaml":
            target = tmp_path / "puma560" / f.name
            if not target.exists():
                target.symlink_to(f)
    path = tmp_path / "puma560" / "cell.yaml"
    path.write_text(text)
    return armguard.load_model(path)


def test_a_model_file_may_name_the_numeric_solver_or_a_module_function(tmp_path, monkeypatch):
    calls = _closed_form_calls(monkeypatch)
    robot = _scene_with_ik(tmp_path, "ik: {puma560: numeric}").scene.robots["puma560"]
    X = robot.link_pose(np.array([0.1, 0.5, -1.0, 0.2, -0.5, 0.3]), robot.tool_link)
    assert robot.inverse_kinematics(X).status.value == "success" and calls == []  # damped least squares
    robot = _scene_with_ik(tmp_path, "ik: {puma560: 'armguard.kinematics._puma:puma560_ik'}").scene.robots["puma560"]
    res = robot.inverse_kinematics(X)
    assert res.status.value == "success" and res.iterations == 0  # closed form: no iteration


@pytest.mark.parametrize("line, match", [
    ("ik: {puma560: nonesuch}", r"ik\.puma560.*unknown IK routine 'nonesuch'"),
    ("ik: {puma560: 'no_such_module:f'}", r"ik\.puma560.*cannot import"),
    ("ik: {arm9: numeric}", r"ik\.arm9.*unknown robot"),
])
def test_an_unknown_ik_routine_is_a_located_error(tmp_path, line, match):
    from armguard._errors import SceneFileError

    with pytest.raises(SceneFileError, match=match):
        _scene_with_ik(tmp_path, line)


def test_a_robot_without_a_routine_warns_once_when_a_command_needs_ik():
    from armguard._errors import ArmguardWarning
    from armguard.kinematics import _ik

    robot = Robot.from_dh("no_routine_arm", [(0.0, 0.0, 0.3, 0.0), (0.0, 0.0, 0.3, 0.0)])
    _ik._WARNED.discard(robot.name)
    X = robot.link_pose(np.array([0.3, 0.2]), robot.tool_link)
    with pytest.warns(ArmguardWarning, match="names no IK routine"):
        robot.inverse_kinematics(X, position_only=False)
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error", ArmguardWarning)
        robot.inverse_kinematics(X)  # once per robot
        robot.with_ik("numeric").with_name("named_numeric").inverse_kinematics(X)  # named: no warning
