"""Grasp error from a wrist force/torque sensor (Smith 1986, seed 004, §III.C: "not yet performed").

An object held in the hand is "weighed" at several hand orientations to find where it sits, and
its inertia measured during controlled rotations to find how it is turned.  Frames: S the sensor
(on the wrist), W the world (gravity ``g_W``), O the object (origin at its centre of mass C).

**The sensor's wrench.**  The sensor measures the wrench it applies to the object, in S, about its
origin, plus constant biases (Newton-Euler for a rigid body in a frame moving with S, angular
velocity ``w`` and acceleration ``a`` in S, S's origin not accelerating):

    f   = m (a x p_SC + w x (w x p_SC) - g_S) + b_f
    tau = I_S a + w x (I_S w) - m p_SC x g_S + b_tau,      g_S = R_WS^T g_W,

with ``I_S = R_SO I_O R_SO^T + m (|p_SC|^2 E - p_SC p_SC^T)`` the inertia about S's origin.

**Weighing** (:func:`weigh`, hand at rest in ``n >= 3`` orientations, not all about one axis):
``f_i = -m g_i + b_f`` is linear in ``(m, b_f)``; ``tau_i = [g_i]x (m p_SC) + b_tau`` linear in the
first moment ``m p_SC`` and ``b_tau``: two least-squares problems.  Their covariances are
``sigma^2 (A^T A)^-1`` (``sigma`` from the residuals, or given), carried to ``p_SC`` to first order.

**Orientation** (:func:`grasp_orientation`, rotations with known ``w``, ``a``): with the biases,
mass and ``p_SC`` known, ``tau - b_tau + m p_SC x g_S = I_S a + w x (I_S w)`` is linear in the six
entries of ``I_S``; the parallel-axis term gives ``I_C``, and ``R_SO`` aligns ``I_O``'s principal
axes with ``I_C``'s (eigenvectors, the sign choice nearest the nominal grasp).  A body whose
principal moments are equal about some axis (a cylinder about its own) cannot show a turn about it:
:attr:`GraspOrientation.unobservable` names the axis and that turn is reported as zero.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from .._errors import UncertaintyError

__all__ = ["Weighing", "weigh", "GraspOrientation", "grasp_orientation", "object_wrench"]

G_W = np.array([0.0, 0.0, -9.80665])
"""Standard gravity in W (m/s^2), z up."""


def _skew(v) -> np.ndarray:
    x, y, z = v
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def _rotations(R_WS, where: str) -> np.ndarray:
    R = np.asarray(R_WS, dtype=np.float64)
    if R.ndim != 3 or R.shape[1:] != (3, 3) or len(R) == 0 or not np.all(np.isfinite(R)):
        raise UncertaintyError(f"{where}: expected (n, 3, 3) finite rotations, got shape {R.shape}")
    if np.abs(R @ np.swapaxes(R, 1, 2) - np.eye(3)).max() > 1e-6:
        raise UncertaintyError(f"{where}: not rotation matrices (R R^T != E)")
    flipped = np.flatnonzero(np.linalg.det(R) < 0.0)
    if flipped.size:  # orthonormal but a reflection: no wrist turns the object so
        raise UncertaintyError(f"{where}[{int(flipped[0])}]: a reflection (det -1), not a rotation")
    return R


def _vectors(v, n: int, where: str) -> np.ndarray:
    v = np.asarray(v, dtype=np.float64)
    if v.shape != (n, 3) or not np.all(np.isfinite(v)):
        raise UncertaintyError(f"{where}: expected ({n}, 3) finite values, got shape {v.shape}"
                               + ("" if v.shape != (n, 3) else " with a non-finite value"))
    return v


def object_wrench(R_WS, mass: float, p_SC, I_C_S, *, w_S=None, a_S=None, b_f=np.zeros(3), b_tau=np.zeros(3),
                  g_W=G_W) -> tuple[np.ndarray, np.ndarray]:
    """``(f, tau)`` (n, 3) each: the sensor's wrench (module docstring) on an object of ``mass`` kg with
    centre of mass ``p_SC`` and inertia ``I_C_S`` (about C, axes of S), at hand orientations ``R_WS``
    (n, 3, 3) with angular velocities ``w_S`` and accelerations ``a_S`` (n, 3; default zero)."""
    R = _rotations(R_WS, "R_WS")
    n = len(R)
    w = np.zeros((n, 3)) if w_S is None else _vectors(w_S, n, "w_S")
    a = np.zeros((n, 3)) if a_S is None else _vectors(a_S, n, "a_S")
    p = np.asarray(p_SC, dtype=np.float64)
    I_S = np.asarray(I_C_S, dtype=np.float64) + mass * (p @ p * np.eye(3) - np.outer(p, p))
    g = np.einsum("nji,j->ni", R, np.asarray(g_W, dtype=np.float64))
    f = mass * (np.cross(a, p) + np.cross(w, np.cross(w, p)) - g) + b_f
    tau = a @ I_S.T + np.cross(w, w @ I_S.T) - mass * np.cross(p, g) + b_tau
    return f, tau


@dataclass(frozen=True)
class Weighing:
    """What weighing at rest found: ``mass`` (kg), ``p_SC`` (m, the centre of mass in S) with its
    covariance ``cov_p_SC`` (3, 3), the sensor biases ``b_f`` (N), ``b_tau`` (N m), the residuals' rms
    (``rms_f``, ``rms_tau``) and ``n`` orientations used."""

    mass: float
    var_mass: float
    p_SC: np.ndarray
    cov_p_SC: np.ndarray
    b_f: np.ndarray
    b_tau: np.ndarray
    rms_f: float
    rms_tau: float
    n: int

    def offset(self, p_SC_nominal) -> np.ndarray:
        """The grasp's position error: ``p_SC - p_SC_nominal`` (m, in S)."""
        return self.p_SC - np.asarray(p_SC_nominal, dtype=np.float64)


