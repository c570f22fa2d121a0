"""Inverse kinematics: per-robot plug-ins (WORKMATE's user-supplied inverse) and a numerical default.

WORKMATE (seed ``004``, "Robot Modeling"): "the modeler must supply a routine to perform the
inverse kinematic calculations ... A pointer to this routine is saved when the model file is
parsed".  Here :func:`register_ik` keeps such a routine per robot *name*; the closed-form PUMA 560
solution (:mod:`._puma`) is registered as ``"puma560"``.  Robots without a plug-in use damped least
squares (Levenberg-Marquardt damping) within joint limits, with random restarts.

Whatever produced it, a solution is accepted only after forward kinematics places the link within
``tol.ik_position`` (m) and ``tol.ik_orientation`` (rad) of the target with every joint within its
limits: ``IKResult.q`` is None unless the status is SUCCESS.
"""

from __future__ import annotations

import enum
import math
import warnings
from dataclasses import dataclass
from typing import Callable, Iterable

import numpy as np

from .._errors import ArmguardWarning, IKError, KinematicsError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from ._frames import invert_pose, rotation_vector_from_matrix
from ._robot import JointType, _check_X

__all__ = ["IKStatus", "IKResult", "register_ik", "unregister_ik", "ik_plugin", "solve_ik", "IKPlugin"]

IKPlugin = Callable[..., Iterable[np.ndarray]]
"""``fn(robot, X_BE, q_seed) -> iterable of q`` — candidate joint vectors (n_joints,) placing
``robot.tool_link`` at ``X_BE`` (4, 4), the pose relative to the robot's root link (base) frame B;
``q_seed`` is None or (n_joints,).  Return nothing when the pose is unreachable; joint limits and
2 pi wrapping are handled by the caller, which also verifies every candidate."""

_PLUGINS: dict[str, IKPlugin] = {}

_UNBOUNDED_REVOLUTE_RANGE = math.pi
"""Random restarts draw an unbounded revolute joint from [-pi, pi] (rad)."""
_UNBOUNDED_PRISMATIC_RANGE = 1.0
"""... and an unbounded prismatic joint from [-1, 1] m."""
_DAMPING_GROWTH = 10.0
"""Levenberg-Marquardt: a rejected step multiplies the damping by this, an accepted one divides by it."""
_DAMPING_MAX = 1e6
"""Damping (m) above which a start is abandoned as stuck."""
_POLISH_ITERATIONS = 20
"""Newton polish iterations applied to plug-in candidates (closed forms lose digits near singularities)."""
_POLISH_RADIUS = 1e-6
"""Only a plug-in candidate already this close (m and rad) is polished: a wrong plug-in stays visible."""


class IKStatus(str, enum.Enum):
    """Outcome of an inverse-kinematics request."""

    SUCCESS = "success"
    NO_CONVERGENCE = "no_convergence"   # the numerical solver did not reach the pose from any start
    OUT_OF_LIMITS = "out_of_limits"     # solutions exist but every one violates a joint limit
    UNREACHABLE = "unreachable"         # the plug-in proved the pose outside the workspace


@dataclass(frozen=True)
class IKResult:
    """Result of :meth:`Robot.inverse_kinematics`.

    ``q`` (n_joints,) rad/m is None unless ``status`` is SUCCESS; ``position_error`` (m) and
    ``orientation_error`` (rad) are those of ``q`` (on failure: of the best attempt, inf if none);
    ``iterations`` counts solver iterations over all starts; ``message`` says why on failure.
    """

    status: IKStatus
    q: np.ndarray | None
    position_error: float
    orientation_error: float
    iterations: int
    message: str = ""

    @property
    def ok(self) -> bool:
        return self.status is IKStatus.SUCCESS


def register_ik(name: str, fn: IKPlugin) -> None:
    """Register ``fn`` as the inverse-kinematics routine of robots named ``name`` (see IKPlugin)."""
    if not callable(fn):
        raise KinematicsError(f"register_ik: fn must be callable, got {fn!r}")
    _PLUGINS[str(name)] = fn


def unregister_ik(name: str) -> None:
    """Remove the plug-in of robots named ``name`` (no error if there is none)."""
    _PLUGINS.pop(str(name), None)


def ik_plugin(name: str) -> IKPlugin | None:
    """The plug-in registered for ``name``, or None."""
    return _PLUGINS.get(str(name))


NUMERIC = "numeric"
"""The routine name of the damped-least-squares solver (the default)."""

_WARNED: set = set()


