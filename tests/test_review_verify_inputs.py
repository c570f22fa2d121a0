"""verify() refuses what it cannot honestly verify, with an ArmguardError, never a verdict.

Found in review: a trajectory whose waypoint drives a joint past its limit (the planar arm's
limits are [-3, 3] rad, ``_verify_fixtures.planar_arm``) was reported SAFE; a non-numeric
``threshold`` or ``payload_mass`` escaped as a bare ValueError instead of a VerificationError.
"""

from __future__ import annotations

import pytest

import armguard
from armguard import VerificationError
from armguard.geometry import Sphere
from armguard.kinematics import Trajectory
from armguard.scene import Scene

from _verify_fixtures import planar_arm


def _scene() -> Scene:
    sc = Scene("inputs")
    sc.add_robot(planar_arm(), self_pairs=[])
    sc.add_body("far", [Sphere([5.0, 5.0, 5.0], 0.1)])
    return sc


@pytest.mark.parametrize("method", ["certified", "sampled"], ids=["certified", "sampled"])
def test_waypoint_outside_joint_limits_is_refused_not_safe(method):
    sc = _scene()
    arm = sc.robots["arm"]
    # a hand-built trajectory (as loaded from YAML): knot 1 puts joint1 at 5 rad, limits [-3, 3]
    tr = Trajectory("arm", arm.joint_names, [0.0, 10.0], [[1.0, 0.0, 0.0], [5.0, 0.0, 0.0]])
    with pytest.raises(VerificationError, match=r"waypoints\[1\].*joint1"):
        armguard.verify(sc, tr, method=method)


def test_waypoints_at_the_limits_are_verified():
    sc = _scene()
    arm = sc.robots["arm"]
    tr = Trajectory("arm", arm.joint_names, [0.0, 10.0], [[-3.0, 0.0, 0.0], [3.0, 0.0, 0.0]])
    assert armguard.verify(sc, tr).safe


@pytest.mark.parametrize(
    "kwargs",
    [{"threshold": "x"}, {"threshold": [1, 2]}, {"payload_mass": "heavy"}, {"payload_mass": None}],
    ids=["threshold-text", "threshold-list", "mass-text", "mass-none"],
)
def test_non_numeric_arguments_raise_verification_error(kwargs):
    sc = _scene()
    tr = Trajectory.joint_interpolated(sc.robots["arm"], [[1.0, 0.0, 0.0], [2.0, 0.0, 0.0]])
    with pytest.raises(VerificationError):
        armguard.verify(sc, tr, **kwargs)
