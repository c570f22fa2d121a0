"""Uncertain rigid transforms in 3-D on SE(3), array-first: no Euler angles, so no poles.

Smith & Cheeseman (Section 6) note that extending (x, y, θ) to six degrees of freedom with
Euler angles puts singularities ("poles") into the Jacobian, and leave it open.  Here a
relation of frame B with respect to frame A is a mean transform ``T_AB`` (4, 4) (B's pose in
A: ``p_A = T_AB p_B``) and a Gaussian perturbation in exponential coordinates applied on the
left, in A's axes::

    T_AB = exp(ξ^) T̄_AB,   ξ ~ N(0, C),   ξ = (ρ, φ) = (ρx, ρy, ρz, φx, φy, φz)

with ``ξ^ = [[φ×, ρ], [0, 0]]``: ``ρ`` (m) first, ``φ`` (rad, a rotation vector) second — the
order of the paper's (x, y, θ).  ``C`` is (6, 6) in m² / m·rad / rad².  exp and log are
smooth everywhere except log at rotations of exactly π (where the axis sign is ambiguous);
the covariance propagation needs only the adjoint, which has no singularity at all:

* compound ``T_AC = T_AB T_BC``:  ``ξ_AC ≈ ξ_AB + Ad(T̄_AB) ξ_BC``, so
  ``C_AC = C_AB + Ad C_BC Ad^T`` (the SE(3) counterpart of Eqns. 1–3; J⊕ = [I | Ad(T̄_AB)]);
* inverse ``T_BA = T_AB^-1``:  ``ξ_BA = -Ad(T̄_AB^-1) ξ_AB``, ``C_BA = Ad C_AB Ad^T``
  (counterpart of Eqn. 4);
* merge: Eqns. (5)–(7) in the tangent space at the first estimate (innovation
  ``log(T̄2 T̄1^-1)``), first order.

``Ad(T) = [[R, p× R], [0, R]]`` in this (ρ, φ) order.  pytransform3d's uncertainty module
uses the same left perturbation and the same exponential coordinates in the opposite order
(rotation first, ``(ω, v)``): ``C_pt3d = P C P^T`` with ``P = [[0, I3], [I3, 0]]``
(:func:`to_pytransform3d_cov`), and its ``concat_globally_uncertain_transforms(T_BC, C_BC,
T_AB, C_AB)`` is :func:`compound` plus Barfoot & Furgale's fourth-order terms.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from ._validate import as_covariance, as_transform, as_vector, symmetrize
from .se2 import _merge

__all__ = [
    "hat",
    "exp",
    "log",
    "adjoint",
    "invert_transform",
    "compound",
    "inverse",
    "merge",
    "to_pytransform3d_cov",
    "from_pytransform3d_cov",
]

_SMALL = 1e-5  # rad: below this angle exp uses its Taylor series (error ~ θ^4 / 120 < 1e-22)
_SWAP = np.block([[np.zeros((3, 3)), np.eye(3)], [np.eye(3), np.zeros((3, 3))]])


def _skew(w: np.ndarray) -> np.ndarray:
    """(..., 3) -> (..., 3, 3) cross-product matrices ``w×``."""
    z = np.zeros(w.shape[:-1])
    return np.stack(
        (
            np.stack((z, -w[..., 2], w[..., 1]), -1),
            np.stack((w[..., 2], z, -w[..., 0]), -1),
            np.stack((-w[..., 1], w[..., 0], z), -1),
        ),
        -2,
    )


def hat(xi) -> np.ndarray:
    """``ξ^`` (..., 4, 4) of exponential coordinates ``xi`` (..., 6) = (ρ m, φ rad)."""
    xi = np.asarray(xi, dtype=np.float64)
    out = np.zeros(xi.shape[:-1] + (4, 4))
    out[..., :3, :3] = _skew(xi[..., 3:])
    out[..., :3, 3] = xi[..., :3]
    return out


_LOG_SERIES = 1e-3
"""Below this angle (rad) ``V``'s and ``V^-1``'s coefficients (:func:`exp`, :func:`log`) come from their Taylor series."""


def _exp(xi: np.ndarray) -> np.ndarray:
    rho, phi = xi[..., :3], xi[..., 3:]
    th2 = np.einsum("...i,...i->...", phi, phi)
    th = np.sqrt(th2)
    small = th < _SMALL
    ths = np.where(small, 1.0, th)
    a = np.where(small, 1.0 - th2 / 6.0, np.sin(ths) / ths)  # sin θ / θ
    sh = np.sin(0.5 * ths) / ths
    b = np.where(small, 0.5 - th2 / 24.0, 2.0 * sh * sh)  # (1 - cos θ) / θ² = 2 sin²(θ/2) / θ² (1 - cos θ cancels)
    # (θ - sin θ) / θ³, its series below _LOG_SERIES (the difference cancels; the next term is below 3e-24)
    series = th < _LOG_SERIES
    tc = np.where(series, 1.0, th)
    c = np.where(series, 1.0 / 6.0 - th2 / 120.0 + th2 * th2 / 5040.0, (tc - np.sin(tc)) / (tc**3))
    k = _skew(phi)
    k2 = k @ k
    eye = np.eye(3)
    r = eye + a[..., None, None] * k + b[..., None, None] * k2
    v = eye + b[..., None, None] * k + c[..., None, None] * k2
    out = np.zeros(xi.shape[:-1] + (4, 4))
    out[..., :3, :3] = r
    out[..., :3, 3] = np.einsum("...ij,...j->...i", v, rho)
    out[..., 3, 3] = 1.0
    return out


def exp(xi) -> np.ndarray:
    """The SE(3) exponential: (..., 6) exponential coordinates (ρ m, φ rad) -> (..., 4, 4).

    Rodrigues' formula for the rotation and ``t = V ρ`` with ``V = I + (1 - cos θ)/θ² φ× +
    (θ - sin θ)/θ³ (φ×)²``; Taylor series below 1e-5 rad (``V``'s last coefficient below 1e-3 rad).
    """
    return _exp(np.asarray(xi, dtype=np.float64))


def _log(t: np.ndarray) -> np.ndarray:
    r = t[..., :3, :3]
    flat = r.reshape(-1, 3, 3)
    phi = Rotation.from_matrix(flat).as_rotvec().reshape(r.shape[:-2] + (3,))
    th2 = np.einsum("...i,...i->...", phi, phi)
    th = np.sqrt(th2)
    # V^-1 = I - ½ φ× + d (φ×)², d = (1 - θ sin θ / (2 (1 - cos θ))) / θ² = (1 - (θ/2) cot(θ/2)) / θ²:
    # written with the half angle (1 - cos θ cancelled: at θ = 1e-5 rad it cost 1e-6 m per metre of
    # translation), and its Taylor series 1/12 + θ²/720 + θ⁴/30240 below 1e-3 rad (where 1 - x cot x
    # cancels; the next term, θ⁶/1209600, is below 1e-24 there)
    small = th < _LOG_SERIES
    h = 0.5 * np.where(small, 1.0, th)
    d = np.where(small, 1.0 / 12.0 + th2 / 720.0 + th2 * th2 / 30240.0, (1.0 - h * np.cos(h) / np.sin(h)) / (4.0 * h * h))
    k = _skew(phi)
    vinv = np.eye(3) - 0.5 * k + d[..., None, None] * (k @ k)
    rho = np.einsum("...ij,...j->...i", vinv, t[..., :3, 3])
    return np.concatenate((rho, phi), axis=-1)


def log(t) -> np.ndarray:
    """The SE(3) logarithm: (..., 4, 4) rigid transforms -> (..., 6) exponential coordinates
    (ρ m, φ rad), ``|φ| <= π``."""
    return _log(np.asarray(t, dtype=np.float64))


def _adjoint(t: np.ndarray) -> np.ndarray:
    r, p = t[:3, :3], t[:3, 3]
    out = np.zeros((6, 6))
    out[:3, :3] = r
    out[:3, 3:] = _skew(p) @ r
    out[3:, 3:] = r
    return out


def adjoint(t) -> np.ndarray:
    """``Ad(T)`` (6, 6) of a rigid transform ``T`` (4, 4), (ρ, φ) order: ``[[R, p× R], [0, R]]``,
    so that ``T exp(ξ^) T^-1 = exp((Ad(T) ξ)^)``."""
    return _adjoint(as_transform(t, "t"))


def _invert(t: np.ndarray) -> np.ndarray:
    out = np.eye(4)
    rt = t[:3, :3].T
    out[:3, :3] = rt
    out[:3, 3] = -rt @ t[:3, 3]
    return out


def invert_transform(t) -> np.ndarray:
    """``T^-1`` (4, 4) of a rigid transform ``T`` (4, 4)."""
    return _invert(as_transform(t, "t"))


def _compound(t1, c1, t2, c2):
    ad = _adjoint(t1)
    return t1 @ t2, symmetrize(c1 + ad @ c2 @ ad.T), ad


def compound(t1, c1, t2, c2, *, tol: Tolerances = DEFAULT_TOLERANCES):
    """Compound ``T_AC = T_AB T_BC`` with ``C_AC = C_AB + Ad(T̄_AB) C_BC Ad(T̄_AB)^T``.

    Parameters
    ----------
    t1 : (4, 4) float64 — mean ``T_AB`` (m for the translation).
    c1 : (6, 6) float64, m² / m·rad / rad² — its covariance, left perturbation in A's axes.
    t2 : (4, 4) float64 — mean ``T_BC``.
    c2 : (6, 6) float64 — its covariance, left perturbation in B's axes.

    Returns
    -------
    t3 : (4, 4) float64 — ``T_AC``.
    c3 : (6, 6) float64 — its covariance in A's axes.
    ad : (6, 6) float64 — ``Ad(T̄_AB)``, the second half of J⊕ = [I | Ad].
    """
    return _compound(
        as_transform(t1, "t1", tol), as_covariance(c1, 6, "c1", tol),
        as_transform(t2, "t2", tol), as_covariance(c2, 6, "c2", tol),
    )


def _inverse(t, c):
    ti = _invert(t)
    ad = _adjoint(ti)
    return ti, symmetrize(ad @ c @ ad.T), -ad


def inverse(t, c, *, tol: Tolerances = DEFAULT_TOLERANCES):
    """Invert ``T_BA = T_AB^-1`` with ``C_BA = Ad(T̄_AB^-1) C_AB Ad(T̄_AB^-1)^T``.

    Parameters
    ----------
    t : (4, 4) float64 — mean ``T_AB``.
    c : (6, 6) float64, m² / m·rad / rad² — its covariance in A's axes.

    Returns
    -------
    ti : (4, 4) float64 — ``T_BA``.
    ci : (6, 6) float64 — its covariance in B's axes.
    j : (6, 6) float64 — the Jacobian ``∂ξ_BA / ∂ξ_AB = -Ad(T̄_AB^-1)``.
    """
    return _inverse(as_transform(t, "t", tol), as_covariance(c, 6, "c", tol))


def _merge3(t1, c1, t2, c2, tol):
    d = _log(t2 @ _invert(t1))
    delta, c3, k = _merge(np.zeros(6), c1, d, c2, tol, angle_index=())
    t3 = _exp(delta) @ t1
    # re-orthonormalise the rotation against round-off
    u, _, vt = np.linalg.svd(t3[:3, :3])
    t3[:3, :3] = u @ vt
    return t3, c3, k


def merge(t1, c1, t2, c2, *, tol: Tolerances = DEFAULT_TOLERANCES):
    """Merge two independent estimates of one transform: Eqns. (5)–(7) in the tangent space.

    Innovation ``d = log(T̄2 T̄1^-1)`` (the left perturbation carrying T̄1 to T̄2),
    ``K = C1 (C1 + C2)^-1``, ``T̄3 = exp((K d)^) T̄1``, ``C3 = C1 - K C1``; first order in
    ``d`` (the left Jacobian of log at d is taken as I, exact when the estimates agree).

    Parameters
    ----------
    t1, t2 : (4, 4) float64 — two estimates of ``T_AB``.
    c1, c2 : (6, 6) float64, m² / m·rad / rad² — their covariances in A's axes.

    Returns
    -------
    t3 : (4, 4) float64, c3 : (6, 6) float64, k : (6, 6) float64 (the gain).
    """
    return _merge3(
        as_transform(t1, "t1", tol), as_covariance(c1, 6, "c1", tol),
        as_transform(t2, "t2", tol), as_covariance(c2, 6, "c2", tol), tol,
    )


def to_pytransform3d_cov(c) -> np.ndarray:
    """Reorder a (6, 6) covariance from this module's (ρ, φ) to pytransform3d's (ω, v) order."""
    c = np.asarray(c, dtype=np.float64)
    return _SWAP @ c @ _SWAP.T


def from_pytransform3d_cov(c) -> np.ndarray:
    """Reorder a (6, 6) covariance from pytransform3d's (ω, v) to this module's (ρ, φ) order."""
    return to_pytransform3d_cov(c)  # the swap is its own inverse


def exp_coords(xi) -> np.ndarray:
    """Validated :func:`exp` of one (6,) vector (ρ m, φ rad) -> (4, 4)."""
    return _exp(as_vector(xi, 6, "xi"))
