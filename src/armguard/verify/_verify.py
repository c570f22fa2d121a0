"""Trajectory verification: sampled (Hermes) and certified (conservative advancement).

Hermes (``001_…`` §2–4) checks "a set of joint coordinates representing different
configurations of the arm during its movement along a planned trajectory" against obstacles
grown by the stopping distance; between two checks the fastest point of the arm moves up to
``Ed = v / f`` (eq. 4-2), so a thin obstacle can slip between samples.  The certified method
closes that gap.  Every Trajectory segment moves on the straight joint-space line
``q(s) = q0 + s (q1 - q0)``, ``s`` in [0, 1]; along it the clearance of pair ``p`` can shrink by
at most ``rate_p * |s' - s|`` where ``rate_p = |q1 - q0| . (lever_a + lever_b)`` (see
:mod:`._motion`).  From an evaluated point with clearances ``d_p``, conservative advancement
steps to ``s + min_p (d_p - m) / rate_p`` — every configuration in between is proven at least
``m`` (the stopping distance) from every obstacle — and evaluates there; it stops at a
collision (``d_p - m <= verify_contact``), at the end of the segment, or when the evaluation
budget is spent (INCOMPLETE).  It cannot step over an obstacle however thin: it never misses a
collision (within ``verify_contact``), and the first collision it reports is the first one.
"""

from __future__ import annotations

import dataclasses
import math
import time as _time

import numpy as np

from ..model import scene_of
from .._errors import KinematicsError, TrajectoryError, VerificationError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from ._advance import advance_step
from ._follow import FollowsScene, VerifierState as _State
from ._oracle import CATEGORIES, WORKSPACE, ClearanceModel
from ._record import _Run
from ._report import (Clearance, ClearanceProfile, Collision, CollisionKind, MethodDetails, VerificationReport,
                      VerificationStatus, speeds_over_limits)
from ._stopping import StoppingDistance, check_stopping_distance
from ._subdivide import Subdivided
from ._timelaw import finite_array as _finite_array
from ._timelaw import profile_times, segment_times, segments_of
from ._trajectory_file import trajectory_of, within_limits

__all__ = ["Verifier", "verify", "DRAKE_JOINT_STEP"]

#: Drake's suggested edge-checking step (rad), used by sampled mode when no frequency is given.
DRAKE_JOINT_STEP = 0.05
_ATTEMPTS = 5  # verifications started over after a scene edit before giving up (StaleModelError)
_SPEED_SAMPLES = 17  # time-law samples per segment used to find its peak speed (both ends and the midpoint)
_OBJECTS = {"link-obstacle": ("arm", "obstacle"), "link-link": ("arm", "arm"), "payload-obstacle": ("payload", "obstacle"),
            "payload-link": ("arm", "payload"), "link-workspace": ("arm", "workspace"),
            "payload-workspace": ("payload", "workspace"), "payload-payload": ("payload", "payload")}


def _float(x, name: str) -> float:
    """``x`` as a float, or a VerificationError naming the argument (range checks are the caller's)."""
    try:
        return float(x)
    except (TypeError, ValueError):
        raise VerificationError(f"{name}: expected a number, got {x!r}") from None


