"""Chains from Denavit-Hartenberg tables (WORKMATE's "A-matrices", seed ``004``; Hermes, seed ``001``).

Row i (joint i, link i) gives the A-matrix from link frame i-1 to link frame i:

* standard: ``A_i = rot(z, theta_i + q_i) trans(z, d_i) trans(x, a_i) rot(x, alpha_i)`` (revolute),
  ``rot(z, theta_i) trans(z, d_i + q_i) trans(x, a_i) rot(x, alpha_i)`` (prismatic);
* modified (Craig): ``A_i = rot(x, alpha_i) trans(x, a_i) rot(z, theta_i + q_i) trans(z, d_i)`` — here
  ``a_i, alpha_i`` are Craig's ``a_{i-1}, alpha_{i-1}``.

Each row becomes a JointSpec ``X_pre @ M(q) @ X_post``: the joint motion about/along the z axis of
the joint frame commutes with ``rot(z, theta)`` and ``trans(z, d)``, so for the standard convention
``X_pre = rot(z, theta) trans(z, d)``, ``X_post = trans(x, a) rot(x, alpha)``, and for the modified
one ``X_pre = rot(x, alpha) trans(x, a) rot(z, theta) trans(z, d)``, ``X_post = I``.
"""

from __future__ import annotations

import math
from typing import Mapping

import numpy as np

from .._errors import KinematicsError
from .._values import refuse_complex_or_bool
from ._frames import rot_x, rot_z, trans
from ._robot import Coupling, DHRow, JointSpec, JointType

__all__ = ["robot_from_dh", "dh_row_from"]

_CONVENTIONS = ("standard", "modified")


def dh_row_from(value, index: int) -> DHRow:
    """Coerce a DHRow, a mapping ``{a, alpha, d, theta?, joint_type?}`` or a tuple to DHRow."""
    try:
        if isinstance(value, DHRow):
            return value
        if isinstance(value, Mapping):
            unknown = set(value) - {"a", "alpha", "d", "theta", "joint_type"}
            if unknown:
                raise KinematicsError(f"unknown keys {sorted(unknown)}; expected a, alpha, d, theta, joint_type")
            return DHRow(**value)
        return DHRow(*value)
    except KinematicsError as exc:
        raise KinematicsError(f"DH row {index}: {exc}") from None
    except TypeError as exc:
        raise KinematicsError(f"DH row {index}: expected (a, alpha, d[, theta[, joint_type]]), got {value!r}: {exc}") from None


def _per_joint(values, n_rows: int, indep_rows: list[int], default: float, name: str) -> list[float]:
    """Limits given per row (n_rows) or per independent joint; returns one value per row."""
    if values is None:
        return [default] * n_rows
    refuse_complex_or_bool(values, name, KinematicsError)
    try:
        arr = np.asarray(values, dtype=np.float64).ravel()
    except (TypeError, ValueError):
        raise KinematicsError(f"{name}: expected numbers (one per DH row or per independent joint), got {values!r}") from None
    if arr.shape[0] == n_rows:
        return [float(x) for x in arr]
    if arr.shape[0] == len(indep_rows):
        out = [default] * n_rows
        for r, x in zip(indep_rows, arr):
            out[r] = float(x)
        return out
    raise KinematicsError(f"{name}: expected {n_rows} values (one per DH row) or {len(indep_rows)} (one per independent joint), got {arr.shape[0]}")


def robot_from_dh(cls, name, rows, *, convention="standard", joint_names=None, link_names=None, lower=None,
                  upper=None, max_velocity=None, max_acceleration=None, couplings=(), link_shapes=None,
                  X_WB=None, X_LT=None):
    """Build a Robot from DH ``rows`` (see the module docstring for the conventions).

    link_names: n_rows + 1 names (base link, then one per joint), default ``link0..linkN``;
    joint_names: one per row, default ``joint1..jointN``; lower/upper/max_velocity/max_acceleration:
    one per row or one per independent joint (rad, m, rad/s, rad/s^2; default unbounded);
    couplings: dependent joints (GMF S-480 parallelogram); X_LT: a fixed tool transform (4, 4) from
    the last link, appended as link ``"tool"``.
    """
    if convention not in _CONVENTIONS:
        raise KinematicsError(f"convention: expected one of {list(_CONVENTIONS)}, got {convention!r}")
    rows = [dh_row_from(r, i) for i, r in enumerate(rows)]
    n = len(rows)
    if n == 0:
        raise KinematicsError("rows: a DH table needs at least one row")
    joint_names = [f"joint{i + 1}" for i in range(n)] if joint_names is None else [str(j) for j in joint_names]
    if len(joint_names) != n:
        raise KinematicsError(f"joint_names: expected {n} names (one per DH row), got {len(joint_names)}")
    link_names = [f"link{i}" for i in range(n + 1)] if link_names is None else [str(ln) for ln in link_names]
    if len(link_names) != n + 1:
        raise KinematicsError(f"link_names: expected {n + 1} names (base link, then one per DH row), got {len(link_names)}")
    if len(set(link_names)) != n + 1 or len(set(joint_names)) != n:
        raise KinematicsError("link_names and joint_names must be unique")
    couplings = [c if isinstance(c, Coupling) else Coupling(**c) for c in couplings]
    coupled = {c.joint: c for c in couplings}
    for c in couplings:
        if c.joint not in joint_names:
            raise KinematicsError(f"coupling: unknown joint {c.joint!r}; joints are {joint_names}")
    indep_rows = [i for i, j in enumerate(joint_names) if j not in coupled or j in coupled[j].terms]
    lo = _per_joint(lower, n, indep_rows, -math.inf, "lower")
    hi = _per_joint(upper, n, indep_rows, math.inf, "upper")
    vm = _per_joint(max_velocity, n, indep_rows, math.inf, "max_velocity")
    am = _per_joint(max_acceleration, n, indep_rows, math.inf, "max_acceleration")
    specs = []
    for i, r in enumerate(rows):
        if convention == "standard":
            X_pre = rot_z(r.theta) @ trans(0, 0, r.d)
            X_post = trans(r.a, 0, 0) @ rot_x(r.alpha)
        else:
            X_pre = rot_x(r.alpha) @ trans(r.a, 0, 0) @ rot_z(r.theta) @ trans(0, 0, r.d)
            X_post = None
        specs.append(JointSpec(
            name=joint_names[i], joint_type=JointType(r.joint_type), parent=link_names[i], child=link_names[i + 1],
            X_pre=X_pre, X_post=X_post, lower=lo[i], upper=hi[i], max_velocity=vm[i], max_acceleration=am[i],
            coupling=coupled.get(joint_names[i]),
        ))
    if X_LT is not None:
        if "tool" in link_names:
            raise KinematicsError("X_LT: a link is already named 'tool'")
        specs.append(JointSpec(name="tool_joint", joint_type=JointType.FIXED, parent=link_names[-1], child="tool", X_pre=X_LT))
    return cls(
        name, link_names[0], specs, joint_names=[joint_names[i] for i in indep_rows], link_shapes=link_shapes,
        X_WB=X_WB, dh=(convention, tuple(rows)),
    )
