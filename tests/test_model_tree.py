"""The Model's kinematic tree compiled from its Pinocchio model (``Model.kinematic_tree``, ``armguard.model._tree``).

Held to three references: Pinocchio's own ``forwardKinematics`` + ``updateFramePlacements`` (the
scene link's pose is ``oMf[link_frames[link]] @ link_placement(link)``), the Robots' trees
(``armguard.detect._common.combined_tree``, the engine's tree before; slow reference
``fk_reference``), and the Detector's distances with the old tree swapped back in.  Every
built-in model and every installed public robot (continuous joints: kinova; mimic: panda's
finger, gmf_s480's coefficient -1 parallelogram), plus scenes built in code (DH rows with
``X_post``, a two-term coupling with an offset that the URDF export writes as a chain of two mimics).
"""

from __future__ import annotations

import functools
import types
import warnings

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import armguard
from armguard import DetectionError
from armguard.detect._common import combined_tree
from armguard.geometry import Sphere
from armguard.kinematics._fk import fk_kernel, fk_reference
from armguard.model import builtin_model_names, known_models, load_model, model_of
from armguard.scene import Scene
from armguard_analytic._engine import _model as engine_model
from armguard.model._tree import pin_tree

from _verify_fixtures import planar_arm

MODELS = list(builtin_model_names()) + [k.name for k in known_models() if k.source != "built-in"]
_AVAILABLE = {k.name: k.available for k in known_models()}


@functools.lru_cache(maxsize=None)
def _model(name):
    if not _AVAILABLE.get(name, False):
        pytest.skip(f"{name} is not installed")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_model(name)


@functools.lru_cache(maxsize=None)
def _coupled_scene() -> Scene:
    """A scene built in code: a DH arm (``X_post`` on every row) whose joint 5 is a two-term
    coupling with an offset, a planar arm mounted off the origin, and a robot of JointSpecs (no DH
    table, no URDF) with unaligned axes and an ``X_post``."""
    from test_detect_cylinder import cylinder_scene

    sc = cylinder_scene()
    X = np.eye(4)
    X[:3, 3] = [0.3, -0.2, 0.1]
    sc.add_robot(planar_arm("planar").with_base(X), self_pairs=[])
    from armguard.kinematics import JointSpec, JointType, Robot, pose_from_xyz_rpy

    specs = [JointSpec("turn", JointType.REVOLUTE, "base", "l1", pose_from_xyz_rpy([0.1, 0, 0.2], [0.3, 0, 0]),
                       np.array([0.6, 0.0, 0.8]), lower=-2.0, upper=2.0, X_post=pose_from_xyz_rpy([0, 0.1, 0], [0, 0.2, 0])),
             JointSpec("reach", JointType.PRISMATIC, "l1", "l2", pose_from_xyz_rpy([0.2, 0, 0], [0, 0, 0.5]),
                       np.array([0.48, 0.6, 0.64]), lower=0.0, upper=0.3)]
    sc.add_robot(Robot("specs", "base", specs, link_shapes={"l2": (Sphere([0.0, 0.0, 0.0], 0.05),)}), self_pairs=[])
    return sc


def _scene_of(name):
    return _coupled_scene() if name == "coded" else _model(name).scene


def _limits(scene):
    rs = list(scene.robots.values())
    lo, hi = np.concatenate([r.lower for r in rs]), np.concatenate([r.upper for r in rs])
    return np.where(np.isfinite(lo), lo, -np.pi), np.where(np.isfinite(hi), hi, np.pi)


def _q(scene, u):
    lo, hi = _limits(scene)
    u = np.resize(np.asarray(u, dtype=np.float64), len(lo))
    return lo + u * (hi - lo)


_U = st.lists(st.floats(0.0, 1.0), min_size=1, max_size=40)
_SETTINGS = settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])


def _pin_poses(model, q_scene):
    pm = model.pin_model
    d = pm.createData()
    pin.forwardKinematics(pm, d, model.pin_q(q_scene))
    pin.updateFramePlacements(pm, d)
    sc = model.scene
    return np.stack([d.oMf[model.link_frames[f"{r}/{ln}"]].homogeneous @ model.link_placement(f"{r}/{ln}")
                     for r in sc.robots for ln in sc.robots[r].link_names])


@pytest.mark.parametrize("name", MODELS + ["coded"])
@_SETTINGS
@given(u=_U)
def test_fk_equals_pinocchio(name, u):
    scene = _scene_of(name)
    model = model_of(scene, geometry=False)
    tree, _, _ = pin_tree(model, tuple(scene.robots))
    q = _q(scene, u)
    X_pin = _pin_poses(model, q)
    assert np.max(np.abs(fk_kernel(tree, q[None])[0] - X_pin)) <= 1e-12
    assert np.max(np.abs(fk_reference(tree, q[None])[0] - X_pin)) <= 1e-12


