"""A pair no joint of the moving robot moves (a base link on its table) fails every margin at once:
the verification report and the Guard say so, and how to disable the pair, instead of leaving the
user to find why every trajectory of the robot is UNSAFE."""

from __future__ import annotations

import numpy as np
import pytest

import armguard
from armguard.geometry import Box
from armguard.kinematics import Trajectory
from armguard.verify import Guard, GuardVerdict


@pytest.fixture(scope="module")
def floored():
    """puma560 with a floor plate 1 mm under its base link (the base box spans z 0.002 .. 0.522 m)."""
    m = armguard.load_model("puma560")
    return m.with_body("floor", [Box(np.array([0.0, 0.0, -0.001]), np.array([0.15, 0.15, 0.002]))])


def _move(model):
    r = model.scene.robots["puma560"]
    q0 = model.scene.home("puma560")
    return q0, Trajectory.joint_interpolated(r, np.array([q0, q0 + 0.1]))


def test_a_fixed_pair_within_the_stopping_distance_is_named_fixed_with_the_way_out(floored):
    _, tr = _move(floored)
    rep = armguard.verify(floored, tr, stopping_distance=0.005)
    c = rep.first_collision
    assert rep.status.value == "collision" and c is not None and c.time == 0.0
    assert {c.a, c.b} == {"puma560/base", "floor"} and c.fixed
    assert "no joint of robot 'puma560' moves puma560/base or floor" in rep.summary()
    assert "with_pair_disabled('puma560/base', 'floor')" in rep.summary()
    clear = armguard.verify(floored.with_pair_disabled("puma560/base", "floor"), tr, stopping_distance=0.005)
    assert clear.first_collision is None or {clear.first_collision.a, clear.first_collision.b} != {"puma560/base", "floor"}


def test_a_moving_pair_within_the_stopping_distance_has_no_such_hint(floored):
    m = armguard.load_model("puma560")  # no floor: the table is 0.237 m from link1 at home
    _, tr = _move(m)
    rep = armguard.verify(m, tr, stopping_distance=0.245)
    c = rep.first_collision
    assert c is not None and not c.fixed  # link2 against the base: link2 moves
    assert "moves either" not in rep.summary() and "no joint of robot" not in rep.summary()


def test_the_guard_says_no_motion_clears_a_fixed_pair(floored):
    q0, _ = _move(floored)
    dec = Guard(floored, stopping_distance=0.005).step(q0, qdot=np.full(6, 0.1))
    assert dec.verdict is GuardVerdict.STOP and set(dec.pair) == {"puma560/base", "floor"}
    assert "no joint of robot 'puma560' moves either side" in dec.reason
    m = armguard.load_model("puma560")
    dec = Guard(m, stopping_distance=0.245).step(q0, qdot=np.full(6, 0.1))
    assert dec.verdict is GuardVerdict.STOP and "moves either side" not in dec.reason
