"""The sensing procedure's glitch test (Smith & Cheeseman, Section 5.2 step 2, Section 6): sound
observations are rejected at the rate the confidence level says (binomial bounds over many
samples), a planted glitch is found at the non-central chi-square rate, and a glitch leaves the
expectation unmerged."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from armguard import UncertaintyError
from armguard.uncertainty import GlitchStatus, UncertainPose2, UncertainPose3, glitch_test, sense, se3

C_PRIOR = np.array([[4e-4, 1e-4, 2e-5], [1e-4, 2.5e-4, -1e-5], [2e-5, -1e-5, 3e-4]])  # m², m·rad, rad²
C_SENSOR = np.diag([1e-4, 2e-4, 1e-4])
ALPHA = 1e-6  # the bounds' own chance of failing a correct rule


def within_binomial(k, n, p):
    lo, hi = stats.binom.interval(1 - ALPHA, n, p)
    return lo <= k <= hi


def sound_observations(expected, n, rng):
    """The truth drawn from the prior, the sensor's reading from the truth (independent errors)."""
    truth = rng.multivariate_normal(expected.mean, expected.cov, size=n)
    return truth + rng.multivariate_normal(np.zeros(3), C_SENSOR, size=n)


@pytest.mark.parametrize("confidence", [0.9, 0.99])
def test_false_rejections_of_sound_observations_match_the_confidence(confidence):
    expected = UncertainPose2([2.0, 1.0, 3.1], C_PRIOR)  # near ±π: the angle must be wrapped
    n = 4000
    z = sound_observations(expected, n, np.random.default_rng(26))
    tests = [glitch_test(expected, UncertainPose2(zi, C_SENSOR), confidence) for zi in z]
    rejected = sum(t.status is GlitchStatus.GLITCH for t in tests)
    assert within_binomial(rejected, n, 1 - confidence), (rejected, n * (1 - confidence))
    assert all((t.status is GlitchStatus.GLITCH) == (t.p_value < 1 - confidence) for t in tests)
    assert tests[0].k2 == pytest.approx(stats.chi2.ppf(confidence, 3), rel=1e-12) and tests[0].dof == 3


def test_a_planted_glitch_is_detected_at_the_noncentral_chi2_rate():
    """The camera locked onto the wrong object (Section 5.2): every reading off by a fixed shift."""
    expected = UncertainPose2([2.0, 1.0, 0.2], C_PRIOR)
    shift = np.array([0.06, -0.03, 0.0])  # m, m, rad
    lam = shift @ np.linalg.solve(C_PRIOR + C_SENSOR, shift)  # non-centrality
    confidence, n = 0.99, 3000
    z = sound_observations(expected, n, np.random.default_rng(27)) + shift
    found = sum(glitch_test(expected, UncertainPose2(zi, C_SENSOR), confidence).status is GlitchStatus.GLITCH
                for zi in z)
    power = stats.ncx2.sf(stats.chi2.ppf(confidence, 3), 3, lam)
    assert 0.3 < power < 0.9  # a shift the rule finds only sometimes: the rate is informative
    assert within_binomial(found, n, power), (found, n * power)
    # a gross glitch: half a metre off with a few centimetres of error
    far = UncertainPose2(expected.mean + [0.5, 0.0, 0.0], C_SENSOR)
    out = sense(expected, far, confidence)
    assert out.status is GlitchStatus.GLITCH and out.test.p_value < 1e-12
    assert out.pose is expected  # not merged


def test_sense_merges_a_consistent_observation():
    expected = UncertainPose2([2.0, 1.0, math.pi - 0.01], C_PRIOR)
    seen = UncertainPose2([2.01, 0.99, -math.pi + 0.01], C_SENSOR)  # 0.02 rad away across ±π
    out = sense(expected, seen, 0.99)
    assert out.status is GlitchStatus.CONSISTENT
    assert abs(out.test.innovation[2] - 0.02) < 1e-12
    want = expected.merge(seen)
    np.testing.assert_allclose(out.pose.mean, want.mean)
    np.testing.assert_allclose(out.pose.cov, want.cov)
    nu = np.array([0.01, -0.01, 0.02])
    assert out.test.mahalanobis2 == pytest.approx(nu @ np.linalg.solve(C_PRIOR + C_SENSOR, nu), rel=1e-9)


def test_false_rejections_in_space():
    rng = np.random.default_rng(28)
    a = rng.normal(size=(6, 6)) * 0.01
    c_prior = a @ a.T + np.eye(6) * 1e-5
    c_sensor = np.diag([1e-4] * 3 + [5e-5] * 3)
    expected = UncertainPose3.from_exp_coords([0.5, 0.2, 0.3, 0.4, -0.2, 1.0], c_prior)
    n, confidence = 2000, 0.95
    rejected = 0
    for _ in range(n):
        xi_truth = rng.multivariate_normal(np.zeros(6), c_prior)
        xi_sensor = rng.multivariate_normal(np.zeros(6), c_sensor)
        t_obs = se3.exp(xi_sensor) @ se3.exp(xi_truth) @ expected.mean
        t = glitch_test(expected, UncertainPose3(t_obs, c_sensor), confidence)
        rejected += t.status is GlitchStatus.GLITCH
    assert t.dof == 6
    assert within_binomial(rejected, n, 1 - confidence), (rejected, n * (1 - confidence))


def test_glitch_test_refuses_bad_arguments():
    p2 = UncertainPose2([0, 0, 0], C_PRIOR)
    p3 = UncertainPose3.identity()
    for bad in (0.0, 1.0, -0.5, float("nan"), "0.9"):
        with pytest.raises(UncertaintyError, match="confidence"):
            glitch_test(p2, p2, bad)
    with pytest.raises(UncertaintyError, match="both be UncertainPose2 or both UncertainPose3"):
        glitch_test(p2, p3)
    exact = UncertainPose2([0, 0, 0], np.zeros((3, 3)))
    with pytest.raises(UncertaintyError, match="singular"):
        glitch_test(exact, exact)