@pytest.mark.parametrize("name", MODELS + ["coded"])
@_SETTINGS
@given(u=_U)
def test_fk_equals_the_robots_tree(name, u):
    scene = _scene_of(name)
    rn = tuple(scene.robots)
    tree, lo, jo = pin_tree(model_of(scene, geometry=False), rn)
    old, lo2, jo2 = combined_tree(scene, rn)
    assert np.array_equal(tree.parent, old.parent) and np.array_equal(lo, lo2) and np.array_equal(jo, jo2)
    q = _q(scene, u)
    assert np.max(np.abs(fk_kernel(tree, q[None])[0] - fk_reference(old, q[None])[0])) <= 1e-12


def test_the_models_exercise_every_joint_kind():
    """The models above hold what the module docstring names (else the tests above prove less)."""
    kinds = set()
    for name in ("gmf_s480", "panda", "kinova"):
        if not _AVAILABLE.get(name, False):
            continue
        pm = _model(name).pin_model
        kinds |= {pm.joints[j].shortname() for j in range(1, pm.njoints)}
    need = {"JointModelMimic", "JointModelRZ"} | ({"JointModelRUBZ"} if _AVAILABLE.get("kinova") else set())
    assert need <= kinds
    gmf = _model("gmf_s480").pin_model
    mimics = [gmf.joints[j].extract() for j in range(1, gmf.njoints) if gmf.joints[j].shortname() == "JointModelMimic"]
    assert [m.scaling for m in mimics] == [-1.0, -1.0]
    tree, _, _ = pin_tree(_model("gmf_s480"), tuple(_model("gmf_s480").scene.robots))
    assert np.sum(tree.term_coeff == -1.0) == 2
    coded = _coupled_scene()
    tree, _, _ = pin_tree(model_of(coded, geometry=False), tuple(coded.robots))
    k = int(np.flatnonzero(np.diff(tree.term_start) == 2)[0])  # the export's chain of two mimics: one two-term row
    assert sorted(tree.term_coeff[tree.term_start[k]:tree.term_start[k + 1]]) == [-1.0, 0.5]


@pytest.mark.parametrize("name", MODELS + ["coded"])
def test_detector_distances_unchanged(name, monkeypatch):
    """Every candidate pair's distance with the pin-built tree equals the Robot-built tree's (1e-9)."""
    scene = _scene_of(name)
    det = armguard.Detector(scene)
    monkeypatch.setattr(engine_model, "engine_tree", lambda sc, rn, model=None: combined_tree(sc, rn))
    ref = armguard.Detector(scene)
    rng = np.random.default_rng(7)
    for u in rng.random((5, len(scene.joint_names))):
        q = _q(scene, u)
        a, b = det.pair_distances(q), ref.pair_distances(q)
        assert np.array_equal(a.pair_index, b.pair_index)
        assert np.max(np.abs(a.distance - b.distance), initial=0.0) <= 1e-9
        ra, rb = det.check(q), ref.check(q)
        assert ra.status == rb.status and (ra.nearest is None) == (rb.nearest is None)
        if ra.nearest is not None:
            assert abs(ra.nearest.distance - rb.nearest.distance) <= 1e-9


def test_a_moved_base_rebuilds_the_model():
    """``set_robot_base`` makes a new Robot: model_of no longer answers with the stale pin_model, and
    the analytic and coal distances follow the new mount."""
    scene = armguard.load_scene("ranger")
    old = model_of(scene)
    r = next(iter(scene.robots))
    X = scene.robots[r].X_WB.copy()
    X[:3, 3] += [0.3, 0.0, 0.0]
    scene.set_robot_base(r, X)
    new = model_of(scene, geometry=False)
    assert new is not old and new.moves_robots_of(scene)
    q = scene.flat_q(scene.default_q())
    np.testing.assert_allclose(_pin_poses(new, q), fk_reference(combined_tree(scene, tuple(scene.robots))[0], q[None])[0],
                               atol=1e-12, rtol=0)
    a = armguard.Detector(scene).pair_distances(q)
    c = armguard.Detector(scene, backend="coal").pair_distances(q)
    assert np.max(np.abs(np.sort(a.distance) - np.sort(c.distance))) <= 1e-6


