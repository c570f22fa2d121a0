"""The on-line guard: collision prediction ahead of the arm inside a controller loop.

SRI (``004_…``, "Application to Robot Controller Design") proposes running the collision
check *ahead* of the arm in the controller, on the motion about to be commanded; Hermes
(``001_…`` §2) runs its on-line check in automatic mode (pre-programmed trajectories),
operator-controlled mode (a joystick) and single-joint mode (retracting one joint at a time),
and obstacles are grown by the stopping distance "the distance required to stop the arm".

:class:`Guard` does that every control cycle: from the current configuration and the
commanded motion it predicts the joint-space straight path the arm will follow over the
next ``horizon_s`` seconds and *certifies* it by conservative advancement (the same lever-arm
bound as :func:`armguard.verify.verify`).  If some configuration of that path comes within
the stopping distance of an obstacle, it answers STOP now — while the arm still has at least
the stopping distance of clearance to brake in.  Choose ``horizon_s`` at least one control
period plus the braking time.  A prediction that cannot be finished within its evaluation
budget answers STOP too (never OK by omission).

Joint limits: the lever-arm bounds hold only within them, so a current configuration ``q``, a
setpoint ``q_cmd_next`` or a ``target`` outside ``[lower, upper]`` (beyond
``Tolerances.joint_limit``) is refused with :class:`~armguard.JointLimitError`, the rule of every
detector entry point (:mod:`armguard.kinematics._limits`).  A velocity extrapolated over the horizon
may run past a limit; the arm stops there, so the predicted path saturates at the limits
(``clip(q + s dq)``: each joint still moves at most ``|dq_i| ds``, so the same certificate holds).

Avoidance instead of stopping: ``Guard(..., avoidance=Damper(...))`` filters every commanded
joint velocity through :func:`armguard.avoidance.avoid_step` (the velocity damper of Faverjon &
Tournassoud on the Model's analytic distance Jacobians; only the guarded robot's joints may move)
before predicting.  The decision then carries the filtered velocity to send (``velocity``) and what
the filter did (``motion``: free / slowed / stopped; ``avoidance``).  Since the filter runs again
next cycle, the motion certified is the filtered velocity over one control period, not extrapolated
over the horizon; the certificate against the stopping distance still decides STOP.  The verdict
is STOP where the filter stopped the arm.  Avoidance needs a velocity: ``q_cmd_next`` or ``qdot``.
"""

from __future__ import annotations

import enum
import math
import time as _time
from dataclasses import dataclass, replace

import numpy as np

from ..model import scene_of
from .._errors import StaleModelError, VerificationError
from .._values import number
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from ..kinematics._limits import limit_error
from ._follow import FollowsScene
from ._oracle import WORKSPACE, ClearanceModel
from ._stopping import StoppingDistance, check_stopping_distance

__all__ = ["Guard", "GuardDecision", "GuardMode", "GuardVerdict"]

_GUARD_EVALUATIONS = 256  # clearance evaluations one prediction may use before answering STOP
_ATTEMPTS = 3  # predictions started over after a scene edit before answering STOP


class GuardMode(enum.Enum):
    """Hermes's on-line modes: AUTOMATIC (a programmed trajectory), OPERATOR_JOG (velocity
    commands from a joystick), SINGLE_JOINT (one joint at a time; a command moving more than
    one joint is refused)."""

    AUTOMATIC = "automatic"
    OPERATOR_JOG = "operator-jog"
    SINGLE_JOINT = "single-joint"


class GuardVerdict(enum.Enum):
    OK = "ok"
    STOP = "stop"


