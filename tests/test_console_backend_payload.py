"""The console's backend panels (coal, fcl) over the same pairs as the analytic one, a held payload's included."""

from __future__ import annotations

import math

import pytest

import armguard
from armguard.console._backends import BackendView
from armguard.console._readout import PanelStatus


@pytest.mark.parametrize("backend", ["coal", "fcl"])
def test_a_held_payload_in_collision_is_on_every_backends_panel(backend):
    """Hermes's shoulder yaw at 200 deg puts the held payload 1.01 m into the tail: the Detector says COLLISION
    with every backend, and so did the console's analytic panel, but its coal and fcl panels dropped the payload's
    pairs (no robot prefix in its owner's name) and showed CLEAR 330 mm."""
    if backend == "fcl":
        pytest.importorskip("fcl")
    model = armguard.load_model("hermes")
    scene = model.scene
    q = dict(scene.default_q())
    j = list(scene.robots["hera"].joint_names).index("shoulder_yaw")
    q["hera"] = q["hera"].copy()
    q["hera"][j] = math.radians(200)
    ref = armguard.Detector(model, threshold=0.05, active="hera", backend=backend).check(scene.flat_q(q))
    assert ref.status.value == "collision" and ref.nearest.a == "payload"
    r = BackendView(model, backend).readout(scene, q, "hera", threshold=0.05, stopping_distance=0.0,
                                            contact=model.tol.length)
    assert r.status is PanelStatus.COLLISION and r.distance == pytest.approx(ref.nearest.distance, abs=1e-6), r