def resolve_ik(routine: str) -> IKPlugin | None:
    """The IK routine a model file names: ``"numeric"`` (None: damped least squares), a name registered
    with :func:`register_ik`, or ``"module:function"`` (imported now -- the seed's "pointer to this routine
    saved when the model file is parsed").  Anything else raises :class:`KinematicsError`."""
    routine = str(routine)
    if routine == NUMERIC:
        return None
    if routine in _PLUGINS:
        return _PLUGINS[routine]
    if ":" in routine:
        import importlib

        module, _, attr = routine.partition(":")
        try:
            fn = getattr(importlib.import_module(module), attr)
        except (ImportError, AttributeError) as exc:
            raise KinematicsError(f"IK routine {routine!r}: cannot import it ({exc})") from None
        if not callable(fn):
            raise KinematicsError(f"IK routine {routine!r} is not callable")
        return fn
    raise KinematicsError(f"unknown IK routine {routine!r}: expected {NUMERIC!r}, a registered name "
                          f"({sorted(_PLUGINS)}) or 'module:function'")


def _plugin_for(robot) -> IKPlugin | None:
    """The routine of ``robot`` (its model's ``ik``, else the one registered for its name, else None: numeric,
    with a warning once per robot name when the model names no routine)."""
    routine = getattr(robot, "ik", None)
    if routine is not None:
        return resolve_ik(routine)
    plugin = ik_plugin(robot.name)
    if plugin is None and robot.name not in _WARNED:
        _WARNED.add(robot.name)
        warnings.warn(f"robot {robot.name!r}: its model names no IK routine (ik:) and none is registered for its "
                      "name; using the numeric solver (damped least squares). Name one, or 'numeric', in the "
                      "model file (docs/models.md)", ArmguardWarning, stacklevel=4)
    return plugin


def _pose_error(X: np.ndarray, X_target: np.ndarray) -> tuple[np.ndarray, float, float]:
    e_p = X_target[:3, 3] - X[:3, 3]
    e_w = rotation_vector_from_matrix(X_target[:3, :3] @ X[:3, :3].T)
    return np.concatenate([e_p, e_w]), float(np.linalg.norm(e_p)), float(np.linalg.norm(e_w))


def _wrap_to_limits(robot, q: np.ndarray, q_ref: np.ndarray) -> np.ndarray:
    """Shift revolute joints by multiples of 2 pi: the copy nearest ``q_ref``, inside limits when one is."""
    q = q.copy()
    two_pi = 2.0 * math.pi
    for k, jt in enumerate(robot.joint_types):
        if jt is not JointType.REVOLUTE:
            continue
        base = q[k] + two_pi * round((q_ref[k] - q[k]) / two_pi)
        cands = [base + two_pi * m for m in (-2, -1, 0, 1, 2)]
        inside = [c for c in cands if robot.lower[k] <= c <= robot.upper[k]]
        pool = inside or cands
        q[k] = min(pool, key=lambda c: abs(c - q_ref[k]))
    return q


class _Solver:
    def __init__(self, robot, i_link: int, link: str, X_target: np.ndarray, tol: Tolerances,
                 position_only: bool = False) -> None:
        self.robot, self.i, self.link, self.X, self.tol = robot, i_link, link, X_target, tol
        self.rows = slice(0, 3) if position_only else slice(0, 6)
        self.position_only = position_only
        self.lo = np.where(np.isfinite(robot.lower), robot.lower, -np.inf)
        self.hi = np.where(np.isfinite(robot.upper), robot.upper, np.inf)
        self.iterations = 0

    def error(self, q):
        return _pose_error(self.robot.forward_kinematics(q)[self.i], self.X)

    def converged(self, ep: float, ew: float) -> bool:
        return ep <= self.tol.ik_position and (self.position_only or ew <= self.tol.ik_orientation)

    def run(self, q: np.ndarray, max_iterations: int) -> tuple[np.ndarray, float, float]:
        """Damped least squares from ``q``, projected onto the limits; returns the best (q, e_p, e_w)."""
        q = np.clip(q, self.lo, self.hi)
        e, ep, ew = self.error(q)
        e = e[self.rows]
        cost = float(e @ e)
        lam = self.tol.ik_damping
        for _ in range(max_iterations):
            if self.converged(ep, ew):
                break
            self.iterations += 1
            J = self.robot.jacobian(q, self.link)[self.rows]
            A = J @ J.T + (lam * lam) * np.eye(J.shape[0])
            dq = J.T @ np.linalg.solve(A, e)
            q_new = np.clip(q + dq, self.lo, self.hi)
            e_new, ep_new, ew_new = self.error(q_new)
            e_new = e_new[self.rows]
            cost_new = float(e_new @ e_new)
            if cost_new < cost:
                q, e, ep, ew, cost = q_new, e_new, ep_new, ew_new, cost_new
                lam = max(lam / _DAMPING_GROWTH, self.tol.ik_damping)
            else:
                lam *= _DAMPING_GROWTH
                if lam > _DAMPING_MAX:
                    break
        return q, ep, ew


