"""A review of kinematics and model in/out: each test is a defect found by running it (wrong answers first).

A joint type given as its string ("prismatic") was exported and checked as revolute (CLEAR at a
collision); limits and joint values that were NaN, booleans or of the wrong length passed; files were
written that did not load back; raw Python errors where a named refusal belongs.
"""

from __future__ import annotations

import math
import shutil

import numpy as np
import pytest
import yaml

import armguard
from armguard import KinematicsError, OutputError, SceneError, SceneFileError, TrajectoryError
from armguard.geometry import Sphere
from armguard.kinematics import JointSpec, JointType, Robot, Trajectory
from armguard.scene import Scene, load_scene, save_scene


def _slider(joint_type) -> Scene:
    """One prismatic joint along x: link l1 (a 5 cm sphere) reaches a ball body at x = 0.5 m at q = 0.5."""
    r = Robot("r", "base", [JointSpec("slide", joint_type, "base", "l1", np.eye(4), axis=[1, 0, 0], lower=-1, upper=1)],
              link_shapes={"l1": [Sphere([0, 0, 0], 0.05)]})
    s = Scene("s")
    s.add_robot(r)
    s.add_body("ball", [Sphere([0.5, 0, 0], 0.05)])
    return s


@pytest.mark.parametrize("joint_type", [JointType.PRISMATIC, "prismatic"])
def test_a_joint_type_given_as_text_is_that_type(joint_type):
    scene = _slider(joint_type)
    assert scene.robots["r"].joints[0].joint_type is JointType.PRISMATIC
    model = armguard.model.model_of(scene)
    X = model.link_poses(np.array([0.5]))
    np.testing.assert_allclose(X["r"][1, :3, 3], [0.5, 0.0, 0.0], atol=1e-12)  # it slides; "prismatic" rotated
    report = armguard.Detector(scene).check(np.array([0.5]))
    assert report.status.name == "COLLISION", report  # was CLEAR


def test_a_fixed_joint_given_as_text_adds_no_joint_and_a_misspelt_type_is_named():
    def robot(jt):
        return Robot("r", "base", [JointSpec("j0", "revolute", "base", "l1", np.eye(4)),
                                   JointSpec("tool", jt, "l1", "tool", np.eye(4))])

    assert robot("fixed").joint_names == robot(JointType.FIXED).joint_names == ("j0",)
    with pytest.raises(KinematicsError, match="joint 'tool': unknown joint type 'fixd'"):
        robot("fixd")
    with pytest.raises(KinematicsError, match="joint 'j': lower: expected a number"):
        JointSpec("j", "revolute", "a", "b", np.eye(4), lower="x")


@pytest.fixture(scope="module")
def ur5():
    return armguard.load_model("ur5")


def test_limit_checks_refuse_nan_and_wrong_lengths(ur5):
    q = ur5.neutral()
    for bad, said in ((q[:3], "expected shape"), (np.r_[q, 99.0], "expected shape"), (np.r_[np.nan, q[1:]], "contains NaN"),
                      (q[None, :3], "expected shape"), (np.ones(6, bool), "expected real joint values")):
        with pytest.raises(KinematicsError, match=said):  # a short q passed (zip), NaN raised a TypeError
            ur5.check_pin_limits(bad)
    ur5.check_pin_limits(q)
    ur5.check_pin_limits(ur5.random_q(3, 0))
    for bad, said in (([np.nan] * 6, "contains NaN"), ([99.0], "expected shape"), ([0.0, 0.0], "expected shape")):
        with pytest.raises(KinematicsError, match=said):  # [99.0] was broadcast over every joint
            ur5.check_limits(bad)
    ur5.check_limits([0.0] * 6)


def test_joint_values_that_are_booleans_or_complex_are_refused(ur5):
    robot = ur5.robots["ur5"]
    for call in (lambda: ur5.link_poses(np.ones(6, bool)), lambda: ur5.link_poses(np.ones(6, complex)),
                 lambda: robot.forward_kinematics([True] * 6), lambda: robot.jacobian(np.ones(6, bool))):
        with pytest.raises(KinematicsError, match="expected real joint values"):
            call()


def test_pin_q_and_random_q_check_their_arguments(ur5):
    with pytest.raises(armguard.ArmguardError, match="q_scene: expected 6 values"):
        ur5.pin_q([0.0, 0.0])
    for n in (2.7, True, -1, "a", math.nan):
        with pytest.raises(armguard.ArmguardError, match="random_q: n: expected an integer >= 0"):
            ur5.random_q(n)
    with pytest.raises(armguard.ArmguardError, match="random_q: rng"):
        ur5.random_q(2, rng="x")
    assert ur5.random_q(2.0, 0).shape == (2, ur5.nq)


def test_a_ranger_scene_from_its_urdf_is_not_saved_as_a_file_that_does_not_load(tmp_path):
    with pytest.raises(SceneError, match="holds the arms"):
        save_scene(load_scene("ranger"), tmp_path / "ranger.yaml")
    assert not (tmp_path / "ranger.yaml").exists()


