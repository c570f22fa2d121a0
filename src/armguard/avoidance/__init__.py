"""Collision avoidance: the closest safe joint velocity to a command (velocity dampers).

Ranger's detector fed collision avoidance; this is that step, on the distance Jacobians of
:meth:`armguard.backends.Checker.pair_distances` (``jacobian=True``).  Every pair closer than the
influence distance ``d_i`` may not close faster than the velocity damper of Faverjon &
Tournassoud ("A local based approach for path planning of manipulators with a high number of
degrees of freedom", ICRA 1987) allows:

    d'(q) v >= -xi (d - d_s) / (d_i - d_s)                                      (1)

with ``d_s`` the stand-off distance and ``xi`` (m/s) the approach speed allowed at ``d_i``; the
filtered velocity ``v`` is the solution of the small QP

    minimise 1/2 |v - v_cmd|^2   subject to (1) for every such pair,  -v_max <= v <= v_max,

and, at a configuration ``q`` (:func:`avoid_step`), each bounded joint may not pass its position limit
within one control period: ``(lower - q) / period <= v <= (upper - q) / period`` (clamped to include 0).

Three changes keep it safe in discrete time and always feasible:

* the damper's rate ``xi / (d_i - d_s)`` is capped at ``1 / period``, so that one control period
  at the allowed rate cannot carry a pair past ``d_s`` (to first order);
* :func:`avoid_step` checks the end of the period itself (second order and beyond): every pair's
  distance at ``q + v period``; where a pair would end below ``d_s`` (or, already inside, closer
  than now) -- a distance curving along the motion, or a pair outside ``d_i`` crossing the band in
  one period -- ``v`` is halved until none does (at most :data:`END_CHECK_HALVINGS` times, then
  stopped).  At the cap the first-order step had carried a Ranger pair 8 mm past a 30 mm
  stand-off at 2 Hz, and into contact with stand-off 0;
* a pair already inside the stand-off distance (``d < d_s``) may not close at all (``d' v >= 0``)
  instead of being pushed out, and a joint at (or, within ``Tolerances.joint_limit``, past) a limit
  may not move further out: ``v = 0`` satisfies every constraint, so the QP is never infeasible and
  stopping is always an answer.

The QP is solved by DAQP (Arnström, Bemporad & Axehill, "A dual active-set solver for embedded
quadratic programming using recursive LDLᵀ updates", IEEE TAC 2022): an active-set method, so
the answer satisfies the constraints to round-off (an ADMM solver's would hold them to its
tolerance only), and the fastest of the dense solvers measured here for tens of constraints
(``docs/avoidance.md``).  Where DAQP reports anything but an optimum, or its answer breaks a
constraint by more than ``Tolerances.avoid_feasibility``, the answer is to stop.
"""

from __future__ import annotations

import enum
import functools
import math
from dataclasses import dataclass

import numpy as np

from .._errors import AvoidanceError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances

__all__ = ["avoid", "avoid_step", "velocity_bounds", "Damper", "Avoidance", "AvoidanceStatus", "robot_rows_and_columns"]


class AvoidanceStatus(str, enum.Enum):
    """What the filter did to the command."""

    FREE = "free"  # the command passes unchanged
    SLOWED = "slowed"  # the command was changed (slowed, deflected or clipped to the limits); the arm still moves
    STOPPED = "stopped"  # the closest safe velocity is zero (or the solver failed): stop