def _random_q(robot, rng: np.random.Generator) -> np.ndarray:
    lo, hi = robot.lower.copy(), robot.upper.copy()
    for k, jt in enumerate(robot.joint_types):
        r = _UNBOUNDED_REVOLUTE_RANGE if jt is JointType.REVOLUTE else _UNBOUNDED_PRISMATIC_RANGE
        if not np.isfinite(lo[k]):
            lo[k] = min(-r, hi[k] - 2 * r) if np.isfinite(hi[k]) else -r
        if not np.isfinite(hi[k]):
            hi[k] = max(r, lo[k] + 2 * r)
    return rng.uniform(lo, hi)


def solve_ik(robot, X_WE, *, q_seed=None, link=None, rng=None, tol: Tolerances = DEFAULT_TOLERANCES,
             position_only: bool = False) -> IKResult:
    """See :meth:`Robot.inverse_kinematics`."""
    X_WE = _check_X(X_WE, "X_WE")
    link = robot.tool_link if link is None else link
    i_link = robot.link_index(link)
    q_ref = np.zeros(robot.n_joints) if q_seed is None else robot.check_q(q_seed).reshape(robot.n_joints)
    if rng is None:
        rng = np.random.default_rng(0)  # deterministic by default; pass rng to vary restarts
    solver = _Solver(robot, i_link, link, X_WE, tol, position_only)
    plugin = _plugin_for(robot) if link == robot.tool_link and not position_only else None
    if plugin is not None:
        return _solve_with_plugin(robot, plugin, solver, X_WE, q_seed, q_ref, tol)
    best = (math.inf, math.inf)
    starts = [np.clip(q_ref, solver.lo, solver.hi)] + [_random_q(robot, rng) for _ in range(tol.ik_restarts)]
    for q0 in starts:
        q, ep, ew = solver.run(q0, tol.ik_max_iterations)
        if solver.converged(ep, ew) and bool(robot.within_limits(q, tol=tol)):
            return IKResult(IKStatus.SUCCESS, q, ep, ew, solver.iterations)
        if ep + ew < sum(best):
            best = (ep, ew)
    return IKResult(
        IKStatus.NO_CONVERGENCE, None, best[0], best[1], solver.iterations,
        f"damped least squares reached no pose within {tol.ik_position:g} m / {tol.ik_orientation:g} rad "
        f"from the seed and {tol.ik_restarts} random starts (best: {best[0]:.3g} m, {best[1]:.3g} rad)",
    )


def _solve_with_plugin(robot, plugin, solver: _Solver, X_WE, q_seed, q_ref, tol) -> IKResult:
    X_BE = invert_pose(robot.X_WB) @ X_WE
    cands = [np.asarray(c, dtype=np.float64).reshape(-1) for c in plugin(robot, X_BE, q_seed)]
    if not cands:
        return IKResult(IKStatus.UNREACHABLE, None, math.inf, math.inf, 0,
                        f"the IK plug-in of {robot.name!r} found the pose outside the workspace")
    good, out_of_limits = [], []
    best = (math.inf, math.inf)
    for c in cands:
        if c.shape != (robot.n_joints,) or not np.all(np.isfinite(c)):
            raise IKError(f"the IK plug-in of {robot.name!r} returned {c!r}; expected {robot.n_joints} finite joint values")
        c = _wrap_to_limits(robot, c, q_ref)
        _, ep, ew = solver.error(c)
        close = ep <= _POLISH_RADIUS and ew <= _POLISH_RADIUS
        if not solver.converged(ep, ew) and close and bool(robot.within_limits(c, tol=tol)):
            # closed forms lose digits near singularities: polish with a few damped Newton steps
            c, ep, ew = solver.run(c, _POLISH_ITERATIONS)
        if ep + ew < sum(best):
            best = (ep, ew)
        if not solver.converged(ep, ew):
            continue
        (good if bool(robot.within_limits(c, tol=tol)) else out_of_limits).append((c, ep, ew))
    if good:
        c, ep, ew = min(good, key=lambda g: float(np.sum((g[0] - q_ref) ** 2)))
        return IKResult(IKStatus.SUCCESS, c, ep, ew, solver.iterations)
    if out_of_limits:
        return IKResult(IKStatus.OUT_OF_LIMITS, None, out_of_limits[0][1], out_of_limits[0][2], solver.iterations,
                        f"{len(out_of_limits)} solution(s) exist but each violates a joint limit")
    return IKResult(IKStatus.NO_CONVERGENCE, None, best[0], best[1], solver.iterations,
                    f"none of the {len(cands)} plug-in solutions reaches the pose within tolerance "
                    "(does the plug-in match this robot's model?)")
