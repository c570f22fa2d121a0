"""Forward kinematics of a flattened joint tree: one numba kernel for any tree, and a reference.

A robot (chain or tree) is flattened, links in topological order (root first), into arrays:

=================  ==========================  ==================================================
array              shape                       meaning
=================  ==========================  ==================================================
``parent``         (n_links,) int64            index of the parent link, -1 for the root
``X_pre``          (n_links, 4, 4) float64     fixed transform parent frame -> joint frame J
``axis``           (n_links, 3) float64        unit joint axis in J (the motion is about/along it)
``jtype``          (n_links,) int64            0 fixed, 1 revolute, 2 prismatic
``X_post``         (n_links, 4, 4) float64     fixed transform after the motion -> link frame L
``has_post``       (n_links,) bool             False where ``X_post`` is the identity (skipped)
``offset``         (n_links,) float64          joint value = offset + sum(coeff * q[term_joint])
``term_start``     (n_links + 1,) int64        the terms of link i are term_start[i]:term_start[i+1]
``term_joint``     (n_terms,) int64            index into q of each term
``term_coeff``     (n_terms,) float64          its coefficient (1 for an ordinary joint)
=================  ==========================  ==================================================

and the pose of link i in W is ``X_WL[i] = X_WL[parent[i]] @ X_pre[i] @ M(axis[i], v_i) @ X_post[i]``
with ``M`` a rotation by ``v_i`` (rad) about ``axis`` or a translation by ``v_i`` (m) along it;
the root's "parent" is the identity, and the robot's base pose ``X_WB`` is folded into the
root's ``X_pre``.  URDF joints have ``X_post = I``; standard DH rows have ``X_post = trans(x, a)
rot(x, alpha)``; couplings (GMF S-480 parallelogram) and URDF mimic joints are extra terms.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

__all__ = ["FlatTree", "fk_kernel", "fk_reference", "joint_frames_reference", "JT_FIXED", "JT_REVOLUTE", "JT_PRISMATIC"]

JT_FIXED = 0
JT_REVOLUTE = 1
JT_PRISMATIC = 2


@dataclass(frozen=True, eq=False)
class FlatTree:
    """The flattened arrays described in the module docstring (read-only, contiguous)."""

    parent: np.ndarray
    X_pre: np.ndarray
    axis: np.ndarray
    jtype: np.ndarray
    X_post: np.ndarray
    has_post: np.ndarray
    offset: np.ndarray
    term_start: np.ndarray
    term_joint: np.ndarray
    term_coeff: np.ndarray

    @property
    def n_links(self) -> int:
        return int(self.parent.shape[0])

    def joint_values(self, q: np.ndarray) -> np.ndarray:
        """``(..., n_links)``: the value of every link's joint (rad or m; 0 for fixed) at ``q`` (..., n)."""
        v = np.broadcast_to(self.offset, q.shape[:-1] + self.offset.shape).copy()
        for i in range(self.n_links):
            for t in range(self.term_start[i], self.term_start[i + 1]):
                v[..., i] += self.term_coeff[t] * q[..., self.term_joint[t]]
        return v


