"""Kinematic models: frames, DH chains, trees, couplings, batched FK vs the reference, Jacobians, errors.

Oracles: closed forms (products of the textbook DH A-matrices, WORKMATE's trans·rot(z)·rot(y)·rot(x)),
the slow NumPy reference FK, and central finite differences for the Jacobian.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from armguard import KinematicsError
from armguard.geometry import Sphere
from armguard.kinematics import (
    PUMA560_DH,
    Coupling,
    DHRow,
    JointSpec,
    JointType,
    Robot,
    dh_modified,
    dh_standard,
    invert_pose,
    pose_from_xyz_rpy,
    xyz_rpy_from_pose,
)
from armguard.kinematics._frames import rot_x, rot_y, rot_z, rotation_vector_from_matrix, trans

SETTINGS = settings(max_examples=40, deadline=None, derandomize=True)
angles = st.floats(-math.pi, math.pi, allow_nan=False)
lengths = st.floats(-2.0, 2.0, allow_nan=False)


def _chain(rows, convention="standard", **kw):
    return Robot.from_dh("chain", rows, convention=convention, **kw)


def _tree_robot() -> Robot:
    """A branching tree: base -> a (revolute x) -> {b (prismatic), c (revolute, mimic of a)}, c -> d (fixed)."""
    R = pose_from_xyz_rpy([0.1, -0.2, 0.3], [0.3, -0.4, 0.5])
    specs = [
        JointSpec("ja", JointType.REVOLUTE, "base", "a", R, axis=[1.0, 0.0, 0.0]),
        JointSpec("jb", JointType.PRISMATIC, "a", "b", pose_from_xyz_rpy([0, 0.2, 0], [0, 0, 0.7]), axis=[0, 1.0, 1.0]),
        JointSpec("jc", JointType.REVOLUTE, "a", "c", pose_from_xyz_rpy([0.3, 0, 0], [1.0, 0, 0]), axis=[0, 0, 1.0],
                  coupling=Coupling("jc", {"ja": -2.0, "je": 0.5}, 0.25)),
        JointSpec("jd", JointType.FIXED, "c", "d", pose_from_xyz_rpy([0, 0, 0.4], [0, 0.2, 0])),
        JointSpec("je", JointType.REVOLUTE, "d", "e", pose_from_xyz_rpy([0.1, 0.1, 0], [0, 0, 0]), axis=[0.3, 0.4, 0.5]),
    ]
    return Robot("tree", "base", specs, X_WB=pose_from_xyz_rpy([1, 2, 3], [0.1, 0.2, 0.3]))


# ------------------------------------------------------------------ frames
@SETTINGS
@given(st.tuples(lengths, lengths, lengths), st.tuples(angles, st.floats(-1.5, 1.5), angles))
def test_pose_from_xyz_rpy_is_workmate_product_and_inverts(xyz, rpy):
    X = pose_from_xyz_rpy(xyz, rpy)
    expected = trans(*xyz) @ rot_z(rpy[2]) @ rot_y(rpy[1]) @ rot_x(rpy[0])
    np.testing.assert_allclose(X, expected, atol=1e-15)
    xyz2, rpy2 = xyz_rpy_from_pose(X)
    np.testing.assert_allclose(pose_from_xyz_rpy(xyz2, rpy2), X, atol=1e-12)
    np.testing.assert_allclose(rpy2, rpy, atol=1e-9)


@SETTINGS
@given(st.sampled_from([-1.0, 1.0]), st.floats(1e-9, 1e-2), angles, angles)
def test_xyz_rpy_from_pose_near_gimbal_lock_reproduces_the_rotation(sign, off, roll, yaw):
    """Near gimbal lock ``atan2(R21, R22)`` divides entries of size ``cos(pitch)``: the angles alone
    lose digits (so101's URDF: 3.7e-6 rad from pi/2 gave 3.2e-11), the rotation they make must not."""
    from scipy.spatial.transform import Rotation

    # made through a quaternion (as a URDF reader may): entries right to ~1e-16 absolute, so the two
    # of size cos(pitch) are not right to 1e-16 relative
    X = np.eye(4)
    X[:3, :3] = Rotation.from_euler("ZYX", [yaw, sign * (math.pi / 2 - off), roll]).as_matrix()
    X[:3, 3] = [0.1, -0.2, 0.3]
    X2 = pose_from_xyz_rpy(*xyz_rpy_from_pose(X))
    np.testing.assert_allclose(X2, X, rtol=0, atol=1e-14)


def test_xyz_rpy_from_pose_at_gimbal_lock_reproduces_pose():
    X = pose_from_xyz_rpy([0, 0, 0], [0.3, math.pi / 2, 0.8])
    np.testing.assert_allclose(pose_from_xyz_rpy(*xyz_rpy_from_pose(X)), X, atol=1e-12)


@pytest.mark.parametrize("angle", [0.0, 1e-9, 0.5, 2.0, math.pi - 1e-7, math.pi], ids=lambda a: f"{a:.3g}")
def test_rotation_vector_round_trip(angle):
    from armguard.kinematics._frames import rotation_about_axis

    k = np.array([0.2, -0.6, 0.77])
    k /= np.linalg.norm(k)
    w = rotation_vector_from_matrix(rotation_about_axis(k, angle)[:3, :3])
    assert abs(np.linalg.norm(w) - angle) < 1e-12
    if angle > 1e-6:
        np.testing.assert_allclose(w / np.linalg.norm(w), k, atol=1e-7)


def test_pose_from_xyz_rpy_rejects_nan():
    with pytest.raises(KinematicsError, match="rpy"):
        pose_from_xyz_rpy([0, 0, 0], [0, float("nan"), 0])


# ------------------------------------------------------------------ DH chains
dh_rows = st.lists(
    st.tuples(lengths, angles, lengths, angles, st.sampled_from(["revolute", "prismatic"])), min_size=1, max_size=7
)


@pytest.mark.parametrize("convention", ["standard", "modified"])
@SETTINGS
@given(rows=dh_rows, data=st.data())
def test_dh_chain_fk_equals_product_of_a_matrices(convention, rows, data):
    robot = _chain([DHRow(*r) for r in rows], convention)
    q = np.array(data.draw(st.lists(angles, min_size=len(rows), max_size=len(rows))))
    X_WL = robot.forward_kinematics(q)
    A = dh_standard if convention == "standard" else dh_modified
    T = np.eye(4)
    for i, (a, alpha, d, theta, jt) in enumerate(rows):
        T = T @ (A(a, alpha, d, theta + q[i]) if jt == "revolute" else A(a, alpha, d + q[i], theta))
        np.testing.assert_allclose(X_WL[i + 1], T, atol=1e-12)


def test_puma_home_pose_closed_form():
    """PUMA 560 at q = 0 (Corke's table), worked by hand from the A-matrices; Corke's *Robotics,
    Vision and Control* prints the same translation for ``p560.fkine(qz)``: (0.4521, -0.1500, 0.4318) m."""
    robot = Robot.from_dh("p", PUMA560_DH)
    X = robot.forward_kinematics(np.zeros(6))[-1]
    # q = 0: link 2 along x (a2), link 3 adds a3 along x, d3 along -y (z1 = -y), d4 along +z (z3 = +z)
    np.testing.assert_allclose(X[:3, 3], [0.4318 + 0.0203, -0.15005, 0.4318], atol=1e-12)


@SETTINGS
@given(st.integers(0, 3), st.integers(1, 6))
def test_batched_fk_matches_reference_for_any_batch_shape(lead_ndim, size):
    robot = _tree_robot()
    rng = np.random.default_rng(lead_ndim * 10 + size)
    shape = (size,) * lead_ndim + (robot.n_joints,)
    q = rng.uniform(-3, 3, shape)
    X = robot.forward_kinematics(q)
    assert X.shape == shape[:-1] + (len(robot.link_names), 4, 4)
    np.testing.assert_allclose(X, robot.forward_kinematics_reference(q), atol=1e-13)


def _random_tree(seed: int) -> Robot:
    """A random tree: parents, joint kinds, axes, origins, post transforms and mimic couplings."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 9))
    specs, movable = [], []
    for i in range(1, n + 1):
        kind = [JointType.FIXED, JointType.REVOLUTE, JointType.PRISMATIC][int(rng.integers(0, 3))]
        coupling = None
        if kind is not JointType.FIXED and movable and rng.random() < 0.3:
            src = movable[int(rng.integers(0, len(movable)))]
            coupling = Coupling(f"j{i}", {src: float(rng.normal())}, float(rng.normal()))
        post = pose_from_xyz_rpy(rng.normal(size=3), rng.normal(size=3)) if rng.random() < 0.5 else None
        specs.append(JointSpec(f"j{i}", kind, f"l{int(rng.integers(0, i))}", f"l{i}",
                               pose_from_xyz_rpy(rng.normal(size=3), rng.normal(size=3)),
                               axis=rng.normal(size=3), X_post=post, coupling=coupling))
        if kind is not JointType.FIXED and coupling is None:
            movable.append(f"j{i}")
    return Robot("random", "l0", specs, X_WB=pose_from_xyz_rpy(rng.normal(size=3), rng.normal(size=3)))


@SETTINGS
@given(st.integers(0, 10**6))
def test_fk_kernel_matches_reference_on_random_trees(seed):
    robot = _random_tree(seed)
    q = np.random.default_rng(seed).uniform(-3, 3, (4, robot.n_joints))
    np.testing.assert_allclose(robot.forward_kinematics(q), robot.forward_kinematics_reference(q), atol=1e-12)
    np.testing.assert_allclose(robot.jacobian(q[0], robot.link_names[-1], [0.1, 0.2, 0.3]),
                               robot.jacobian_reference(q[0], robot.link_names[-1], [0.1, 0.2, 0.3]), atol=1e-12)


def test_tree_structure_and_coupling_values():
    robot = _tree_robot()
    assert robot.joint_names == ("ja", "jb", "je")
    assert robot.link_names == ("base", "a", "b", "c", "d", "e")
    assert robot.parent_link("e") == "d" and robot.parent_link("base") is None
    assert robot.adjacent_pairs == frozenset({("a", "base"), ("a", "b"), ("a", "c"), ("c", "d"), ("d", "e")})
    q = np.array([0.3, 0.1, -0.7])
    v = robot.flat_tree.joint_values(q)
    assert v[robot.link_index("c")] == pytest.approx(0.25 - 2.0 * 0.3 + 0.5 * -0.7)
    np.testing.assert_allclose(robot.forward_kinematics(np.zeros(3))[0], robot.X_WB, atol=0)


def test_gmf_s480_parallelogram_keeps_forearm_orientation():
    """GMF S-480 (WORKMATE, seed 004): through the parallelogram the forearm's pitch follows its own
    actuator only.  In DH the elbow angle is a drive coupling theta3 = q3 - q2, so link 3's absolute
    pitch (theta2 + theta3) does not change when the upper arm (q2) moves."""
    rows = [DHRow(0.3, -math.pi / 2, 0.9), DHRow(0.9, 0.0, 0.0), DHRow(0.15, -math.pi / 2, 0.0)]
    robot = Robot.from_dh("gmf", rows, joint_names=["j1", "j2", "j3"], couplings=[Coupling("j3", {"j3": 1.0, "j2": -1.0})])
    assert robot.joint_names == ("j1", "j2", "j3")
    np.testing.assert_allclose(robot.flat_tree.joint_values(np.array([0.2, 0.9, 0.4]))[3], 0.4 - 0.9)
    q_a = np.array([0.2, 0.1, 0.4])
    q_b = np.array([0.2, 0.9, 0.4])
    R_a = robot.forward_kinematics(q_a)[3, :3, :3]
    R_b = robot.forward_kinematics(q_b)[3, :3, :3]
    np.testing.assert_allclose(R_a, R_b, atol=1e-12)
    assert not np.allclose(robot.forward_kinematics(q_a)[3, :3, 3], robot.forward_kinematics(q_b)[3, :3, 3])


# ------------------------------------------------------------------ Jacobian
def _numeric_jacobian(robot, q, link, p_L, h=1e-6):
    J = np.zeros((6, robot.n_joints))
    for k in range(robot.n_joints):
        dq = np.zeros(robot.n_joints)
        dq[k] = h
        Xp = robot.forward_kinematics(q + dq)[robot.link_index(link)]
        Xm = robot.forward_kinematics(q - dq)[robot.link_index(link)]
        J[:3, k] = ((Xp[:3, :3] @ p_L + Xp[:3, 3]) - (Xm[:3, :3] @ p_L + Xm[:3, 3])) / (2 * h)
        J[3:, k] = rotation_vector_from_matrix(Xp[:3, :3] @ Xm[:3, :3].T) / (2 * h)
    return J


@pytest.mark.parametrize("which", ["tree-e", "tree-b", "tree-c", "puma-tool"])
def test_jacobian_equals_finite_differences(which):
    rng = np.random.default_rng(7)
    if which.startswith("tree"):
        robot, link = _tree_robot(), which[-1]
    else:
        robot = Robot.from_dh("p", PUMA560_DH, X_LT=trans(0.01, 0.02, 0.1), X_WB=pose_from_xyz_rpy([1, 0, 0], [0, 0, 1]))
        link = "tool"
    for _ in range(5):
        q = rng.uniform(-2, 2, robot.n_joints)
        p_L = rng.uniform(-0.3, 0.3, 3)
        J = robot.jacobian(q, link, p_L)
        np.testing.assert_allclose(J, _numeric_jacobian(robot, q, link, p_L), atol=1e-7)


def test_jacobian_kernel_matches_reference():
    robot = _tree_robot()
    q = np.random.default_rng(9).uniform(-2, 2, (7, robot.n_joints))
    for link in robot.link_names:
        np.testing.assert_allclose(robot.jacobian(q, link, [0.1, -0.2, 0.3]),
                                   robot.jacobian_reference(q, link, [0.1, -0.2, 0.3]), atol=1e-14)


def test_jacobian_broadcasts_over_batches():
    robot = _tree_robot()
    q = np.random.default_rng(1).uniform(-1, 1, (4, 3, robot.n_joints))
    J = robot.jacobian(q)
    assert J.shape == (4, 3, 6, robot.n_joints)
    np.testing.assert_allclose(J[2, 1], robot.jacobian(q[2, 1]), atol=1e-15)


# ------------------------------------------------------------------ copies and shapes
def test_with_base_moves_every_link_rigidly():
    robot = Robot.from_dh("p", PUMA560_DH)
    X_WB = pose_from_xyz_rpy([0.5, -0.2, 0.8], [0.1, 0.2, 0.3])
    q = np.random.default_rng(3).uniform(-1, 1, (5, 6))
    moved = robot.with_base(X_WB)
    np.testing.assert_allclose(moved.forward_kinematics(q), X_WB @ robot.forward_kinematics(q), atol=1e-14)
    assert robot.X_WB.tolist() == np.eye(4).tolist()  # the original is unchanged


def test_with_link_shapes_and_name_return_copies():
    robot = Robot.from_dh("p", PUMA560_DH)
    s = Sphere([0, 0, 0], 0.1)
    r2 = robot.with_link_shapes({"link3": [s]}).with_name("other")
    assert r2.link_shapes["link3"] == (s,) and robot.link_shapes["link3"] == ()
    assert r2.name == "other" and robot.name == "p"
    with pytest.raises(KinematicsError, match="unknown link 'nope'"):
        robot.with_link_shapes({"nope": [s]})


def test_tool_transform_appends_tool_link():
    robot = Robot.from_dh("p", PUMA560_DH, X_LT=trans(0, 0, 0.2))
    assert robot.link_names[-1] == "tool" and robot.tool_link == "tool"
    X = robot.forward_kinematics(np.full(6, 0.3))
    np.testing.assert_allclose(X[-1], X[-2] @ trans(0, 0, 0.2), atol=1e-15)


def test_limits_per_row_or_per_independent_joint():
    rows = [DHRow(0.1, 0, 0)] * 3
    c = [Coupling("joint2", {"joint1": 1.0})]
    a = _chain(rows, lower=[-1, -2, -3], upper=[1, 2, 3], couplings=c)
    b = _chain(rows, lower=[-1, -3], upper=[1, 3], couplings=c)
    np.testing.assert_array_equal(a.lower, [-1, -3])
    np.testing.assert_array_equal(b.upper, [1, 3])
    assert a.within_limits([0.5, 2.9]) and not a.within_limits([0.5, 3.1])


# ------------------------------------------------------------------ bad input
@pytest.mark.parametrize(
    "q, match",
    [
        ([0.0, float("nan"), 0, 0, 0, 0], "NaN"),
        ([0.0, 0, 0, float("inf"), 0, 0], "NaN or infinite"),
        ([0.0] * 5, "6 values"),
        (np.zeros((3, 7)), "6 values"),
        ("abc", "numbers"),
    ],
    ids=["nan", "inf", "short", "batch-wrong-length", "not-numbers"],
)
def test_bad_q_raises(q, match):
    robot = Robot.from_dh("p", PUMA560_DH)
    with pytest.raises(KinematicsError, match=match):
        robot.forward_kinematics(q)


@pytest.mark.parametrize(
    "rows, match",
    [
        ([(0.1, 0.0, float("nan"))], "DH row 0.*DHRow.d"),
        ([(0.1, 0.0)], "DH row 0"),
        ([(0.1, 0.0, 0.0, 0.0, "spherical")], "unknown joint type 'spherical'"),
        ([{"a": 1, "alpha": 0, "d": 0, "bogus": 1}], "unknown keys"),
        ([], "at least one row"),
    ],
    ids=["nan-d", "too-short", "bad-type", "unknown-key", "empty"],
)
def test_bad_dh_row_raises(rows, match):
    with pytest.raises(KinematicsError, match=match):
        Robot.from_dh("bad", rows)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(couplings=[Coupling("joint9", {"joint1": 1})]), "unknown joint 'joint9'"),
        (dict(couplings=[Coupling("joint2", {"joint3": 1}), Coupling("joint3", {"joint2": 1})]), "cycle"),
        (dict(lower=[0, 0], upper=[1, 1]), "expected 3 values"),
        (dict(lower=[1, 0, 0], upper=[0, 1, 1]), "lower <= upper"),
        (dict(convention="craig"), "convention"),
        (dict(link_names=["a", "b"]), "link_names"),
        (dict(X_WB=np.full((4, 4), np.nan)), "X_WB"),
    ],
    ids=["coupling-unknown", "coupling-cycle", "limits-length", "limits-order", "convention", "link-names", "nan-base"],
)
def test_bad_model_raises(kwargs, match):
    with pytest.raises(KinematicsError, match=match):
        _chain([DHRow(0.1, 0, 0)] * 3, **kwargs)


def test_unknown_link_lists_links():
    robot = Robot.from_dh("p", PUMA560_DH)
    with pytest.raises(KinematicsError, match="unknown link 'hand'"):
        robot.link_index("hand")


def test_check_limits_names_the_joint():
    robot = Robot.from_dh("p", PUMA560_DH, lower=[-1] * 6, upper=[1] * 6)
    with pytest.raises(KinematicsError, match="joint 'joint4' = 1.5"):
        robot.check_limits([0, 0, 0, 1.5, 0, 0])


def test_robot_pickles_for_distributed_workers():
    import pickle

    robot = _tree_robot().with_link_shapes({"e": [Sphere([0, 0, 0.1], 0.05)]})
    back = pickle.loads(pickle.dumps(robot))
    q = np.array([0.3, 0.1, -0.2])
    np.testing.assert_array_equal(back.forward_kinematics(q), robot.forward_kinematics(q))
    assert back.joint_names == robot.joint_names and back.couplings == robot.couplings
    assert back.link_shapes["e"][0].radius == 0.05


def test_invert_pose_is_inverse():
    X = pose_from_xyz_rpy([1, 2, 3], [0.4, 0.5, 0.6])
    np.testing.assert_allclose(invert_pose(X) @ X, np.eye(4), atol=1e-15)
