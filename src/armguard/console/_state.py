"""The console's state machine: everything the operator console does, without a browser.

:class:`ConsoleState` holds the configuration of every arm, the active arm, the control mode,
the detection settings (on/off, threshold, stopping distance, workspace box) and the player of a
canned test run or a verified trajectory; each command checks its input first and raises
:class:`~armguard.console.ConsoleInputError` without changing anything when it is bad.  The
viser layer (:mod:`._app`) only binds widgets to these commands and draws what
:meth:`ConsoleState.snapshot` returns.

Ranger's GUI (Bon & Seraji 1997, seed ``000`` section 6) gives the controls: joint or Cartesian
control of the active arm (end-effector position / orientation and the arm angle), detection
on/off with a threshold, bounding-box limits, a stand-off distance, canned Setup / Test cases
with trapezoidal motions.  WORKMATE (Smith 1986, seed ``004`` section 4) gives the time line.
"""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass

import numpy as np

from ..model import scene_of
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from ._avoid import AvoidMixin
from ._backends import compare_readouts
from ._motion import MotionMixin
from ._notices import NoticesMixin
from ._overlays import OverlayMixin
from ._playback import PlaybackMixin
from ._sources import BackendFailed, SourcesMixin
from ._targets import TargetsMixin
from ._parse import ConsoleInputError, parse_number, parse_numbers, wrap_continuous
from ._readout import Readout, readout_from_report, readout_off
from ._timeline import Timeline

__all__ = ["ConsoleState", "Snapshot", "Player", "MODES", "DEFAULT_THRESHOLD", "PROFILE_SAMPLES"]

MODES = ("joint", "cartesian")
DEFAULT_THRESHOLD = 0.05
"""Detection threshold (m) when neither the caller nor a canned test sets one (the detector's default)."""
PROFILE_SAMPLES = 200
"""Samples of the clearance profile drawn on the time line (evenly spaced in time)."""
MAX_DISTANCE_SETTING = 10.0
"""Largest threshold / stopping distance the console accepts (m): larger is a typing error."""


@dataclass(frozen=True)
class Player:
    """What the time line plays: a ``trajectory`` of ``robot`` for a canned ``run`` or a ``verified`` one,
    or a canned run with avoidance on (``avoid``: ``trajectory`` and ``report`` are its
    :class:`~._avoid.AvoidedRun`, ``clearance`` the filtered least distance).

    ``times`` (N,) s and ``clearance`` (N,) m sample the minimum signed distance along it (empty for
    canned runs); ``report`` is the verification report (verified only).
    """

    kind: str
    name: str
    robot: str
    trajectory: object
    timeline: Timeline
    times: np.ndarray
    clearance: np.ndarray
    report: object = None


@dataclass(frozen=True)
class Snapshot:
    """A consistent copy of what the console shows (taken under the state's lock).

    ``q``: robot -> (n_joints,) float64 (rad or m); ``readout`` the distance panel; ``version``
    increases with every change.  ``backend`` the panel's backend, ``compare`` a
    ``Comparison`` with the second backend (or None); ``update_us`` the state's update after the
    change (the check, the comparison, terrain and uncertainty; not the panel's HTML or the
    drawing), beside ``readout.elapsed_us``, the check alone;
    ``ee_pose`` (4, 4) the active arm's tool pose now; ``run_state`` of the canned test:
    ``""``, ``"running"``, ``"done"``, ``"back at the start"`` (played backwards to t = 0),
    ``"stopped"`` (by the operator), ``"stopped by detection"``, or with avoidance on ``"filtering"`` and ``"stopped short by avoidance"``,
    with ``run_detail`` saying when (``"at t = 5.00 s"``) and, when detection stopped it (or
    the avoidance filter finished), the link, the obstacle and the distance; ``changes`` what the last model reload changed; ``terrain`` a
    :class:`~._overlays.TerrainView` (the pyramid boxes the last check tested) or None;
    ``sigmas`` the :class:`armguard.uncertainty.SigmaReport` of the uncertain placements or None;
    ``target`` ``(p_WE (3,) m, rpy (3,) rad, typed)`` the Cartesian target (:meth:`ConsoleState.target`);
    ``workspace_corners`` ``(lower, upper)`` the corner fields' values ((3,) m or None each);
    ``others`` the other arms within the threshold (:class:`~._notices.OtherArm`, :mod:`._notices`).
    """

    version: int
    q: dict
    active: str
    mode: str
    detection: bool
    threshold: float
    stopping_distance: float
    workspace: tuple | None
    readout: Readout
    message: str
    message_is_error: bool
    player: Player | None
    arm_angle: float
    backend: str = "analytic"
    compare: object = None
    update_us: float = 0.0
    ee_pose: np.ndarray | None = None
    run_state: str = ""
    run_detail: str = ""
    changes: str = ""
    terrain: object = None
    sigmas: object = None
    target: tuple | None = None
    workspace_corners: tuple = (None, None)
    others: tuple = ()


