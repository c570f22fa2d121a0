"""The Model's one forward kinematics (``Model.kinematic_tree`` / ``link_poses``, compiled from
``pin_model``) and the framework moving links with it.

* ``Model.link_poses`` / ``robot_link_poses`` / ``shapes_at`` against the Robots' own chains
  (``Scene.link_poses``, ``Scene.shapes_at``: the reference) on built-ins, public robots and scenes
  built in code from DH tables (standard and modified, a prismatic and a coupled joint), and
  against Pinocchio's ``forwardKinematics`` itself.
* The verifier, the terrain guard, the console, the uncertainty checks, the cspace constant and
  the clip backend compute with it: with the Robots' ``forward_kinematics`` made to raise, each
  still answers, and as before.
"""

from __future__ import annotations

import functools
import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import armguard
from armguard.kinematics import Robot
from armguard.model import kinematics_of, known_models, load_model, model_of
from armguard.scene import Scene
from armguard.geometry import Box

from _verify_fixtures import planar_arm, spatial_arm

_PUBLIC = {k.name: k.available for k in known_models() if k.source != "built-in"}
MODELS = ["ranger", "puma560", "gmf_s480", "hermes", "rover"] + [n for n in ("kinova", "panda", "z1") if n in _PUBLIC]


@functools.lru_cache(maxsize=None)
def _model(name):
    if name.startswith("coded-"):
        sc = Scene(name)
        sc.add_robot(spatial_arm(name.split("-", 1)[1]))
        sc.add_robot(planar_arm("planar"))
        sc.set_robot_base("planar", np.array([[0, -1, 0, 1.0], [1, 0, 0, 0.2], [0, 0, 1, 0.1], [0, 0, 0, 1]], float))
        sc.add_body("crate", [Box([0.6, 0.3, 0.2], [0.1, 0.1, 0.1])])
        return model_of(sc)
    if name in _PUBLIC and not _PUBLIC[name]:
        pytest.skip(f"{name}: its package is not installed")
    return load_model(name)


def _q(model, u):
    rs = list(model.robots.values())
    lo, hi = np.concatenate([r.lower for r in rs]), np.concatenate([r.upper for r in rs])
    lo, hi = np.where(np.isfinite(lo), lo, -np.pi), np.where(np.isfinite(hi), hi, np.pi)
    u = np.resize(np.asarray(u, dtype=np.float64), len(lo))
    return lo + u * (hi - lo)


_ALL = MODELS + ["coded-standard", "coded-modified"]
_SETTINGS = settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])


@pytest.mark.parametrize("name", _ALL)
@_SETTINGS
@given(u=st.lists(st.floats(0.0, 1.0), min_size=1, max_size=30))
def test_link_poses_equal_the_robots_chains_and_pinocchio(name, u):
    model = _model(name)
    q = _q(model, u)
    mine, ref = model.link_poses(q), model.scene.link_poses(q)
    assert list(mine) == list(ref)
    for r in ref:
        assert mine[r].shape == ref[r].shape
        assert np.max(np.abs(mine[r] - ref[r])) <= 1e-12, r
        k0 = sum(len(model.robots[n].joint_names) for n in list(model.robots)[:list(model.robots).index(r)])
        q_r = q[k0:k0 + len(model.robots[r].joint_names)]
        assert np.max(np.abs(model.robot_link_poses(r, q_r) - ref[r])) <= 1e-12
    pm = model.pin_model
    d = pm.createData()
    pin.forwardKinematics(pm, d, model.pin_q(q))
    pin.updateFramePlacements(pm, d)
    for r, rob in model.robots.items():
        for i, ln in enumerate(rob.link_names):
            X_pin = d.oMf[model.link_frames[f"{r}/{ln}"]].homogeneous @ model.link_placement(f"{r}/{ln}")
            assert np.max(np.abs(mine[r][i] - X_pin)) <= 1e-12, (r, ln)


@pytest.mark.parametrize("name", ["puma560", "coded-standard"])
def test_batches_mappings_and_shapes(name):
    model = _model(name)
    rng = np.random.default_rng(3)
    Q = np.stack([_q(model, rng.random(20)) for _ in range(6)]).reshape(2, 3, -1)
    batch = model.link_poses(Q)
    for r, X in batch.items():
        assert X.shape[:2] == (2, 3)
        assert np.max(np.abs(X[1, 2] - model.link_poses(Q[1, 2])[r])) <= 1e-15
    as_map = model.scene.split_q(Q[0, 0])
    assert all(np.array_equal(model.link_poses(as_map)[r], model.link_poses(Q[0, 0])[r]) for r in as_map)
    mine, ref = model.shapes_at(Q[0, 1]), model.scene.shapes_at(Q[0, 1])
    assert [(a.owner, a.kind) for a in mine] == [(b.owner, b.kind) for b in ref]
    for a, b in zip(mine, ref):
        assert np.max(np.abs(np.asarray(a.shape.core_points) - np.asarray(b.shape.core_points))) <= 1e-12


