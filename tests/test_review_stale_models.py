"""A model precomputed from a scene must not keep answering after the scene changed.

Found in review: a ``Verifier`` (and a ``Guard``) built before ``scene.add_body(...)`` kept
verifying against the old obstacle set and said SAFE for a trajectory that runs through the
new body; the Detector likewise says CLEAR.  Closed-form geometry: the planar arm of
``_verify_fixtures`` reaches x = 1.2 m at q = 0; a sphere of radius 5 cm centred there is hit.
"""

from __future__ import annotations

import numpy as np

import armguard
from armguard.geometry import Sphere
from armguard.kinematics import Trajectory
from armguard.scene import Scene
from armguard.verify import Guard, Verifier

from _verify_fixtures import planar_arm


def _scene() -> Scene:
    sc = Scene("stale")
    sc.add_robot(planar_arm(), self_pairs=[])
    sc.add_body("far", [Sphere([5.0, 5.0, 5.0], 0.1)])
    return sc


def _sweep(sc: Scene) -> Trajectory:
    return Trajectory.joint_interpolated(sc.robots["arm"], [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])


def test_revision_counts_changes_to_checked_geometry():
    sc = _scene()
    r0 = sc.revision
    sc.add_body("post", [Sphere([1.2, 0.0, 0.0], 0.05)])
    r1 = sc.revision
    sc.disable_pair("arm", "post")
    r2 = sc.revision
    sc.remove_body("post")
    r3 = sc.revision
    assert r0 < r1 < r2 < r3


def test_verifier_reused_after_add_body_sees_the_new_body():
    sc = _scene()
    v = Verifier(sc)
    tr = _sweep(sc)
    assert v.verify(tr).safe
    sc.add_body("post", [Sphere([1.2, 0.0, 0.0], 0.05)])
    rep = v.verify(tr)
    assert not rep.safe
    assert rep.first_collision.obstacle == "post"


def test_verifier_reused_after_remove_body_forgets_it():
    sc = _scene()
    sc.add_body("post", [Sphere([1.2, 0.0, 0.0], 0.05)])
    v = Verifier(sc)
    tr = _sweep(sc)
    assert not v.verify(tr).safe
    sc.remove_body("post")
    assert v.verify(tr).safe


def test_guard_reused_after_add_body_stops():
    sc = _scene()
    g = Guard(sc, horizon_s=0.5, period_s=0.01)
    q = np.array([0.3, 0.0, 0.0])
    assert g.step(q, qdot=[-1.0, 0.0, 0.0]).ok
    sc.add_body("post", [Sphere([1.2, 0.0, 0.0], 0.05)])
    d = g.step(q, qdot=[-1.0, 0.0, 0.0])
    assert not d.ok and d.pair[1] == "post"


def test_detector_reused_after_add_body_sees_the_new_body():
    sc = _scene()
    det = armguard.Detector(sc, threshold=0.05)
    q = np.zeros(3)
    assert det.check(q).status.value == "clear"
    sc.add_body("post", [Sphere([1.2, 0.0, 0.0], 0.05)])
    assert det.check(q).status.value == "collision"