@njit(cache=True, fastmath=False)
def _fk_kernel(q, parent, X_pre, axis, jtype, X_post, has_post, offset, term_start, term_joint, term_coeff, out):
    """Scalar-style batched FK: ``q`` (M, n) -> ``out`` (M, n_links, 4, 4), see the module docstring."""
    n_cfg = q.shape[0]
    n_links = parent.shape[0]
    for m in range(n_cfg):
        for i in range(n_links):
            # parent pose P (3x4), identity for the root
            p = parent[i]
            if p < 0:
                p00 = 1.0; p01 = 0.0; p02 = 0.0; p03 = 0.0
                p10 = 0.0; p11 = 1.0; p12 = 0.0; p13 = 0.0
                p20 = 0.0; p21 = 0.0; p22 = 1.0; p23 = 0.0
            else:
                P = out[m, p]
                p00 = P[0, 0]; p01 = P[0, 1]; p02 = P[0, 2]; p03 = P[0, 3]
                p10 = P[1, 0]; p11 = P[1, 1]; p12 = P[1, 2]; p13 = P[1, 3]
                p20 = P[2, 0]; p21 = P[2, 1]; p22 = P[2, 2]; p23 = P[2, 3]
            # A = P @ X_pre[i]
            B = X_pre[i]
            b00 = B[0, 0]; b01 = B[0, 1]; b02 = B[0, 2]; b03 = B[0, 3]
            b10 = B[1, 0]; b11 = B[1, 1]; b12 = B[1, 2]; b13 = B[1, 3]
            b20 = B[2, 0]; b21 = B[2, 1]; b22 = B[2, 2]; b23 = B[2, 3]
            a00 = p00 * b00 + p01 * b10 + p02 * b20
            a01 = p00 * b01 + p01 * b11 + p02 * b21
            a02 = p00 * b02 + p01 * b12 + p02 * b22
            a03 = p00 * b03 + p01 * b13 + p02 * b23 + p03
            a10 = p10 * b00 + p11 * b10 + p12 * b20
            a11 = p10 * b01 + p11 * b11 + p12 * b21
            a12 = p10 * b02 + p11 * b12 + p12 * b22
            a13 = p10 * b03 + p11 * b13 + p12 * b23 + p13
            a20 = p20 * b00 + p21 * b10 + p22 * b20
            a21 = p20 * b01 + p21 * b11 + p22 * b21
            a22 = p20 * b02 + p21 * b12 + p22 * b22
            a23 = p20 * b03 + p21 * b13 + p22 * b23 + p23
            jt = jtype[i]
            if jt != 0:
                v = offset[i]
                for t in range(term_start[i], term_start[i + 1]):
                    v += term_coeff[t] * q[m, term_joint[t]]
                kx = axis[i, 0]; ky = axis[i, 1]; kz = axis[i, 2]
                if jt == 1:
                    # Rodrigues: R = c I + s [k]x + (1 - c) k k^T ; A[:, :3] <- A[:, :3] @ R
                    c = np.cos(v); s = np.sin(v); w = 1.0 - c
                    r00 = c + w * kx * kx; r01 = w * kx * ky - s * kz; r02 = w * kx * kz + s * ky
                    r10 = w * kx * ky + s * kz; r11 = c + w * ky * ky; r12 = w * ky * kz - s * kx
                    r20 = w * kx * kz - s * ky; r21 = w * ky * kz + s * kx; r22 = c + w * kz * kz
                    t00 = a00 * r00 + a01 * r10 + a02 * r20
                    t01 = a00 * r01 + a01 * r11 + a02 * r21
                    t02 = a00 * r02 + a01 * r12 + a02 * r22
                    t10 = a10 * r00 + a11 * r10 + a12 * r20
                    t11 = a10 * r01 + a11 * r11 + a12 * r21
                    t12 = a10 * r02 + a11 * r12 + a12 * r22
                    t20 = a20 * r00 + a21 * r10 + a22 * r20
                    t21 = a20 * r01 + a21 * r11 + a22 * r21
                    t22 = a20 * r02 + a21 * r12 + a22 * r22
                    a00 = t00; a01 = t01; a02 = t02
                    a10 = t10; a11 = t11; a12 = t12
                    a20 = t20; a21 = t21; a22 = t22
                else:
                    a03 += (a00 * kx + a01 * ky + a02 * kz) * v
                    a13 += (a10 * kx + a11 * ky + a12 * kz) * v
                    a23 += (a20 * kx + a21 * ky + a22 * kz) * v
            if has_post[i]:
                C = X_post[i]
                b00 = C[0, 0]; b01 = C[0, 1]; b02 = C[0, 2]; b03 = C[0, 3]
                b10 = C[1, 0]; b11 = C[1, 1]; b12 = C[1, 2]; b13 = C[1, 3]
                b20 = C[2, 0]; b21 = C[2, 1]; b22 = C[2, 2]; b23 = C[2, 3]
                t00 = a00 * b00 + a01 * b10 + a02 * b20
                t01 = a00 * b01 + a01 * b11 + a02 * b21
                t02 = a00 * b02 + a01 * b12 + a02 * b22
                t03 = a00 * b03 + a01 * b13 + a02 * b23 + a03
                t10 = a10 * b00 + a11 * b10 + a12 * b20
                t11 = a10 * b01 + a11 * b11 + a12 * b21
                t12 = a10 * b02 + a11 * b12 + a12 * b22
                t13 = a10 * b03 + a11 * b13 + a12 * b23 + a13
                t20 = a20 * b00 + a21 * b10 + a22 * b20
                t21 = a20 * b01 + a21 * b11 + a22 * b21
                t22 = a20 * b02 + a21 * b12 + a22 * b22
                t23 = a20 * b03 + a21 * b13 + a22 * b23 + a23
                a00 = t00; a01 = t01; a02 = t02; a03 = t03
                a10 = t10; a11 = t11; a12 = t12; a13 = t13
                a20 = t20; a21 = t21; a22 = t22; a23 = t23
            O = out[m, i]
            O[0, 0] = a00; O[0, 1] = a01; O[0, 2] = a02; O[0, 3] = a03
            O[1, 0] = a10; O[1, 1] = a11; O[1, 2] = a12; O[1, 3] = a13
            O[2, 0] = a20; O[2, 1] = a21; O[2, 2] = a22; O[2, 3] = a23
            O[3, 0] = 0.0; O[3, 1] = 0.0; O[3, 2] = 0.0; O[3, 3] = 1.0


