"""A Model's joint limits: :meth:`Model.check_pin_limits`, :meth:`Model.within_pin_limits` (Pinocchio's order)
and :meth:`Model.check_limits` (the scene's), defined here and bound to the Model as its methods."""

from __future__ import annotations

import numpy as np

from .._errors import KinematicsError
from .._values import refuse_complex_or_bool

__all__ = ["check_pin_limits", "within_pin_limits", "pin_limit_table", "check_limits", "UNIT_CIRCLE"]

UNIT_CIRCLE = 1e-6  # compiled into the analytic backend's _pair_rows._scene_row: after an edit, `make clean-cache`
"""A continuous joint's ``(cos, sin)`` in ``q`` is refused when ``|cos² + sin² − 1|`` exceeds this: off the
unit circle Pinocchio's placement is not a rotation (coal then checks a scaled, sheared link; the
analytic backend reads the angle, so the two gave different verdicts), and 1e-6 scales a link 1 m
away by at most 0.5 µm, within the contact band."""


def check_pin_limits(self, Q, where: str = "q") -> None:
    """Raise :class:`~armguard.JointLimitError` when Pinocchio-ordered ``Q`` ``(nq,)`` or ``(M, nq)`` leaves
    a joint's limits (continuous joints have none): the rule of :mod:`armguard.kinematics._limits`,
    for every backend's ``check_q`` / ``check_Q``."""
    _, bounds, lo, hi = self._pin_limit_table()
    if getattr(Q, "dtype", None) != np.float64:
        refuse_complex_or_bool(Q, where, KinematicsError)  # True read as 1 rad, a complex value as its real part
    Q = np.asarray(Q, dtype=np.float64)
    if Q.shape[-1:] != (len(bounds),) or Q.ndim > 2:  # zip() would check a short q's first joints only
        raise KinematicsError(f"{where}: expected shape ({len(bounds)},) or (M, {len(bounds)}): "
                              f"{self.q_layout(Q.shape[-1] if Q.ndim else None)}, got {Q.shape}")
    if Q.ndim == 1:  # one configuration: a plain loop (0.5 µs on 6 joints; numpy's compares took 2-5)
        for (a, b), x in zip(bounds, Q.tolist()):
            if not a <= x <= b:
                break
        else:
            return
    elif np.all(Q >= [a for a, _ in bounds]) and np.all(Q <= [b for _, b in bounds]):
        return
    from ..kinematics._limits import limit_error

    err = limit_error(where, Q, self.q_joint_names, lo, hi, self.tol.joint_limit, f"model.within_pin_limits({where}) masks them")
    if err is None:  # no joint outside: a NaN failed the test (it compares false everywhere)
        raise KinematicsError(f"{where}: contains NaN: {Q.tolist()}")
    raise err


def pin_limit_table(self) -> tuple:
    """``(pin_model, [(low, high)] with the allowance, lower, upper)``, continuous joints unbounded: once per pin_model."""
    lim = self.__dict__.get("_pin_limits")
    if lim is None or lim[0] is not self.pin_model:  # an edit may append an arm
        lo = np.array(self.pin_model.lowerPositionLimit, dtype=np.float64)
        hi = np.array(self.pin_model.upperPositionLimit, dtype=np.float64)
        cq = self.continuous_q
        lo[cq], lo[cq + 1], hi[cq], hi[cq + 1] = -np.inf, -np.inf, np.inf, np.inf
        allowance = self.tol.joint_limit
        lim = self._pin_limits = (self.pin_model, list(zip((lo - allowance).tolist(), (hi + allowance).tolist())), lo, hi)
    return lim


def within_pin_limits(self, Q) -> np.ndarray:
    """``(M,) bool`` (or a bool for one ``(nq,)``): the rows of Pinocchio-ordered ``Q`` a Checker answers for,
    every value finite, each joint within its limits and the allowance (what :meth:`check_pin_limits` lets
    through) and each continuous joint's ``(cos, sin)`` on the unit circle (:data:`UNIT_CIRCLE`, as
    ``check_q``): mask a batch with it, ``checker.collides(Q[ok])``, where a row outside gets no verdict."""
    _, bounds, _, _ = self._pin_limit_table()
    if getattr(Q, "dtype", None) != np.float64:
        refuse_complex_or_bool(Q, "Q", KinematicsError)
    Q = np.asarray(Q, dtype=np.float64)
    if Q.shape[-1:] != (len(bounds),) or Q.ndim > 2:
        raise KinematicsError(f"Q: expected shape ({len(bounds)},) or (M, {len(bounds)}), got {Q.shape}")
    a, b = np.array(bounds).T.reshape(2, -1) if bounds else (np.zeros(0), np.zeros(0))
    with np.errstate(invalid="ignore"):
        ok = np.all((Q >= a) & (Q <= b) & np.isfinite(Q), axis=-1)
        cq = np.asarray(self.continuous_q, dtype=np.int64)
        if cq.size:
            ok &= np.all(np.abs(Q[..., cq] ** 2 + Q[..., cq + 1] ** 2 - 1.0) <= UNIT_CIRCLE, axis=-1)
    return ok


def check_limits(self, q_scene, where: str = "q") -> None:
    """Raise :class:`~armguard.JointLimitError` when the flat scene ``q`` ``(n,)`` leaves a joint's limits."""
    from ..kinematics._limits import limit_error

    robots = [r for _, r in self._robots]  # the robots pin_model moves
    if not robots:
        return
    lo = np.concatenate([r.lower for r in robots])
    hi = np.concatenate([r.upper for r in robots])
    refuse_complex_or_bool(q_scene, where, KinematicsError)
    try:
        q = np.asarray(q_scene, dtype=np.float64)
    except (TypeError, ValueError):
        raise KinematicsError(f"{where}: expected {len(lo)} joint values, got {q_scene!r}") from None
    if q.shape != lo.shape:  # one value was broadcast over every joint
        raise KinematicsError(f"{where}: expected shape {lo.shape} in the scene's order "
                              f"{list(self._spec.joint_names)}, got {q.shape}")
    if np.isnan(q).any():
        raise KinematicsError(f"{where}: contains NaN: {q.tolist()}")
    err = limit_error(where, q, self._spec.joint_names, lo, hi, self.tol.joint_limit)
    if err is not None:
        raise err