def test_a_moved_base_keeps_the_srdf_groups_and_states():
    """The Model after ``set_robot_base`` (derived from the loaded one: the same joint and link
    names, ``armguard.model._derive``) answers the SRDF groups and states it was loaded with."""
    model = armguard.load_model("panda")
    scene = model.scene
    groups = sorted(model.srdf.groups)
    before = {g: model.group_joints(g) for g in groups}
    r = next(iter(scene.robots))
    X = scene.robots[r].X_WB.copy()
    X[:3, 3] += [0.3, 0.0, 0.0]
    scene.set_robot_base(r, X)
    new = model_of(scene)
    assert new is not model and new.srdf is model.srdf and new.pin_model is not model.pin_model
    assert {g: new.group_joints(g) for g in groups} == before
    assert len(new.srdf.states) == len(model.srdf.states)
    pin_joints = set(new.joint_names)
    for st in new.srdf.states:  # the states name the new model's joints
        assert set(st.values) <= pin_joints
    scene.set_robot_base(r, np.eye(4))  # moved again: still carried
    assert {g: model_of(scene).group_joints(g) for g in groups} == before


def test_a_copy_and_a_new_body_keep_the_kinematic_model():
    scene = armguard.load_scene("hermes")
    m = model_of(scene)
    cp = scene.copy()
    assert model_of(cp, geometry=False) is m
    scene.add_body("extra", [Sphere([5.0, 5.0, 5.0], 0.1)])
    assert model_of(scene, geometry=False) is m


_ODD_URDF = """<?xml version="1.0"?>
<robot name="odd">
  <link name="world"/>
  <link name="base"><collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <joint name="mount" type="fixed"><parent link="world"/><child link="base"/><origin xyz="0.1 0.2 0.3" rpy="0.1 0.2 0.3"/></joint>
  <link name="l1"><collision><geometry><sphere radius="0.05"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><origin xyz="0 0 0.2" rpy="0.3 0 0"/>
    <axis xyz="0.6 0 0.8"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
  <link name="l2"><collision><geometry><sphere radius="0.05"/></geometry></collision></link>
  <joint name="j2" type="continuous"><parent link="l1"/><child link="l2"/><origin xyz="0.3 0 0" rpy="0 0.4 0"/>
    <axis xyz="0 0.6 -0.8"/><limit effort="1" velocity="1"/></joint>
  <link name="l3"><collision><geometry><sphere radius="0.05"/></geometry></collision></link>
  <joint name="j3" type="prismatic"><parent link="l2"/><child link="l3"/><origin xyz="0.1 0.1 0" rpy="0 0 0.5"/>
    <axis xyz="0.48 0.6 0.64"/><limit lower="-0.2" upper="0.3" effort="1" velocity="1"/></joint>
  <link name="l4"><collision><geometry><sphere radius="0.05"/></geometry></collision></link>
  <joint name="j4" type="revolute"><parent link="l3"/><child link="l4"/><origin xyz="0 0.2 0" rpy="0 0 0"/>
    <axis xyz="0 0 -1"/><limit lower="-3" upper="3" effort="1" velocity="1"/>
    <mimic joint="j1" multiplier="2.0" offset="0.3"/></joint>
  <link name="l5"><collision><geometry><sphere radius="0.05"/></geometry></collision></link>
  <joint name="j5" type="fixed"><parent link="l4"/><child link="l5"/><origin xyz="0.05 0 0.1" rpy="0 0.2 0"/></joint>
  <link name="l6"><collision><geometry><sphere radius="0.05"/></geometry></collision></link>
  <joint name="j6" type="prismatic"><parent link="l5"/><child link="l6"/><origin xyz="0 0 0.1" rpy="0 0 0"/>
    <axis xyz="0.6 0.8 0"/><limit lower="-0.1" upper="0.1" effort="1" velocity="1"/>
    <mimic joint="j3" multiplier="-0.5" offset="0.02"/></joint>
</robot>
"""


@pytest.fixture(scope="module")
def odd_model(tmp_path_factory):
    """Every one-DoF joint kind off the axes: revolute, continuous and prismatic about unaligned axes,
    a revolute mimic about -z (multiplier 2, offset 0.3), a prismatic mimic (multiplier -0.5, offset
    0.02), a fixed joint between them."""
    path = tmp_path_factory.mktemp("odd") / "odd.urdf"
    path.write_text(_ODD_URDF)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_model(path)


def test_the_odd_model_holds_the_joint_kinds(odd_model):
    pm = odd_model.pin_model
    assert [pm.joints[j].shortname() for j in range(1, pm.njoints)] == [
        "JointModelRevoluteUnaligned", "JointModelRevoluteUnboundedUnaligned", "JointModelPrismaticUnaligned",
        "JointModelMimic", "JointModelMimic"]
    assert [(pm.joints[j].extract().scaling, pm.joints[j].extract().offset) for j in (4, 5)] == [(2.0, 0.3), (-0.5, 0.02)]


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(u=_U)
def test_unaligned_continuous_and_offset_mimic_joints(odd_model, u):
    scene = odd_model.scene
    rn = tuple(scene.robots)
    tree, _, _ = pin_tree(odd_model, rn)
    q = _q(scene, u)
    X_pin = _pin_poses(odd_model, q)
    assert np.max(np.abs(fk_kernel(tree, q[None])[0] - X_pin)) <= 1e-12
    assert np.max(np.abs(fk_reference(combined_tree(scene, rn)[0], q[None])[0] - X_pin)) <= 1e-12


