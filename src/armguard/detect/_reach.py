"""Conservative reach and motion bounds of link geometry, from the kinematic chain alone.

Ranger (seed ``000``, §2 and footnote 3) kept per-link *obstacle lists* of the objects within a
link's reach, built by hand, and named their automatic construction future work (§7).  We
build them from two bounds that hold for *every* configuration inside the joint limits:

**Joint anchor points.**  For a movable joint k, let ``c_k`` be the origin of its joint frame
J_k (``X_WJ = X_WP @ X_pre``); the joint's motion is a rotation about (or translation along)
an axis through ``c_k``.  ``c_k`` is fixed in the parent body and, for a revolute joint, also
in the child body.  Two consecutive movable joints ``k -> k'`` on a chain therefore have
anchors fixed in one rigid body (the one between them), so ``|c_k - c_k'|`` is the same at
every configuration; a prismatic joint k adds at most its stroke ``s_k = sum_i |coeff_i|
(upper_i - lower_i)`` (infinite for an unlimited prismatic joint).

**Reach.**  For an element g on link L whose movable chain is ``k_1 .. k_K`` (root to L), with
bounding sphere ``(o_g, r_g)`` fixed in L's last body::

    rho_{g,k_j} = sum_{i=j}^{K-1} (|c_{k_i} - c_{k_i+1}| + s_{k_i}) + s_{k_K} + |o_g - c_{k_K}| + r_g

bounds the distance from ``c_{k_j}`` to any point of g (triangle inequality along the chain).
``c_{k_1}`` is fixed in W, so g stays inside the *reach sphere* ``(c_{k_1}, rho_{g,k_1})``.

**Motion (lever arms).**  Moving joint value ``v_k`` by ``dv`` moves each point of g by at most
``|dv| rho_{g,k}`` (revolute: the point turns about an axis through ``c_k`` at distance
<= ``rho_{g,k}``) or ``|dv|`` (prismatic).  Going from q to q' one joint at a time (each bound
holds at any configuration), every point of g moves at most
``sum_i |q_i - q'_i| lever[g, i]`` with ``lever[g, i] = sum_k |coeff_{k,i}| rho_{g,k}`` (or
``|coeff_{k,i}|`` for prismatic k).  Signed distance between convex sets is 1-Lipschitz in
the Hausdorff distance, so ``d(q') >= d(q) - motion_a - motion_b``: the anytime lower bound.
"""

from __future__ import annotations

import numpy as np

__all__ = ["ChainBounds", "chain_bounds"]


class ChainBounds:
    """Reach spheres and lever arms of moving elements (see the module docstring).

    ``reach_center`` ``(G, 3) float64, m`` (W) and ``reach_radius`` ``(G,) float64, m`` (inf when an
    unlimited prismatic joint is on the chain); ``lever`` ``(G, n_q) float64`` (m per rad, or 1 per
    m for prismatic joints).
    """

    def __init__(self, reach_center, reach_radius, lever):
        self.reach_center = reach_center
        self.reach_radius = reach_radius
        self.lever = lever


def chain_bounds(tree, lower, upper, elem_link, elem_sphere_L, q_ref) -> ChainBounds:
    """Bounds for elements on links of ``tree`` (a kinematics FlatTree over global links).

    ``lower``, ``upper`` ``(n_q,)`` joint limits (rad or m; +-inf allowed); ``elem_link`` ``(G,)``
    global link index of each moving element; ``elem_sphere_L`` ``(G, 4)`` bounding sphere
    ``[centre (m, in L), radius (m)]``; ``q_ref`` ``(n_q,)`` any configuration (the bounds do
    not depend on it; it only fixes where the rigid distances are measured).
    """
    from ..kinematics._fk import JT_PRISMATIC, joint_frames_reference

    X_WL, X_WJ = joint_frames_reference(tree, np.asarray(q_ref, dtype=np.float64))
    n_links = tree.n_links
    n_q = int(np.asarray(lower).shape[0])
    span = np.asarray(upper, dtype=np.float64) - np.asarray(lower, dtype=np.float64)
    # movable chain (root first) of every link
    chains: list[list[int]] = []
    for i in range(n_links):
        chain = []
        k = i
        while k >= 0:
            if tree.jtype[k] != 0:
                chain.append(k)
            k = int(tree.parent[k])
        chains.append(chain[::-1])
    stroke = np.zeros(n_links)
    for k in range(n_links):
        if tree.jtype[k] == JT_PRISMATIC:
            s = 0.0
            for t in range(tree.term_start[k], tree.term_start[k + 1]):
                c = abs(float(tree.term_coeff[t]))
                if c > 0.0:
                    s += c * span[tree.term_joint[t]]
            stroke[k] = s
    anchor = X_WJ[:, :3, 3]
    G = len(elem_link)
    reach_center = np.zeros((G, 3))
    reach_radius = np.zeros(G)
    lever = np.zeros((G, n_q))
    for g in range(G):
        L = int(elem_link[g])
        o_W = X_WL[L, :3, :3] @ elem_sphere_L[g, :3] + X_WL[L, :3, 3]
        r = float(elem_sphere_L[g, 3])
        chain = chains[L]
        if not chain:  # rigidly fixed in W
            reach_center[g] = o_W
            reach_radius[g] = r
            continue
        K = chain[-1]
        rho = float(np.linalg.norm(o_W - anchor[K])) + r + stroke[K]
        rhos = {K: rho}
        for j in range(len(chain) - 2, -1, -1):
            k, k2 = chain[j], chain[j + 1]
            rho = rho + float(np.linalg.norm(anchor[k] - anchor[k2])) + stroke[k]
            rhos[k] = rho
        reach_center[g] = anchor[chain[0]]
        reach_radius[g] = rhos[chain[0]]
        for k in chain:
            arm = 1.0 if tree.jtype[k] == JT_PRISMATIC else rhos[k]
            for t in range(tree.term_start[k], tree.term_start[k + 1]):
                lever[g, int(tree.term_joint[t])] += abs(float(tree.term_coeff[t])) * arm
    return ChainBounds(reach_center, reach_radius, lever)
