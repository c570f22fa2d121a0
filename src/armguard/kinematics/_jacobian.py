"""Geometric Jacobian of a point of a link, from the joint frames of the flattened tree."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .._errors import KinematicsError
from ._fk import JT_FIXED, JT_REVOLUTE, fk_kernel

__all__ = ["jacobian", "jacobian_reference"]


@njit(cache=True)
def _jacobian_kernel(X_WL, i_link, p_L, parent, X_pre, axis, jtype, term_start, term_joint, term_coeff, J):
    """Scalar-style Jacobian for each configuration m: ``J[m]`` (6, n) from the link poses ``X_WL[m]``."""
    for m in range(X_WL.shape[0]):
        T = X_WL[m, i_link]
        px = T[0, 0] * p_L[0] + T[0, 1] * p_L[1] + T[0, 2] * p_L[2] + T[0, 3]
        py = T[1, 0] * p_L[0] + T[1, 1] * p_L[1] + T[1, 2] * p_L[2] + T[1, 3]
        pz = T[2, 0] * p_L[0] + T[2, 1] * p_L[1] + T[2, 2] * p_L[2] + T[2, 3]
        for r in range(6):
            for c in range(J.shape[2]):
                J[m, r, c] = 0.0
        i = i_link
        while i > 0:
            jt = jtype[i]
            if jt != 0:
                p = parent[i]
                P = X_WL[m, p]
                B = X_pre[i]
                kx = axis[i, 0]; ky = axis[i, 1]; kz = axis[i, 2]
                # joint frame X_WJ = P @ B: its rotation applied to the axis, and its origin
                bx = B[0, 0] * kx + B[0, 1] * ky + B[0, 2] * kz
                by = B[1, 0] * kx + B[1, 1] * ky + B[1, 2] * kz
                bz = B[2, 0] * kx + B[2, 1] * ky + B[2, 2] * kz
                wx = P[0, 0] * bx + P[0, 1] * by + P[0, 2] * bz
                wy = P[1, 0] * bx + P[1, 1] * by + P[1, 2] * bz
                wz = P[2, 0] * bx + P[2, 1] * by + P[2, 2] * bz
                if jt == 1:
                    ox = P[0, 0] * B[0, 3] + P[0, 1] * B[1, 3] + P[0, 2] * B[2, 3] + P[0, 3]
                    oy = P[1, 0] * B[0, 3] + P[1, 1] * B[1, 3] + P[1, 2] * B[2, 3] + P[1, 3]
                    oz = P[2, 0] * B[0, 3] + P[2, 1] * B[1, 3] + P[2, 2] * B[2, 3] + P[2, 3]
                    dx = px - ox; dy = py - oy; dz = pz - oz
                    vx = wy * dz - wz * dy; vy = wz * dx - wx * dz; vz = wx * dy - wy * dx
                    rx = wx; ry = wy; rz = wz
                else:
                    vx = wx; vy = wy; vz = wz
                    rx = 0.0; ry = 0.0; rz = 0.0
                for t in range(term_start[i], term_start[i + 1]):
                    c = term_coeff[t]
                    k = term_joint[t]
                    J[m, 0, k] += c * vx; J[m, 1, k] += c * vy; J[m, 2, k] += c * vz
                    J[m, 3, k] += c * rx; J[m, 4, k] += c * ry; J[m, 5, k] += c * rz
            i = parent[i]


def jacobian(robot, q: np.ndarray, link: str | None, p_L) -> np.ndarray:
    """Fast path of :func:`jacobian_reference` (a numba kernel over the FK kernel's poses); same contract."""
    tree = robot.flat_tree
    i_link = robot.link_index(robot.tool_link if link is None else link)
    p_L = _check_p(p_L)
    lead = q.shape[:-1]
    X_WL = fk_kernel(tree, q).reshape((math.prod(lead), tree.n_links, 4, 4))
    J = np.empty((X_WL.shape[0], 6, robot.n_joints))
    _jacobian_kernel(X_WL, i_link, p_L, tree.parent, tree.X_pre, tree.axis, tree.jtype, tree.term_start,
                     tree.term_joint, tree.term_coeff, J)
    return J.reshape(lead + (6, robot.n_joints))


def _check_p(p_L) -> np.ndarray:
    if p_L is None:
        return np.zeros(3)
    p = np.asarray(p_L, dtype=np.float64)
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise KinematicsError(f"p_L: expected a finite 3-vector (m), got {p_L!r}")
    return p


def jacobian_reference(robot, q: np.ndarray, link: str | None, p_L) -> np.ndarray:
    """``(..., 6, n_joints)``: ``[v_WP; w_WL]`` of point ``p_L`` (3,) m of ``link`` per unit joint speed.

    Column of a revolute joint with unit axis ``k_W`` through ``o_W``: ``[k_W x (p_W - o_W); k_W]``;
    of a prismatic joint: ``[k_W; 0]``.  A joint driven by couplings (GMF S-480, URDF mimic)
    adds ``coeff *`` its column to each independent joint it depends on.  ``q`` is validated.
    """
    tree = robot.flat_tree
    i_link = robot.link_index(robot.tool_link if link is None else link)
    p_L = _check_p(p_L)
    X_WL = fk_kernel(tree, q)
    lead = q.shape[:-1]
    J = np.zeros(lead + (6, robot.n_joints))
    X_target = X_WL[..., i_link, :, :]
    p_WP = X_target[..., :3, :3] @ p_L + X_target[..., :3, 3]
    i = i_link
    while i > 0:
        jt = int(tree.jtype[i])
        if jt != JT_FIXED:
            p = int(tree.parent[i])
            X_WJ = X_WL[..., p, :, :] @ tree.X_pre[i] if p >= 0 else np.broadcast_to(tree.X_pre[i], lead + (4, 4))
            k_W = X_WJ[..., :3, :3] @ tree.axis[i]
            if jt == JT_REVOLUTE:
                col_v = np.cross(k_W, p_WP - X_WJ[..., :3, 3])
                col_w = k_W
            else:
                col_v = k_W
                col_w = np.zeros_like(k_W)
            for t in range(tree.term_start[i], tree.term_start[i + 1]):
                c = tree.term_coeff[t]
                k = tree.term_joint[t]
                J[..., :3, k] += c * col_v
                J[..., 3:, k] += c * col_w
        i = int(tree.parent[i])
    return J
