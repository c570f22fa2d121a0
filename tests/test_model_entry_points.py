"""Every entry point that takes a scene takes a Model as well (``armguard.model.scene_of``), and
answers as it does for the Model's scene: the Model is the one thing a user needs to hold."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import armguard
from armguard.kinematics import Trajectory
from armguard.model import scene_of


@pytest.fixture(scope="module")
def model():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return armguard.load_model("puma560")


@pytest.fixture(scope="module")
def trajectory(model):
    r = next(iter(model.robots))
    robot = model.robots[r]
    q0 = model.scene.home(r)
    q1 = np.clip(q0 + 0.3, robot.lower, robot.upper)
    return Trajectory(r, robot.joint_names, [0.0, 1.0], [q0, q1])


def test_scene_of_gives_a_models_scene_and_a_scene_as_it_is(model):
    bound = scene_of(model)  # a copy of the system the Model holds, whose Model it is (model.scene stays the user's)
    assert bound is not model.scene and bound is scene_of(model) and armguard.model.model_of(bound) is model
    assert scene_of(model.scene) is model.scene
    assert scene_of("puma560") == "puma560"  # a name goes on to the loader as before


def test_verify_takes_a_model(model, trajectory):
    a, b = armguard.verify(model, trajectory), armguard.verify(model.scene, trajectory)
    assert a.status == b.status and a.min_clearance == b.min_clearance
    many = armguard.verify_many(model, [trajectory, trajectory])
    assert [r.status for r in many] == [b.status, b.status]


def test_verifier_guard_and_clearance_model_take_a_model(model):
    from armguard.verify import ClearanceModel, Guard, Verifier

    assert Verifier(model).scene is scene_of(model)  # the Model's own copy of its system, not model.scene
    assert Guard(model) is not None
    q = model.scene_q(model.neutral())
    a, b = ClearanceModel(model), ClearanceModel(model.scene)
    assert a.scene is scene_of(model)
    for x, y in zip(a.distances(q), b.distances(q)):
        np.testing.assert_array_equal(x, y)


def test_reference_and_cspace_helpers_take_a_model(model):
    from armguard.cspace import ed_constant, map_links, random_configurations
    from armguard.detect import check_reference

    q = model.scene_q(model.neutral())
    a, b = check_reference(model, q, 0.05), check_reference(model.scene, q, 0.05)
    assert a.status == b.status and np.array_equal(np.asarray(a.min_distance), np.asarray(b.min_distance))
    np.testing.assert_array_equal(random_configurations(model, 5, 3), random_configurations(model.scene, 5, 3))
    a, b = map_links(model, None), map_links(model.scene, None)
    assert a.joints == b.joints and a.links == b.links and np.array_equal(a.lever, b.lever)
    assert ed_constant(model) == ed_constant(model.scene)


def test_verify_with_confidence_takes_a_model(model, trajectory):
    from armguard.console._overlays import isotropic_placement
    from armguard.uncertainty import verify_with_confidence

    body = next(iter(model.bodies))
    placement = isotropic_placement(model.scene, body, 0.002)
    a = verify_with_confidence(model, trajectory, [placement], 0.99)
    b = verify_with_confidence(model.scene, trajectory, [placement], 0.99)
    assert a.report.status == b.report.status and a.report.min_clearance == b.report.min_clearance


def test_the_console_state_takes_a_model(model):
    from armguard.console._serve import make_state

    state = make_state(model)
    assert list(state._scene.robots) == list(model.robots) and list(state._scene.bodies) == list(model.bodies)
