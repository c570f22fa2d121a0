"""Grasp error from a wrist force/torque sensor (armguard.program._grasp): exact on noiseless emulated
wrenches; on noisy ones the centre-of-mass error has the stated covariance (Monte Carlo, chi-square
with 3 dof) and shrinks with more orientations; a symmetric object's hidden turn is named, not made up."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats
from scipy.spatial.transform import Rotation

from armguard import UncertaintyError
from armguard.program import grasp_orientation, object_wrench, weigh

MASS = 1.2
P_TRUE = np.array([0.02, -0.015, 0.135])
R_TRUE = Rotation.from_rotvec(np.radians(10.0) * np.array([0.6, 0.8, 0.0])).as_matrix()
I_BOX = np.diag([0.004, 0.006, 0.009])
B_F, B_TAU = np.array([0.3, -0.2, 0.5]), np.array([0.02, 0.01, -0.03])


def _emulate(rng, n, I_O, sigma_f=0.0, sigma_tau=0.0, rotations=12):
    I_C_S = R_TRUE @ I_O @ R_TRUE.T
    R = Rotation.random(n, random_state=rng).as_matrix()
    f, tau = object_wrench(R, MASS, P_TRUE, I_C_S, b_f=B_F, b_tau=B_TAU)
    w8 = weigh(R, f + rng.normal(0, sigma_f, f.shape) if sigma_f else f,
               tau + rng.normal(0, sigma_tau, tau.shape) if sigma_tau else tau,
               sigma_f=sigma_f or None, sigma_tau=sigma_tau or None)
    R2 = Rotation.random(rotations, random_state=rng).as_matrix()
    w, a = rng.normal(0, 2.0, (rotations, 3)), rng.normal(0, 20.0, (rotations, 3))
    _, tau2 = object_wrench(R2, MASS, P_TRUE, I_C_S, w_S=w, a_S=a, b_f=B_F, b_tau=B_TAU)
    if sigma_tau:
        tau2 = tau2 + rng.normal(0, sigma_tau, tau2.shape)
    return w8, grasp_orientation(w8, R2, w, a, tau2, I_O, np.eye(3))


def test_noiseless_wrenches_give_the_grasp_exactly():
    w8, go = _emulate(np.random.default_rng(0), 5, I_BOX)
    assert w8.mass == pytest.approx(MASS, abs=1e-12)
    np.testing.assert_allclose(w8.p_SC, P_TRUE, atol=1e-12)
    np.testing.assert_allclose(w8.b_f, B_F, atol=1e-12)
    np.testing.assert_allclose(w8.b_tau, B_TAU, atol=1e-12)
    np.testing.assert_allclose(w8.offset([0, 0, 0.12]), P_TRUE - [0, 0, 0.12], atol=1e-12)
    np.testing.assert_allclose(go.R_SO, R_TRUE, atol=1e-9)
    np.testing.assert_allclose(go.error, Rotation.from_matrix(R_TRUE).as_rotvec(), atol=1e-9)
    assert go.unobservable is None


def test_the_centre_of_mass_error_has_the_stated_covariance():
    """400 noisy weighings (8 orientations): the Mahalanobis distances of p_SC's error follow chi-square(3)."""
    rng = np.random.default_rng(1)
    d2 = []
    for _ in range(400):
        R = Rotation.random(8, random_state=rng).as_matrix()
        f, tau = object_wrench(R, MASS, P_TRUE, I_BOX, b_f=B_F, b_tau=B_TAU)
        w8 = weigh(R, f + rng.normal(0, 0.2, f.shape), tau + rng.normal(0, 0.02, tau.shape), sigma_f=0.2, sigma_tau=0.02)
        e = w8.p_SC - P_TRUE
        d2.append(float(e @ np.linalg.solve(w8.cov_p_SC, e)))
    assert np.mean(d2) == pytest.approx(3.0, rel=0.15)
    assert stats.kstest(d2, "chi2", args=(3,)).pvalue > 0.01


