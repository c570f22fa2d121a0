"""The Detector, the verifier and the CLI on any backend: the same API and answers, from the interface."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

import armguard
from armguard.backends import get_backend
from armguard.cli import main
from armguard.detect._backend import CheckerDetector
from armguard.geometry import Box, Capsule
from armguard.kinematics import Robot
from armguard.scene import Scene


@pytest.mark.parametrize("name, active", [("ranger", "left_arm"), ("hermes", None), ("puma560", None)],
                         ids=["ranger", "hermes", "puma560"])
def test_detector_reports_agree_across_backends(name, active):
    scene = armguard.load_scene(name)
    exact = armguard.Detector(scene, threshold=0.1, active=active)
    coal = armguard.Detector(scene, threshold=0.1, active=active, backend="coal")
    assert isinstance(coal, CheckerDetector) and coal.n_pairs == exact.n_pairs
    model = armguard.load_model(name)
    for q in model.random_q(40, 3):
        qs = model.scene_q(q)
        a, b = exact.check(qs), coal.check(qs)
        assert a.status == b.status
        assert set(a.by_category) == set(b.by_category)
        for cat, pa in a.by_category.items():
            assert b.by_category[cat].distance == pytest.approx(pa.distance, abs=1e-6)
    Q = model.scene_q(model.random_q(200, 4))
    np.testing.assert_array_equal(exact.collides_many(Q), coal.collides_many(Q))
    np.testing.assert_allclose(exact.check_many(Q).min_distance, coal.check_many(Q).min_distance, atol=1e-6)


def test_the_environment_variable_picks_the_detector_backend(monkeypatch):
    scene = armguard.load_scene("hermes")
    monkeypatch.setenv("ARMGUARD_BACKEND", "coal")
    assert isinstance(armguard.Detector(scene), CheckerDetector)
    fused = armguard.Detector(scene, backend="analytic")  # the analytic backend's declared fast path
    assert type(fused) is get_backend("analytic").ranger_detector({}) and not isinstance(fused, CheckerDetector)


def test_verify_on_coal_finds_the_same_first_collision():
    scene = armguard.load_scene("hermes")
    traj = scene.trajectories["stow_misaligned"]
    a = armguard.verify(scene, traj)
    c = armguard.verify(scene, traj, backend="coal")
    assert a.status == c.status and not c.safe
    assert c.first_collision.obstacle == a.first_collision.obstacle == "tail"
    assert c.first_collision.time == pytest.approx(a.first_collision.time, abs=1e-6)


def test_a_scene_built_in_code_gets_a_model_for_any_backend():
    arm = Robot.from_dh("arm", [(0.5, 0.0, 0.0), (0.4, 0.0, 0.0)], lower=[-3, -3], upper=[3, 3],
                        link_shapes={"link1": [Capsule([-0.5, 0, 0], [0, 0, 0], 0.05)],
                                     "link2": [Capsule([-0.4, 0, 0], [0, 0, 0], 0.05)]})
    scene = Scene("cell")
    scene.add_robot(arm)
    scene.add_body("block", [Box([0.6, 0.6, 0.0], [0.1, 0.1, 0.1])])
    det_a = armguard.Detector(scene, threshold=0.0)
    det_c = armguard.Detector(scene, threshold=0.0, backend="coal")
    for q in np.random.default_rng(0).uniform(-3, 3, size=(50, 2)):
        assert det_c.check(q).nearest.distance == pytest.approx(det_a.check(q).nearest.distance, abs=1e-9)


def test_an_out_of_limit_configuration_is_refused_by_every_backend():
    scene = armguard.load_scene("hermes")
    q = scene.flat_q(scene.default_q()).copy()
    q[1] = 10.0
    for b in ("analytic", "coal"):
        with pytest.raises(armguard.JointLimitError, match="hera/shoulder_pitch"):
            armguard.Detector(scene, backend=b).check(q)


def test_cli_backend_option():
    runner = CliRunner()
    res = runner.invoke(main, ["--backend", "coal", "check", "hermes", "--json"])
    assert res.exit_code in (0, 1), res.output
    assert '"status"' in res.output
    bad = runner.invoke(main, ["--backend", "nonesuch", "check", "hermes"])
    assert bad.exit_code != 0 and "installed backends" in bad.output


def test_the_cli_choice_does_not_outlive_the_command():
    from armguard.backends import resolve

    CliRunner().invoke(main, ["--backend", "coal", "info", "hermes"])
    assert resolve()[0] == "analytic"


def test_a_verdicts_only_backend_says_what_it_cannot_answer():
    scene = armguard.load_scene("puma560")
    det = armguard.Detector(scene, backend="clip")
    Q = np.tile(scene.flat_q(scene.default_q()), (4, 1))
    assert det.collides_many(Q).shape == (4,)
    with pytest.raises(armguard.BackendError, match="verdicts only"):
        det.check(scene.default_q())


def test_a_scene_with_an_exact_cylinder_exports_and_checks_on_coal():
    from armguard.geometry import Cylinder

    arm = Robot.from_dh("arm", [(0.5, 0.0, 0.0)], lower=[-3], upper=[3],
                        link_shapes={"link1": [Capsule([-0.5, 0, 0], [0, 0, 0], 0.05)]})
    scene = Scene("cell")
    scene.add_robot(arm)
    scene.add_body("post", [Cylinder([0.3, 0.4, 0.0], np.eye(3), 0.1, 0.5)])
    det_a = armguard.Detector(scene, threshold=0.0)
    det_c = armguard.Detector(scene, threshold=0.0, backend="coal")
    assert not det_c.model.notes  # the cylinder reaches coal as a coal.Cylinder, no representation note
    for q in np.linspace(-3, 3, 25)[:, None]:
        a, c = det_a.check(q).nearest.distance, det_c.check(q).nearest.distance
        if a > 1e-6:
            assert c == pytest.approx(a, abs=1e-6)
        else:
            assert c <= 1e-6
