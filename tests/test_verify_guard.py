"""The on-line guard: STOP early enough to brake within the stopping distance; modes; the example loop."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

from armguard import VerificationError
from armguard.geometry import Capsule
from armguard.scene import Scene
from armguard.verify import ClearanceModel, Guard, GuardMode, GuardVerdict, StoppingDistance

from _verify_fixtures import planar_arm

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "online_guard.py"


def _scene():
    sc = Scene("guard")
    sc.add_robot(planar_arm(radius=0.005), self_pairs=[])
    sc.add_body("rod", [Capsule([0.9, 0.5, -0.2], [0.9, 0.5, 0.2], 0.003)])  # a thin rod in the sweep
    return sc


@pytest.mark.parametrize("speed", [0.3, 1.0, 2.0], ids=["0.3rad/s", "1rad/s", "2rad/s"])
def test_guard_stops_while_the_stopping_distance_is_still_there(speed):
    """Constant-speed sweep into a thin rod: after STOP the arm brakes over at most the stopping
    distance (Cartesian), so it must never have less than that when STOP comes, and the guard
    must say STOP before any collision; horizon = one period + braking time."""
    sc = _scene()
    period, sd = 0.01, 0.04
    horizon = period + sd / (speed * 1.6)  # braking time at the arm's fastest-point speed (1.6 m lever bound)
    guard = Guard(sc, stopping_distance=sd, horizon_s=horizon, period_s=period)
    model = ClearanceModel(sc, source="reference")
    q = np.zeros(3)
    qd = np.array([speed, 0.0, 0.0])
    stopped = None
    for k in range(int(3.0 / (speed * period))):
        dec = guard.step(q, q + qd * period)
        if dec.verdict is GuardVerdict.STOP:
            stopped = dec
            break
        # the step just allowed must be clear of the stopping distance all along (dense check)
        for s in np.linspace(0.0, 1.0, 21):
            assert model.reference_distances(q + s * qd * period)[0].min() > sd
        q = q + qd * period
    assert stopped is not None, "the guard never stopped a sweep into the rod"
    assert stopped.clearance > sd  # STOP came with the braking distance still available
    assert stopped.pair == ("arm/link3", "rod") or stopped.pair[1] == "rod"
    assert 0.0 <= stopped.time_to_collision <= horizon
    assert stopped.predicted_clearance <= sd + 1e-6


def test_guard_ok_when_moving_away_and_jog_velocity():
    sc = _scene()
    guard = Guard(sc, stopping_distance=0.03, horizon_s=0.2, period_s=0.01, mode=GuardMode.OPERATOR_JOG)
    dec = guard.step(np.zeros(3), qdot=np.array([-0.5, 0.0, 0.0]))
    assert dec.ok and math.isinf(dec.time_to_collision) and dec.predicted_clearance > 0.03


def test_guard_automatic_mode_segment_target():
    sc = _scene()
    guard = Guard(sc, stopping_distance=0.02, horizon_s=1.0, period_s=0.01)
    # the commanded segment runs through the rod: STOP; a segment that stops short: OK
    assert guard.step(np.zeros(3), target=np.array([1.0, 0.0, 0.0])).verdict is GuardVerdict.STOP
    assert guard.step(np.zeros(3), target=np.array([0.2, 0.0, 0.0])).ok


def test_single_joint_mode_refuses_two_joints():
    sc = _scene()
    guard = Guard(sc, stopping_distance=0.02, horizon_s=0.2, period_s=0.01, mode=GuardMode.SINGLE_JOINT)
    assert guard.step(np.zeros(3), qdot=np.array([-0.2, 0.0, 0.0])).ok
    dec = guard.step(np.zeros(3), qdot=np.array([-0.2, 0.1, 0.0]))
    assert dec.verdict is GuardVerdict.STOP and "single-joint" in dec.reason


def test_guard_step_function_stopping_distance_grows_with_speed():
    sc = _scene()
    sd = StoppingDistance.hermes(max_speed=4.0, max_distance=0.1)
    guard = Guard(sc, stopping_distance=sd, horizon_s=0.05, period_s=0.01)
    slow = guard.step(np.zeros(3), qdot=np.array([0.1, 0.0, 0.0]))
    fast = guard.step(np.zeros(3), qdot=np.array([2.0, 0.0, 0.0]))
    assert slow.stopping_distance < fast.stopping_distance
    too_fast = guard.step(np.zeros(3), qdot=np.array([5.0, 0.0, 0.0]))
    assert too_fast.verdict is GuardVerdict.STOP  # above the table: never OK by omission


def test_a_target_with_no_speed_is_held_to_the_table_at_its_top_speed():
    """A target alone gives no speed: the table's value at 0 m/s (0 with ``at_rest``) said OK 43 mm from a pair
    whose table reaches 100 mm; the arm may move at any speed the table holds."""
    sd = StoppingDistance.hermes(max_speed=4.0, max_distance=0.1, at_rest=1e-6)
    guard = Guard(_scene(), stopping_distance=sd, horizon_s=0.05, period_s=0.01)
    d = guard.step(np.zeros(3), target=np.array([0.05, 0.0, 0.0]))
    assert d.stopping_distance == sd.max_distance == 0.1
    if d.ok:  # OK only when every prediction keeps the whole top stopping distance
        assert d.predicted_clearance > 0.1
    slow = guard.step(np.zeros(3), target=np.array([0.05, 0.0, 0.0]), qdot=np.array([0.01, 0.0, 0.0]))
    assert slow.stopping_distance < 0.1  # with a speed, the table's value at that speed


@pytest.mark.parametrize("mass", [-3.0, "x", math.nan, math.inf])
def test_a_bad_payload_mass_is_refused_when_the_guard_is_made(mass):
    with pytest.raises(VerificationError, match="payload_mass"):
        Guard(_scene(), stopping_distance=0.02, horizon_s=0.1, period_s=0.01, payload_mass=mass)


def test_a_payload_above_the_tables_masses_is_refused_when_the_guard_is_made():
    """Every step stopped, saying the commanded speed was outside the table."""
    sd = StoppingDistance.hermes(max_speed=4.0, max_distance=0.1, max_mass=5.0)
    with pytest.raises(VerificationError, match=r"payload_mass: 10 kg is above the stopping-distance table's masses"):
        Guard(_scene(), stopping_distance=sd, horizon_s=0.1, period_s=0.01, payload_mass=10.0)
    Guard(_scene(), stopping_distance=sd, horizon_s=0.1, period_s=0.01, payload_mass=5.0)


@pytest.mark.parametrize(
    "call",
    [
        lambda g: g.step([np.nan, 0, 0], qdot=[0, 0, 0]),
        lambda g: g.step([0, 0, 0]),
        lambda g: g.step([0, 0], qdot=[0, 0]),
        lambda g: g.step([0, 0, 0], [0.1, 0, 0], qdot=[1, 0, 0]),
    ],
    ids=["nan-q", "no-command", "wrong-length", "two-commands"],
)
def test_guard_bad_input_raises(call):
    with pytest.raises(VerificationError):
        call(Guard(_scene(), stopping_distance=0.02, horizon_s=0.1, period_s=0.01))


def test_example_control_loop_runs():
    spec = importlib.util.spec_from_file_location("online_guard", EXAMPLE)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    log = mod.main()
    assert log["stopped_at"] is not None and log["clearance_at_stop"] > mod.STOPPING_DISTANCE
    assert log["retract"] == "ok" and log["two_joints"] == "stop"
    # with avoidance the same sweep is slowed short of the rod, never below the 80 mm stand-off less 1 mm
    assert log["avoidance"]["slowed"] > 0 and log["avoidance"]["free"] > 0
    assert log["avoidance_min_clearance"] >= 0.08 - 1e-3


def test_a_prediction_out_of_evaluations_is_a_stop_marked_unfinished():
    """A link sweeping parallel to a plate 0.5 mm outside the stopping distance: the prediction's work grows as
    1/gap and runs out of evaluations; the STOP says so (``finished`` False), so a controller can tell it from a
    predicted collision (which stays ``finished``)."""
    from armguard.geometry import Box, Capsule
    from armguard.kinematics import DHRow, Robot
    from armguard.scene import Scene
    from armguard.verify import Guard

    robot = Robot.from_dh("arm", [DHRow(1.0, 0.0, 0.0)], lower=[-3.0], upper=[3.0],
                          link_shapes={"link1": (Capsule([-1.0, 0, 0], [0, 0, 0], 0.02),)})

    def guard(top):
        sc = Scene("graze")
        sc.add_robot(robot, self_pairs=[])
        sc.add_body("plate", [Box(center=[0.0, 0.0, top - 0.05], half_extents=[2.0, 2.0, 0.05])])
        return Guard(sc, stopping_distance=0.01, horizon_s=0.1, period_s=0.002)

    grazing = [guard(-0.02 - 0.01 - 0.5e-3).step(np.array([0.01 * k]), qdot=np.array([1.0])) for k in range(20)]
    out = [d for d in grazing if not d.ok]
    assert out and all(not d.finished and "evaluation budget" in d.reason for d in out)
    assert all(d.finished for d in grazing if d.ok)
    hit = guard(-0.005).step(np.array([0.0]), qdot=np.array([1.0]))  # the plate within the stopping distance
    assert not hit.ok and hit.finished
