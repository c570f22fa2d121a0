"""Joint-space trajectories: knots joined by straight joint-space lines with a time law per segment.

Every segment moves all joints along the straight line between its two knots; the time law
(:mod:`._profile`: trapezoidal, triangular or linear) only sets the speed along it.  The
trajectory verifier relies on this.  Builders: joint-interpolated through waypoints (WORKMATE's
"generalized joint-interpolated motion ... through a series of saved poses"), synchronised
trapezoids (joint mode; Ranger's canned tests move in task space, :mod:`._task_motion`), Cartesian straight lines through IK
and tool poses relative to a variable base frame (WORKMATE, seed ``004`` "Training").
"""

from __future__ import annotations

import math
from typing import Iterable, Iterator, Sequence

import numpy as np

from .._errors import KinematicsError, TrajectoryError
from .._values import number, refuse_complex_or_bool
from ._frames import rotation_about_axis, rotation_vector_from_matrix
from ._profile import blend_for_duration, min_time_trapezoid, path_ds, path_s, pose_samples
from ._robot import _check_X

__all__ = ["Trajectory", "PROFILES"]

PROFILES = ("trapezoidal", "linear")

_TIME_SLACK = 1e-12
"""Relative slack (of the duration) for a query time at the ends of the trajectory (round-off)."""
MAX_SAMPLES = 100_000_000
"""The most samples :meth:`Trajectory.sample` makes at once (10^8 rows: 5 GB for six joints)."""