def _lstsq(A: np.ndarray, y: np.ndarray, sigma) -> tuple[np.ndarray, np.ndarray, float]:
    x, *_ = np.linalg.lstsq(A, y, rcond=None)
    r = y - A @ x
    dof = max(len(y) - A.shape[1], 1)
    s2 = float(r @ r) / dof if sigma is None else float(sigma) ** 2
    return x, s2 * np.linalg.inv(A.T @ A), float(np.sqrt(np.mean(r ** 2)))


def weigh(R_WS, f_S, tau_S, *, g_W=G_W, sigma_f: float | None = None, sigma_tau: float | None = None) -> Weighing:
    """The object's mass and centre of mass from wrenches at rest (module docstring).  ``sigma_f``,
    ``sigma_tau``: the sensor's noise (N, N m) for the covariance, else estimated from the residuals."""
    for name, sigma in (("sigma_f", sigma_f), ("sigma_tau", sigma_tau)):
        if sigma is not None and (isinstance(sigma, bool) or not isinstance(sigma, (int, float, np.floating, np.integer))
                                  or not (math.isfinite(sigma) and sigma > 0.0)):
            raise UncertaintyError(f"weigh: {name}: expected the sensor's noise, a finite number > 0, or None "
                                   f"(estimated from the residuals), got {sigma!r}")
    R = _rotations(R_WS, "R_WS")
    n = len(R)
    f, tau = _vectors(f_S, n, "f_S"), _vectors(tau_S, n, "tau_S")
    g = np.einsum("nji,j->ni", R, np.asarray(g_W, dtype=np.float64))  # g_S per pose
    # the hand must turn about two axes: else the first moment along the common axis is not seen
    if n < 3 or np.linalg.matrix_rank(g - g.mean(axis=0), tol=1e-3 * np.linalg.norm(g_W)) < 2:
        raise UncertaintyError(f"weigh: {n} orientations leave the centre of mass unobservable; give at least 3 "
                               "with gravity along directions that span a plane in the sensor frame")
    E = np.eye(3)
    A_f = np.zeros((3 * n, 4))
    A_f[:, 0] = -g.reshape(-1)
    A_f[:, 1:] = np.tile(E, (n, 1))
    x_f, cov_f, rms_f = _lstsq(A_f, f.reshape(-1), sigma_f)
    A_t = np.zeros((3 * n, 6))
    for i in range(n):
        A_t[3 * i:3 * i + 3, :3] = _skew(g[i])
        A_t[3 * i:3 * i + 3, 3:] = E
    x_t, cov_t, rms_t = _lstsq(A_t, tau.reshape(-1), sigma_tau)
    m = float(x_f[0])
    if not m > 0.0:
        raise UncertaintyError(f"weigh: the estimated mass is {m:.4g} kg: no object is held (or the data are wrong)")
    first = x_t[:3]
    p = first / m
    # first order: p = first / m, with m and first from independent problems
    J_first, J_m = np.eye(3) / m, -first[:, None] / m ** 2
    cov_p = J_first @ cov_t[:3, :3] @ J_first.T + J_m @ J_m.T * cov_f[0, 0]
    return Weighing(m, float(cov_f[0, 0]), p, cov_p, x_f[1:], x_t[3:], rms_f, rms_t, n)


