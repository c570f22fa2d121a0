"""Robot–camera calibration's estimator (Horn / Umeyama, closed form) and its covariance: exact on
noiseless points (against a plain SVD solution), and on noisy ones the error has the stated
covariance (Monte Carlo: the Mahalanobis distances follow chi-square with 6 dof)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from armguard import UncertaintyError
from armguard.program import fit_rigid_transform, pose
from armguard.uncertainty import se3

X_TRUE = pose([0.55, -0.02, 1.48], [3.1, 0.05, 1.2])


def _points(rng, n=8):
    return rng.uniform([-0.15, -0.15, 0.0], [0.15, 0.15, 0.3], size=(n, 3))


def _kabsch(A, B):
    """The slow obvious reference: SVD of the cross-covariance, reflection removed."""
    a0, b0 = A.mean(0), B.mean(0)
    U, _, Vt = np.linalg.svd((A - a0).T @ (B - b0))
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt))])
    R = U @ D @ Vt
    return R, a0 - R @ b0


def test_noiseless_points_give_the_transform_exactly():
    rng = np.random.default_rng(0)
    p_B = _points(rng)
    p_A = p_B @ X_TRUE[:3, :3].T + X_TRUE[:3, 3]
    fit = fit_rigid_transform(p_A, p_B)
    np.testing.assert_allclose(fit.X_AB, X_TRUE, atol=1e-12)
    R, t = _kabsch(p_A, p_B)
    np.testing.assert_allclose(fit.X_AB[:3, :3], R, atol=1e-12)
    np.testing.assert_allclose(fit.X_AB[:3, 3], t, atol=1e-12)
    assert fit.rms < 1e-12


def test_the_error_has_the_stated_covariance():
    rng = np.random.default_rng(1)
    sigma = 0.001
    p_B = _points(rng)
    clean = p_B @ X_TRUE[:3, :3].T + X_TRUE[:3, 3]
    d2 = []
    for _ in range(400):
        fit = fit_rigid_transform(clean + rng.normal(0.0, sigma, clean.shape), p_B, sigma=sigma)
        xi = se3.log(X_TRUE @ np.linalg.inv(fit.X_AB))  # X_true = exp(xi) X_est: the left perturbation
        d2.append(float(xi @ np.linalg.solve(fit.pose.cov, xi)))
    d2 = np.array(d2)
    assert abs(d2.mean() / 6.0 - 1.0) < 0.15  # chi-square, 6 dof: mean 6
    assert np.mean(d2 > stats.chi2.ppf(0.99, 6)) < 0.03
    # the error itself: within a few mm of the truth with 1 mm noise and 8 points
    assert np.linalg.norm(fit.X_AB[:3, 3] - X_TRUE[:3, 3]) < 0.005


def test_sigma_is_estimated_from_the_residuals():
    rng = np.random.default_rng(2)
    p_B = _points(rng, 40)
    p_A = p_B @ X_TRUE[:3, :3].T + X_TRUE[:3, 3] + rng.normal(0.0, 0.002, (40, 3))
    fit = fit_rigid_transform(p_A, p_B)
    assert 0.0015 < fit.sigma < 0.0025 and fit.n == 40


def test_collinear_or_malformed_points_are_refused():
    line = np.outer(np.linspace(0, 1, 5), [1.0, 2.0, 0.5])
    with pytest.raises(UncertaintyError, match="collinear"):
        fit_rigid_transform(line, line)
    with pytest.raises(UncertaintyError, match="N >= 3"):
        fit_rigid_transform(np.zeros((2, 3)), np.zeros((2, 3)))
    bad = np.eye(3)
    bad[0, 0] = np.nan
    with pytest.raises(UncertaintyError, match="finite"):
        fit_rigid_transform(bad, np.eye(3))


@pytest.mark.parametrize("n", [4, 12])
def test_an_estimated_sigma_widens_the_covariance_so_its_contours_hold(n):
    """With sigma estimated from the residuals of few points the covariance was overconfident: 11.6 % of
    4-point fits fell beyond its chi-square(6) 99 % contour.  Widened by Student's correction at 99.9 % (the
    clearance checks' default confidence), about 0.1 % fall beyond that contour, and at most 1 % beyond the 99 % one."""
    rng = np.random.default_rng(11)
    p_B = _points(rng, n)
    clean = p_B @ X_TRUE[:3, :3].T + X_TRUE[:3, 3]
    d2 = []
    for _ in range(4000):
        fit = fit_rigid_transform(clean + rng.normal(0.0, 0.001, clean.shape), p_B)
        xi = se3.log(X_TRUE @ np.linalg.inv(fit.X_AB))
        d2.append(float(xi @ np.linalg.solve(fit.pose.cov, xi)))
    d2 = np.array(d2)
    assert np.mean(d2 > stats.chi2.ppf(0.999, 6)) <= 0.003  # 0.1 % expected: 4 of 4000 (12 is far in the tail)
    assert np.mean(d2 > stats.chi2.ppf(0.99, 6)) < 0.012
    assert np.median(d2) > 0.5  # not widened past all use: chi-square(6)'s median is 5.35