@dataclass(frozen=True)
class Damper:
    """The velocity damper's settings.

    ``stand_off`` (m) the distance ``d_s`` no pair may close below; ``influence`` (m) the distance
    ``d_i > d_s`` within which a pair is constrained; ``approach_speed`` (m/s) ``xi``, the closing
    speed allowed at ``d_i``; ``period`` (s) the control period; ``velocity_limit`` (rad/s or m/s)
    a number or ``(nv,)`` per velocity column, ``|v| <= velocity_limit``.
    """

    stand_off: float
    influence: float
    approach_speed: float
    period: float
    velocity_limit: float | tuple = math.inf

    def __post_init__(self) -> None:
        for name in ("stand_off", "influence", "approach_speed", "period"):
            v = getattr(self, name)
            if isinstance(v, bool) or not (isinstance(v, (int, float)) and math.isfinite(v)):  # True is no 1 m
                raise AvoidanceError(f"Damper.{name}: expected a finite number, got {v!r}")
        if self.stand_off < 0.0:
            raise AvoidanceError(f"Damper.stand_off: expected >= 0 m, got {self.stand_off}")
        if not self.influence > self.stand_off:
            raise AvoidanceError(f"Damper.influence: expected more than stand_off ({self.stand_off} m), got {self.influence}")
        if not self.approach_speed > 0.0:
            raise AvoidanceError(f"Damper.approach_speed: expected > 0 m/s, got {self.approach_speed}")
        if not self.period > 0.0:
            raise AvoidanceError(f"Damper.period: expected > 0 s, got {self.period}")
        try:
            raw = np.asarray(self.velocity_limit)
        except (TypeError, ValueError):  # ragged
            raw = np.array([np.nan])
        # text ('1.0'), bools, complex: refused, not read as numbers
        lim = raw.astype(np.float64) if raw.dtype.kind in "iuf" else np.array([np.nan])
        if lim.ndim > 1 or lim.size == 0 or np.any(np.isnan(lim)) or np.any(lim < 0.0):
            raise AvoidanceError(f"Damper.velocity_limit: expected a number or one per velocity column, each >= 0 "
                                 f"(inf: none), got {self.velocity_limit!r}")

    @functools.cached_property
    def _limits(self) -> dict:
        """nv -> ``(nv,)`` velocity limits, made once per column count (the dataclass is frozen)."""
        return {}

    def limits(self, nv: int) -> np.ndarray:
        """``(nv,)`` read-only: the velocity limit of each column."""
        lim = self._limits.get(nv)
        if lim is None:
            try:
                lim = np.array(np.broadcast_to(np.asarray(self.velocity_limit, dtype=np.float64), (nv,)))
            except ValueError as exc:
                raise AvoidanceError(f"Damper.velocity_limit: expected a number or {nv} numbers, got "
                                     f"{self.velocity_limit!r}") from exc
            lim.flags.writeable = False
            self._limits[nv] = lim
        return lim

    def rate(self) -> float:
        """The damper's rate ``xi / (d_i - d_s)`` (1/s), capped at ``1 / period``."""
        return min(self.approach_speed / (self.influence - self.stand_off), 1.0 / self.period)

    def bound(self, distance: np.ndarray) -> np.ndarray:
        """The least allowed ``d'`` (m/s) of pairs at ``distance`` ``(k,)`` (m): the right side of (1)."""
        return -self.rate() * np.maximum(np.asarray(distance, dtype=np.float64) - self.stand_off, 0.0)


@dataclass(frozen=True)
class Avoidance:
    """One avoidance step.

    ``velocity`` ``(nv,)`` the filtered joint velocity; ``commanded`` ``(nv,)`` the command;
    ``status`` an :class:`AvoidanceStatus`; ``rows`` ``(k,) int`` the rows (of the distances given)
    that were constrained (closer than ``influence``); ``rate`` ``(k,)`` their allowed least
    ``d'`` (m/s) and ``closing`` ``(k,)`` their ``d'`` at ``velocity`` (``closing >= rate``);
    ``min_distance`` (m) the least distance given; ``solver`` a note (``"daqp: optimal"``,
    ``"none: no pair within influence"``, ``"none: 2 pairs within influence, moved by no joint"``, or why it stopped).
    """

    velocity: np.ndarray
    commanded: np.ndarray
    status: AvoidanceStatus
    rows: np.ndarray
    rate: np.ndarray
    closing: np.ndarray
    min_distance: float
    solver: str

    @property
    def solver_failed(self) -> bool:
        """STOPPED because DAQP gave no optimum, or one that broke a constraint: no closest safe velocity was
        found (a zero optimum is a true answer; this is none)."""
        return self.solver.startswith("daqp: ") and self.solver.endswith("; stopped")


def _all_finite(*arrays) -> bool:
    """Every entry of every array finite: one sum each first (finite in the common case); only a
    sum that is not (an overflow, or a NaN or infinity) looks entry by entry."""
    for a in arrays:
        if not math.isfinite(float(a.sum())) and not np.isfinite(a).all():
            return False
    return True