@dataclass(frozen=True)
class GuardDecision:
    """One cycle's answer.

    ``verdict`` OK or STOP; ``reason`` in words; ``clearance`` (m) now (smallest pair);
    ``predicted_clearance`` (m) a proven lower bound on the clearance along the predicted path
    (up to where a collision was predicted, if one was); ``time_to_collision`` (s) until the
    predicted path first comes within the stopping distance (``inf`` when it does not within the
    horizon; ``0`` when the command gives no speed — a ``target`` alone — since the arm may get
    there at once); ``pair`` the owners ``(a, b)`` that decide; ``stopping_distance`` (m) used;
    ``evaluations`` clearance evaluations spent; ``elapsed_us`` wall time of the step.
    With ``Guard(avoidance=...)``: ``velocity`` ``(n_joints,)`` rad/s or m/s the filtered joint
    velocity to command (zeros on STOP), ``avoidance`` the filter's
    :class:`~armguard.avoidance.Avoidance` (pin velocity order); both None otherwise.
    ``finished`` False where the STOP is the prediction's evaluation budget running out (a link
    grazing a surface near the stopping distance), not a collision predicted: a controller may slow
    the command down and try again rather than stop hard; False too where the avoidance filter's
    solver found no answer (``Avoidance.solver_failed``).
    """

    verdict: GuardVerdict
    reason: str
    clearance: float
    predicted_clearance: float
    time_to_collision: float
    pair: tuple[str, str] | None
    stopping_distance: float
    evaluations: int
    elapsed_us: float
    velocity: np.ndarray | None = None
    avoidance: object = None
    finished: bool = True

    @property
    def ok(self) -> bool:
        return self.verdict is GuardVerdict.OK

    @property
    def motion(self) -> str | None:
        """With avoidance: ``"free"`` (the command passes), ``"slowed"`` (changed, still moving) or
        ``"stopped"`` (the filter or the certificate stopped the arm); None without avoidance."""
        if self.avoidance is None:
            return None
        return "stopped" if not self.ok else self.avoidance.status.value


class _GuardState:
    """What one step reads (:meth:`Guard._build`, published whole): ``model`` (the ClearanceModel),
    ``base`` (the flat configuration of every robot), ``k0:k1`` (the guarded joints in it), ``names``,
    ``lower``, ``upper``, ``lo_ok``, ``hi_ok`` (their limits, and with the tolerance), ``mine`` (the
    pairs with a side on the guarded robot: the only ones its motion changes, and the only ones it
    answers for, as a verification of it); with avoidance ``v_index``, ``damper``, ``pin_model``,
    ``checker``, ``nv``."""

    __slots__ = ("model", "base", "k0", "k1", "names", "lower", "upper", "lo_ok", "hi_ok", "mine", "v_index", "damper",
                 "pin_model", "checker", "nv")


def _full(st: _GuardState, q_robot: np.ndarray) -> np.ndarray:
    """The flat configuration with the guarded robot at ``q_robot``, the others where ``st`` holds them."""
    q = st.base.copy()
    q[st.k0 : st.k1] = q_robot
    return q


def _still_hint(model, pair) -> str:
    """What the Guard's STOP reason adds when no joint moves either side of ``pair`` (a base link on
    its table: no motion changes that clearance), else nothing."""
    if not model.still(*pair):
        return ""
    if WORKSPACE in pair:
        return ("; no joint moves that part, so no path changes this clearance: enlarge the workspace box "
                "(Scene.set_workspace) if it is by design")
    return ("; no joint moves either side, so no path changes this clearance: disable the pair (Model.with_pair_disabled, "
            "a scene file's pairs: disable:) if that closeness is by design")


def _time_to(s: float, T: float) -> float:
    """Time (s) to reach fraction ``s`` of a predicted path that takes ``T`` s; 0 when ``s`` is 0 or the
    duration is unknown (``T`` inf: no commanded speed), never NaN."""
    return 0.0 if s == 0.0 or math.isinf(T) else s * T


