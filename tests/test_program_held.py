"""The FIND's uncertainty of an object the hand holds: a payload placement of verify_with_confidence,
grown as it was where it lay, and bound again where it is set down (its covariance carried by the
hand's motion).  The example stacking program checks every motion with cylinder_a's growth."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import armguard.uncertainty as unc
from armguard import UncertaintyError
from armguard.uncertainty import UncertainPlacement, UncertainPose3, se3

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "workmate"


@pytest.fixture(scope="module")
def exact_calibration(tmp_path_factory):
    """The example cell's camera where it really stands (tests/test_program.py's fixture)."""
    from armguard.program import Calibration, load_cell, write_calibration

    cell = load_cell(EXAMPLE / "cell.yaml")
    return write_calibration(Calibration(X_camera=cell.camera.X_WC_real), tmp_path_factory.mktemp("cal") / "exact.yaml")


def test_the_held_object_is_grown_on_every_motion_as_where_it_lay(monkeypatch, exact_calibration):
    from armguard.program import run_program

    calls = []
    real = unc.verify_with_confidence

    def spy(scene, trajectory, placements, confidence=0.999, **kw):
        out = real(scene, trajectory, placements, confidence, **kw)
        calls.append(({p.name: ("payload" if p.name in scene.payloads else "body") for p in placements}, out.growth))
        return out

    monkeypatch.setattr(unc, "verify_with_confidence", spy)
    run = run_program(EXAMPLE / "stack.yaml", seed=0, calibration=exact_calibration)
    assert run.ok, run.stopped
    assert len(calls) == len(run.motions) == 7
    kinds = [c[0].get("cylinder_a") for c in calls]
    # approach and grasp: found, lying; depart, then PLACE's approach and release: held; PLACE's depart: set down
    assert kinds == ["body", "body", "payload", "payload", "payload", "body", "body"], kinds
    g = [c[1]["cylinder_a"] for c in calls]
    assert g[0] > 1e-3  # millimetres: five sigmas of the camera's noise
    np.testing.assert_allclose(g, g[0], rtol=1e-9)  # the same displacement, moved with the hand


def test_a_payload_placement_grows_the_payload_by_its_shapes_sigma_at_the_grasp():
    scene = armguard_scene_with_payload()
    X_WP = scene.link_pose(scene.home("puma560"), "puma560", scene.robots["puma560"].tool_link)
    cov = np.diag([1e-6, 4e-6, 1e-6, 1e-5, 1e-5, 4e-5])
    p = UncertainPlacement("held", UncertainPose3(X_WP, cov))
    traj = np.array([scene.home("puma560")] * 2)
    from armguard.kinematics import Trajectory

    tr = Trajectory.trapezoidal(scene.robots["puma560"], traj[0], traj[1] + 0.01)
    out = unc.verify_with_confidence(scene, tr, [p], 0.99)
    shapes_W = [s.transformed(X_WP) for s in scene.payloads["held"].shapes]
    assert out.growth["held"] == pytest.approx(out.k * p.sigma_max(shapes_W), rel=1e-12)
    grown = out.scene.payloads["held"]
    assert grown.link == scene.payloads["held"].link and np.array_equal(grown.X_LP, scene.payloads["held"].X_LP)
    assert grown.shapes[0].radius == pytest.approx(scene.payloads["held"].shapes[0].radius + out.growth["held"])
    assert set(out.scene.disabled_pairs) == set(scene.disabled_pairs)
    # turned by the hand: the same growth (the conjugate displacement)
    T = se3.exp(np.array([0.1, -0.2, 0.05, 0.3, -0.1, 0.7]))
    Ad = se3.adjoint(T)
    moved = UncertainPlacement("held", UncertainPose3(T @ X_WP, Ad @ cov @ Ad.T))
    assert moved.sigma_max([s.transformed(T @ X_WP) for s in scene.payloads["held"].shapes]) == pytest.approx(
        p.sigma_max(shapes_W), rel=1e-9)
    with pytest.raises(UncertaintyError, match="not a body or robot or payload.*payloads \\['held'\\]"):
        unc.verify_with_confidence(scene, tr, [UncertainPlacement("nothing", UncertainPose3(X_WP, cov))], 0.99)
    with pytest.raises(UncertaintyError, match="not a body or robot of"):  # the clearance checks take no payload
        import armguard

        unc.clearance_sigmas(armguard.Detector(scene), scene.home("puma560"), [p])


def armguard_scene_with_payload():
    import armguard
    from armguard.geometry import Capsule

    scene = armguard.load_scene("puma560")
    tool = scene.robots["puma560"].tool_link
    scene.attach_payload("held", "puma560", tool, [Capsule([0.0, 0.0, 0.05], [0.0, 0.0, 0.15], 0.02)])
    return scene