@dataclass(frozen=True)
class GraspOrientation:
    """What the controlled rotations found: ``I_C_S`` the inertia about C in S's axes, ``R_SO`` the
    object's orientation in S, ``error`` the rotation vector (rad) of ``R_SO R_SO_nominal^T``, and
    ``unobservable`` the axis (in S) about which equal principal moments hide a turn (None if none)."""

    I_C_S: np.ndarray
    R_SO: np.ndarray
    error: np.ndarray
    unobservable: np.ndarray | None
    rms_tau: float


def grasp_orientation(weighing: Weighing, R_WS, w_S, a_S, tau_S, I_O, R_SO_nominal, *, g_W=G_W,
                      isotropy: float = 0.05) -> GraspOrientation:
    """The object's orientation from torques during rotations with known ``w_S``, ``a_S`` (n, 3), given the
    weighing and the object's inertia ``I_O`` about C in its own axes (module docstring).  Principal
    moments closer than ``isotropy`` (relative) count as equal."""
    R = _rotations(R_WS, "R_WS")
    n = len(R)
    w, a, tau = _vectors(w_S, n, "w_S"), _vectors(a_S, n, "a_S"), _vectors(tau_S, n, "tau_S")
    m, p = weighing.mass, weighing.p_SC
    g = np.einsum("nji,j->ni", R, np.asarray(g_W, dtype=np.float64))
    y = (tau - weighing.b_tau + m * np.cross(p, g)).reshape(-1)
    # I = [[Ixx, Ixy, Ixz], [Ixy, Iyy, Iyz], [Ixz, Iyz, Izz]] -> unknowns (Ixx, Iyy, Izz, Ixy, Ixz, Iyz)
    basis = []
    for (i, j) in ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)):
        B = np.zeros((3, 3))
        B[i, j] = B[j, i] = 1.0
        basis.append(B)
    A = np.zeros((3 * n, 6))
    for k, B in enumerate(basis):
        A[:, k] = (a @ B.T + np.cross(w, w @ B.T)).reshape(-1)
    if np.linalg.matrix_rank(A) < 6:
        raise UncertaintyError("grasp_orientation: the rotations do not excite every inertia entry; rotate about "
                               "at least three independent axes (with accelerations)")
    x, *_ = np.linalg.lstsq(A, y, rcond=None)
    rms = float(np.sqrt(np.mean((y - A @ x) ** 2)))
    I_S = sum(c * B for c, B in zip(x, basis))
    I_C = I_S - m * (p @ p * np.eye(3) - np.outer(p, p))
    lam_c, V = np.linalg.eigh(I_C)
    lam_o, U = np.linalg.eigh(np.asarray(I_O, dtype=np.float64))
    R_nom = np.asarray(R_SO_nominal, dtype=np.float64)
    best = None
    for signs in ((1, 1, 1), (1, -1, -1), (-1, 1, -1), (-1, -1, 1)):
        R_SO = V @ np.diag(signs) @ U.T
        if np.linalg.det(R_SO) < 0:
            R_SO = V @ np.diag([-s for s in signs]) @ U.T
        ang = float(np.linalg.norm(Rotation.from_matrix(R_SO @ R_nom.T).as_rotvec()))
        if best is None or ang < best[0]:
            best = (ang, R_SO)
    R_SO = best[1]
    scale = float(np.max(np.abs(lam_o)))
    gaps = np.abs(np.diff(lam_o)) / scale
    unobs = None
    if gaps.min() < isotropy:
        if gaps.max() < isotropy:
            raise UncertaintyError("grasp_orientation: the object's inertia is isotropic: its orientation cannot be seen")
        k = 2 if gaps[0] < isotropy else 0  # the distinct principal axis (of I_O and of I_C): the symmetry axis
        axis_nom = R_nom @ U[:, k]
        axis_S = V[:, k] if V[:, k] @ axis_nom >= 0.0 else -V[:, k]
        # only the axis is seen: the least rotation taking the nominal axis onto it (no turn about it)
        c = np.cross(axis_nom, axis_S)
        angle = float(np.arctan2(np.linalg.norm(c), axis_nom @ axis_S))
        rotvec = np.zeros(3) if np.linalg.norm(c) < 1e-15 else c / np.linalg.norm(c) * angle
        R_SO = Rotation.from_rotvec(rotvec).as_matrix() @ R_nom
        unobs = axis_S
    err = Rotation.from_matrix(R_SO @ R_nom.T).as_rotvec()
    return GraspOrientation(I_C, R_SO, err, unobs, rms)