class Verifier(FollowsScene):
    """Verifies trajectories of one robot of ``scene`` (the precomputation made explicit).

    Parameters
    ----------
    scene : armguard.scene.Scene
    robot : str | None
        The moving robot (default: the trajectory's ``robot_name``, or the scene's only robot).
    q_others : mapping robot -> (n_joints,) | None
        Where the other robots stand, and where the moving robot's joints a trajectory or an edge leaves out
        are held (default: ``scene.default_q()``).
    source : "auto" | "detector" | "reference"
        Where clearances come from (:class:`ClearanceModel`).
    tol : Tolerances
    backend, backend_options : str, mapping
        The backend the detector source takes its distances from (argument > ``$ARMGUARD_BACKEND``
        > ``armguard.toml`` > ``"analytic"``); the motion bounds are the scene's, whatever the backend.

    One Verifier may verify on several threads at once, and its scene may be edited meanwhile: each
    verification reads the clearance model once and counts its own evaluations; one that finds the
    scene changed under it (:class:`armguard.StaleModelError`) starts again on the scene as it is,
    up to 5 times, so every report is of one state of the scene, never a mix.
    """

    def __init__(self, scene, *, robot: str | None = None, q_others=None, source: str = "auto", tol: Tolerances = DEFAULT_TOLERANCES,
                 backend: str | None = None, backend_options=None) -> None:
        scene = scene_of(scene, "Verifier")  # a Model: its scene
        self.scene = scene
        self.tol = tol
        self._source = source
        self._backend = (backend, backend_options)
        self._robot = robot
        if q_others is not None and not hasattr(q_others, "items"):
            raise VerificationError(f"q_others: expected a mapping robot name -> joint values, got {type(q_others).__name__}")
        self._q_others = None if q_others is None else dict(q_others)
        self._follow()

    def _build(self) -> _State:
        """The clearance model and every robot's configuration of the scene as it is now."""
        model = ClearanceModel(self.scene, source=self._source, tol=self.tol, backend=self._backend[0],
                               backend_options=self._backend[1])
        base = self.scene.default_q()
        if self._q_others is not None:
            for k, v in self._q_others.items():
                if k not in base:
                    raise VerificationError(f"q_others names unknown robot {k!r}; robots are {list(base)}")
                base[k] = within_limits(self.scene.robots[k], _finite_array(v, f"q_others[{k!r}]"), f"q_others[{k!r}]")
        return _State(model, base)

    # ------------------------------------------------------------ helpers
    def _robot_of(self, trajectory, robot: str | None) -> str:
        names = list(self.scene.robots)
        own = getattr(trajectory, "robot_name", None)
        r = robot or self._robot or own
        if not r and len(names) == 1:  # a trajectory that names no robot: the scene's only one
            r = names[0]
        if r not in self.scene.robots:
            raise VerificationError(f"robot {r!r} is not in the scene; robots are {names}")
        if own and own != r and own in self.scene.robots:  # never a verdict on an arm the trajectory is not for
            raise VerificationError(f"robot {r!r}: the trajectory is for robot {own!r} of this scene; verify it on "
                                    f"{own!r} (robot= names the arm of a trajectory that names none, or one not "
                                    "in the scene)")
        return r

    def _over_robot(self, trajectory, r: str, base: dict):
        """``(trajectory, held)``: a trajectory naming a subset of robot ``r``'s joints (any order)
        over all of them, the others held where the verifier holds the robot (its home, or
        ``q_others[r]``); ``held`` those joints and values."""
        from ..kinematics import Trajectory

        rob = self.scene.robots[r]
        if tuple(trajectory.joint_names) == tuple(rob.joint_names):
            return trajectory, {}
        inner = trajectory._t if isinstance(trajectory, Subdivided) else trajectory
        if not isinstance(inner, Trajectory):
            raise VerificationError(
                f"trajectory joints {list(trajectory.joint_names)} do not match robot {r!r} joints {list(rob.joint_names)}")
        try:
            full, held = inner.over_joints(rob.joint_names, base[r])
        except TrajectoryError as exc:
            raise VerificationError(f"robot {r!r}: {exc}") from None
        return (Subdivided(full, trajectory.n) if inner is not trajectory else full), held

    def _flat(self, robot: str, base: dict):
        base = self.scene.flat_q(base)
        k0 = 0
        for name, rob in self.scene.robots.items():
            if name == robot:
                return base, k0, k0 + len(rob.joint_names)
            k0 += len(rob.joint_names)
        raise VerificationError(f"unknown robot {robot!r}")  # pragma: no cover - checked before

    def _check_knots_in_limits(self, segs, rname: str, pieces: int = 1) -> None:
        """A knot outside the joint limits is a motion the arm cannot make: no verdict (segments are
        straight joint-space lines, so knots within the limits keep the whole path within them).  The
        waypoints checked are the given trajectory's (every ``pieces``-th knot of a Subdivided one: its
        pieces' knots lie on the lines between them)."""
        rob = self.scene.robots[rname]
        knots = ([segs[0][2]] + [sg[3] for sg in segs])[::pieces]
        if bool(np.all(rob.within_limits(np.stack(knots), tol=self.tol))):  # one batched test; the loop names the culprit
            return
        for k, q in enumerate(knots):
            try:
                rob.check_limits(q, tol=self.tol)
            except KinematicsError as exc:
                raise VerificationError(f"trajectory waypoints[{k}]: {exc}") from None

    def _segment_speeds(self, trajectory, segs, k0: int, k1: int, model: ClearanceModel) -> tuple:
        """``(speeds, bound)``: per segment, the speed (m/s) of the arm's fastest point at the time law's peak, and
        whether it is a bound (closed form) or the largest of :data:`_SPEED_SAMPLES` samples (any other time law)."""
        from ..kinematics import Trajectory

        if not len(model.parts):
            return np.zeros(len(segs)), True

        def fastest_point(peak_qd, bound: bool) -> tuple:  # (segments, joints) -> max over parts of lever . |qd|
            qd = np.zeros((len(segs), model.n_q))
            qd[:, k0:k1] = _finite_array(peak_qd, "trajectory velocity")
            return np.max(qd @ model.lever[:-1].T, axis=1), bound

        if type(trajectory).velocity is Trajectory.velocity:
            # the trapezoid time law's peak path speed is its plateau (or triangle apex) 1 / (T - tb)
            # (kinematics._profile.path_ds): the peak joint speeds in closed form, no sampling
            dt = np.diff(np.asarray(trajectory.times, dtype=np.float64))
            v = 1.0 / (dt - np.asarray(trajectory.blend_times, dtype=np.float64))
            W = np.asarray(trajectory.waypoints, dtype=np.float64)
            return fastest_point(np.abs(v[:, None] * (W[1:] - W[:-1])), True)
        exact = getattr(trajectory, "piece_peak_joint_speeds", None)
        exact = exact() if exact is not None else None
        if exact is not None and len(exact) == len(segs):  # Subdivided(Trajectory): each piece's peak in closed form
            return fastest_point(exact, True)
        # the ends too (an accelerating piece peaks at its end), each taken 1e-9 of the segment inside it: at a
        # knot a constant-speed segment's velocity is its neighbour's
        u = np.linspace(0.0, 1.0, _SPEED_SAMPLES)
        u[0], u[-1] = 1e-9, 1.0 - 1e-9
        ts = np.concatenate([t0 + u * (t1 - t0) for t0, t1, _, _ in segs])
        V = np.abs(_finite_array(trajectory.velocity(ts), "trajectory velocity")).reshape(len(segs), _SPEED_SAMPLES, -1)
        return fastest_point(V.max(axis=1), False)

    # ------------------------------------------------------------ the check
    def _trajectory_name(self, trajectory) -> str:
        """The trajectory's own name, else its name among the scene's canned trajectories."""
        own = getattr(trajectory, "name", None)
        if own:
            return str(own)
        inner = trajectory._t if isinstance(trajectory, Subdivided) else trajectory
        for key, canned in getattr(self.scene, "trajectories", {}).items():
            if canned is inner:
                return str(key)
        return "trajectory"

    def verify(self, trajectory, *, stopping_distance=0.0, method: str = "certified", frequency: float | None = None,
               joint_step: float | None = None, robot: str | None = None, threshold: float | None = None,
               payload_mass: float = 0.0, name: str | None = None) -> VerificationReport:
        """Verify ``trajectory``; see :func:`verify` for the parameters."""
        t_start = _time.perf_counter()
        trajectory, name = trajectory_of(self.scene, trajectory, name)
        if method not in ("certified", "sampled"):
            raise VerificationError(f"method: expected 'certified' or 'sampled', got {method!r}")
        sd = check_stopping_distance(stopping_distance)
        if frequency is not None:
            frequency = _float(frequency, "frequency")
            if not math.isfinite(frequency) or frequency <= 0.0:
                raise VerificationError(f"frequency: expected a finite number > 0 (Hz), got {frequency}")
        if joint_step is not None:
            joint_step = _float(joint_step, "joint_step")
            if not math.isfinite(joint_step) or joint_step <= 0.0:
                raise VerificationError(f"joint_step: expected a finite number > 0 (rad), got {joint_step}")
        if frequency is not None and joint_step is not None:  # joint_step was dropped: fewer checks than asked for
            raise VerificationError("give frequency or joint_step, not both: sampled mode checks at one or the other")
        if method == "certified" and (frequency is not None or joint_step is not None):  # they were ignored
            raise VerificationError(f"{'frequency' if frequency is not None else 'joint_step'}: sampled mode's option; "
                                    "the certified method bounds every instant, with no step to choose")
        if method == "sampled" and frequency is None and joint_step is None:
            joint_step = DRAKE_JOINT_STEP
        thr = 0.05 if threshold is None else _float(threshold, "threshold")
        if not math.isfinite(thr) or thr < 0.0:
            raise VerificationError(f"threshold: expected a finite number >= 0 (m), got {thr}")
        mass = _float(payload_mass, "payload_mass")
        if not math.isfinite(mass) or mass < 0.0:
            raise VerificationError(f"payload_mass: expected a finite number >= 0 (kg), got {mass}")
        args = (sd, method, frequency, joint_step, robot, thr, mass, name, t_start)
        return self._on_one_state(lambda st: self._verify_once(st, trajectory, *args), _ATTEMPTS, "verify this trajectory")

    def check_edges(self, Q0, Q1, *, robot: str | None = None, joints=None, margin: float | dict = 0.0,
                    max_evaluations: int | None = None, first_contact: bool = False, continuous: str = "line",
                    progress=None):
        """Certify the straight joint-space edges ``Q0[i] -> Q1[i]`` ``(M, n)`` or ``(n,)`` (one side may be a
        single configuration) of one robot (``robot="*"``: of every robot at once, the scene's flat joint order):
        its joints in its order, or those ``joints`` names (the others held where this Verifier holds them),
        within limits.  :class:`EdgeResults`: ``CLEAR`` for every
        configuration at least ``margin`` (m; or by pair category, ``{"arm-arm": 0.0, "*": 0.02}``) clear,
        ``INCOMPLETE`` after ``max_evaluations`` per edge
        (``Tolerances.edge_max_evaluations``); ``first_contact``: a COLLISION's ``s`` is the first contact
        along the edge (more evaluations); ``continuous="shortest"`` turns continuous joints the short way
        (default: along the angle's line, as trajectories); ``progress(done, total)`` is called now and then.
        The covering: :mod:`armguard.verify._edges`."""
        from ._edges import check_edges_on

        return self._on_one_state(lambda st: check_edges_on(self, st, Q0, Q1, robot, margin, max_evaluations, joints,
                                                                 first_contact, continuous, progress),
                                  _ATTEMPTS, "check these edges")

    def _verify_once(self, st, trajectory, sd, method, frequency, joint_step, robot, thr, mass, name, t_start):
        """One verification with the clearance model and configurations ``st`` (:meth:`_current`)."""
        model, base_q = st.model, st.base
        rname = self._robot_of(trajectory, robot)
        named = self._trajectory_name(trajectory) if name is None else name
        pieces = trajectory.n if isinstance(trajectory, Subdivided) else 1
        trajectory, held = self._over_robot(trajectory, rname, base_q)
        base, k0, k1 = self._flat(rname, base_q)
        segs = segments_of(trajectory)
        self._check_knots_in_limits(segs, rname, pieces)
        speeds, bound = self._segment_speeds(trajectory, segs, k0, k1, model)
        if isinstance(sd, StoppingDistance):
            if not bound and len({x for row in sd.table for x in row}) > 1:  # a sampled peak bounds nothing (a 3 ms spike)
                raise VerificationError(f"a speed-dependent stopping distance needs each segment's peak speed, which a "
                                        f"{type(trajectory).__name__} gives in no closed form (its velocity is only sampled): "
                                        "give it piece_peak_joint_speeds() (per segment, the peak |qdot| of each joint), "
                                        "or verify with a constant stopping distance")
            margins = np.array([sd.at(v, mass) for v in speeds])
        else:
            margins = np.full(len(segs), sd)
        run = _Run(model, base, k0, k1, rname, capacity=2 * len(segs) + 2)
        run.pieces = pieces  # segment numbers are the given trajectory's
        if not run.moving.any():
            raise VerificationError(f"robot {rname!r} has no pair to check (no shapes, or every pair with it disabled)")
        if method == "certified":
            status, reason, lower, intervals, where = self._certified(segs, margins, run)
            ed = 0.0
        else:
            status, reason, lower, intervals, where, ed = self._sampled(trajectory, segs, margins, run, frequency, joint_step, speeds)
        rep = self._report(trajectory, rname, segs, run, status, reason, lower, intervals, where, ed, speeds, margins, method,
                           frequency, joint_step, thr, sd, named, t_start, k0)
        over = speeds_over_limits(trajectory, self.scene.robots[rname])
        return dataclasses.replace(rep, held_joints=held, over_speed=over) if held or over else rep

    def _certified(self, segs, margins, run):
        """Conservative advancement along every segment; returns (status, reason, lower bound, intervals, where).

        The per-pair arithmetic after each evaluation (gap, next step, interval lower bound) is one
        call of :func:`._advance.advance_step`; the pair rates of all segments are computed at once.
        """
        model, tol = run.model, self.tol
        contact = tol.verify_contact
        budget = tol.verify_max_evaluations
        lower = math.inf
        intervals = 0
        n_seg = len(segs)
        Q0 = np.stack([sg[2] for sg in segs])
        Q1 = np.stack([sg[3] for sg in segs])
        dQ = np.zeros((n_seg, model.n_q))
        dQ[:, run.k0 : run.k1] = Q1 - Q0
        rates_all = np.abs(dQ) @ model.pair_lever.T  # (segments, pairs): pair_rates of every segment at once
        finite = np.all(np.isfinite(rates_all), axis=1)
        same_knot = np.zeros(n_seg, dtype=bool)
        same_knot[1:] = np.all(Q1[:-1] == Q0[1:], axis=1)
        row = -1  # the evaluation at the end of the previous segment
        for si in range(n_seg):
            m = float(margins[si])
            q0, q1 = Q0[si], Q1[si]
            dq = q1 - q0
            rates = rates_all[si]
            if not finite[si]:
                raise VerificationError("the motion bound is infinite (an unbounded prismatic joint): certified mode cannot bound this motion")
            s = 0.0
            if row < 0 or not same_knot[si]:
                row = run.eval(si, 0.0, q0)
            prev, L = row, 0.0
            while True:
                g, i_min, step, lb = advance_step(run.D[row], run.D[prev], rates, m, L, prev != row)
                if g != g:
                    raise VerificationError(f"a clearance in segment {si // run.pieces} is NaN: no verdict")
                if prev != row:
                    lower = min(lower, lb)
                    intervals += 1
                if g <= contact:
                    return VerificationStatus.COLLISION, "", lower, intervals, (si, s, int(i_min))
                if s >= 1.0:
                    break
                s_next = min(1.0, s + step)
                if not s_next > s:
                    return VerificationStatus.INCOMPLETE, f"no progress in segment {si // run.pieces} (clearance {g:.3g} m)", lower, intervals, (si, s, None)
                if run.n >= budget:
                    return VerificationStatus.INCOMPLETE, f"evaluation budget ({budget}) spent in segment {si // run.pieces}", lower, intervals, (si, s, None)
                prev, L = row, s_next - s
                row = run.eval(si, s_next, q1 if s_next == 1.0 else q0 + s_next * dq)
                s = s_next
        return VerificationStatus.SAFE, "", lower, intervals, None

    def _sample_counts(self, segs, frequency, joint_step) -> np.ndarray | None:
        """Per-segment joint-space steps of ``joint_step`` (None with ``frequency``); a request for more
        samples than ``Tolerances.verify_max_evaluations`` is refused before any work or memory is spent."""
        cap = self.tol.verify_max_evaluations
        if frequency is not None:
            duration = float(segs[-1][1] - segs[0][0])
            n = duration * frequency + 2.0
            if not n <= cap:
                raise VerificationError(
                    f"frequency: {frequency:g} Hz over the trajectory's {duration:g} s asks for {n:.3g} samples; at most "
                    f"{cap} (Tolerances.verify_max_evaluations): lower the frequency or use method='certified'")
            return None
        widest = np.array([float(np.max(np.abs(sg[3] - sg[2]))) if len(sg[2]) else 0.0 for sg in segs])
        steps = np.maximum(1.0, np.ceil(widest / joint_step))
        if not float(np.sum(steps)) + 1.0 <= cap:
            raise VerificationError(
                f"joint_step: {joint_step:g} rad asks for {float(np.sum(steps)) + 1.0:.3g} samples; at most {cap} "
                "(Tolerances.verify_max_evaluations): raise joint_step or use method='certified'")
        return steps.astype(np.int64)

    def _sampled(self, trajectory, segs, margins, run, frequency, joint_step, speeds):
        model = run.model
        steps = self._sample_counts(segs, frequency, joint_step)
        if frequency is not None:
            ts, Q = trajectory.sample(frequency=frequency)
            ts = _finite_array(ts, "sample times")
            Q = _finite_array(Q, "samples")
            starts = np.array([sg[0] for sg in segs])
            seg_of = np.clip(np.searchsorted(starts, ts, side="right") - 1, 0, len(segs) - 1)
            ed = float(np.max(speeds)) / frequency
            points = []
            for t, q, si in zip(ts, Q, seg_of):
                t0, t1, q0, q1 = segs[si]
                dq = q1 - q0
                k = int(np.argmax(np.abs(dq)))
                s = float((q[k] - q0[k]) / dq[k]) if dq[k] != 0.0 else (t - t0) / max(t1 - t0, 1e-300)
                points.append((int(si), min(max(s, 0.0), 1.0), q, float(t)))
        else:
            ed = 0.0
            points = []
            for si, (t0, t1, q0, q1) in enumerate(segs):
                dq = q1 - q0
                n = int(steps[si])
                rate_max = float(np.max(model.pair_rates(run.full_dq(dq)))) if len(model.owner_a) else 0.0
                ed = max(ed, rate_max / n)
                first = 0 if si == 0 else 1
                for k in range(first, n + 1):
                    s = k / n
                    points.append((si, s, q0 + s * dq, None))
        for si, s, q, t in points:
            row = run.eval(si, s, q, t)  # may grow run.D: index it after
            d = run.D[row]
            gap = d - margins[si]
            if np.isnan(gap).any():
                raise VerificationError(f"a clearance in segment {si // run.pieces} is NaN: no verdict")
            if float(gap.min()) <= 0.0:
                return VerificationStatus.COLLISION, "", -math.inf, 0, (si, s, int(np.argmin(gap))), ed
        return VerificationStatus.SAFE, "", -math.inf, 0, None, ed

    # ------------------------------------------------------------ the report
    def _report(self, trajectory, rname, segs, run, status, reason, lower, intervals, where, ed, speeds, margins, method,
                frequency, joint_step, thr, sd, name, t_start, k0):
        model = run.model
        collision = None
        if where is not None:
            si, s_c, pair = where
            if status is VerificationStatus.COLLISION:
                t_last = float(run.t[run.n - 1])
                t_c = t_last if t_last == t_last else float(segment_times(trajectory, segs, [si], [s_c])[0])
                collision = self._collision(run, si, t_c, pair, rname, float(margins[si]))
            else:
                t_c = float(segment_times(trajectory, segs, [si], [s_c])[0])
                reason = reason + f" (t = {t_c:.4f} s)"
        # the profile
        n = run.n
        seg_idx = run.seg[:n]
        s_arr = run.s[:n]
        t_known = run.t[:n].copy()
        need = np.isnan(t_known)
        if np.any(need):  # a segment's ends are its knot times; only points inside need the time law inverted
            t_seg0 = np.array([sg[0] for sg in segs])
            t_seg1 = np.array([sg[1] for sg in segs])
            at0 = need & (s_arr <= 0.0)
            at1 = need & (s_arr >= 1.0)
            t_known[at0] = t_seg0[seg_idx[at0]]
            t_known[at1] = t_seg1[seg_idx[at1]]
            need &= ~(at0 | at1)
            if np.any(need):
                t_known[need] = profile_times(trajectory, segs, seg_idx[need], s_arr[need])
        D = run.D[:n]  # (M, P)
        order = np.argsort(t_known, kind="stable")
        times = t_known[order]
        D = D[order]
        by_cat = {}
        for c_i, c in enumerate(CATEGORIES):
            cols = (model.category_code == c_i) & run.moving
            if np.any(cols):
                by_cat[c] = D[:, cols].min(axis=1)
        overall = D.min(axis=1)
        i_min = int(np.argmin(overall))
        p_min = int(np.argmin(D[i_min]))
        q_min = run.Q[order[i_min]].copy()
        min_at = Clearance(float(overall[i_min]), float(times[i_min]), model.owner_a[p_min], model.owner_b[p_min], model.category[p_min], q_min)
        profile = ClearanceProfile(times, overall, by_cat)
        details = MethodDetails(
            method=method,
            samples_evaluated=int(run.n),
            intervals_certified=int(intervals) if method == "certified" else 0,
            frequency=frequency,
            joint_step=joint_step if method == "sampled" else None,
            max_speed=float(np.max(speeds)),
            discretisation_error=float(ed),
            source=model.source, backend=str(getattr(model._det, "backend", "") or "") if model.source == "detector" else "",
        )
        return VerificationReport(
            status=status,
            first_collision=collision,
            min_clearance=float(overall[i_min]),
            min_clearance_at=min_at,
            min_clearance_lower_bound=float(lower) if method == "certified" and np.isfinite(lower) else (float(overall[i_min]) if method == "certified" and lower == math.inf else -math.inf),
            profile=profile,
            details=details,
            stopping_distance=float(np.max(margins)),
            threshold=thr,
            scene=str(getattr(self.scene, "name", "scene")),
            robot=rname,
            trajectory=name or self._trajectory_name(trajectory),
            duration=float(segs[-1][1] - segs[0][0]),
            elapsed_s=_time.perf_counter() - t_start,
            reason=reason,
            stopping_distance_function=sd if isinstance(sd, StoppingDistance) else None,
            stopping_times=np.array([sg[0] for sg in segs] + [segs[-1][1]], dtype=np.float64),
            stopping_values=np.asarray(margins, dtype=np.float64).copy(),
        )

    def _moves(self, owner: str, run) -> bool:
        """Whether the moving robot's joints move any point of ``owner`` (a part with a lever arm)."""
        return run.model.moves(owner, run.k0, run.k1)

    def _collision(self, run, si, t_c, pair, rname, margin: float) -> Collision:
        model = run.model
        q_full = run.full_q(run.n - 1)
        pA, pB = run.last_witnesses()
        pA = np.array(pA[pair])
        pB = np.array(pB[pair])
        a, b = model.owner_a[pair], model.owner_b[pair]
        check = model.check[pair]
        if check == "link-link" and self._moves(b, run) and not self._moves(a, run):
            a, b, pA, pB = b, a, pB, pA  # name the moving link as the link, the still one as the obstacle
        d = float(run.D[run.n - 1, pair])
        contact = max(self.tol.length, self.tol.verify_contact)  # apart beyond both: a stopping-distance violation
        link = a.split("/", 1)[1] if "/" in a else None
        payload = a if check.startswith("payload-") else (b if check == "payload-link" else None)
        feature = None
        if b != WORKSPACE and "/" not in b:
            feature = _feature_of(self.scene, q_full, b, pB, self.tol)
        return Collision(
            time=t_c,
            q=np.array(q_full[run.k0 : run.k1]),
            distance=d,
            link=link,
            obstacle=b,
            payload=payload,
            feature=feature,
            p_W=0.5 * (pA + pB),
            p_WA=pA,
            p_WB=pB,
            a=a,
            b=b,
            category=model.category[pair],
            check=check,
            objects=_OBJECTS[check],
            segment=int(si) // run.pieces,
            stopping_distance=margin,
            kind=CollisionKind.STOPPING_DISTANCE if d > contact and margin > 0.0 else CollisionKind.CONTACT,
            fixed=run.model.still(a, b),
        )


