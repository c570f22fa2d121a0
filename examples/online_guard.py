"""An example control loop with the on-line guard (SRI's collision prediction, Hermes's modes).

A 3-link arm sweeps towards a thin rod.  Every 10 ms cycle the controller asks the guard about
the next setpoint; the guard predicts the commanded motion over its horizon and answers STOP
while the arm still has the stopping distance to brake in.  Then the operator jogs one joint
away (single-joint mode), which the guard lets through.  Last, the same sweep with avoidance on
(``Guard(..., avoidance=Damper(...))``): the guard slows the arm short of the rod instead of
stopping it, and the arm keeps its stand-off.

Run: ``python examples/online_guard.py``
"""

from __future__ import annotations

import numpy as np

from armguard.avoidance import Damper
from armguard.geometry import Capsule
from armguard.kinematics import DHRow, Robot
from armguard.scene import Scene
from armguard.verify import Guard, GuardMode

PERIOD_S = 0.01  # control period (s)
STOPPING_DISTANCE = 0.05  # m: what the brakes need at this speed (Hermes grows obstacles by it)
HORIZON_S = 0.1  # s: one period plus the braking time, comfortably


def build_scene() -> Scene:
    links = (0.5, 0.4, 0.3)
    robot = Robot.from_dh(
        "arm", [DHRow(a, 0.0, 0.0) for a in links], lower=[-3.0] * 3, upper=[3.0] * 3,
        link_shapes={f"link{i + 1}": (Capsule([-a, 0, 0], [0, 0, 0], 0.02),) for i, a in enumerate(links)},
    )
    scene = Scene("guard-demo")
    scene.add_robot(robot, self_pairs=[])
    scene.add_body("rod", [Capsule([0.9, 0.5, -0.2], [0.9, 0.5, 0.2], 0.01)])
    return scene


def main() -> dict:
    scene = build_scene()
    guard = Guard(scene, stopping_distance=STOPPING_DISTANCE, horizon_s=HORIZON_S, period_s=PERIOD_S)
    q = np.array([0.0, 0.0, 0.0])
    qdot = np.array([0.8, 0.0, 0.0])  # automatic mode: the programmed sweep, rad/s
    log = {"cycles": 0, "stopped_at": None, "clearance_at_stop": None, "min_clearance": np.inf}
    for k in range(300):
        q_next = q + qdot * PERIOD_S
        decision = guard.step(q, q_next)
        log["cycles"] = k + 1
        log["min_clearance"] = min(log["min_clearance"], decision.clearance)
        if not decision.ok:
            log["stopped_at"] = k * PERIOD_S
            log["clearance_at_stop"] = decision.clearance
            print(f"t = {k * PERIOD_S:.2f} s: STOP — {decision.reason}")
            print(f"  clearance now {decision.clearance * 1e3:.1f} mm >= stopping distance {STOPPING_DISTANCE * 1e3:.0f} mm;"
                  f" predicted {decision.predicted_clearance * 1e3:.1f} mm, time to collision {decision.time_to_collision:.3f} s")
            break
        q = q_next
    # the operator retracts joint 1 alone (single-joint mode): the guard checks that motion too
    jog = Guard(scene, stopping_distance=STOPPING_DISTANCE, horizon_s=HORIZON_S, period_s=PERIOD_S,
                mode=GuardMode.SINGLE_JOINT)
    back = jog.step(q, qdot=np.array([-0.5, 0.0, 0.0]))
    both = jog.step(q, qdot=np.array([-0.5, 0.3, 0.0]))
    print(f"single-joint retract: {back.verdict.value} ({back.reason})")
    print(f"two joints at once in single-joint mode: {both.verdict.value} ({both.reason})")
    log["retract"] = back.verdict.value
    log["two_joints"] = both.verdict.value
    # the same sweep with avoidance: the commanded velocity is filtered instead of stopped
    damper = Damper(stand_off=0.08, influence=0.2, approach_speed=0.3, period=PERIOD_S, velocity_limit=1.0)
    avoiding = Guard(scene, stopping_distance=STOPPING_DISTANCE, horizon_s=HORIZON_S, period_s=PERIOD_S,
                     avoidance=damper)
    q = np.array([0.0, 0.0, 0.0])
    motions = {"free": 0, "slowed": 0, "stopped": 0}
    least = np.inf
    for _ in range(300):
        decision = avoiding.step(q, qdot=qdot)
        motions[decision.motion] += 1
        least = min(least, decision.clearance)
        q = q + decision.velocity * PERIOD_S
    print(f"with avoidance: {motions} over 300 cycles; least clearance {least * 1e3:.1f} mm "
          f"(stand-off {damper.stand_off * 1e3:.0f} mm); joint 1 at {q[0]:.2f} rad")
    log["avoidance"] = motions
    log["avoidance_min_clearance"] = least
    return log


if __name__ == "__main__":
    main()
