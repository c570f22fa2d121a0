"""Geometric Jacobian of a point of a link, from the joint frames of the flattened tree."""

from __future__ import annotations

import numpy as np

from .._errors import KinematicsError
from ._fk import JT_FIXED, JT_REVOLUTE, fk_kernel

__all__ = ["jacobian"]


def jacobian(robot, q: np.ndarray, link: str | None, p_L) -> np.ndarray:
    """``(..., 6, n_joints)``: ``[v_WP; w_WL]`` of point ``p_L`` (3,) m of ``link`` per unit joint speed.

    Column of a revolute joint with unit axis ``k_W`` through ``o_W``: ``[k_W x (p_W - o_W); k_W]``;
    of a prismatic joint: ``[k_W; 0]``.  A joint driven by couplings (GMF S-480, URDF mimic)
    adds ``coeff *`` its column to each independent joint it depends on.  ``q`` is validated.
    """
    tree = robot.flat_tree
    i_link = robot.link_index(robot.tool_link if link is None else link)
    if p_L is None:
        p_L = np.zeros(3)
    p_L = np.asarray(p_L, dtype=np.float64)
    if p_L.shape != (3,) or not np.all(np.isfinite(p_L)):
        raise KinematicsError(f"p_L: expected a finite 3-vector (m), got {p_L!r}")
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
