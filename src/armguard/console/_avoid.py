"""Collision avoidance in the console: Ranger's "avoidance on/off" and stand-off distance (seed ``000`` section 6).

With avoidance on, a canned test's Run plays the test through the velocity-damper filter of
:mod:`armguard.avoidance` instead of stopping by detection.  The run is computed first, as
:func:`armguard.avoidance.run_canned` computes it (a control loop at :data:`AVOID_PERIOD`: the
profile's velocity plus a pull back to it, filtered by :func:`~armguard.avoidance.avoid_step` over
the moving robot's pairs, for the profile's duration plus :data:`AVOID_SETTLE_S`), here keeping
every step: the commanded configuration (the profile), the filtered one, and the least distance
of each.  The time line then plays the filtered motion; at its end the panel says what the filter
did: reached the goal untouched, slid along an obstacle to the goal, or stopped short (how far
along, the least distance, the stand-off).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._parse import ConsoleInputError, parse_number

__all__ = ["AvoidMixin", "AvoidedRun", "avoid_canned", "console_damper", "DEFAULT_STAND_OFF", "MAX_STAND_OFF",
           "AVOID_PERIOD", "AVOID_INFLUENCE_MARGIN", "AVOID_APPROACH_SPEED", "AVOID_VELOCITY_LIMIT", "AVOID_GAIN",
           "AVOID_SETTLE_S", "GOAL_REACHED"]

DEFAULT_STAND_OFF = 0.05
"""Stand-off distance (m) at start: the first row of ``docs/avoidance.md``'s canned-test table."""
MAX_STAND_OFF = 10.0
"""Largest stand-off the console accepts (m), as for the threshold and the stopping distance."""
AVOID_PERIOD = 0.01
"""Control period (s) of the avoidance loop: 100 Hz, as the benchmark's canned runs."""
AVOID_INFLUENCE_MARGIN = 0.15
"""The damper's influence distance is the stand-off plus this (m)."""
AVOID_APPROACH_SPEED = 0.3
"""The damper's approach speed at the influence distance (m/s)."""
AVOID_VELOCITY_LIMIT = 1.0
"""Joint velocity limit of the avoidance loop (rad/s or m/s)."""
AVOID_GAIN = 5.0
"""Pull back to the profile (1/s): :func:`armguard.avoidance.run_canned`'s default."""
AVOID_SETTLE_S = 2.0
"""Seconds the loop runs past the profile's end: :func:`armguard.avoidance.run_canned`'s default."""
GOAL_REACHED = 0.999
"""A run whose progress (fraction of the joint-space way to the goal) is at least this reached the goal."""


def console_damper(stand_off: float):
    """The :class:`~armguard.avoidance.Damper` the console runs with stand-off ``stand_off`` (m)."""
    from ..avoidance import Damper

    return Damper(stand_off=float(stand_off), influence=float(stand_off) + AVOID_INFLUENCE_MARGIN,
                  approach_speed=AVOID_APPROACH_SPEED, period=AVOID_PERIOD, velocity_limit=AVOID_VELOCITY_LIMIT)


@dataclass(frozen=True)
class AvoidedRun:
    """A canned test run with avoidance on, every control step kept.

    ``times`` (n+1,) s; ``q_cmd`` / ``q`` (n+1, n_joints) the commanded (the test's profile, held
    at its end) and the filtered configurations of ``robot`` (rad or m); ``distance_cmd`` /
    ``distance`` (n+1,) m the least distance over the robot's pairs at each; ``statuses`` the
    filter's ``{"free": n, "slowed": n, "stopped": n}`` over the n steps; ``progress`` (0..1) the
    fraction of the joint-space way to the goal covered; ``stand_off`` (m).
    """

    name: str
    robot: str
    stand_off: float
    times: np.ndarray
    q_cmd: np.ndarray
    q: np.ndarray
    distance_cmd: np.ndarray
    distance: np.ndarray
    statuses: dict
    progress: float

    # -- as a trajectory for the time line ---------------------------------------------------
    @property
    def duration(self) -> float:
        return float(self.times[-1])

    def at(self, t: float) -> np.ndarray:
        """The filtered configuration at ``t`` s (linear between control steps)."""
        x = min(max(float(t), 0.0), self.duration)
        return np.array([np.interp(x, self.times, self.q[:, j]) for j in range(self.q.shape[1])])

    def commanded_at(self, t: float) -> np.ndarray:
        """The commanded configuration at ``t`` s (linear between control steps)."""
        x = min(max(float(t), 0.0), self.duration)
        return np.array([np.interp(x, self.times, self.q_cmd[:, j]) for j in range(self.q_cmd.shape[1])])

    # -- what happened ----------------------------------------------------------------------
    @property
    def steps(self) -> int:
        return len(self.times) - 1

    @property
    def min_distance(self) -> float:
        return float(np.min(self.distance))

    @property
    def contact(self) -> bool:
        return bool(np.any(self.distance <= 0.0))

    @property
    def reached(self) -> bool:
        return self.progress >= GOAL_REACHED

    @property
    def acted(self) -> int:
        """Steps the filter changed the command (slowed, deflected or stopped)."""
        return int(self.statuses.get("slowed", 0) + self.statuses.get("stopped", 0))

    @property
    def outcome(self) -> str:
        """``"contact"``, ``"stopped short"``, ``"slid"`` (reached the goal, the filter acting on
        the way) or ``"free"`` (reached the goal, the filter never acting)."""
        if self.contact:
            return "contact"
        if not self.reached:
            return "stopped short"
        return "slid" if self.acted else "free"

    def summary(self) -> str:
        """One line for the panel, e.g. ``stopped short at 87.0 % of the way to the goal, least
        distance 200.0 mm (stand-off 200 mm); the filter acted on 571 of 1300 steps``."""
        least = f"least distance {self.min_distance * 1000:.1f} mm (stand-off {self.stand_off * 1000:g} mm)"
        acted = f"the filter acted on {self.acted} of {self.steps} steps"
        o = self.outcome
        if o == "contact":
            return f"CONTACT despite avoidance: {least}; {acted}"
        if o == "stopped short":
            return f"stopped short at {100.0 * self.progress:.1f} % of the way to the goal, {least}; {acted}"
        if o == "slid":
            return f"reached the goal sliding along the obstacle, {least}; {acted}"
        return f"reached the goal, the filter never acting; {least}"