# ---------------------------------------------------------------- what the engine cannot express
def _fake(pm, links, n_q):
    robot = types.SimpleNamespace(link_names=tuple(links), joint_names=tuple(f"j{k}" for k in range(n_q)))
    fid = {f"r/{ln}": pm.getFrameId(ln) for ln in links}
    return types.SimpleNamespace(name="fake", pin_model=pm, robots={"r": robot}, q_index=np.arange(n_q), _circular=np.zeros(0, int),
                                 link_frames=fid, link_placement=lambda link: np.eye(4))


def test_a_spherical_joint_is_refused():
    pm = pin.Model()
    base = pm.addBodyFrame("base", 0, pin.SE3.Identity(), 0)
    j = pm.addJoint(0, pin.JointModelSpherical(), pin.SE3.Identity(), "ball")
    jf = pm.addJointFrame(j, base)
    pm.addBodyFrame("l1", j, pin.SE3.Identity(), jf)
    with pytest.raises(DetectionError, match="ball.*JointModelSpherical"):
        pin_tree(_fake(pm, ["base", "l1"], 1), ("r",))


def test_a_chain_that_is_not_one_motion_is_refused():
    """Two revolute joints with an offset between them and no scene link between: no one row."""
    pm = pin.Model()
    base = pm.addBodyFrame("base", 0, pin.SE3.Identity(), 0)
    j1 = pm.addJoint(0, pin.JointModelRZ(), pin.SE3.Identity(), "j0")
    f1 = pm.addBodyFrame("mid", j1, pin.SE3.Identity(), pm.addJointFrame(j1, base))
    j2 = pm.addJoint(j1, pin.JointModelRZ(), pin.SE3(np.eye(3), np.array([0.1, 0.0, 0.0])), "j1")
    pm.addBodyFrame("l2", j2, pin.SE3.Identity(), pm.addJointFrame(j2, f1))
    with pytest.raises(DetectionError, match="not one motion"):
        pin_tree(_fake(pm, ["base", "l2"], 2), ("r",))
    tree, _, _ = pin_tree(_fake(pm, ["base", "mid", "l2"], 2), ("r",))  # with the middle link it is two rows
    q = np.array([0.3, -0.7])
    d = pm.createData()
    pin.framesForwardKinematics(pm, d, q)
    assert np.max(np.abs(fk_reference(tree, q[None])[0][2] - d.oMf[pm.getFrameId("l2")].homogeneous)) <= 1e-15


def test_an_added_robot_keeps_the_srdf_groups_and_states():
    """``add_robot`` changes the kinematics: the new robot is appended to the loaded Model's
    ``pin_model`` (``armguard.model._derive``), whose joints and links keep their names, so the
    Model keeps the very SRDF it was loaded with and answers its groups and states as before."""
    model = armguard.load_model("panda")
    scene = model.scene
    groups = sorted(model.srdf.groups)
    before = {g: model.group_joints(g) for g in groups}
    r = next(iter(scene.robots))
    X = np.eye(4)
    X[:3, 3] = [1.5, 0.0, 0.0]
    scene.add_robot(scene.robots[r].with_name("second").with_base(X))
    new = model_of(scene)
    assert new is not model and new.srdf is model.srdf
    assert {g: new.group_joints(g) for g in groups} == before
    pin_joints = set(new.joint_names)
    for st in new.srdf.states:  # the states name the new model's joints
        assert set(st.values) <= pin_joints


def test_a_rebuilt_model_carries_the_srdf_over(monkeypatch):
    """Where no Model can be derived (``derive_model`` returns None: a robot removed or changed
    otherwise), ``model_of`` rebuilds through the URDF writer, which renames joints and links, and
    carries the SRDF over (``carry_srdf``): the groups answer as before."""
    from armguard.model import _derive

    model = armguard.load_model("panda")
    scene = model.scene
    groups = sorted(model.srdf.groups)
    before = {g: model.group_joints(g) for g in groups}
    X = np.eye(4)
    X[:3, 3] = [1.5, 0.0, 0.0]
    scene.add_robot(scene.robots[next(iter(scene.robots))].with_name("second").with_base(X))
    monkeypatch.setattr(_derive, "derive_model", lambda model, scene: None)
    new = model_of(scene)
    assert new is not model and new.srdf is not None and "carried over" in new.srdf.found
    assert {g: new.group_joints(g) for g in groups} == before
    pin_joints = set(new.joint_names)
    for st in new.srdf.states:  # the states name the rebuilt model's joints
        assert set(st.values) <= pin_joints