def fk_kernel(tree: FlatTree, q: np.ndarray) -> np.ndarray:
    """Batched FK through the numba kernel: ``q`` (..., n) float64 (validated) -> (..., n_links, 4, 4)."""
    lead = q.shape[:-1]
    q2 = np.ascontiguousarray(q.reshape((math.prod(lead), q.shape[-1])))  # explicit count: n_joints may be 0
    out = np.empty((q2.shape[0], tree.n_links, 4, 4))
    _fk_kernel(
        q2, tree.parent, tree.X_pre, tree.axis, tree.jtype, tree.X_post, tree.has_post,
        tree.offset, tree.term_start, tree.term_joint, tree.term_coeff, out,
    )
    return out.reshape(lead + (tree.n_links, 4, 4))


def _motion(jtype: int, axis: np.ndarray, v: float) -> np.ndarray:
    from ._frames import rotation_about_axis

    if jtype == JT_REVOLUTE:
        return rotation_about_axis(axis, v)
    M = np.eye(4)
    if jtype == JT_PRISMATIC:
        M[:3, 3] = axis * v
    return M


def joint_frames_reference(tree: FlatTree, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Slow reference for one configuration ``q`` (n,): ``(X_WL, X_WJ)``, each (n_links, 4, 4).

    ``X_WJ[i] = X_WL[parent] @ X_pre[i]`` is the joint frame (the axis is fixed in it).  Plain
    products of 4x4 matrices, one link at a time: the definition the kernel is tested against.
    """
    v = tree.joint_values(q)
    X_WL = np.zeros((tree.n_links, 4, 4))
    X_WJ = np.zeros((tree.n_links, 4, 4))
    for i in range(tree.n_links):
        P = np.eye(4) if tree.parent[i] < 0 else X_WL[tree.parent[i]]
        X_WJ[i] = P @ tree.X_pre[i]
        X_WL[i] = X_WJ[i] @ _motion(int(tree.jtype[i]), tree.axis[i], float(v[i])) @ tree.X_post[i]
    return X_WL, X_WJ


def fk_reference(tree: FlatTree, q: np.ndarray) -> np.ndarray:
    """Slow reference FK: ``q`` (..., n) -> (..., n_links, 4, 4), one configuration at a time."""
    lead = q.shape[:-1]
    q2 = q.reshape((math.prod(lead), q.shape[-1]))
    out = np.stack([joint_frames_reference(tree, qi)[0] for qi in q2]) if q2.shape[0] else np.empty((0, tree.n_links, 4, 4))
    return out.reshape(lead + (tree.n_links, 4, 4))