class Guard(FollowsScene):
    """Streaming collision prediction for one robot of ``scene``.

    Parameters
    ----------
    scene : armguard.scene.Scene
    stopping_distance : float (m) or StoppingDistance
        The braking distance; with a :class:`StoppingDistance` it follows the commanded speed
        (of the fastest point of the arm) and ``payload_mass`` (kg); a ``target`` with no ``qdot``
        gives no speed, and the table's value at its top speed is used.
    horizon_s : float, s
        How far ahead the commanded motion is predicted (>= one control period + braking time).
    period_s : float, s
        Control period: a next setpoint ``q_cmd_next`` is reached in this time.
    robot : str | None
        The guarded robot (default: the scene's only robot); the others stand at ``q_others``.
    mode : GuardMode
    avoidance : armguard.avoidance.Damper | None
        Filter the commanded velocity instead of only stopping (see the module docstring); its
        ``velocity_limit`` is a number or one per joint of the guarded robot; its ``period`` is
        the control period of the filter (``period_s`` is used for ``q_cmd_next``).

    One Guard may be stepped from several threads, and its scene edited meanwhile: a step reads the
    guard's state once (the clearance model, the guarded joints' span and limits), and a step that
    finds the scene changed under it (:class:`armguard.StaleModelError`) predicts again on the scene
    as it is; after 3 such attempts it answers STOP.
    """

    def __init__(self, scene, *, stopping_distance=0.0, horizon_s: float = 0.5, period_s: float = 0.01,
                 robot: str | None = None, mode: GuardMode = GuardMode.AUTOMATIC, payload_mass: float = 0.0,
                 q_others=None, source: str = "auto", tol: Tolerances = DEFAULT_TOLERANCES, avoidance=None) -> None:
        scene = scene_of(scene, "Guard")  # a Model: its scene
        self.scene = scene
        self.avoidance = avoidance
        self.tol = tol
        self.stopping_distance = check_stopping_distance(stopping_distance)
        for nm, v in (("horizon_s", horizon_s), ("period_s", period_s)):
            if not math.isfinite(float(v)) or float(v) <= 0.0:
                raise VerificationError(f"{nm}: expected a finite number > 0 (s), got {v}")
        self.horizon_s = float(horizon_s)
        self.period_s = float(period_s)
        if self.horizon_s < self.period_s:
            raise VerificationError("horizon_s must be at least one control period (period_s)")
        self.mode = GuardMode(mode)
        self.payload_mass = number(payload_mass, "payload_mass", VerificationError, low=0.0, unit=" (kg)")
        sd = self.stopping_distance
        if isinstance(sd, StoppingDistance) and self.payload_mass > sd.mass_edges[-1]:  # every step stopped, "speed"
            raise VerificationError(f"payload_mass: {self.payload_mass:g} kg is above the stopping-distance table's "
                                    f"masses (up to {sd.mass_edges[-1]:g} kg)")
        names = list(scene.robots)
        if robot is None:
            if len(names) != 1:
                raise VerificationError(f"the scene has robots {names}: name the guarded one (robot=...)")
            robot = names[0]
        if robot not in scene.robots:
            raise VerificationError(f"robot {robot!r} is not in the scene; robots are {names}")
        self.robot = robot
        self._source = source
        self._q_others = None if q_others is None else dict(q_others)
        self._follow()

    def _build(self) -> _GuardState:
        """The clearance model, the other robots' configuration and the guarded joints of the scene as it is now."""
        scene = self.scene
        st = _GuardState()
        st.model = ClearanceModel(scene, source=self._source, tol=self.tol)
        base = scene.default_q()
        if self._q_others is not None:
            base.update({k: np.asarray(v, dtype=np.float64) for k, v in self._q_others.items()})
        st.base = scene.flat_q(base)
        k0 = 0
        for name, rob in scene.robots.items():
            if name == self.robot:
                break
            k0 += len(rob.joint_names)
        rob = scene.robots[self.robot]
        st.k0, st.k1 = k0, k0 + len(rob.joint_names)
        st.names = tuple(f"{self.robot}/{j}" for j in rob.joint_names)
        st.lower, st.upper = np.asarray(rob.lower, dtype=np.float64), np.asarray(rob.upper, dtype=np.float64)
        a = self.tol.joint_limit
        st.lo_ok, st.hi_ok = st.lower - a, st.upper + a
        st.mine = st.model.moving_pairs(self.robot)
        if not st.mine.any():  # nothing of it checked: no OK to give (as verify refuses such a robot)
            raise VerificationError(f"robot {self.robot!r} has no pair to check (no shapes, or every pair with it disabled)")
        if self.avoidance is not None:
            self._prepare_avoidance(st, self.avoidance)
        return st

    def _prepare_avoidance(self, st: _GuardState, damper) -> None:
        """The Model's analytic Checker, the guarded joints' velocity columns, and a damper whose
        velocity limits are zero on every other column (only this robot moves), into ``st``."""
        from ..avoidance import Damper
        from ..backends import checker
        from ..model import model_of

        if not isinstance(damper, Damper):
            raise VerificationError(f"avoidance: expected an armguard.avoidance.Damper, got {type(damper).__name__}")
        mdl = model_of(self.scene)
        pm = mdl.pin_model
        v_of_q = {int(pm.joints[j].idx_q): int(pm.joints[j].idx_v) for j in range(1, pm.njoints) if pm.joints[j].nq > 0}
        st.v_index = np.array([v_of_q[int(i)] for i in mdl.q_index[st.k0 : st.k1]], dtype=np.int64)
        n, nv = st.k1 - st.k0, int(pm.nv)
        lim = np.asarray(damper.velocity_limit, dtype=np.float64)
        if lim.ndim == 1 and lim.shape == (nv,) and n != nv:
            lim = lim[st.v_index]
        try:
            lim = np.broadcast_to(lim, (n,))
        except ValueError:
            raise VerificationError(f"avoidance.velocity_limit: expected a number or {n} numbers (the joints of "
                                    f"{self.robot!r}), got {damper.velocity_limit!r}") from None
        full = np.zeros(nv)
        full[st.v_index] = lim
        st.damper = replace(damper, velocity_limit=tuple(float(x) for x in full))
        st.pin_model, st.checker, st.nv = mdl, checker(mdl, "analytic"), nv

    def _in_limits(self, st: _GuardState, a: np.ndarray, name: str) -> np.ndarray:
        exc = limit_error(f"Guard.step: {name}", a, st.names, st.lower, st.upper, self.tol.joint_limit)
        if exc is not None:
            raise exc
        return a

    @staticmethod
    def _check(st: _GuardState, x, name: str) -> np.ndarray:
        a = np.asarray(x, dtype=np.float64)
        if a.shape != (st.k1 - st.k0,):
            raise VerificationError(f"{name}: expected {st.k1 - st.k0} joint values, got shape {a.shape}")
        if not np.all(np.isfinite(a)):
            raise VerificationError(f"{name}: contains NaN or infinite values")
        return a

    def step(self, q, q_cmd_next=None, *, qdot=None, target=None) -> GuardDecision:
        """One control cycle.

        Parameters
        ----------
        q : (n_joints,) rad or m
            The current configuration.
        q_cmd_next : (n_joints,) | None
            The next setpoint (reached in ``period_s``): the commanded joint velocity is
            ``(q_cmd_next - q) / period_s``, extrapolated over the horizon.
        qdot : (n_joints,) rad/s | None
            Or a commanded joint velocity (operator jog), extrapolated over the horizon.
        target : (n_joints,) | None
            Or the end of the commanded segment (automatic mode): the predicted path is the
            segment ``q -> target``, cut at the horizon when ``qdot`` gives its speed.

        Exactly one of ``q_cmd_next`` / ``qdot`` / ``target`` (``target`` may come with ``qdot``).
        With ``avoidance``: ``q_cmd_next`` or ``qdot`` only; the decision's ``velocity`` is the one to send.
        """
        t_start = _time.perf_counter()
        try:
            if self.avoidance is None:
                return self._on_one_state(lambda st: self._step(st, q, q_cmd_next, qdot, target, self.horizon_s),
                                          _ATTEMPTS, "predict")
            return self._on_one_state(lambda st: self._avoid(st, q, q_cmd_next, qdot, target, t_start), _ATTEMPTS, "predict")
        except StaleModelError as exc:  # never OK from a prediction that did not finish on one scene
            sd = self.stopping_distance
            m = sd.max_distance if isinstance(sd, StoppingDistance) else float(sd)
            dec = self._decide(GuardVerdict.STOP, str(exc), math.nan, -math.inf, 0.0, None, m, 0, t_start)
            return dec if self.avoidance is None else replace(dec, velocity=np.zeros(len(self._st.names)))

    def _avoid(self, st: _GuardState, q, q_cmd_next, qdot, target, t_start: float) -> GuardDecision:
        """:meth:`step` with the avoidance filter, on the state ``st``."""
        q = self._in_limits(st, self._check(st, q, "q"), "q")
        if target is not None:
            raise VerificationError("step with avoidance: a target is not filtered; give the commanded velocity, "
                                    "q_cmd_next or qdot")
        if (q_cmd_next is None) == (qdot is None):
            raise VerificationError("step with avoidance: give the commanded velocity as one of q_cmd_next or qdot, "
                                    f"{'not both' if qdot is not None else 'got neither'}")
        if q_cmd_next is not None:
            qd = (self._in_limits(st, self._check(st, q_cmd_next, "q_cmd_next"), "q_cmd_next") - q) / self.period_s
        else:
            qd = self._check(st, qdot, "qdot")
        from ..avoidance import AvoidanceStatus, avoid_step

        v_cmd = np.zeros(st.nv)
        v_cmd[st.v_index] = qd
        damper = st.damper
        moving = np.flatnonzero(qd)
        if self.mode is GuardMode.SINGLE_JOINT and len(moving) == 1:  # the filter may slow that joint, move no other
            lim = np.zeros(st.nv)  # (it deflected a one-joint jog into a slide of several, then stopped by this mode)
            col = int(st.v_index[moving[0]])
            lim[col] = damper.limits(st.nv)[col]
            damper = replace(damper, velocity_limit=tuple(float(x) for x in lim))
        av = avoid_step(st.checker, st.pin_model.pin_q(_full(st, q)), v_cmd, damper, tol=self.tol)
        v = np.array(av.velocity[st.v_index])
        dec = self._step(st, q, None, v, None, damper.period, checked=True)
        if av.status is AvoidanceStatus.STOPPED and dec.ok:
            dec = replace(dec, verdict=GuardVerdict.STOP, reason=f"avoidance stopped the arm ({av.solver})",
                          finished=not av.solver_failed)  # a solver that gave no answer: not a finished decision
        if not dec.ok:
            v = np.zeros_like(v)
        v.flags.writeable = False
        return replace(dec, velocity=v, avoidance=av, elapsed_us=(_time.perf_counter() - t_start) * 1e6)

    def _step(self, st: _GuardState, q, q_cmd_next, qdot, target, horizon_s: float, checked: bool = False) -> GuardDecision:
        """The prediction and its certificate over ``horizon_s`` on the state ``st`` (``checked``: ``q`` is
        checked already)."""
        t_start = _time.perf_counter()
        if not checked:
            q = self._in_limits(st, self._check(st, q, "q"), "q")
        if q_cmd_next is not None:
            if qdot is not None or target is not None:
                raise VerificationError("give q_cmd_next, or qdot (optionally with target), or target")
            qd = (self._in_limits(st, self._check(st, q_cmd_next, "q_cmd_next"), "q_cmd_next") - q) / self.period_s
            q_end = q + qd * horizon_s
        elif target is not None:
            tgt = self._in_limits(st, self._check(st, target, "target"), "target")
            qd = None if qdot is None else self._check(st, qdot, "qdot")
            q_end = tgt
            if qd is not None:
                # how long the segment takes at this speed; predict no further than the horizon
                with np.errstate(divide="ignore", invalid="ignore"):
                    ratios = np.where(np.abs(qd) > 0.0, np.abs(tgt - q) / np.abs(qd), np.where(tgt == q, 0.0, np.inf))
                t_seg = float(np.max(ratios)) if len(ratios) else 0.0
                if t_seg > horizon_s:
                    q_end = q + (tgt - q) * (horizon_s / t_seg)
        elif qdot is not None:
            qd = self._check(st, qdot, "qdot")
            q_end = q + qd * horizon_s
        else:
            raise VerificationError("step: give the commanded motion (q_cmd_next, qdot or target)")
        dq = q_end - q
        # the predicted duration of the path q -> q_end (for the time to collision)
        if qd is None:
            T = math.inf
        else:
            with np.errstate(divide="ignore", invalid="ignore"):
                r = np.where(np.abs(qd) > 0.0, np.abs(dq) / np.abs(qd), 0.0)
            T = float(np.max(r)) if len(r) else 0.0
        model = st.model
        full_dq = np.zeros(model.n_q)
        full_dq[st.k0 : st.k1] = dq
        if qd is not None:
            full_qd = np.zeros(model.n_q)
            full_qd[st.k0 : st.k1] = qd
            speed = model.max_point_speed(full_qd)
        else:  # a target with no speed: the arm may move at any speed the table holds (its value at 0 said OK 43 mm
            speed = None  # from a pair with a 100 mm table)
        sd = self.stopping_distance
        if isinstance(sd, StoppingDistance):
            try:
                m = sd.at(sd.speed_edges[-1] if speed is None else speed, self.payload_mass)
            except VerificationError as exc:
                return self._decide(GuardVerdict.STOP, f"commanded speed outside the stopping-distance table: {exc}",
                                    math.nan, -math.inf, 0.0, None, sd.max_distance, 0, t_start)
        else:
            m = float(sd)
        if self.mode is GuardMode.SINGLE_JOINT and int(np.count_nonzero(dq)) > 1:
            moving = [self.scene.robots[self.robot].joint_names[i] for i in np.flatnonzero(dq)]
            return self._decide(GuardVerdict.STOP, f"single-joint mode: joints {moving} commanded together",
                                math.nan, -math.inf, math.inf, None, m, 0, t_start)
        rates = model.pair_rates(full_dq)
        pos = rates > 0.0
        s = 0.0
        d = np.where(st.mine, model.distances(_full(st, q))[0], np.inf)  # another robot's pairs: not this guard's
        evals = 1
        now = float(d.min())
        lower = now
        contact = self.tol.verify_contact
        while True:
            gap = d - m
            if np.isnan(gap).any():  # never a verdict from a NaN: stop
                return self._decide(GuardVerdict.STOP, f"a clearance is NaN at {s:.3f} of the commanded segment: no "
                                    "prediction", now, -math.inf, _time_to(s, T), None, m, evals, t_start)
            i = int(np.argmin(gap))
            if gap[i] <= contact:
                pair = (model.owner_a[i], model.owner_b[i])
                ttc = _time_to(s, T)
                if s == 0.0:
                    why = f"clearance {d[i] * 1e3:.1f} mm is within the stopping distance {m * 1e3:.1f} mm now"
                elif math.isinf(T):
                    why = (f"predicted to come within the stopping distance {m * 1e3:.1f} mm at {s:.3f} of the "
                           "commanded segment (no speed given)")
                else:
                    why = f"predicted to come within the stopping distance {m * 1e3:.1f} mm in {ttc:.3f} s"
                why += f" ({pair[0]} / {pair[1]})" + _still_hint(model, pair)
                return self._decide(GuardVerdict.STOP, why, now, min(lower, float(d[i])), ttc, pair, m, evals, t_start)
            if s >= 1.0 or not np.any(pos):
                break
            step = float(np.min(gap[pos] / rates[pos]))
            s_next = min(1.0, s + step)
            if evals >= _GUARD_EVALUATIONS or not s_next > s:
                return replace(self._decide(GuardVerdict.STOP, "prediction not finished within its evaluation budget",
                                            now, lower, _time_to(s, T), (model.owner_a[i], model.owner_b[i]), m, evals,
                                            t_start), finished=False)
            # saturated at the limits (see the module docstring); q itself is within them
            d_next = np.where(st.mine, model.distances(_full(st, np.clip(q + s_next * dq, st.lo_ok, st.hi_ok)))[0], np.inf)
            evals += 1
            L = s_next - s
            lower = min(lower, float(np.min(np.minimum(np.minimum(d, d_next), 0.5 * (d + d_next - rates * L)))))
            s, d = s_next, d_next
        return self._decide(GuardVerdict.OK, "predicted path clear of the stopping distance", now, lower, math.inf, None, m, evals, t_start)

    @staticmethod
    def _decide(verdict, reason, now, lower, ttc, pair, m, evals, t_start) -> GuardDecision:
        return GuardDecision(verdict, reason, float(now), float(lower), float(ttc), pair, float(m), int(evals),
                             (_time.perf_counter() - t_start) * 1e6)