def test_more_orientations_and_less_noise_give_smaller_errors():
    def median_error(n, sf, st):
        rng = np.random.default_rng(2)
        return np.median([np.linalg.norm(_emulate(rng, n, I_BOX, sf, st)[0].p_SC - P_TRUE) for _ in range(60)])

    assert median_error(32, 0.2, 0.02) < 0.7 * median_error(4, 0.2, 0.02)
    assert median_error(8, 0.05, 0.005) < 0.5 * median_error(8, 0.2, 0.02)


def test_the_orientation_is_found_within_its_noise():
    rng = np.random.default_rng(3)
    errs = [np.linalg.norm(Rotation.from_matrix(_emulate(rng, 8, I_BOX, 0.05, 0.005, rotations=40)[1].R_SO @ R_TRUE.T)
                           .as_rotvec()) for _ in range(20)]
    assert np.degrees(np.median(errs)) < 3.0  # the turn itself is 10 degrees


def test_a_symmetric_object_names_the_turn_it_cannot_see():
    """A cylinder (I_xx = I_yy): its axis's tilt is found exactly, a turn about the axis is not invented."""
    I_cyl = np.diag([0.006, 0.006, 0.002])
    w8, go = _emulate(np.random.default_rng(4), 6, I_cyl)
    axis_true = R_TRUE @ [0.0, 0.0, 1.0]
    np.testing.assert_allclose(go.unobservable, axis_true, atol=1e-9)
    np.testing.assert_allclose(go.R_SO @ [0.0, 0.0, 1.0], axis_true, atol=1e-9)
    assert abs(go.error @ axis_true) < 1e-9  # no turn about the axis itself


@pytest.mark.parametrize("n, axis_only", [(2, False), (6, True)])
def test_orientations_that_cannot_show_the_centre_of_mass_are_refused(n, axis_only):
    rng = np.random.default_rng(5)
    R = (Rotation.from_rotvec(np.outer(rng.uniform(-3, 3, n), [0, 0, 1])) if axis_only else
         Rotation.random(n, random_state=rng)).as_matrix()
    f, tau = object_wrench(R, MASS, P_TRUE, I_BOX)
    with pytest.raises(UncertaintyError, match="unobservable"):
        weigh(R, f, tau)


def test_a_nan_wrench_is_refused():
    R = Rotation.random(5, random_state=np.random.default_rng(6)).as_matrix()
    f, tau = object_wrench(R, MASS, P_TRUE, I_BOX)
    f[2, 1] = np.nan
    with pytest.raises(UncertaintyError, match="f_S"):
        weigh(R, f, tau)


def test_a_reflection_is_refused_as_a_rotation():
    """R R^T = E holds for a reflection too: the orientations were accepted with det -1."""
    R = Rotation.random(5, random_state=np.random.default_rng(6)).as_matrix()
    f, tau = object_wrench(R, MASS, P_TRUE, I_BOX)
    R[3] = R[3] @ np.diag([1.0, 1.0, -1.0])
    with pytest.raises(UncertaintyError, match=r"R_WS\[3\].*reflection"):
        weigh(R, f, tau)


def test_the_example_table_runs():
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "examples"))
    try:
        import grasp_error
    finally:
        sys.path.pop(0)
    text = grasp_error.table(noise=((0.05, 0.005),), poses=(4, 16), trials=10)
    assert text.count("mm") == 2 and "N = 16" in text


def test_weigh_refuses_a_noise_that_is_no_positive_number_and_no_data():
    """sigma_f=-1 was accepted (a covariance from a negative noise); no orientations raised numpy's
    zero-size error."""
    R = np.tile(np.eye(3), (3, 1, 1))
    for kw in (dict(sigma_f=-1.0), dict(sigma_tau="x"), dict(sigma_f=np.nan)):
        with pytest.raises(UncertaintyError, match="expected the sensor's noise"):
            weigh(R, np.zeros((3, 3)), np.zeros((3, 3)), **kw)
    with pytest.raises(UncertaintyError, match=r"R_WS: expected \(n, 3, 3\)"):
        weigh(np.zeros((0, 3, 3)), np.zeros((0, 3)), np.zeros((0, 3)))
