"""Joint limits on the entry points of the detector, the guard and the Model: the one rule for a
configuration outside them.

Every bound the detector prunes with (the obstacle lists of :mod:`armguard.detect._reach`, the
lever arms of the anytime lower bounds, the verifier's motion bounds) holds for configurations
*within* the joint limits.  A configuration with a joint outside
``[lower - tol.joint_limit, upper + tol.joint_limit]`` is therefore refused by every entry point
-- ``Detector.check`` (plain, lazy, budget), ``pair_distances``, ``check_many``,
``collides_many``, ``check_many_bruteforce``, ``Guard.step`` and ``Model.check_limits`` -- with
a :class:`~armguard.JointLimitError` naming the joint, its value and its limits.  The test itself
runs inside the compiled kernel (two comparisons per joint, before forward kinematics); this
module only builds the limit rows and the error.
"""

from __future__ import annotations

import numpy as np

from .._errors import JointLimitError

__all__ = ["limit_rows", "limit_error"]


def limit_rows(lower: np.ndarray, upper: np.ndarray, allowance: float) -> np.ndarray:
    """``(n_q, 2) float64``: each joint's ``[lower - allowance, upper + allowance]`` (rad or m; +-inf kept)."""
    lo = np.asarray(lower, dtype=np.float64).reshape(-1)
    hi = np.asarray(upper, dtype=np.float64).reshape(-1)
    return np.ascontiguousarray(np.stack([lo - allowance, hi + allowance], axis=1).reshape(-1, 2))


def limit_error(where: str, Q, names, lower, upper, allowance: float, mask_hint: str | None = None) -> JointLimitError | None:
    """The error for the first entry of ``Q`` ``(M, n_q)`` (or ``(n_q,)``) outside its limits, or None.

    ``where`` names the entry point; with several rows the row number is added to it, and with
    ``mask_hint`` how many rows are outside and the hint (how to mask them)."""
    Q = np.asarray(Q, dtype=np.float64)
    Q2 = Q.reshape(1, -1) if Q.ndim == 1 else Q
    lo = np.asarray(lower, dtype=np.float64) - allowance
    hi = np.asarray(upper, dtype=np.float64) + allowance
    with np.errstate(invalid="ignore"):
        bad = (Q2 < lo) | (Q2 > hi)
    if not bad.any():
        return None
    m, j = (int(x) for x in np.argwhere(bad)[0])
    place = f"{where} row {m}" if Q.ndim == 2 else where
    if Q.ndim == 2 and mask_hint and len(Q2) > 1:
        place += f" ({int(bad.any(axis=1).sum())} of {len(Q2)} rows outside their limits; {mask_hint})"
    return JointLimitError(place, names[j], Q2[m, j], lower[j], upper[j], allowance)
