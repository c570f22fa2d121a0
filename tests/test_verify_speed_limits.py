"""A trajectory faster than a joint's max_velocity: the verification report says so
(``over_speed`` and a summary line), its verdict still for the motion as commanded; before, a pan of
1.5 rad in 0.1 s (4.8x ur5's 3.15 rad/s) verified SAFE with no word of it."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import armguard
from armguard.kinematics import Trajectory


@pytest.fixture(scope="module")
def ur5():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return armguard.load_model("ur5")


def _pan(model, seconds: float):
    r = model.scene.robots["ur5"]
    q0 = model.scene.home("ur5")
    q1 = q0.copy()
    q1[0] += 1.5
    return Trajectory("ur5", r.joint_names, [0.0, seconds], [q0, q1])


def test_a_pan_faster_than_its_limit_is_said_to_be(ur5):
    rep = armguard.verify(ur5, _pan(ur5, 0.1))
    assert rep.over_speed == {"shoulder_pan_joint": (pytest.approx(15.0), pytest.approx(3.15))}
    assert "joint shoulder_pan_joint: peak speed 15 exceeds its max_velocity 3.15" in rep.summary()
    assert json.loads(rep.to_json())["over_speed"]["shoulder_pan_joint"] == pytest.approx([15.0, 3.15])


def test_a_pan_within_its_limit_says_nothing(ur5):
    rep = armguard.verify(ur5, _pan(ur5, 1.0))  # 1.5 rad/s
    assert rep.over_speed == {} and "max_velocity" not in rep.summary()


def test_the_speed_dependent_verification_says_it_too(ur5):
    """``--speed-dependent`` verifies a subdivided trajectory (``Subdivided``), which had no
    ``peak_velocity``: its report said nothing of the over-speed."""
    from armguard.verify._subdivide import Subdivided

    rep = armguard.verify(ur5, Subdivided(_pan(ur5, 0.1), 4))
    assert "shoulder_pan_joint" in rep.over_speed