def avoid_canned(model, name: str, stand_off: float, checker) -> AvoidedRun:
    """Run the canned test ``name`` of ``model.scene`` with avoidance at ``stand_off`` (m), keeping
    every step (:func:`armguard.avoidance.run_canned` with the console's damper, recorded)."""
    from ..avoidance import robot_rows_and_columns, run_canned

    run = run_canned(model, name, console_damper(stand_off), gain=AVOID_GAIN, settle_s=AVOID_SETTLE_S,
                     checker=checker, record=True)
    rows, ks, _ = robot_rows_and_columns(model, run.robot)
    q_full = model.scene.flat_q({r: np.asarray(v) for r, v in model.scene.canned_tests[name].setup.items()})

    def least(qr) -> float:
        full = q_full.copy()
        full[ks] = qr
        return float(checker.pair_distances(model.pin_q(full), pairs=rows).distance.min(initial=math.inf))

    times = AVOID_PERIOD * np.arange(run.steps + 1)
    return AvoidedRun(name, run.robot, float(stand_off), times, run.q_cmd_path, run.q_path,
                      np.array([least(x) for x in run.q_cmd_path]), run.distance_path, dict(run.statuses),
                      run.progress)


class AvoidMixin:
    """Avoidance on/off, the stand-off distance and canned runs with avoidance; mixed into ConsoleState
    (uses its lock, model, scene, player and run state)."""

    _avoidance = False
    _stand_off = DEFAULT_STAND_OFF
    _avoid_checker = (None, None)  # (model, its analytic checker)

    def avoidance_settings(self) -> tuple[bool, float]:
        """``(on, stand_off m)``."""
        with self._lock:
            return self._avoidance, self._stand_off

    def set_avoidance(self, on: bool) -> None:
        """Canned runs with the avoidance filter (on) or stopping by detection (off).  Needs the scene's Model."""
        with self._lock:
            if on and self._model is None:
                raise ConsoleInputError(f"avoidance: scene {self._scene.name!r} has no Model (distance Jacobians "
                                        "need one); avoidance stays off")
            self._avoidance = bool(on)
            self._changed(f"avoidance {'on' if on else 'off'}"
                          + (f": canned runs keep {self._stand_off * 1000:g} mm off" if on else ""))

    def set_stand_off(self, value) -> float:
        """Stand-off distance (m; a number or its text, 0..10): no pair may close below it with avoidance on."""
        x = parse_number(value, "stand-off distance", lo=0.0, hi=MAX_STAND_OFF, unit="m")
        with self._lock:
            self._stand_off = x
            self._changed()
            return x

    def _avoid_checker_for(self, model):
        m, c = self._avoid_checker
        if m is not model:
            from ..backends import checker

            c = checker(model, "analytic")
            self._avoid_checker = (model, c)
        return c

    def _run_avoiding(self, name: str):
        """Ranger's Test button with avoidance on: Setup, filter the whole motion, then play it."""
        from ._state import Player
        from ._timeline import Timeline

        test = self._test(name)
        self.setup(name)
        with self._lock:
            model, stand_off = self._model, self._stand_off
            if model is None or name not in model.scene.canned_tests:
                raise ConsoleInputError(f"{name} with avoidance: the scene has no Model with this test; "
                                        "turn avoidance off to run it with detection")
            self._run_state, self._run_detail = "filtering", f"with avoidance, stand-off {stand_off * 1000:g} mm"
            self._filtering = token = object()  # Stop (another thread, meanwhile) clears it
            self._changed(f"{name}: filtering the motion with avoidance (stand-off {stand_off * 1000:g} mm)")
        run = avoid_canned(model, name, stand_off, self._avoid_checker_for(model))  # seconds: outside the lock
        with self._lock:
            if getattr(self, "_filtering", None) is not token:  # the arm moved after Stop
                raise ConsoleInputError(f"{name} with avoidance: stopped while the motion was filtered; nothing ran")
            self._filtering = None
            if self._model is not model:
                self._run_state, self._run_detail = "stopped", "the model was reloaded while the motion was filtered"
                raise ConsoleInputError(f"{name} with avoidance: the model was reloaded meanwhile; run it again")
            self._stop_player()
            tl = Timeline(run.duration)
            self._player = Player("avoid", name, test.robot, run, tl, run.times, run.distance, run)
            self._apply_player_time(0.0)
            tl.play()
            self._run_state, self._run_detail = "running", f"with avoidance, stand-off {stand_off * 1000:g} mm"
            self._changed(f"running {name} with avoidance (stand-off {stand_off * 1000:g} mm)")
            return self._player

    def _tick_avoid(self, p, t: float) -> bool:
        """The time line of a run with avoidance moved to ``t``: at its end, say what the filter did."""
        if self._back_or_again(p, t) or t < p.timeline.duration:
            return True
        p.timeline.pause()
        run = p.report
        self._run_state = "stopped short by avoidance" if run.outcome == "stopped short" else "done"
        self._run_detail = f"at t = {t:.2f} s: {run.summary()}"
        self._message_is_error = run.contact
        self._message = f"{p.name}: {self._run_state} {self._run_detail}"
        return True