def _array(value, name: str, ndim: int) -> np.ndarray:
    refuse_complex_or_bool(value, name, TrajectoryError)
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise TrajectoryError(f"{name}: expected numbers, got {value!r}") from exc
    if arr.ndim != ndim:
        raise TrajectoryError(f"{name}: expected a {ndim}-d array, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise TrajectoryError(f"{name}: contains NaN or infinite values")
    arr.flags.writeable = False
    return arr


def _limits(robot, value, default: np.ndarray, name: str) -> np.ndarray:
    if value is None:
        return np.asarray(default, dtype=np.float64)
    try:
        arr = np.broadcast_to(np.asarray(value, dtype=np.float64), (robot.n_joints,)).copy()
    except (TypeError, ValueError):
        raise TrajectoryError(f"{name}: expected one number or {robot.n_joints} numbers (one per joint), "
                              f"got {value!r}") from None
    if np.any(np.isnan(arr)) or np.any(arr <= 0.0):
        raise TrajectoryError(f"{name}: expected values > 0 (one per joint), got {arr.tolist()}")
    return np.minimum(arr, default)  # never faster than the robot allows


def _peak_acc_of(traj: "Trajectory", mask: np.ndarray) -> np.ndarray:
    """Peak joint accelerations over the segments selected by ``mask`` (n_segments,) bool."""
    dt = np.diff(traj.times)[mask]
    D = np.abs(np.diff(traj.waypoints, axis=0))[mask]
    tb = traj.blend_times[mask]
    return (D / ((dt - tb) * tb)[:, None]).max(axis=0)


class Trajectory:
    """An immutable joint-space trajectory.

    robot_name : str ("" for None: names no robot; the verifier takes a scene's only one);  joint_names : tuple[str, ...]
    times : (N,) float64, s, strictly increasing (N >= 2)
    waypoints : (N, n_joints) float64, rad or m
    blend_times : (N - 1,) float64, s — acceleration time of each segment's trapezoid (0: linear)
    duration : float, s (``times[-1] - times[0]``)
    """

    def __init__(self, robot_name: str, joint_names: Sequence[str], times, waypoints, blend_times=None) -> None:
        self._robot_name = "" if robot_name is None else str(robot_name)  # None: no robot named (not "None")
        if isinstance(joint_names, str) or not isinstance(joint_names, Iterable):  # "j1" read as ('j', '1')
            raise TrajectoryError(f"joint_names: expected a sequence of joint names, got {joint_names!r}")
        self._joint_names = tuple(str(j) for j in joint_names)
        if not self._joint_names:  # it moved nothing: a verdict on the robot held at home, for any motion
            raise TrajectoryError("joint_names: a trajectory moves at least one joint, got none")
        t = _array(times, "times", 1)
        w = _array(waypoints, "waypoints", 2)
        if t.shape[0] < 2:
            raise TrajectoryError(f"times: a trajectory needs at least 2 knots, got {t.shape[0]}")
        if w.shape != (t.shape[0], len(self._joint_names)):
            raise TrajectoryError(
                f"waypoints: expected shape ({t.shape[0]}, {len(self._joint_names)}) (knots x joints), got {w.shape}")
        dt = np.diff(t)
        if np.any(dt <= 0.0):
            k = int(np.argmax(dt <= 0.0))
            raise TrajectoryError(f"times: must be strictly increasing; times[{k}] = {t[k]} >= times[{k + 1}] = {t[k + 1]}")
        with np.errstate(over="ignore", divide="ignore"):
            fast = ~np.all(np.isfinite(np.diff(w, axis=0) / dt[:, None]), axis=1) | ~np.isfinite(1.0 / dt)
        if np.any(fast):  # knots so close the speed between them is past the largest float: no bound holds
            k = int(np.argmax(fast))
            raise TrajectoryError(f"times: times[{k}] = {float(t[k])!r} and times[{k + 1}] = {float(t[k + 1])!r} are so close that the speed "
                                  f"from waypoints[{k}] to waypoints[{k + 1}] is not a finite number")
        tb = np.zeros(t.shape[0] - 1) if blend_times is None else _array(blend_times, "blend_times", 1)
        if tb.shape != dt.shape:
            raise TrajectoryError(f"blend_times: expected {dt.shape[0]} values (one per segment), got {tb.shape[0]}")
        with np.errstate(over="ignore", divide="ignore"):
            tiny = (tb > 0.0) & ~np.isfinite(1.0 / tb)  # a subnormal blend: 1 / tb overflows and at() gave NaN
        if np.any(tiny):
            k = int(np.argmax(tiny))
            raise TrajectoryError(f"blend_times[{k}]: {float(tb[k])!r} s is too short to divide by (give 0 for a "
                                  "segment without a blend)")
        bad = (tb < 0.0) | (tb > 0.5 * dt * (1.0 + _TIME_SLACK))
        if np.any(bad):
            k = int(np.argmax(bad))
            raise TrajectoryError(f"blend_times[{k}]: {tb[k]:g} s must lie in [0, half the segment duration {0.5 * dt[k]:g} s]")
        tb = np.minimum(tb, 0.5 * dt)
        tb.flags.writeable = False
        self._times, self._waypoints, self._blend = t, w, tb

    robot_name = property(lambda self: self._robot_name)
    joint_names = property(lambda self: self._joint_names)
    times = property(lambda self: self._times)
    waypoints = property(lambda self: self._waypoints)
    blend_times = property(lambda self: self._blend)

    @property
    def duration(self) -> float:
        return float(self._times[-1] - self._times[0])

    @property
    def n_segments(self) -> int:
        return int(self._times.shape[0] - 1)

    def __repr__(self) -> str:
        return f"Trajectory({self._robot_name!r}, {self._times.shape[0]} knots, {self.duration:.3f} s)"

    def over_joints(self, joint_names: Sequence[str], hold) -> tuple["Trajectory", dict]:
        """This trajectory over all of ``joint_names`` (a robot's joints, in its order), when it names a
        subset of them (in any order): its own joints keep their values, every other joint is held
        at ``hold[k]`` (``(len(joint_names),)``, e.g. the robot's home) at every knot.

        Returns ``(trajectory, held)``, ``held`` the held joints ``{name: value}`` in ``joint_names``'s
        order (empty, and ``self``, when it already names exactly ``joint_names``).  A joint named
        twice or not in ``joint_names`` is a :class:`~armguard.TrajectoryError`."""
        names = tuple(str(j) for j in joint_names)
        if self._joint_names == names:
            return self, {}
        seen = set()
        for j in self._joint_names:
            if j in seen:
                raise TrajectoryError(f"joint_names: {j!r} is named twice")
            if j not in names:
                raise TrajectoryError(f"joint_names: {j!r} is not a joint of robot {self._robot_name!r}; its joints are {list(names)}")
            seen.add(j)
        h = np.asarray(hold, dtype=np.float64)
        if h.shape != (len(names),) or not np.all(np.isfinite(h)):
            raise TrajectoryError(f"hold: expected {len(names)} finite values (one per joint {list(names)}), got {h.tolist()}")
        W = np.repeat(h[None, :], self._times.shape[0], axis=0)
        col = {j: k for k, j in enumerate(names)}
        for i, j in enumerate(self._joint_names):
            W[:, col[j]] = self._waypoints[:, i]
        held = {j: float(h[k]) for k, j in enumerate(names) if j not in seen}
        return Trajectory(self._robot_name, names, self._times, W, self._blend), held

    # ------------------------------------------------------------------ evaluation
    def _locate(self, t) -> tuple[np.ndarray, np.ndarray]:
        try:
            t = np.asarray(t, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise TrajectoryError(f"t: expected times in s, got {t!r}") from exc
        if not np.all(np.isfinite(t)):
            raise TrajectoryError("t: contains NaN or infinite values")
        t0, t1 = self._times[0], self._times[-1]
        slack = _TIME_SLACK * max(1.0, self.duration)
        if np.any(t < t0 - slack) or np.any(t > t1 + slack):
            raise TrajectoryError(f"t: outside the trajectory's time span [{t0}, {t1}] s "
                                  f"(got [{float(np.min(t))}, {float(np.max(t))}])")
        t = np.clip(t, t0, t1)
        seg = np.clip(np.searchsorted(self._times, t, side="right") - 1, 0, self.n_segments - 1)
        return t, seg

    def at(self, t) -> np.ndarray:
        """Joint values at times ``t`` (...) s: ``(..., n_joints)`` rad or m (the exact segment time law)."""
        t, seg = self._locate(t)
        T = self._times[seg + 1] - self._times[seg]
        s = path_s(t - self._times[seg], T, self._blend[seg])
        q0, q1 = self._waypoints[seg], self._waypoints[seg + 1]
        q = q0 + s[..., None] * (q1 - q0)
        return np.where((s == 1.0)[..., None], q1, q)  # exactly the knot at a segment's end

    def velocity(self, t) -> np.ndarray:
        """Joint velocities at ``t`` (...) s: ``(..., n_joints)`` rad/s or m/s (right limit at a knot)."""
        t, seg = self._locate(t)
        T = self._times[seg + 1] - self._times[seg]
        ds = path_ds(t - self._times[seg], T, self._blend[seg])
        return ds[..., None] * (self._waypoints[seg + 1] - self._waypoints[seg])

    def peak_velocity(self) -> np.ndarray:
        """``(n_joints,)``: largest |joint speed| over the trajectory (rad/s or m/s)."""
        dt = np.diff(self._times)
        v = np.abs(np.diff(self._waypoints, axis=0)) / (dt - self._blend)[:, None]
        return v.max(axis=0)

    def peak_acceleration(self) -> np.ndarray:
        """``(n_joints,)``: largest |joint acceleration| inside segments (rad/s^2; inf for a linear law)."""
        dt = np.diff(self._times)
        D = np.abs(np.diff(self._waypoints, axis=0))
        with np.errstate(divide="ignore", invalid="ignore"):
            a = np.where(D > 0, D / ((dt - self._blend) * self._blend)[:, None], 0.0)
        return a.max(axis=0)

    def sample(self, *, frequency: float | None = None, dt: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Sample at ``frequency`` (Hz) or every ``dt`` (s), from the start, the end time included.

        Returns ``(t (M,) s, q (M, n_joints))``.  Exactly one of ``frequency`` and ``dt`` is given.
        """
        if (frequency is None) == (dt is None):
            raise TrajectoryError("sample: give exactly one of frequency (Hz) and dt (s)")
        if frequency is not None:  # 0 Hz divided by zero; text, True: raw errors or 1 Hz
            step = 1.0 / number(frequency, "sample: frequency", TrajectoryError, low=0.0, low_open=True, unit=" (Hz)")
        else:
            step = number(dt, "sample: dt", TrajectoryError, low=0.0, low_open=True, unit=" (s)")
        if not math.isfinite(step) or step <= 0.0:
            raise TrajectoryError(f"sample: the time step must be finite and > 0, got {step}")
        n = int(math.floor(self.duration / step * (1.0 + _TIME_SLACK)))
        if n > MAX_SAMPLES:  # dt = 1e-300 asked numpy for 10^300 samples
            raise TrajectoryError(f"sample: {n + 1:.3g} samples of {step:g} s over {self.duration:g} s; at most "
                                  f"{MAX_SAMPLES + 1:,} (a larger step, or sample a part with at())")
        t = self._times[0] + step * np.arange(n + 1)
        if self._times[-1] - t[-1] > _TIME_SLACK * max(1.0, self.duration):
            t = np.append(t, self._times[-1])
        t[-1] = self._times[-1]  # the end exactly (a last step within round-off of it is snapped)
        return t, self.at(t)

    def segments(self) -> Iterator[tuple[float, float, np.ndarray, np.ndarray]]:
        """Yield ``(t0, t1, q0, q1)`` per segment; each moves on the straight joint-space line q0 -> q1."""
        for k in range(self.n_segments):
            yield float(self._times[k]), float(self._times[k + 1]), self._waypoints[k], self._waypoints[k + 1]

    def check(self, robot, *, tol=None) -> None:
        """Raise TrajectoryError if the trajectory does not fit ``robot``: joint names, limits, max speeds.

        Joint limits are checked at the knots (segments are straight lines between them, so a box of
        limits holds in between); speeds and accelerations at their peaks.  Constant-speed (linear)
        segments change speed at their knots in a step — a sampled path such as
        :meth:`cartesian_line` — and are checked for speed only.
        """
        from .._tolerance import DEFAULT_TOLERANCES

        tol = DEFAULT_TOLERANCES if tol is None else tol
        if tuple(robot.joint_names) != self._joint_names:
            raise TrajectoryError(f"trajectory joints {list(self._joint_names)} differ from robot "
                                  f"{robot.name!r}'s {list(robot.joint_names)}")
        for k, q in enumerate(self._waypoints):
            try:
                robot.check_limits(q, tol=tol)
            except KinematicsError as exc:
                raise TrajectoryError(f"waypoints[{k}]: {exc}") from None
        linear = self._blend == 0.0
        if np.all(linear):  # constant-speed segments (dense samples): speeds only, see the docstring
            checks = (("velocity", self.peak_velocity(), robot.max_velocity),)
        else:
            checks = (("velocity", self.peak_velocity(), robot.max_velocity),
                      ("acceleration", _peak_acc_of(self, ~linear), robot.max_acceleration))
        for name, peak, lim in checks:
            over = peak > lim * (1.0 + _TIME_SLACK)
            if np.any(over):
                j = int(np.argmax(over))
                raise TrajectoryError(f"joint {self._joint_names[j]!r}: peak {name} {peak[j]:.6g} exceeds "
                                      f"max_{name} {lim[j]:.6g}")

    # ------------------------------------------------------------------ builders
    @classmethod
    def joint_interpolated(cls, robot, waypoints, *, max_velocity=None, max_acceleration=None, times=None,
                           profile: str = "trapezoidal") -> "Trajectory":
        """Through ``waypoints`` (N, n_joints), stopping at each (trapezoidal) or at constant speed (linear).

        Without ``times`` each segment takes the shortest time that keeps every joint within
        ``max_velocity`` (rad/s) and ``max_acceleration`` (rad/s^2) (default: the robot's; lower values
        slow down), all joints synchronised on the segment.  With ``times`` (N,) s the given timing is
        checked against those limits.  Waypoints must be within joint limits.
        """
        if profile not in PROFILES:
            raise TrajectoryError(f"profile: expected one of {list(PROFILES)}, got {profile!r}")
        if not hasattr(robot, "n_joints"):  # a name: the Robot is model.robots[name] (its limits are needed)
            raise TrajectoryError(f"robot: expected a Robot (e.g. model.robots[{robot!r}]), got {type(robot).__name__} "
                                  f"{robot!r}")
        W = _array(waypoints, "waypoints", 2)
        if W.shape[0] < 2 or W.shape[1] != robot.n_joints:
            raise TrajectoryError(f"waypoints: expected at least 2 rows of {robot.n_joints} joint values, got shape {W.shape}")
        for k, q in enumerate(W):
            try:
                robot.check_limits(q)
            except KinematicsError as exc:
                raise TrajectoryError(f"waypoints[{k}]: {exc}") from None
        vmax = _limits(robot, max_velocity, robot.max_velocity, "max_velocity")
        amax = _limits(robot, max_acceleration, robot.max_acceleration, "max_acceleration")
        if profile == "linear":
            amax = np.full_like(amax, np.inf)
        D = np.abs(np.diff(W, axis=0))
        if times is None:
            t, tb = [0.0], []
            for k, d in enumerate(D):
                try:
                    T, b = min_time_trapezoid(d, vmax, amax)
                except ValueError as exc:
                    raise TrajectoryError(f"segment {k}: {exc}; give times= or limits") from None
                if T <= 0.0:
                    raise TrajectoryError(f"waypoints[{k}] and waypoints[{k + 1}] are equal; give times= for a dwell")
                t.append(t[-1] + T)
                tb.append(b)
            return cls(robot.name, robot.joint_names, t, W, tb)
        t = _array(times, "times", 1)
        if t.shape[0] != W.shape[0]:
            raise TrajectoryError(f"times: expected {W.shape[0]} values (one per waypoint), got {t.shape[0]}")
        tb = []
        for k, d in enumerate(D):
            T = float(t[k + 1] - t[k])
            if T <= 0.0:
                raise TrajectoryError(f"times: must be strictly increasing; times[{k}] = {t[k]} >= times[{k + 1}] = {t[k + 1]}")
            b = blend_for_duration(T, d, vmax, amax)
            if b is None:
                Tmin = min_time_trapezoid(d, vmax, amax)[0]
                raise TrajectoryError(f"segment {k}: duration {T:.6g} s is shorter than the {Tmin:.6g} s the joint "
                                      "velocity/acceleration limits allow")
            tb.append(0.0 if profile == "linear" else b)
        return cls(robot.name, robot.joint_names, t, W, tb)

    @classmethod
    def trapezoidal(cls, robot, q_start, q_goal, *, max_velocity=None, max_acceleration=None) -> "Trajectory":
        """Shortest synchronised trapezoidal-velocity move ``q_start -> q_goal`` (a canned test's ``goal`` motion)."""
        W = np.stack([robot.check_q(q_start), robot.check_q(q_goal)])  # a short q was a raw numpy error
        return cls.joint_interpolated(robot, W, max_velocity=max_velocity, max_acceleration=max_acceleration)

    @classmethod
    def cartesian_line(cls, robot, q_start, X_WE_goal, *, speed: float = 0.1, angular_speed: float = 0.5,
                       acceleration: float = math.inf, angular_acceleration: float = math.inf,
                       frequency: float = 50.0, X_WF=None, link: str | None = None, rng=None, tol=None) -> "Trajectory":
        """Straight line of ``link`` (default the tool link) from its pose at ``q_start`` to the goal.

        ``X_WE_goal`` (4, 4) is the goal pose relative to frame F, whose pose in W is ``X_WF`` (4, 4,
        default identity) — WORKMATE's variable base frame, e.g. a part located at run time.  The
        position moves at up to ``speed`` (m/s), the orientation about a fixed axis at up to
        ``angular_speed`` (rad/s), synchronised; with finite ``acceleration`` (m/s^2) /
        ``angular_acceleration`` (rad/s^2) the motion along the line is a trapezoid (Ranger's canned
        tests move the end effector so), else constant speed.  Poses are sampled at ``frequency`` (Hz)
        and solved by IK (seeded by the previous sample); between samples the arm moves on
        joint-space lines (constant speed within a sample interval).
        Raises TrajectoryError naming the sample where IK fails or a joint would exceed its speed.
        """
        from .._tolerance import DEFAULT_TOLERANCES

        tol = DEFAULT_TOLERANCES if tol is None else tol
        for name, val in (("speed", speed), ("angular_speed", angular_speed), ("frequency", frequency),
                          ("acceleration", acceleration), ("angular_acceleration", angular_acceleration)):
            finite_required = name not in ("acceleration", "angular_acceleration")
            if not (isinstance(val, (int, float)) and val > 0 and (math.isfinite(val) or not finite_required)):
                raise TrajectoryError(f"{name}: expected a {'finite ' if finite_required else ''}number > 0, got {val!r}")
        try:
            q0 = robot.check_limits(q_start, tol=tol).reshape(robot.n_joints)
            X_WF = np.eye(4) if X_WF is None else _check_X(X_WF, "X_WF")
            X_goal = X_WF @ _check_X(X_WE_goal, "X_WE_goal")
            X_start = robot.link_pose(q0, link)
        except KinematicsError as exc:
            raise TrajectoryError(f"cartesian_line: {exc}") from None
        dp = X_goal[:3, 3] - X_start[:3, 3]
        w = rotation_vector_from_matrix(X_goal[:3, :3] @ X_start[:3, :3].T)
        angle = float(np.linalg.norm(w))
        duration, blend = min_time_trapezoid(np.array([float(np.linalg.norm(dp)), angle]),
                                             np.array([speed, angular_speed], dtype=np.float64),
                                             np.array([acceleration, angular_acceleration], dtype=np.float64))
        if duration == 0.0:
            raise TrajectoryError("cartesian_line: the goal equals the start pose")
        n = pose_samples(duration, frequency, "cartesian_line", TrajectoryError)
        times = np.linspace(0.0, duration, n + 1)
        s_path = path_s(times, duration, blend)
        axis = w / angle if angle > 0.0 else np.array([0.0, 0.0, 1.0])
        qs = [q0]
        for k in range(1, n + 1):
            s = float(s_path[k])
            X = np.eye(4)
            X[:3, :3] = rotation_about_axis(axis, s * angle)[:3, :3] @ X_start[:3, :3]
            X[:3, 3] = X_start[:3, 3] + s * dp
            if k == n:
                X = X_goal
            res = robot.inverse_kinematics(X, q_seed=qs[-1], link=link, rng=rng, tol=tol)
            if not res.ok:
                raise TrajectoryError(f"cartesian_line: inverse kinematics failed at sample {k} of {n} "
                                      f"(t = {times[k]:.4g} s): {res.status.value}: {res.message}")
            qs.append(res.q)
        traj = cls(robot.name, robot.joint_names, times, np.stack(qs))
        over = traj.peak_velocity() > robot.max_velocity
        if np.any(over):
            j = int(np.argmax(over))
            raise TrajectoryError(f"cartesian_line: joint {robot.joint_names[j]!r} would move at "
                                  f"{traj.peak_velocity()[j]:.4g} > max_velocity {robot.max_velocity[j]:.4g} "
                                  "(near a singularity or an IK branch change); lower the speed")
        return traj

    @classmethod
    def through_poses(cls, robot, q_start, poses, *, mode: str = "joint", X_WF=None, link: str | None = None,
                      speed: float = 0.1, angular_speed: float = 0.5, frequency: float = 50.0,
                      max_velocity=None, max_acceleration=None, rng=None, tol=None) -> "Trajectory":
        """WORKMATE's tool trajectory: a series of poses (K, 4, 4) relative to frame F (pose ``X_WF``).

        ``mode="joint"``: IK at each pose (seeded by the previous), then joint-interpolated
        trapezoids; ``mode="line"``: straight Cartesian lines between consecutive poses.
        """
        if mode not in ("joint", "line"):
            raise TrajectoryError(f"mode: expected 'joint' or 'line', got {mode!r}")
        P = _array(poses, "poses", 3)
        if P.shape[1:] != (4, 4) or P.shape[0] < 1:
            raise TrajectoryError(f"poses: expected (K, 4, 4) with K >= 1, got {P.shape}")
        q = np.asarray(q_start, dtype=np.float64)
        if mode == "line":
            parts = []
            for k, X in enumerate(P):
                tr = cls.cartesian_line(robot, q, X, speed=speed, angular_speed=angular_speed, frequency=frequency,
                                        X_WF=X_WF, link=link, rng=rng, tol=tol)
                parts.append(tr)
                q = tr.waypoints[-1]
            return cls.concatenate(parts)
        try:
            X_WF = np.eye(4) if X_WF is None else _check_X(X_WF, "X_WF")
        except KinematicsError as exc:
            raise TrajectoryError(str(exc)) from None
        qs = [robot.check_q(q).reshape(robot.n_joints)]
        for k, X in enumerate(P):
            res = robot.inverse_kinematics(X_WF @ X, q_seed=qs[-1], link=link, rng=rng,
                                           **({} if tol is None else {"tol": tol}))
            if not res.ok:
                raise TrajectoryError(f"poses[{k}]: inverse kinematics failed: {res.status.value}: {res.message}")
            qs.append(res.q)
        return cls.joint_interpolated(robot, np.stack(qs), max_velocity=max_velocity, max_acceleration=max_acceleration)

    @classmethod
    def concatenate(cls, parts: Sequence["Trajectory"]) -> "Trajectory":
        """Join trajectories end to start (each next one starts where the previous ended), times shifted."""
        if not parts:
            raise TrajectoryError("concatenate: no trajectories")
        for k, p in enumerate(parts):
            if not isinstance(p, Trajectory):
                raise TrajectoryError(f"concatenate: parts[{k}]: expected a Trajectory, got {type(p).__name__}")
        first = parts[0]
        t, w, b = [first.times - first.times[0]], [first.waypoints], [first.blend_times]
        end = first.duration
        for k, p in enumerate(parts[1:], start=1):
            if p.joint_names != first.joint_names:
                raise TrajectoryError(f"concatenate: parts[{k}] has joints {list(p.joint_names)}, expected {list(first.joint_names)}")
            if not np.array_equal(p.waypoints[0], w[-1][-1]):
                raise TrajectoryError(f"concatenate: parts[{k}] does not start where parts[{k - 1}] ends")
            t.append(p.times[1:] - p.times[0] + end)
            w.append(p.waypoints[1:])
            b.append(p.blend_times)
            end += p.duration
        return cls(first.robot_name, first.joint_names, np.concatenate(t), np.concatenate(w), np.concatenate(b))

    # ------------------------------------------------------------------ files
    def to_dict(self) -> dict:
        """Plain-Python form (YAML/JSON ready); floats are written exactly (repr round trip)."""
        from ._trajectory_io import trajectory_to_dict

        return trajectory_to_dict(self)

    @classmethod
    def from_dict(cls, d, *, file: str | None = None) -> "Trajectory":
        """Inverse of :meth:`to_dict`; TrajectoryError (SceneFileError when ``file`` is given) names the key."""
        from ._trajectory_io import trajectory_from_dict

        return trajectory_from_dict(cls, d, file=file)

    def save_yaml(self, path) -> None:
        """Write the trajectory to a YAML file."""
        from ._trajectory_io import save_yaml

        save_yaml(self, path)

    @classmethod
    def load_yaml(cls, path, *, groups=None) -> "Trajectory":
        """Read a trajectory written by :meth:`save_yaml`; SceneFileError names the file and the key.
        ``groups`` (e.g. ``model.group_joints``) resolves a ``joint_names`` that names an SRDF group."""
        from ._trajectory_io import load_yaml

        return load_yaml(cls, path, groups)
