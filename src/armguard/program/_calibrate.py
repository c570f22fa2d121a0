"""Robot–camera calibration's estimator: the least-squares rigid transform between two point sets,
in closed form, with its first-order covariance.

Horn, "Closed-form solution of absolute orientation using unit quaternions" (JOSA A 4(4), 1987)
and Umeyama, "Least-squares estimation of transformation parameters between two point patterns"
(IEEE PAMI 13(4), 1991), without scale: the rotation comes from scipy's
``Rotation.align_vectors`` (the same SVD / quaternion solution) on the centred points, the
translation from the centroids.  The covariance is Smith & Cheeseman's first-order one: with the
pose's left perturbation ``ξ = (ρ, φ)`` in A's axes (:class:`~armguard.uncertainty.UncertainPose3`),
each point's prediction moves by ``J_i ξ``, ``J_i = [I | −[p_i]×]``, and ``Σ = σ² (Σ J_iᵀ J_i)⁻¹``
for isotropic point noise of variance σ² per axis.  For anisotropic noise of covariance ``C`` (3, 3)
per point (a camera measures depth better or worse than across the image) the estimator is the
same (Horn's closed form weighs every axis alike) and its covariance the sandwich
``H⁻¹ (Σ J_iᵀ C J_i) H⁻¹``, ``H = Σ J_iᵀ J_i``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._errors import UncertaintyError

__all__ = ["RigidFit", "fit_rigid_transform"]


@dataclass(frozen=True)
class RigidFit:
    """``pose`` (UncertainPose3: X_AB with its covariance), ``rms`` (m, the residuals' root mean
    square), ``sigma`` (m, the per-axis noise used for the covariance: with ``cov`` given, the root
    of its largest eigenvalue), ``n`` (points)."""

    pose: object
    rms: float
    sigma: float
    n: int

    @property
    def X_AB(self) -> np.ndarray:
        return np.array(self.pose.mean)


def _skew(v) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def fit_rigid_transform(p_A, p_B, sigma: float | None = None, *, cov=None) -> RigidFit:
    """``X_AB`` minimising ``Σ |p_A[i] − X_AB p_B[i]|²`` for ``p_A``, ``p_B`` (N, 3) the same points in
    frames A and B (N >= 3, not collinear).  ``sigma`` (m): the per-axis noise of the point
    differences (default: estimated from the residuals, ``rms² · 3N / (3N − 6)``, which needs N >= 3);
    or ``cov`` (3, 3, m²): their covariance in A's axes, the same for every point (not with ``sigma``).

    With ``sigma`` estimated, the pose's covariance is widened by ``6 F⁻¹(0.999; 6, ν) / χ²₆⁻¹(0.999)``,
    ``ν = 3N − 6``: the error's Mahalanobis distance under an estimated σ follows ``6 F(6, ν)``, not
    ``χ²₆`` (Student's correction), so the covariance's 99.9 % contour (the confidence the clearance checks
    use by default) holds the truth 99.9 % of the time; a lower confidence's (99 %) errs on the safe side, a higher one's not
    (5.35× at N = 4, 1.37× at N = 12, 1.08× at N = 40; unwidened, 11.6 % of N = 4 fits fell outside the 99 % one)."""
    from scipy.spatial.transform import Rotation

    from ..uncertainty import UncertainPose3

    A = np.asarray(p_A, dtype=np.float64)
    B = np.asarray(p_B, dtype=np.float64)
    if A.ndim != 2 or A.shape[1] != 3 or A.shape != B.shape or A.shape[0] < 3:
        raise UncertaintyError(f"fit_rigid_transform: expected two (N, 3) arrays with N >= 3, got {A.shape} and {B.shape}")
    if not (np.all(np.isfinite(A)) and np.all(np.isfinite(B))):
        raise UncertaintyError("fit_rigid_transform: the points must be finite")
    a0, b0 = A.mean(axis=0), B.mean(axis=0)
    s = np.linalg.svd(B - b0, compute_uv=False)
    if s[1] <= 1e-9 * max(s[0], 1e-300):
        raise UncertaintyError("fit_rigid_transform: the points are collinear (or coincide); the rotation is undetermined")
    rot, _ = Rotation.align_vectors(A - a0, B - b0)
    R = rot.as_matrix()
    X = np.eye(4)
    X[:3, :3] = R
    X[:3, 3] = a0 - R @ b0
    pred = B @ R.T + X[:3, 3]
    res = A - pred
    n = A.shape[0]
    rms = float(np.sqrt(np.mean(np.sum(res ** 2, axis=1))))
    est = cov is None and sigma is None
    if cov is not None:
        if sigma is not None:
            raise UncertaintyError("fit_rigid_transform: give sigma or cov, not both")
        C = np.asarray(cov, dtype=np.float64)
        if C.shape != (3, 3) or not np.all(np.isfinite(C)) or not np.allclose(C, C.T, rtol=1e-9, atol=1e-300) \
                or np.linalg.eigvalsh(0.5 * (C + C.T))[0] < -1e-12 * max(float(np.abs(C).max()), 1e-300):
            raise UncertaintyError(f"fit_rigid_transform: cov must be a finite symmetric positive semi-definite (3, 3) "
                                   f"matrix, got {np.array2string(C, precision=3)}")
        C = 0.5 * (C + C.T)
        sigma = float(np.sqrt(max(np.linalg.eigvalsh(C)[-1], 0.0)))
    elif sigma is None:
        sigma = float(np.sqrt(np.sum(res ** 2) / (3 * n - 6)))
        from scipy import stats

        widen = 6.0 * float(stats.f.ppf(0.999, 6, 3 * n - 6)) / float(stats.chi2.ppf(0.999, 6))
    elif not (np.isfinite(sigma) and sigma >= 0.0):
        raise UncertaintyError(f"fit_rigid_transform: sigma must be a finite number >= 0, got {sigma!r}")
    if cov is None:
        C = float(sigma) ** 2 * (widen if est else 1.0) * np.eye(3)
    H, M = np.zeros((6, 6)), np.zeros((6, 6))
    for p in pred:
        J = np.hstack([np.eye(3), -_skew(p)])
        H += J.T @ J
        M += J.T @ C @ J
    Hi = np.linalg.inv(H)
    out = Hi @ M @ Hi  # sigma² H⁻¹ for isotropic noise
    return RigidFit(UncertainPose3(X, 0.5 * (out + out.T)), rms, float(sigma), n)
