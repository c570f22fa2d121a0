"""Ranger's canned tests run with collision avoidance on.

Each canned test (:class:`armguard.model.CannedTest`: every robot at ``setup``, then ``robot`` moves
on a trapezoidal profile in its end-effector coordinates, its arm angle or its joints; the goal is the
profile's last configuration) is played as a control loop at ``damper.period``: the command
is the profile's velocity plus a proportional pull back to the profile (``gain`` 1/s), filtered by
:func:`~armguard.avoidance.avoid_step` over the moving robot's pairs (only its joints may move),
then integrated.  The loop runs for the profile's duration plus ``settle_s``.  The result says
whether any pair of the robot touched, its least distance, and how far the arm got towards the goal
(the joint-space fraction ``1 - |goal - q_end| / |goal - q_start|``).
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, replace

import numpy as np

__all__ = ["CannedRun", "run_canned", "run_canned_all"]


@dataclass(frozen=True)
class CannedRun:
    """One canned test with avoidance on.

    ``name``, ``robot``; ``steps`` control steps run; ``start_distance`` / ``min_distance`` /
    ``end_distance`` (m) the least distance over the robot's pairs at the start, over the run and at
    the end; ``contact``: some pair at distance <= 0 at some step; ``progress`` (0..1) the fraction of
    the joint-space way to the goal covered; ``statuses`` ``{"free": n, "slowed": n, "stopped": n}``;
    ``q_end`` ``(n_joints,)`` the robot's configuration at the end (rad or m).  With ``record=True``
    every step is kept: ``q_cmd_path`` / ``q_path`` ``(steps + 1, n_joints)`` the commanded (the
    profile, held at its end) and the filtered configurations, ``distance_path`` ``(steps + 1,)`` the
    least distance at each filtered one (m); otherwise ``None``.
    """

    name: str
    robot: str
    steps: int
    start_distance: float
    min_distance: float
    end_distance: float
    contact: bool
    progress: float
    statuses: dict
    q_end: np.ndarray
    q_cmd_path: np.ndarray | None = None
    q_path: np.ndarray | None = None
    distance_path: np.ndarray | None = None

    def holds(self, stand_off: float, slack: float = 1e-3) -> bool:
        """No contact, and the least distance at least ``min(stand_off, start_distance) - slack``."""
        return not self.contact and self.min_distance >= min(stand_off, self.start_distance) - slack


def robot_rows_and_columns(model, robot: str):
    """The Model pair rows with ``robot`` (or its payload) on a side, its flat joint indices, and
    their Pinocchio velocity columns: what one avoidance step for ``robot`` filters."""
    pairs = model.pairs
    pre = robot + "/"
    payloads = {n for n, p in model.scene.payloads.items() if p.robot == robot}
    mine = lambda o: o.startswith(pre) or o in payloads  # noqa: E731
    rows = np.array([k for k, (a, b) in enumerate(zip(pairs.owner_a, pairs.owner_b)) if mine(a) or mine(b)],
                    dtype=np.int64)
    pm = model.pin_model
    v_of_q = {int(pm.joints[j].idx_q): int(pm.joints[j].idx_v) for j in range(1, pm.njoints) if pm.joints[j].nq > 0}
    ks = [k for k, n in enumerate(model.scene.joint_names) if n.startswith(pre)]
    cols = np.array([v_of_q[int(model.q_index[k])] for k in ks], dtype=np.int64)
    return rows, np.array(ks, dtype=np.int64), cols


def run_canned(model, test, damper, *, gain: float = 5.0, settle_s: float = 2.0, checker=None,
               record: bool = False) -> CannedRun:
    """Play canned test ``test`` (a :class:`~armguard.model.CannedTest` of ``model.scene``, or its
    name) with avoidance ``damper`` (see the module docstring); ``record`` keeps every step."""
    from ..backends import checker as make_checker
    from . import avoid_step

    from .._errors import AvoidanceError

    scene = model.scene
    if isinstance(test, str):
        if test not in scene.canned_tests:
            raise AvoidanceError(f"run_canned: {test!r} is not a canned test of {scene.name!r} (its tests: "
                                 f"{', '.join(scene.canned_tests) or 'none'})")
        test = scene.canned_tests[test]
    if not hasattr(test, "trajectory") or not hasattr(test, "robot"):
        raise AvoidanceError(f"run_canned: expected a canned test of the model or its name, got {type(test).__name__}")
    for name, v in (("settle_s", settle_s), ("gain", gain)):
        if not (isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v >= 0.0):
            raise AvoidanceError(f"run_canned: {name}: expected a finite number >= 0, got {v!r}")
    c = checker if checker is not None else make_checker(model, "analytic")
    rows, ks, cols = robot_rows_and_columns(model, test.robot)
    nv = int(model.pin_model.nv)
    lim = np.zeros(nv)
    given = np.asarray(damper.velocity_limit, dtype=np.float64)
    # a number, one per velocity column of the model (Damper's (nv,)), or one per column of the test's robot
    lim[cols] = given[cols] if given.shape == (nv,) else damper.limits(len(cols))
    d_robot = replace(damper, velocity_limit=tuple(float(x) for x in lim))  # only the test's robot moves
    robot = scene.robots[test.robot]
    lo, hi = np.asarray(robot.lower, dtype=np.float64), np.asarray(robot.upper, dtype=np.float64)
    traj = test.trajectory(scene)
    q_full = scene.flat_q({**{r: np.asarray(v) for r, v in test.setup.items()}})
    q = q_full[ks].copy()
    q_start = q.copy()

    def least(qr) -> float:
        full = q_full.copy()
        full[ks] = qr
        return float(c.pair_distances(model.pin_q(full), pairs=rows).distance.min(initial=math.inf))

    d0 = least(q)
    dmin, contact, seen = d0, d0 <= 0.0, Counter()
    dt = damper.period
    n = int(math.ceil((traj.duration + settle_s) / dt))
    q_cmds, qs, ds = [], [q.copy()], [d0]
    for i in range(n):
        t = min(i * dt, traj.duration)
        ref_q = np.asarray(traj.at(t), dtype=np.float64)
        if record:
            q_cmds.append(ref_q)
        ref_v = traj.velocity(t) if i * dt < traj.duration else np.zeros_like(q)
        v_cmd = np.zeros(nv)
        v_cmd[cols] = ref_v + gain * (ref_q - q)
        full = q_full.copy()
        full[ks] = q
        out = avoid_step(c, model.pin_q(full), v_cmd, d_robot, pairs=rows)
        seen[out.status.value] += 1
        q = np.clip(q + out.velocity[cols] * dt, lo, hi)
        d = least(q)
        dmin = min(dmin, d)
        contact |= d <= 0.0
        if record:
            qs.append(q.copy())
            ds.append(d)
    goal = np.asarray(traj.at(traj.duration), dtype=np.float64)  # a joint goal, or the task motion's end through IK
    way = float(np.linalg.norm(goal - q_start))
    progress = 1.0 if way == 0.0 else max(0.0, 1.0 - float(np.linalg.norm(goal - q)) / way)
    paths = (np.array(q_cmds + [goal]), np.array(qs), np.array(ds)) if record else (None, None, None)
    return CannedRun(test.name, test.robot, n, d0, dmin, least(q), bool(contact), progress,
                     {k: seen.get(k, 0) for k in ("free", "slowed", "stopped")}, q, *paths)


def run_canned_all(model, damper, **kwargs) -> list:
    """:func:`run_canned` for every canned test of ``model.scene``, in their order."""
    from ..backends import checker as make_checker

    c = kwargs.pop("checker", None) or make_checker(model, "analytic")
    return [run_canned(model, t, damper, checker=c, **kwargs) for t in model.scene.canned_tests.values()]