def _feature_of(scene, q, owner: str, p_W: np.ndarray, tol):
    """The face / edge / vertex of ``owner``'s shape nearest ``p_W`` (None when geometry offers no feature_at)."""
    try:
        from ..geometry import distance, feature_at
        from ..geometry import Sphere
    except ImportError:
        return None
    from ..model import kinematics_of

    kin = kinematics_of(scene)
    shapes = [it.shape for it in scene.shapes_at(q, poses=kin.link_poses(q) if kin is not None else {}) if it.owner == owner]
    if not shapes:
        return None
    probe = Sphere(p_W, 0.0)
    best = min(shapes, key=lambda s: abs(distance(probe, s, tol=tol).distance))
    try:
        return feature_at(best, p_W, tol)
    except Exception:  # noqa: BLE001 - a feature is a courtesy of the report, never part of the verdict
        return None


def verify(scene, trajectory, *, stopping_distance=0.0, method: str = "certified", frequency: float | None = None,
           joint_step: float | None = None, robot: str | None = None, threshold: float | None = None,
           payload_mass: float = 0.0, q_others=None, source: str = "auto", name: str | None = None,
           tol: Tolerances = DEFAULT_TOLERANCES, backend: str | None = None, backend_options=None) -> VerificationReport:
    """Verify a trajectory of one robot of ``scene`` against every checked pair (Hermes's four checks).

    Parameters
    ----------
    scene : armguard.scene.Scene
    trajectory : armguard.kinematics.Trajectory, or the path of a trajectory YAML file
        Every segment moves on the straight joint-space line between its knots.  A file is read
        and checked against the scene (:func:`load_trajectory`: an error names the file, the key
        and its line).
    stopping_distance : float (m) or StoppingDistance
        Obstacles are grown by it (Hermes): a pair closer than this is a collision.  A
        :class:`StoppingDistance` gives it per segment from the segment's peak speed (of the
        fastest point of the arm) and ``payload_mass`` (kg).
    method : "certified" | "sampled"
        certified: conservative advancement, proven between evaluations (never misses a
        collision); sampled: Hermes's discrete checks at ``frequency`` (Hz) along the time law,
        or every ``joint_step`` (rad, default 0.05, Drake's suggestion) in joint space (one of
        the two: both, or either with the certified method, is a VerificationError); it
        reports Hermes's discretisation error ``Ed = v / f``.  A request for more samples than
        ``Tolerances.verify_max_evaluations`` (200 000) is refused (VerificationError) before
        any work; certified mode spends at most that many evaluations and reports INCOMPLETE.
    robot : str | None
        The moving robot (default: the trajectory's ``robot_name``); the others stand at
        ``q_others`` (default: ``scene.default_q()``).
    threshold : float | None, m
        Warning threshold drawn on the plot (default 0.05).
    source : "auto" | "detector" | "reference"
        Where clearances come from (the Detector's pair distances, or shapes + exact distances).
    name : str | None
        The trajectory's name in the report.
    backend, backend_options : str, mapping
        Whose distances the clearances are (see :class:`Verifier`).

    Returns
    -------
    VerificationReport
        SAFE, COLLISION (with the first collision) or INCOMPLETE (never read as safe).
    """
    scene = scene_of(scene, "verification")  # a Model: its scene
    v = Verifier(scene, robot=robot, q_others=q_others, source=source, tol=tol, backend=backend,
                 backend_options=backend_options)
    return v.verify(trajectory, stopping_distance=stopping_distance, method=method, frequency=frequency,
                    joint_step=joint_step, robot=robot, threshold=threshold, payload_mass=payload_mass, name=name)