def test_bad_input_is_refused():
    model = _model("puma560")
    with pytest.raises(armguard.ArmguardError):
        model.link_poses(np.full(len(model.scene.joint_names), np.nan))
    with pytest.raises(armguard.ArmguardError):
        model.link_poses(np.zeros(len(model.scene.joint_names) + 1))
    with pytest.raises(armguard.ArmguardError, match="unknown robot"):
        model.robot_link_poses("no-such-robot", np.zeros(6))


def test_kinematics_of():
    model = _model("ranger")
    assert kinematics_of(model) is model
    assert kinematics_of(model.scene) is model
    assert kinematics_of(Scene("empty")) is None
    sc = model.scene.copy()
    sc.add_body("crate", [Box([3.0, 0.0, 0.0], [0.1, 0.1, 0.1])])
    assert kinematics_of(sc) is model  # a body added: the same kinematics


def test_one_tree_per_model_across_threads():
    model = _model("coded-modified")
    model.__dict__.pop("_kinematic_trees", None)
    barrier = threading.Barrier(4)  # four threads ask at once: one compile, one tree
    with ThreadPoolExecutor(4) as ex:
        out = list(ex.map(lambda _: (barrier.wait(), model.kinematic_tree())[1], range(4)))
    assert len(out) == 4 and all(o is out[0] for o in out)


# ---------------------------------------------------------------- the framework moves links with the Model
@pytest.fixture
def no_robot_fk(monkeypatch):
    """The Robots' own chains refuse to move: whatever still answers moved its links with the Model."""
    def refuse(self, q):
        raise AssertionError(f"Robot.forward_kinematics called for {self.name!r}")

    monkeypatch.setattr(Robot, "forward_kinematics", refuse)


def _trajectory(model, robot, n=5, seed=0):
    from armguard.kinematics import Trajectory

    rob = model.robots[robot]
    rng = np.random.default_rng(seed)
    lo, hi = np.asarray(rob.lower), np.asarray(rob.upper)
    W = lo + (hi - lo) * (0.3 + 0.4 * rng.random((n, len(lo))))
    return Trajectory(robot, rob.joint_names, np.arange(n, dtype=np.float64), W)


@pytest.mark.parametrize("name", ["puma560", "coded-standard"])
def test_the_verifier_moves_links_with_the_model(name, monkeypatch):
    model = _model(name)
    robot = next(iter(model.robots))
    traj = _trajectory(model, robot)
    before = armguard.verify(model, traj, robot=robot)
    from armguard.verify._oracle import ClearanceModel

    lever_before = ClearanceModel(model).lever
    monkeypatch.setattr(Robot, "forward_kinematics", lambda self, q: (_ for _ in ()).throw(AssertionError("Robot FK")))
    after = armguard.verify(model, traj, robot=robot)
    assert after.status == before.status
    assert after.min_clearance == pytest.approx(before.min_clearance, abs=1e-12)
    assert np.max(np.abs(ClearanceModel(model).lever - lever_before)) <= 1e-9


def test_the_terrain_guard_moves_links_with_the_model(monkeypatch):
    from armguard.terrain import ElevationMap, TerrainGuard

    model = _model("rover")
    z = np.zeros((64, 64))
    z[20:30, 20:30] = 0.3
    em = ElevationMap.from_heights(z, 0.05, origin=(-1.6, -1.6))
    q = model.scene.flat_q(model.scene.default_q())
    before = TerrainGuard(model, em).check(q)
    monkeypatch.setattr(Robot, "forward_kinematics", lambda self, q: (_ for _ in ()).throw(AssertionError("Robot FK")))
    after = TerrainGuard(model, em).check(q)
    assert after.status == before.status
    assert after.distance == pytest.approx(before.distance, abs=1e-12)


def test_the_console_and_cspace_move_links_with_the_model(monkeypatch):
    from armguard.console._meshes import item_frames
    from armguard.cspace import ed_constant

    model = _model("puma560")
    q = model.scene.default_q()
    frames_before, ed_before = item_frames(model.scene, q), ed_constant(model)
    monkeypatch.setattr(Robot, "forward_kinematics", lambda self, q: (_ for _ in ()).throw(AssertionError("Robot FK")))
    frames_after, ed_after = item_frames(model.scene, q), ed_constant(model)
    assert len(frames_after) == len(frames_before)
    assert max(float(np.max(np.abs(a - b))) for a, b in zip(frames_after, frames_before)) <= 1e-12
    assert ed_after == ed_before
