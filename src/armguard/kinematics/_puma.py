"""Closed-form inverse kinematics of the PUMA 560 (the example IK plug-in, registered as ``"puma560"``).

WORKMATE (seed ``004``) modelled the PUMA 560 from its A-matrices and took its inverse kinematics
from a user-supplied routine.  The PUMA's published standard DH table (Corke, *Robotics, Vision
and Control*; Craig's values in the standard convention) is :data:`PUMA560_DH`:

====  =========  =======  ==========  ==========================
i     a_i (m)    alpha_i  d_i (m)     limits (deg)
====  =========  =======  ==========  ==========================
1     0          +90 deg  0           -160 .. 160
2     0.4318     0        0           -45 .. 225
3     0.0203     -90 deg  0.15005     -225 .. 45
4     0          +90 deg  0.4318      -110 .. 170
5     0          -90 deg  0           -100 .. 100
6     0          0        0           -266 .. 266
====  =========  =======  ==========  ==========================

The solution (after Paul & Zhang 1986; derived here in the notation of this table, so it also
accepts a base height ``d1``, the shoulder offset split as ``d2 + d3``, a flange ``d6``, the signs
of the +-90 deg twists, DH angle offsets, and a fixed tool link after link 6):

* wrist centre ``w = p_6 - d6 z_6``.  In frame 1, ``w`` has lateral coordinate
  ``w_x sin(t1) - w_y cos(t1) = s1 (d2 + d3)`` with ``s1 = sin(alpha_1)``, so
  ``t1 = phi + asin(D / r)`` or ``phi + pi - asin(D / r)`` with ``phi = atan2(w_y, w_x)``,
  ``r = |w_xy|``, ``D = s1 (d2 + d3)`` (shoulder left/right).
* in the arm plane ``X = w_x cos t1 + w_y sin t1``, ``Y = s1 (w_z - d1)``; the forearm from the
  elbow is ``L (cos(t2 + t3 + beta), sin(...))`` with ``d4' = -sin(alpha_3) d4``,
  ``L = hypot(a3, d4')``, ``beta = atan2(d4', a3)``; so
  ``cos(t3 + beta) = (X^2 + Y^2 - a2^2 - L^2) / (2 a2 L)`` (elbow up/down) and
  ``t2 = atan2(Y, X) - atan2(L sin(t3 + beta), a2 + L cos(t3 + beta))``.
* wrist: ``R_36 = R_03^T R_06 = rot(z, t4) rot(y, -s4 t5) rot(z, t6)`` (ZYZ Euler angles, since
  ``rot(x, alpha_4) rot(z, t5) rot(x, -alpha_4) = rot(y, -s4 t5)`` with ``s4 = sin(alpha_4)``), two
  solutions (wrist flip); at the wrist singularity ``t5 = 0`` the seed's ``t4`` is kept.

Up to eight solutions are returned; the caller wraps, limits and verifies them by FK.
"""

from __future__ import annotations

import math

import numpy as np

from .._errors import IKError
from ._frames import dh_standard, invert_pose
from ._robot import DHRow

__all__ = ["PUMA560_DH", "PUMA560_LOWER", "PUMA560_UPPER", "puma560_ik"]

PUMA560_DH = (
    DHRow(0.0, math.pi / 2, 0.0),
    DHRow(0.4318, 0.0, 0.0),
    DHRow(0.0203, -math.pi / 2, 0.15005),
    DHRow(0.0, math.pi / 2, 0.4318),
    DHRow(0.0, -math.pi / 2, 0.0),
    DHRow(0.0, 0.0, 0.0),
)
"""Standard DH rows of the PUMA 560 (m, rad), as published by Corke (puma560 model)."""

PUMA560_LOWER = tuple(math.radians(x) for x in (-160.0, -45.0, -225.0, -110.0, -100.0, -266.0))
PUMA560_UPPER = tuple(math.radians(x) for x in (160.0, 225.0, 45.0, 170.0, 100.0, 266.0))
"""Joint limits (rad) of the PUMA 560, as published by Corke (qlim)."""

_STRUCTURE_TOL = 1e-12
"""How exactly (m, rad) the DH table must have the PUMA structure (zeros and +-90 deg twists)."""
_WRIST_SINGULAR = 1e-12
"""``|sin(t5)|`` below which the wrist is singular and t4 is taken from the seed."""


_IDENTIFY_SAMPLES = 8
"""Seeded configurations at which a robot without a DH table must move link 6 as PUMA560_DH does."""
_EDGE = 1e-12
"""Relative rounding allowed where the closed form meets the workspace's edge (a cosine, the wrist's distance from
the shoulder axis): the candidates are judged by forward kinematics afterwards."""


def _identified_rows(robot) -> tuple[DHRow, ...]:
    """PUMA560_DH, when ``robot`` (built from URDF: no DH table) moves its link 6 exactly as that
    table does, relative to its root link, at :data:`_IDENTIFY_SAMPLES` seeded configurations."""
    why = (f"puma560 plug-in: robot {robot.name!r} has no DH table and does not move its link 6 as the "
           "PUMA 560's standard DH table does (see PUMA560_DH)")
    if robot.n_joints != 6 or len(robot.link_names) < 7:
        raise IKError(why)
    rng = np.random.default_rng(0)
    root, six = robot.link_names[0], robot.link_names[6]
    for q in rng.uniform(PUMA560_LOWER, PUMA560_UPPER, size=(_IDENTIFY_SAMPLES, 6)):
        X_06 = invert_pose(robot.link_pose(q, root)) @ robot.link_pose(q, six)
        D = np.eye(4)
        for row, t in zip(PUMA560_DH, q):
            D = D @ dh_standard(row.a, row.alpha, row.d, t + row.theta)
        if not np.abs(X_06 - D).max() <= 1e-9:
            raise IKError(why)
    return PUMA560_DH