def _duration_of(trajectory) -> float:
    return float(trajectory.duration)


class ConsoleState(MotionMixin, TargetsMixin, SourcesMixin, OverlayMixin, AvoidMixin, NoticesMixin, PlaybackMixin):
    """The operator console's state and commands (thread-safe; no GUI).

    Parameters
    ----------
    scene : armguard.scene.Scene
        Copied: workspace changes made in the console do not touch the caller's scene.
    threshold : float, m
        Initial detection threshold.
    stopping_distance : float, m
        Ranger's stand-off distance: a canned run halts when the arm comes this close.
    tol : Tolerances
    model : armguard.model.Model, optional
        The scene's model: with it, every installed backend can compute the panel
        (:meth:`set_backend`) and a second one be compared (:meth:`set_compare`).
    """

    def __init__(self, scene, *, threshold: float = DEFAULT_THRESHOLD, stopping_distance: float = 0.0,
                 tol: Tolerances = DEFAULT_TOLERANCES, model=None) -> None:
        scene = scene_of(scene, "console")  # a Model: its scene
        if not scene.robots:
            raise ConsoleInputError(f"scene {scene.name!r} has no robot to drive")
        self._lock = threading.RLock()
        self._scene = scene.copy()
        self._tol = tol
        self._q = {k: np.array(v, dtype=np.float64) for k, v in self._scene.default_q().items()}
        self._active = next(iter(self._scene.robots))
        self._mode = "joint"
        self._detection = True
        self._threshold = parse_number(threshold, "threshold", lo=0.0, hi=MAX_DISTANCE_SETTING, unit="m")
        self._stopping = parse_number(stopping_distance, "stopping distance", lo=0.0, hi=MAX_DISTANCE_SETTING, unit="m")
        self._message = ""
        self._message_is_error = False
        self._player: Player | None = None
        self._arm_angle = 0.0
        self._version = 0
        self._detector = None
        self._readout = readout_off(self._threshold)
        self._model = model
        self._views: dict = {}
        self._refused: dict = {}
        self._distance_backends: tuple | None = None
        self._backend = "analytic"
        self._compare_with: str | None = None
        self._comparison = None
        self._update_us = 0.0
        self._run_state = ""
        self._run_detail = ""
        self._changes = ""
        self._rebuild_detector()
        self._evaluate()

    # ------------------------------------------------------------------ reading
    @property
    def scene(self):
        """The console's own copy of the scene."""
        return self._scene

    @property
    def robots(self) -> tuple[str, ...]:
        return tuple(self._scene.robots)

    @property
    def detector(self):
        return self._detector

    @property
    def version(self) -> int:
        return self._version

    def snapshot(self) -> Snapshot:
        with self._lock:
            ws = self._scene.workspace
            return Snapshot(
                version=self._version,
                q={k: v.copy() for k, v in self._q.items()},
                active=self._active,
                mode=self._mode,
                detection=self._detection,
                threshold=self._threshold,
                stopping_distance=self._stopping,
                workspace=None if ws is None else (ws.lo.copy(), ws.hi.copy()),
                readout=self._readout,
                message=self._message,
                message_is_error=self._message_is_error,
                player=self._player,
                arm_angle=self._arm_angle,
                backend=self._backend,
                compare=self._comparison,
                update_us=self._update_us,
                ee_pose=np.array(self._robot(self._active).link_pose(self._q[self._active])),
                run_state=self._run_state,
                run_detail=self._run_detail,
                changes=self._changes,
                terrain=self._terrain_view,
                sigmas=self._sigmas,
                target=self._target_now(),
                workspace_corners=self.workspace_corners(),
                others=self._others,
            )

    def joint_limits(self, robot: str) -> tuple[np.ndarray, np.ndarray]:
        """``(lower, upper)``, each (n_joints,) float64, rad or m."""
        r = self._robot(robot)
        return np.array(r.lower), np.array(r.upper)

    def ee_pose(self, robot: str | None = None) -> np.ndarray:
        """``X_WE`` (4, 4): pose of the robot's tool link at the current configuration."""
        with self._lock:
            name = self._active if robot is None else robot
            return np.array(self._robot(name).link_pose(self._q[name]))

    # ------------------------------------------------------------------ internals
    def _robot(self, name: str):
        try:
            return self._scene.robots[name]
        except KeyError:
            raise ConsoleInputError(f"unknown arm {name!r}; arms are {list(self._scene.robots)}") from None

    def _rebuild_detector(self) -> None:
        from ..detect import Detector

        self._detector = Detector(self._scene, self._threshold, stopping_distance=self._stopping,
                                  active=self._active, tol=self._tol)
        self._attach_overlays()

    def _evaluate(self) -> None:
        """Recompute the panel at the current configuration and bump the version (lock held)."""
        t0 = time.perf_counter()
        self._comparison = None
        if self._detection:
            failed = []  # said in the panel; the detector answers from now on
            try:
                self._readout = self._readout_of(self._backend)
            except BackendFailed as exc:
                self._backend = "analytic"
                failed.append(f"{exc}; the panel is back on analytic")
                self._readout = self._readout_of("analytic")
            if self._compare_with is not None:
                try:
                    self._comparison = compare_readouts(self._readout, self._readout_of(self._compare_with))
                except BackendFailed as exc:
                    self._compare_with = None
                    failed.append(f"{exc}; comparison off")
            if failed:
                self._message, self._message_is_error = "; ".join(failed), True
        else:
            self._readout = readout_off(self._threshold)
        self._evaluate_overlays()
        self._evaluate_others()
        self._update_us = (time.perf_counter() - t0) * 1e6
        self._version += 1

    def _changed(self, message: str = "") -> None:
        self._message = message
        self._message_is_error = False
        self._evaluate()

    def _checked_q(self, robot: str, values) -> np.ndarray:
        r = self._robot(robot)
        q = np.asarray(values, dtype=np.float64)
        lo, hi = np.asarray(r.lower), np.asarray(r.upper)
        for j in range(len(q)):
            if not (lo[j] - self._tol.joint_limit <= q[j] <= hi[j] + self._tol.joint_limit):
                raise ConsoleInputError(
                    f"{robot}/{r.joint_names[j]}: {q[j]:.10g} is outside its limits [{lo[j]:.10g}, {hi[j]:.10g}]; "
                    "value kept unchanged"
                )
        return np.clip(q, lo, hi)

    def _arm_moved(self, robot: str) -> str:
        """The arm ``robot`` moved other than by its arm angle: the active arm's arm-angle label goes back to 0
        (docs/console.md; it kept the last value, and the next slider move was taken from it).  Returns
        :meth:`_taken_over`'s note."""
        if robot == self._active:
            self._arm_angle = 0.0
        return self._taken_over(robot)

    # ------------------------------------------------------------------ settings
    def set_active(self, robot: str) -> None:
        """Select the active arm (the one driven and checked against everything)."""
        with self._lock:
            self._robot(robot)
            if robot != self._active:
                self._cancel_filtering("another arm selected")
            p = self._player
            if (p is not None and p.kind in ("run", "avoid") and self._run_state in ("running", "filtering")
                    and robot != p.robot):  # the run stops on the active arm's readout: it would stop checking its arm
                raise ConsoleInputError(f"{p.robot} is running {p.name}: stop it before selecting another arm "
                                        "(a run is stopped by the readout of the arm it moves)")
            self._active = robot
            self._arm_angle = 0.0
            self._detector.set_active(robot)
            self._changed()

    def set_mode(self, mode: str) -> None:
        """``"joint"`` or ``"cartesian"`` control."""
        if mode not in MODES:
            raise ConsoleInputError(f"mode: expected one of {list(MODES)}, got {mode!r}")
        with self._lock:
            self._mode = mode
            self._changed()

    def set_detection(self, on: bool) -> None:
        """Turn obstacle detection on or off (off: the panel is grey, never green)."""
        with self._lock:
            self._detection = bool(on)
            self._changed()

    def set_threshold(self, value) -> float:
        """Detection threshold (m; a number or its text, 0..10)."""
        x = parse_number(value, "threshold", lo=0.0, hi=MAX_DISTANCE_SETTING, unit="m")
        with self._lock:
            self._threshold = x
            self._detector.set_threshold(x)
            self._changed()
            return x

    def set_stopping_distance(self, value) -> float:
        """Stand-off / stopping distance (m; 0..10): a canned run halts this close to an obstacle."""
        x = parse_number(value, "stopping distance", lo=0.0, hi=MAX_DISTANCE_SETTING, unit="m")
        with self._lock:
            self._stopping = x
            self._detector.set_stopping_distance(x)
            self._changed()
            return x

    # ------------------------------------------------------------------ joint control
    def joint_units(self, robot: str) -> tuple[str, ...]:
        """Per joint of ``robot``, the unit the operator types: ``"deg"`` (revolute) or ``"m"`` (prismatic)."""
        r = self._robot(robot)
        types = getattr(r, "joint_types", None) or ("revolute",) * r.n_joints
        return tuple("m" if "prismatic" in str(getattr(t, "value", t)).lower() else "deg" for t in types)

    def set_joint(self, robot: str, index: int, value, *, deg: bool = False) -> float:
        """Set one joint (rad or m; a number or its text); outside its limits raises.

        With ``deg`` a revolute joint's value is in degrees and a refusal names the limits in
        degrees (the console's joint fields); prismatic joints stay in m.  A continuous joint (no
        limits) takes any angle, one past a whole turn wrapped into -180..180 deg, with a note
        (:func:`~._parse.wrap_continuous`; its slider spans -360..360 deg).
        """
        with self._lock:
            self._cancel_filtering("a joint typed")
            r = self._robot(robot)
            if isinstance(index, bool) or not isinstance(index, (int, np.integer)) or not 0 <= index < r.n_joints:
                raise ConsoleInputError(f"{robot}: joint index {index!r}: expected an integer in 0..{r.n_joints - 1}")
            j = int(index)
            in_deg = deg and self.joint_units(robot)[j] == "deg"
            unit = "deg" if in_deg else ("m" if self.joint_units(robot)[j] == "m" else "rad")
            field = f"{robot}/{r.joint_names[j]}"
            k = 180.0 / math.pi if in_deg else 1.0
            lo, hi = float(r.lower[j]) * k, float(r.upper[j]) * k
            slack = self._tol.joint_limit * k
            x = parse_number(value, field, lo=lo, hi=hi, unit=unit, slack=slack)
            note = ""
            if unit != "m" and not (math.isfinite(lo) or math.isfinite(hi)):
                x, note = wrap_continuous(x, field, k, unit)
            q = self._q[robot].copy()
            q[j] = x / k
            self._q[robot] = self._checked_q(robot, q)
            self._changed("; ".join(x for x in (note, self._arm_moved(robot)) if x))
            return float(self._q[robot][j])

    def set_joints(self, robot: str, values, *, scale: float = 1.0) -> np.ndarray:
        """Set every joint of ``robot`` from numbers or text (times ``scale``, e.g. pi/180 for degrees)."""
        with self._lock:
            self._cancel_filtering("joints typed")
            r = self._robot(robot)
            q = parse_numbers(values, f"{robot} joints", r.n_joints, scale=scale)
            self._q[robot] = self._checked_q(robot, q)
            self._changed(self._arm_moved(robot))
            return self._q[robot].copy()

    def set_q(self, q) -> None:
        """Set every arm at once (a mapping robot -> joints, or flat over ``scene.joint_names``)."""
        parts = self._scene.split_q(q)
        with self._lock:
            self._cancel_filtering("the arms set")
            new = {name: self._checked_q(name, v) for name, v in parts.items()}
            self._q = new
            notes = [self._arm_moved(self._active)] + [self._taken_over(r) for r in new if r != self._active]
            self._changed("; ".join(x for x in notes if x))

    # ------------------------------------------------------------------ canned tests
    def canned_tests(self) -> tuple[str, ...]:
        return tuple(self._scene.canned_tests)

    def _test(self, name: str):
        try:
            return self._scene.canned_tests[name]
        except KeyError:
            raise ConsoleInputError(f"unknown canned test {name!r}; tests are {list(self._scene.canned_tests)}") from None

    def setup(self, name: str) -> None:
        """Ranger's Setup button: pose every arm, select the active arm, detection on at the test's threshold."""
        test = self._test(name)
        with self._lock:
            self._stop_player()
            self._q = {k: np.array(v, dtype=np.float64) for k, v in test.setup.items()}
            self._active = test.robot
            self._arm_angle = 0.0
            self._threshold = float(test.threshold)
            self._detection = True
            self._detector.set_active(test.robot)
            self._detector.set_threshold(self._threshold)
            self._run_state = ""
            self._run_detail = ""
            self._changed(f"setup {name}: {test.description}".rstrip(": "))

    def run(self, name: str) -> Player:
        """Ranger's Test button: Setup, then play the test's trapezoidal motion with detection live
        (with avoidance on, the filtered motion instead: :meth:`AvoidMixin._run_avoiding`)."""
        if self._avoidance:
            return self._run_avoiding(name)
        test = self._test(name)
        traj = test.trajectory(self._scene)
        self.setup(name)
        with self._lock:
            tl = Timeline(_duration_of(traj))
            self._player = Player("run", name, test.robot, traj, tl, np.zeros(0), np.zeros(0))
            tl.play()
            self._run_state = "running"
            self._run_detail = ""
            self._changed(f"running {name}")
            return self._player

    # ------------------------------------------------------------------ verified trajectories
    def trajectories(self) -> tuple[str, ...]:
        return tuple(self._scene.trajectories)

    def load_trajectory(self, name: str, *, samples: int = PROFILE_SAMPLES) -> Player:
        """Verify the scene's trajectory ``name`` and put it on the time line (paused at t = 0).

        The clearance profile (minimum signed distance over the checked categories, m) is
        sampled at ``samples`` evenly spaced times with the detector's batch check; the
        verification report comes from :func:`armguard.verify.verify`.
        """
        from ..verify import verify

        try:
            traj = self._scene.trajectories[name]
        except KeyError:
            raise ConsoleInputError(f"unknown trajectory {name!r}; trajectories are {list(self._scene.trajectories)}") from None
        robot = traj.robot_name
        with self._lock:
            guard = self._terrain_guard()
            if guard is None:
                report = verify(self._scene, traj, stopping_distance=self._stopping)
            else:  # the terrain too (a verdict without it said safe where the arm goes through the ground)
                from ..terrain import verify_with_terrain

                report = verify_with_terrain(self._scene, traj, guard, stopping_distance=self._stopping)
            T = _duration_of(traj)
            times = np.linspace(0.0, T, max(2, int(samples)))
            base = {k: v.copy() for k, v in self._q.items()}
            rows = []
            for t in times:
                base[robot] = np.asarray(traj.at(float(t)), dtype=np.float64)
                rows.append(self._scene.flat_q(base))
            det = type(self._detector)(self._scene, self._threshold, stopping_distance=self._stopping,
                                       active=robot, tol=self._tol)
            batch = det.check_many(np.array(rows))
            clearance = np.min(np.asarray(batch.min_distance, dtype=np.float64), axis=1)
            if guard is not None:  # the profile against the terrain too, as the panel checks it
                ground = [guard.check(q, threshold=self._threshold, stopping_distance=self._stopping).distance for q in rows]
                clearance = np.minimum(clearance, np.asarray(ground, dtype=np.float64))
            safe = getattr(report, "safe", None)
            return self.show_verified(name, traj, times, clearance, report,
                                      f"verified {name}: {'safe' if safe else 'NOT safe'}")

    def show_verified(self, name: str, traj, times, clearance, report, message: str = "") -> Player:
        """Put an already verified trajectory on the time line (paused at t = 0): ``times`` (N,) s and
        ``clearance`` (N,) m its clearance profile, ``report`` what the Time line tab shows (its
        ``summary()``)."""
        with self._lock:
            robot = traj.robot_name
            self._robot(robot)
            self._stop_player()
            tl = Timeline(_duration_of(traj))
            self._player = Player("verified", name, robot, traj, tl, np.asarray(times, dtype=np.float64),
                                  np.asarray(clearance, dtype=np.float64), report)
            self._active = robot
            self._detector.set_active(robot)
            self._apply_player_time(0.0)
            self._changed(message)
            return self._player