def test_a_prismatic_joint_without_limits_is_refused_where_it_is_written(tmp_path):
    """A scene file's prismatic joint without limits loaded, then every check failed on the URDF it became
    (naming a deleted temporary file); a Robot with such a joint, or a one-sided revolute one, likewise."""
    doc = {"armguard_scene": 1, "name": "s", "units": {"angle": "deg", "length": "m"},
           "robots": [{"name": "arm", "joints": [{"a": 0.3, "limits": [-90, 90]}, {"type": "prismatic", "a": 0.0, "d": 0.1}],
                       "link_shapes": {"link2": [{"type": "sphere", "xyz": [0, 0, 0], "radius": 0.05}]}}]}
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump(doc))
    with pytest.raises(SceneFileError, match=r"robots\[0\]\.joints\[1\].*a prismatic joint needs limits"):
        load_scene(path)
    doc["robots"][0]["joints"][1]["limits"] = [-0.1, 0.1]
    path.write_text(yaml.safe_dump(doc))
    assert load_scene(path).robots["arm"].upper[1] == 0.1
    from armguard.kinematics import DHRow

    r = Robot.from_dh("arm", [DHRow(0.3, 0, 0), DHRow(0.0, 0, 0.1, joint_type="prismatic")], lower=[-1, -math.inf],
                      upper=[1, math.inf], link_shapes={"link2": [Sphere([0, 0, 0], 0.05)]})
    s = Scene("s")
    s.add_robot(r)
    with pytest.raises(SceneError, match="joint 'joint2' \\(prismatic\\).*needs both limits finite"):
        armguard.model.model_of(s)
    with pytest.raises(SceneError, match="a prismatic joint without limits cannot be written"):
        save_scene(s, tmp_path / "out.yaml")
    assert not (tmp_path / "out.yaml").exists()


def test_trajectory_inputs_are_named(ur5):
    robot = ur5.robots["ur5"]
    home = ur5.scene.home("ur5")
    tr = Trajectory.joint_interpolated(robot, [home, home + 0.1])
    for kwargs, said in ((dict(frequency=0), "frequency: expected a finite number > 0"),  # ZeroDivisionError
                         (dict(frequency="x"), "frequency: expected"), (dict(dt=True), "dt: expected"),
                         (dict(dt=1e-300), "samples of 1e-300 s")):  # numpy: "Maximum allowed size exceeded"
        with pytest.raises(TrajectoryError, match=said):
            tr.sample(**kwargs)
    with pytest.raises(KinematicsError, match="q must have 6 values"):
        Trajectory.trapezoidal(robot, home[:3], home)
    for names in (5, "j1"):  # "j1" was read as the joints ('j', '1')
        with pytest.raises(TrajectoryError, match="joint_names: expected a sequence"):
            Trajectory("ur5", names, [0.0, 1.0], [[0.0], [1.0]])
    with pytest.raises(TrajectoryError, match=r"parts\[1\]: expected a Trajectory, got str"):
        Trajectory.concatenate([tr, "x"])


def test_export_into_what_is_not_a_folder_is_an_output_error(tmp_path):
    from armguard.model.export import export_scene

    src = armguard.load_model("gmf_s480").scene
    a_file = tmp_path / "afile"
    a_file.write_text("x")
    with pytest.raises(OutputError, match="afile"):
        export_scene(src, a_file / "out")
    (tmp_path / "d").mkdir()
    (tmp_path / "d" / "meshes").write_text("x")
    with pytest.raises(OutputError, match="meshes: it exists and is not a folder"):
        export_scene(src, tmp_path / "d")


def test_package_dirs_may_be_one_folder(tmp_path):
    """``package_dirs="<folder>"`` was read as one-letter folders ("mesh file not found")."""
    from armguard.model._public import public_robot_files

    urdf, _ = public_robot_files("ur5")
    share = next(p for p in urdf.parents if p.name == "share")
    copy = tmp_path / "ur5.urdf"
    shutil.copy(urdf, copy)
    one = armguard.load_model(copy, package_dirs=str(share))
    listed = armguard.load_model(copy, package_dirs=[share])
    assert [g.meshPath for g in one.collision_model.geometryObjects] == \
        [g.meshPath for g in listed.collision_model.geometryObjects]


def test_frame_helpers_and_builders_name_what_they_refuse():
    from armguard.kinematics import Coupling, DHRow, invert_pose, xyz_rpy_from_pose

    for call, said in ((lambda: invert_pose(np.eye(3)), r"expected rigid transforms \(\.\.\., 4, 4\)"),  # IndexError
                       (lambda: invert_pose("x"), "expected rigid transforms"),
                       (lambda: xyz_rpy_from_pose(np.diag([2.0, 2.0, 2.0, 1.0])), "not a rigid transform"),  # rpy 0
                       (lambda: Robot.from_dh("r", [DHRow(0.1, 0, 0)], lower=["x"], upper=[1]), "lower: expected numbers"),
                       (lambda: Coupling("j", [1, 2]), r"terms: expected a mapping"),
                       (lambda: Robot("r", "base", [1]), r"joints\[0\]: expected a JointSpec"),
                       (lambda: Robot.from_dh("r", [DHRow(0.1, 0, 0)]).with_link_shapes([1]), "expected a mapping")):
        with pytest.raises(KinematicsError, match=said):
            call()
    X = invert_pose(np.stack([np.eye(4)] * 2))
    assert X.shape == (2, 4, 4)