def _check_structure(robot) -> tuple[DHRow, ...]:
    dh = robot.dh
    if dh is None:
        rows = _identified_rows(robot)  # the built-in puma560 comes from URDF
    elif dh[0] != "standard" or len(dh[1]) != 6:
        raise IKError(f"puma560 plug-in: robot {robot.name!r} must be built from a 6-row standard DH table")
    else:
        rows = dh[1]
    z = _STRUCTURE_TOL
    ok = (
        all(r.joint_type == "revolute" for r in rows) and robot.n_joints == 6 and not robot.couplings
        and abs(rows[0].a) < z and abs(rows[3].a) < z and abs(rows[4].a) < z and abs(rows[5].a) < z
        and abs(rows[4].d) < z and abs(rows[1].alpha) < z and abs(rows[5].alpha) < z
        and abs(abs(math.sin(rows[0].alpha)) - 1) < z and abs(abs(math.sin(rows[2].alpha)) - 1) < z
        and abs(abs(math.sin(rows[3].alpha)) - 1) < z and abs(rows[4].alpha + rows[3].alpha) < z
        and abs(rows[1].a) > z
    )
    if not ok:
        raise IKError(f"puma560 plug-in: robot {robot.name!r} does not have the PUMA 560 structure (see PUMA560_DH)")
    return rows


def _tool_from_link6(robot) -> np.ndarray:
    """Fixed transform ``X_6E`` from DH link 6 to ``robot.tool_link`` (fixed joints only)."""
    six = robot.link_names[6]
    X = np.eye(4)
    link = robot.tool_link
    while link != six:
        spec = robot.joint_of_link(link)
        if spec is None or spec.joint_type.value != "fixed":
            raise IKError(f"puma560 plug-in: tool link {robot.tool_link!r} is not rigidly attached to {six!r}")
        post = np.eye(4) if spec.X_post is None else spec.X_post
        X = spec.X_pre @ post @ X
        link = spec.parent
    return X


def _zyz(R: np.ndarray, a_seed: float) -> list[tuple[float, float, float]]:
    """All ``(a, b, c)`` with ``R = rot(z, a) rot(y, b) rot(z, c)`` (two; one family when singular)."""
    sb = math.hypot(R[0, 2], R[1, 2])
    if sb < _WRIST_SINGULAR:
        if R[2, 2] > 0:  # b = 0: R = rot(z, a + c)
            return [(a_seed, 0.0, math.atan2(R[1, 0], R[0, 0]) - a_seed)]
        return [(a_seed, math.pi, math.atan2(R[1, 0], R[1, 1]) + a_seed)]  # b = pi: R = rot(z, a - c) rot(y, pi)
    b = math.atan2(sb, R[2, 2])
    a = math.atan2(R[1, 2], R[0, 2])
    c = math.atan2(R[2, 1], -R[2, 0])
    return [(a, b, c), (a + math.pi, -b, c + math.pi)]


def puma560_ik(robot, X_BE: np.ndarray, q_seed) -> list[np.ndarray]:
    """Closed-form IK plug-in (see the module docstring): up to 8 candidate ``q`` (6,) rad for ``X_BE`` (4, 4)."""
    rows = _check_structure(robot)
    X_B6 = X_BE @ invert_pose(_tool_from_link6(robot))
    a2, a3 = rows[1].a, rows[2].a
    d1, d23, d4, d6 = rows[0].d, rows[1].d + rows[2].d, rows[3].d, rows[5].d
    s1, s4 = math.sin(rows[0].alpha), math.sin(rows[3].alpha)
    d4p = -math.sin(rows[2].alpha) * d4
    offsets = np.array([r.theta for r in rows])
    seed = np.zeros(6) if q_seed is None else np.asarray(q_seed, dtype=np.float64)
    w = X_B6[:3, 3] - d6 * X_B6[:3, 2]
    r = math.hypot(w[0], w[1])
    D = s1 * d23
    if r < abs(D) * (1.0 - _EDGE):  # beyond rounding (a pose at the edge is kept: the FK check below judges it)
        return []
    phi = math.atan2(w[1], w[0])
    asin_ = math.asin(max(-1.0, min(1.0, D / r))) if r > 0 else 0.0
    L = math.hypot(a3, d4p)
    beta = math.atan2(d4p, a3)
    out = []
    for t1 in (phi + asin_, phi + math.pi - asin_):
        X = w[0] * math.cos(t1) + w[1] * math.sin(t1)
        Y = s1 * (w[2] - d1)
        c = (X * X + Y * Y - a2 * a2 - L * L) / (2.0 * a2 * L)
        if abs(c) > 1.0 + _EDGE:  # the elbow stretched or folded: c a rounding past +-1 still solves (it said
            continue              # "outside the workspace" for 7 of 20 reachable stretched-elbow poses)
        g = math.acos(max(-1.0, min(1.0, c)))
        for t3b in (g, -g):
            t3 = t3b - beta
            t2 = math.atan2(Y, X) - math.atan2(L * math.sin(t3b), a2 + L * math.cos(t3b))
            R_03 = (dh_standard(rows[0].a, rows[0].alpha, rows[0].d, t1)
                    @ dh_standard(a2, rows[1].alpha, rows[1].d, t2)
                    @ dh_standard(a3, rows[2].alpha, rows[2].d, t3))[:3, :3]
            R_36 = R_03.T @ X_B6[:3, :3]
            for a, b, cc in _zyz(R_36, seed[3] + offsets[3]):
                t5 = -s4 * b if s4 != 0 else b
                theta = np.array([t1, t2, t3, a, t5, cc])
                out.append(theta - offsets)
    return out