def _check_command(v_cmd, nv: int) -> np.ndarray:
    """``v_cmd`` as a fresh ``(nv,)`` float64 array (a copy: a caller reusing its buffer does not change a result's
    ``commanded``); complex and bool entries refused (``1+1j`` dropped its imaginary part, ``True`` read 1 rad/s)."""
    from .._values import refuse_complex_or_bool

    refuse_complex_or_bool(v_cmd, "v_cmd", AvoidanceError)
    try:
        v = np.array(v_cmd, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise AvoidanceError(f"v_cmd: expected {nv} numbers, got {v_cmd!r}") from exc
    if v.shape != (nv,):
        raise AvoidanceError(f"v_cmd: expected shape ({nv},) (pin_model's velocity columns), got {v.shape}")
    if not _all_finite(v):
        raise AvoidanceError(f"v_cmd: contains NaN or infinite values: {v.tolist()}")
    return v


def _bounded_joints(pin_model) -> tuple:
    """``(idx_q, idx_v)`` int64 arrays of the one-coordinate joints (revolute, prismatic; not a mimic,
    not a continuous joint's (cos, sin)) with a finite limit on either side, made once per model."""
    got = _BOUNDED.get(id(pin_model))
    if got is not None and got[0] is pin_model:
        return got[1]
    iq, iv = [], []
    lo, hi = pin_model.lowerPositionLimit, pin_model.upperPositionLimit
    for jm in pin_model.joints[1:]:
        if jm.nq == 1 and jm.nv == 1 and "Mimic" not in jm.shortname():
            i = int(jm.idx_q)
            if math.isfinite(lo[i]) or math.isfinite(hi[i]):
                iq.append(i)
                iv.append(int(jm.idx_v))
    out = (np.asarray(iq, dtype=np.int64), np.asarray(iv, dtype=np.int64))
    _BOUNDED[id(pin_model)] = (pin_model, out)
    return out


_BOUNDED: dict = {}  # id(pin_model) -> (pin_model, its bounded joints): a few models per process


def velocity_bounds(pin_model, q, damper: "Damper") -> tuple[np.ndarray, np.ndarray]:
    """``(lo, hi)`` ``(nv,)``: the damper's velocity limits, tightened so that one control period at
    the bound cannot carry a joint past its position limit, ``(lower - q) / period <= v <= (upper - q)
    / period``; each bound clamped to include 0 (a joint at or, within the allowance, past a limit may
    stay or move back in: stopping is always an answer).  ``q``: Pinocchio's configuration."""
    lim = damper.limits(pin_model.nv)
    lo, hi = -lim, lim.copy()
    iq, iv = _bounded_joints(pin_model)
    if len(iq):
        qq = np.asarray(q, dtype=np.float64)[iq]
        period = damper.period
        hi[iv] = np.minimum(hi[iv], np.maximum((pin_model.upperPositionLimit[iq] - qq) / period, 0.0))
        lo[iv] = np.maximum(lo[iv], np.minimum((pin_model.lowerPositionLimit[iq] - qq) / period, 0.0))
    return lo, hi


def avoid(v_cmd, distances, damper: Damper, *, bounds=None, tol: Tolerances = DEFAULT_TOLERANCES) -> Avoidance:
    """The closest joint velocity to ``v_cmd`` ``(nv,)`` that keeps every pair of ``distances``
    (a :class:`~armguard.backends.PairDistances` with ``jacobian``) within its velocity damper
    (see the module docstring).  Never infeasible: at worst the answer is to stop.  ``bounds``:
    ``(lo, hi)`` velocity bounds in place of the damper's ``±velocity_limit``
    (:func:`velocity_bounds`: the joint limits too)."""
    jac = getattr(distances, "jacobian", None)
    if jac is None:
        raise AvoidanceError("avoid: the distances carry no Jacobian; ask pair_distances(q, jacobian=True)")
    jac = np.asarray(jac, dtype=np.float64)
    d = np.asarray(distances.distance, dtype=np.float64)
    if jac.ndim != 2 or jac.shape[0] != len(d):
        raise AvoidanceError(f"avoid: {len(d)} distances but a Jacobian of shape {jac.shape}")
    nv = jac.shape[1]
    v_cmd = _check_command(v_cmd, nv)
    if not _all_finite(d, jac):
        raise AvoidanceError("avoid: a distance or a Jacobian entry is NaN or infinite; no velocity can be given")
    lo, hi = (-damper.limits(nv), damper.limits(nv)) if bounds is None else \
        (np.asarray(bounds[0], dtype=np.float64), np.asarray(bounds[1], dtype=np.float64))
    if lo.shape != (nv,) or hi.shape != (nv,) or not np.all(lo <= 0.0) or not np.all(hi >= 0.0):  # NaN: refused
        raise AvoidanceError(f"avoid: bounds must be two ({nv},) arrays of numbers with lo <= 0 <= hi")
    near = d < damper.influence
    rows = np.flatnonzero(near & (np.einsum("ij,ij->i", jac, jac) > tol.avoid_row ** 2))
    A = np.ascontiguousarray(jac[rows])
    b = damper.bound(d[rows])
    dmin = float(d.min()) if len(d) else math.inf
    clipped = np.minimum(np.maximum(v_cmd, lo), hi)
    if len(rows) == 0 or np.all(A @ clipped >= b):
        return _result(clipped, v_cmd, rows, b, A, dmin, _quiet_note(len(rows), int(near.sum())), tol)
    import daqp

    big = 1e30  # DAQP's "no bound"
    upper = np.concatenate([np.minimum(hi, big), np.full(len(rows), big)])
    lower = np.concatenate([np.maximum(lo, -big), b])
    x, _, flag, _ = daqp.solve(np.eye(nv), -v_cmd, A, upper, lower, np.zeros(nv + len(rows), dtype=np.intc))
    x = np.clip(np.asarray(x, dtype=np.float64), lo, hi)  # the limits exactly (DAQP meets them to its tolerance)
    if flag != 1 or not np.all(np.isfinite(x)):
        return _result(np.zeros(nv), v_cmd, rows, b, A, dmin, f"daqp: exit flag {flag}; stopped", tol)
    worst = max(float(np.max(b - A @ x, initial=0.0)), float(np.max(x - hi, initial=0.0)),
                float(np.max(lo - x, initial=0.0)))
    if worst > tol.avoid_feasibility:
        return _result(np.zeros(nv), v_cmd, rows, b, A, dmin, f"daqp: a constraint broken by {worst:.3g}; stopped", tol)
    return _result(x, v_cmd, rows, b, A, dmin, "daqp: optimal", tol)


def _quiet_note(k: int, near: int) -> str:
    """The note of a step that leaves the command as it is (clipped to the bounds): ``k`` damper rows, of
    ``near`` pairs within influence (the others' distances do not move with the joints)."""
    if k:
        return "none: no constraint binds"
    return "none: no pair within influence" if not near else \
        f"none: {near} pair{'s' if near > 1 else ''} within influence, moved by no joint"


def _result(v, v_cmd, rows, b, A, dmin, note, tol) -> Avoidance:
    still = tol.avoid_still
    if len(v) and float(np.abs(v).max()) <= still and float(np.abs(v_cmd).max()) > still:
        status = AvoidanceStatus.STOPPED
    elif not len(v) or float(np.abs(v - v_cmd).max()) <= still:
        status = AvoidanceStatus.FREE
    else:
        status = AvoidanceStatus.SLOWED
    return Avoidance(v, v_cmd, status, rows, b, A @ v, dmin, note)


def avoid_step(checker, q, v_cmd, damper: Damper, *, pairs=None, tol: Tolerances = DEFAULT_TOLERANCES) -> Avoidance:
    """:func:`avoid` at configuration ``q`` with ``checker``'s distances: every pair's distance
    (or the Model rows ``pairs``: one arm's, say) and the Jacobians of the pairs within
    ``damper.influence`` -- all rows in one call where the checker computes Jacobians with its
    distances (``jacobian_with_distances``, the analytic backend), else those rows only.
    ``rows`` of the result are Model pair rows.  The velocity bounds are :func:`velocity_bounds` at
    ``q``: the damper's limits and the joint limits (a joint commanded past its limit is slowed to reach
    it in one period, not past it: the next step's ``q`` stays a configuration a checker answers for).
    The arithmetic around the QP is compiled (:mod:`._fast`); :func:`avoid` is its reference, which has no
    end-of-period check (module docstring): a step that check scaled or stopped says so in ``solver``."""
    from ..backends import check_pairs, check_q
    from ._fast import filter_velocity

    model = checker.model
    if pairs is None:
        idx = None
    elif type(pairs) is np.ndarray and pairs.dtype == np.int64 and pairs.ndim == 1 and pairs.flags.c_contiguous:
        idx = pairs  # the checker refuses rows outside the Model's
    else:
        idx = check_pairs(model, pairs)
    if type(q) is not np.ndarray or q.dtype != np.float64:
        q = check_q(model, q)
    if getattr(checker, "jacobian_with_distances", False):
        r = checker.pair_distances(q, pairs=idx, jacobian=True)
        d, J, near = r.distance, r.jacobian, idx
    else:
        r = checker.pair_distances(q, pairs=idx)
        k = np.flatnonzero(r.distance < damper.influence)
        near = k if idx is None else idx[k]
        sub = r.take(k)
        d, J = sub.distance, checker.distance_jacobian(q, sub, near)[0]
    nv = J.shape[1]
    if type(v_cmd) is not np.ndarray or v_cmd.dtype != np.float64 or v_cmd.shape != (nv,):
        v_cmd = _check_command(v_cmd, nv)
    else:
        v_cmd = v_cmd.copy()  # the result's ``commanded``: not the caller's buffer, which it may reuse
    d = np.ascontiguousarray(d, dtype=np.float64)
    J = np.ascontiguousarray(J, dtype=np.float64)
    lo, hi = velocity_bounds(model.pin_model, q, damper)
    v, rows, rate, closing, status, note = filter_velocity(v_cmd, d, J, lo, hi, damper, tol)
    if status is AvoidanceStatus.STOPPED and note.startswith("none:"):  # no damper acted: the bounds stopped it
        note = f"joint or velocity limits: the command clipped to 0 ({note})"
    dist = r.distance
    dmin = float(dist.min()) if len(dist) else math.inf
    if np.any(v):
        v2, why = _end_checked(checker, q, v, dist, idx, damper)
        if v2 is not v:
            v, note, closing = v2, f"{note}; {why}", J[rows] @ v2
            status = AvoidanceStatus.STOPPED if not np.any(v) else AvoidanceStatus.SLOWED
    if near is not None:
        rows = near[rows]
    return _new_avoidance(v, v_cmd, status, rows, rate, closing, dmin, note)


END_CHECK_HALVINGS = 10
"""Halvings of a step's velocity the end-of-period check tries before it stops the arm (1/1024 of it)."""


def _end_checked(checker, q, v, d_now, idx, damper: Damper):
    """``(v, note)``: ``v`` when no pair ends the period ``q + v period`` below the stand-off (or, already inside
    it, closer than now), else ``v`` halved until none does (zeros after :data:`END_CHECK_HALVINGS`), with a note
    naming the pair."""
    import pinocchio as pin

    pm = checker.model.pin_model
    # outside the stand-off: not below it at all; inside: not closer than now (less round-off: unmoved pairs)
    floor = np.where(d_now >= damper.stand_off, damper.stand_off, d_now - 1e-12)
    scale = 1.0
    for k in range(END_CHECK_HALVINGS + 1):
        q_end = pin.integrate(pm, q, v * (scale * damper.period))
        d_end = checker.pair_distances(q_end, pairs=idx).distance
        bad = ~(d_end >= floor)  # a NaN distance is no proof: halved too
        if not bad.any():
            if k == 0:
                return v, ""
            return v * scale, (f"end-of-period check: scaled by 1/{2 ** k} (a pair would have ended the period "
                               f"{1e3 * worst_d:.2f} mm apart, stand-off {1e3 * damper.stand_off:.2f} mm)")
        i = int(np.flatnonzero(bad)[0])
        if k == 0:
            worst_d = float(d_end[i])
        scale *= 0.5
    return np.zeros_like(v), (f"end-of-period check: stopped (a pair would end the period {1e3 * worst_d:.2f} mm apart "
                              f"at 1/{2 ** END_CHECK_HALVINGS} of the step, stand-off {1e3 * damper.stand_off:.2f} mm)")


def _new_avoidance(velocity, commanded, status, rows, rate, closing, min_distance, solver, _new=object.__new__):
    """``Avoidance(...)`` without the frozen dataclass's ``__init__`` (one step's hot path)."""
    o = _new(Avoidance)
    o.__dict__.update(velocity=velocity, commanded=commanded, status=status, rows=rows, rate=rate, closing=closing,
                      min_distance=min_distance, solver=solver)
    return o


from ._canned import CannedRun, robot_rows_and_columns, run_canned, run_canned_all  # noqa: E402 - uses avoid_step above

__all__ += ["CannedRun", "run_canned", "run_canned_all"]
