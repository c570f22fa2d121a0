"""armguard.uncertainty in the plane: Smith & Cheeseman's compounding, reversal, merging, network
reduction, confidence ellipses, region probabilities and polar sensors."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy import stats

import armguard
from armguard import ArmguardError, UncertaintyError
from armguard.uncertainty import (
    Box2,
    Polygon2,
    UncertainPose2,
    confidence_for_k2,
    ellipse,
    k2_for_confidence,
    polar_to_cartesian,
    probability_inside,
    reduce_network,
    se2,
)

ROOT = Path(__file__).resolve().parent.parent
PAPER = yaml.safe_load((ROOT / "reference" / "seeds" / "smith_cheeseman.yaml").read_text(encoding="utf-8"))
CONST = PAPER["constants"]
FD_STEP = 1e-6  # central differences: truncation ~ step², round-off ~ eps / step


def pose(x, y, th, cov=None, seed=0):
    if cov is None:
        a = np.random.default_rng(seed).normal(size=(3, 3)) * 0.05
        cov = a @ a.T
    return UncertainPose2([x, y, th], cov)


def numeric_jacobian(f, x):
    x = np.asarray(x, dtype=float)
    cols = []
    for i in range(x.size):
        e = np.zeros_like(x)
        e[i] = FD_STEP
        cols.append((f(x + e) - f(x - e)) / (2 * FD_STEP))
    return np.stack(cols, axis=1)


# --- compounding (Eqns. 1-3) ----------------------------------------------------------------


def test_compound_mean_is_the_frame_transform():
    x1, x2 = np.array([1.0, 2.0, 0.7]), np.array([0.5, -0.3, -1.1])
    c, s = math.cos(x1[2]), math.sin(x1[2])
    T1 = np.array([[c, -s, x1[0]], [s, c, x1[1]], [0, 0, 1]])
    c2, s2 = math.cos(x2[2]), math.sin(x2[2])
    T2 = np.array([[c2, -s2, x2[0]], [s2, c2, x2[1]], [0, 0, 1]])
    T3 = T1 @ T2
    x3 = se2.compound_mean(x1, x2)
    np.testing.assert_allclose(x3[:2], T3[:2, 2], atol=1e-15)
    assert math.isclose(math.atan2(T3[1, 0], T3[0, 0]), se2.wrap_angle(x3[2]), abs_tol=1e-15)


def test_compound_jacobians_match_finite_differences():
    x1, x2 = np.array([1.0, 2.0, 0.7]), np.array([0.5, -0.3, -1.1])
    j1, j2 = se2.compound_jacobians(x1, x2)
    np.testing.assert_allclose(j1, numeric_jacobian(lambda a: se2.compound_mean(a, x2), x1), atol=1e-8)
    np.testing.assert_allclose(j2, numeric_jacobian(lambda b: se2.compound_mean(x1, b), x2), atol=1e-8)


def test_compound_covariance_is_eqn3():
    a, b = pose(1, 2, 0.7, seed=1), pose(0.5, -0.3, -1.1, seed=2)
    j1, j2 = a.compound_jacobians(b)
    J = np.hstack((j1, j2))
    want = J @ np.block([[a.cov, np.zeros((3, 3))], [np.zeros((3, 3)), b.cov]]) @ J.T
    np.testing.assert_allclose(a.compound(b).cov, want, atol=1e-15)


def test_compound_dependent_relations_use_the_cross_covariance():
    a, b = pose(1, 0, 0.3, seed=3), pose(2, 1, -0.4, seed=4)
    joint = np.random.default_rng(5).normal(size=(6, 6)) * 0.05
    joint = joint @ joint.T
    a = UncertainPose2(a.mean, joint[:3, :3])
    b = UncertainPose2(b.mean, joint[3:, 3:])
    j1, j2 = a.compound_jacobians(b)
    J = np.hstack((j1, j2))
    np.testing.assert_allclose(a.compound(b, cross_cov=joint[:3, 3:]).cov, J @ joint @ J.T, atol=1e-15)
    with pytest.raises(UncertaintyError, match="joint covariance"):
        a.compound(b, cross_cov=np.eye(3))  # not PSD together with the diagonal blocks


def test_serial_variances_add_in_one_dimension():
    # Section 4.1: reduced to one dimension, "variances in series transformations simply add"
    a = UncertainPose2([1.0, 0, 0], np.diag([0.04, 0, 0]))
    b = UncertainPose2([2.0, 0, 0], np.diag([0.09, 0, 0]))
    assert math.isclose(a.compound(b).cov[0, 0], 0.04 + 0.09, rel_tol=1e-15)


# --- reversal (Eqn. 4) ----------------------------------------------------------------------


def test_reverse_jacobian_matches_finite_differences_and_inverts_the_frame():
    x = np.array([1.5, -0.5, 2.2])
    np.testing.assert_allclose(se2.reverse_jacobian(x), numeric_jacobian(se2.reverse_mean, x), atol=1e-8)
    back = se2.compound_mean(x, se2.reverse_mean(x))
    np.testing.assert_allclose(back, [0, 0, 0], atol=1e-15)


def test_reverse_covariance_is_j_c_jt():
    a = pose(1.5, -0.5, 2.2, seed=6)
    j = a.reverse_jacobian()
    np.testing.assert_allclose(a.reverse().cov, j @ a.cov @ j.T, atol=1e-15)


# --- merging (Eqns. 5-8) --------------------------------------------------------------------


def test_merge_reduces_to_eqn8_in_one_dimension():
    v1, v2, x1, x2 = 0.04, 0.01, 1.0, 1.2
    a = UncertainPose2([x1, 0, 0], np.diag([v1, 1, 1]))
    b = UncertainPose2([x2, 0, 0], np.diag([v2, 1, 1]))
    m = a.merge(b)
    assert math.isclose(m.cov[0, 0], v1 * v2 / (v1 + v2), rel_tol=1e-14)
    assert math.isclose(m.mean[0], (v2 * x1 + v1 * x2) / (v1 + v2), rel_tol=1e-14)


def test_merge_is_the_information_form():
    a, b = pose(1, 2, 0.3, seed=7), pose(1.1, 1.9, 0.35, seed=8)
    m = a.merge(b)
    info = np.linalg.inv(a.cov) + np.linalg.inv(b.cov)
    np.testing.assert_allclose(m.cov, np.linalg.inv(info), rtol=1e-9, atol=1e-15)
    want = np.linalg.solve(info, np.linalg.solve(a.cov, a.mean) + np.linalg.solve(b.cov, b.mean))
    np.testing.assert_allclose(m.mean, want, rtol=1e-9)


def test_merge_wraps_the_angle_innovation():
    a = UncertainPose2([0, 0, math.pi - 0.1], np.eye(3) * 0.01)
    b = UncertainPose2([0, 0, -math.pi + 0.1], np.eye(3) * 0.01)
    assert math.isclose(se2.wrap_angle(a.merge(b).mean[2]), math.pi, abs_tol=1e-12)


def test_merge_with_an_exact_estimate_keeps_it_and_singular_sums_raise():
    exact = UncertainPose2([1, 2, 0.3], np.zeros((3, 3)))
    rough = pose(1.5, 2.5, 0.1, seed=9)
    m = rough.merge(exact)
    np.testing.assert_allclose(m.mean, exact.mean, atol=1e-12)
    np.testing.assert_allclose(m.cov, 0.0, atol=1e-15)
    with pytest.raises(UncertaintyError, match="singular"):
        exact.merge(exact)


# --- networks (Section 4.1) -----------------------------------------------------------------


def test_reduce_network_series_parallel_and_reversed_sensor():
    # Fig. 1: W -A-> L1 -B-> L2 -C-> L3 -D-> L4, and a sensor S giving W relative to L4
    A, B, C, D = (pose(1, 0, math.pi / 2, np.diag([1e-4, 1e-4, 1e-4])) for _ in range(4))
    G = UncertainPose2.chain(A, B, C, D)
    S = UncertainPose2(G.reverse().mean + [0.01, -0.01, 0.005], np.diag([4e-4, 4e-4, 1e-4]))
    net = [("W", "L1", A), ("L1", "L2", B), ("L2", "L3", C), ("L3", "L4", D), ("L4", "W", S), ("L2", "X", A)]
    got = reduce_network(net, "W", "L4")
    want = G.merge(S.reverse())
    np.testing.assert_allclose(got.mean, want.mean, atol=1e-12)
    np.testing.assert_allclose(got.cov, want.cov, atol=1e-15)
    back = UncertainPose2.reduce(net, "L4", "W")  # merged pointing L4 -> W, as asked
    np.testing.assert_allclose(back.mean, S.merge(G.reverse()).mean, atol=1e-12)
    np.testing.assert_allclose(back.mean, got.reverse().mean, atol=1e-4)  # equal to first order only


def test_reduce_network_deletes_a_link_of_a_wheatstone_bridge_and_refuses_disconnected_frames():
    e = pose(1, 0, 0, np.eye(3) * 1e-3)
    bridge = [("s", "a", e), ("s", "b", e), ("a", "b", e), ("a", "t", e), ("b", "t", e)]
    with pytest.raises(UncertaintyError, match="Wheatstone"):
        reduce_network(bridge, "s", "t", irreducible="raise")
    # the paper's remedy, by default: the deletion with the least det C (here the bridge link)
    by_hand = reduce_network(bridge[:2] + bridge[3:], "s", "t", irreducible="raise")
    got = reduce_network(bridge, "s", "t")
    np.testing.assert_allclose(got.mean, by_hand.mean, atol=1e-15)
    np.testing.assert_allclose(got.cov, by_hand.cov, atol=1e-18)
    with pytest.raises(UncertaintyError, match="no chain"):
        reduce_network([("s", "a", e), ("t", "b", e)], "s", "t")
    with pytest.raises(UncertaintyError, match="not in the network"):
        reduce_network([("s", "a", e)], "s", "t")


# --- confidence (Appendix A) ----------------------------------------------------------------


@pytest.mark.parametrize("key", ["k2_50", "k2_90"])
def test_k2_constants_of_appendix_a(key):
    c = CONST[key]
    k2 = k2_for_confidence(c["confidence"], c["dim"])
    assert abs(k2 - c["value"]) <= 0.5 * 10.0 ** -c["decimals"]
    assert math.isclose(k2, stats.chi2.ppf(c["confidence"], c["dim"]), rel_tol=1e-12)
    assert math.isclose(confidence_for_k2(k2, c["dim"]), c["confidence"], rel_tol=1e-12)


@pytest.mark.parametrize("dim", [1, 2, 3, 4, 6])
def test_confidence_closed_forms_are_chi_square(dim):
    for k2 in (0.1, 1.0, 4.605, 11.3):
        assert math.isclose(confidence_for_k2(k2, dim), stats.chi2.cdf(k2, dim), rel_tol=1e-12)
        assert math.isclose(k2_for_confidence(stats.chi2.cdf(k2, dim), dim), k2, rel_tol=1e-9)


def test_ellipse_matches_the_quadratic_form_of_appendix_a():
    p = pose(1.0, 2.0, 0.3, np.array([[0.04, 0.015, 0.0], [0.015, 0.01, 0.0], [0.0, 0.0, 0.01]]))
    e = p.ellipse(CONST["k2_90"]["confidence"])
    inv = np.linalg.inv(p.cov[:2, :2])
    A, B, C = inv[0, 0], inv[0, 1], inv[1, 1]
    # Appendix A: major axis at ½ arctan(2B / (A - C)) (mod π/2: the formula gives an axis)
    axis = 0.5 * math.atan2(2 * B, A - C)
    assert math.isclose(math.tan(2 * e.angle), math.tan(2 * axis), rel_tol=1e-9)
    pts = e.points(64) - p.mean[:2]
    np.testing.assert_allclose(np.einsum("ij,jk,ik->i", pts, inv, pts), e.k2, rtol=1e-12)
    assert e.half_axes[0] >= e.half_axes[1]


def test_ellipse_of_an_exact_position_is_a_point():
    e = ellipse([1, 2], np.zeros((2, 2)), 0.5)
    np.testing.assert_allclose(e.half_axes, 0.0)
    assert e.contains([[1, 2]]).all()


# --- probability inside a region --------------------------------------------------------------


def test_probability_inside_box_matches_scipy():
    m, c = np.array([0.3, -0.2]), np.array([[0.5, 0.2], [0.2, 0.3]])
    box = Box2([-0.4, -1.0], [1.2, 0.5])
    want = stats.multivariate_normal(m, c).cdf(box.upper, lower_limit=box.lower)
    assert math.isclose(probability_inside(m, c, box), want, abs_tol=1e-6)  # scipy's CDF: abseps 1e-5


def test_probability_inside_nonconvex_polygon_either_orientation_and_ellipse():
    m, c = np.array([0.0, 0.0]), np.array([[0.2, 0.05], [0.05, 0.1]])
    L = Polygon2([[-1, -1], [1, -1], [1, 1], [0.2, 1], [0.2, -0.2], [-1, -0.2]])  # an L, mean on an edge
    p_ccw = probability_inside(m, c, L)
    p_cw = probability_inside(m, c, Polygon2(L.vertices[::-1]))
    assert math.isclose(p_ccw, p_cw, abs_tol=1e-12)
    # oracle: sum of boxes (the L is two rectangles)
    mvn = stats.multivariate_normal(m, c)
    want = mvn.cdf([1, -0.2], lower_limit=[-1, -1]) + mvn.cdf([1, 1], lower_limit=[0.2, -0.2])
    assert math.isclose(p_ccw, want, abs_tol=1e-6)
    # the confidence ellipse as a fine polygon holds its confidence
    for key in ("k2_50", "k2_90"):
        conf = CONST[key]["confidence"]
        e = ellipse(m, c, conf)
        poly = Polygon2(e.points(4000))
        assert math.isclose(probability_inside(m, c, poly), conf, abs_tol=1e-5)  # polygon inscribed in the ellipse


def test_probability_inside_exact_and_degenerate_positions():
    box = Box2([0, 0], [1, 1])
    assert probability_inside([0.5, 0.5], np.zeros((2, 2)), box) == 1.0
    assert probability_inside([1.5, 0.5], np.zeros((2, 2)), box) == 0.0
    with pytest.raises(UncertaintyError, match="singular"):
        probability_inside([0.5, 0.5], np.diag([0.1, 0.0]), box)
    assert math.isclose(pose(0.5, 0.5, 0, np.diag([0.01, 0.01, 1.0])).probability_inside(box),
                        (stats.norm.cdf(5) - stats.norm.cdf(-5)) ** 2, abs_tol=1e-9)


# --- polar sensor (Appendix B) --------------------------------------------------------------


def test_polar_to_cartesian_mean_jacobian_and_covariance():
    p, c = np.array([2.0, 0.6, 0.1]), np.diag([0.01, 0.001, 0.002])
    x, cx, R = polar_to_cartesian(p, c)
    np.testing.assert_allclose(x, [2 * math.cos(0.6), 2 * math.sin(0.6), 0.1], atol=1e-15)
    f = lambda q: np.array([q[0] * math.cos(q[1]), q[0] * math.sin(q[1]), q[2]])  # noqa: E731
    np.testing.assert_allclose(R, numeric_jacobian(f, p), atol=1e-8)
    # the paper's form of R: [[x/r, -y, 0], [y/r, x, 0], [0, 0, 1]]
    np.testing.assert_allclose(R, [[x[0] / 2, -x[1], 0], [x[1] / 2, x[0], 0], [0, 0, 1]], atol=1e-15)
    np.testing.assert_allclose(cx, R @ c @ R.T, atol=1e-15)
    np.testing.assert_allclose(UncertainPose2.from_polar(p, c).cov, cx)
    with pytest.raises(UncertaintyError, match="range"):
        polar_to_cartesian([-1.0, 0, 0], c)


# --- validation ---------------------------------------------------------------------------


def test_uncertainty_error_is_an_armguard_value_error():
    assert issubclass(UncertaintyError, ArmguardError) and issubclass(UncertaintyError, ValueError)
    assert armguard.UncertaintyError is UncertaintyError and "UncertaintyError" in armguard.__all__


@pytest.mark.parametrize(
    "mean,cov,match",
    [
        ([0, 0, np.nan], np.eye(3), "NaN"),
        ([0, 0], np.eye(3), "shape"),
        ([0, 0, 0], np.eye(2), "shape"),
        ([0, 0, 0], np.full((3, 3), np.inf), "NaN"),
        ([0, 0, 0], [[1, 0.5, 0], [0, 1, 0], [0, 0, 1]], "symmetric"),
        ([0, 0, 0], np.diag([1.0, -0.1, 1.0]), "semi-definite"),
        ("abc", np.eye(3), "numeric"),
    ],
)
def test_invalid_relations_raise(mean, cov, match):
    with pytest.raises(UncertaintyError, match=match):
        UncertainPose2(mean, cov)


@pytest.mark.parametrize(
    "cov,match",
    [
        # an angle variance below zero beside large position variances (m² and rad² in one matrix):
        # a tolerance relative to the largest entry accepted it, and a merge then moved the angle
        # away from both estimates
        (np.diag([100.0, 100.0, -5e-8]), "variance is negative"),
        (np.diag([1.0, 1.0, -5e-10]), "variance is negative"),
        # a covariance between x and the angle given with two signs: symmetrising set it to 0
        ([[100.0, 0.0, 4e-8], [0.0, 100.0, 0.0], [-4e-8, 0.0, 1e-7]], "symmetric"),
        # a correlation of 1.26 between a large and a small variance
        ([[100.0, 0.0, 0.004], [0.0, 100.0, 0.0], [0.004, 0.0, 1e-7]], "semi-definite"),
    ],
)
def test_covariance_checks_hold_each_entry_in_its_own_units(cov, match):
    with pytest.raises(UncertaintyError, match=match):
        UncertainPose2([0, 0, 0], cov)


def test_a_merge_with_small_angle_variances_stays_between_its_estimates():
    p = UncertainPose2([0, 0, 0], np.diag([100.0, 100.0, 5e-8]))
    q = UncertainPose2([0, 0, 1e-3], np.diag([1.0, 1.0, 1e-7]))
    m = p.merge(q)
    assert 0.0 < m.mean[2] < 1e-3 and m.cov[2, 2] > 0.0


def test_a_singular_covariance_with_round_off_is_accepted_as_given():
    u = np.array([1.0, 2.0, 3.0]) / math.sqrt(14.0)
    c = 0.01 * np.outer(u, u)  # rank one: two eigenvalues zero, to round-off either side
    c[0, 0] -= 1e-19
    np.testing.assert_array_equal(UncertainPose2([0, 0, 0], c).cov, c)
    c[0, 0] = -1e-15  # beyond round-off of 0.01: a negative variance
    with pytest.raises(UncertaintyError, match="variance is negative"):
        UncertainPose2([0, 0, 0], c)


def test_round_off_asymmetry_is_accepted_and_removed():
    c = np.array([[1.0, 0.3, 0.0], [0.3 + 1e-12, 1.0, 0.0], [0.0, 0.0, 1.0]])
    p = UncertainPose2([0, 0, 0], c)
    np.testing.assert_array_equal(p.cov, p.cov.T)
    assert armguard.DEFAULT_TOLERANCES.covariance_relative * 1.0 > 1e-12


def test_results_are_read_only():
    p = pose(1, 2, 3)
    with pytest.raises(ValueError):
        p.mean[0] = 5.0


def test_mahalanobis2_of_a_direction_known_exactly_is_infinite():
    """A singular covariance knows a direction exactly: an observation off the mean along it is
    impossible (inf), where the pseudo-inverse called it a perfect fit (0.0); along the known
    directions, and for a regular covariance, the distance is d^T C^-1 d."""
    p = UncertainPose2([0.0, 0.0, 0.0], np.diag([1e-4, 0.0, 1e-4]))
    assert p.mahalanobis2([0.0, 1.0, 0.0]) == np.inf
    assert p.mahalanobis2([0.01, 0.0, 0.0]) == pytest.approx(1.0, rel=1e-12)
    assert p.mahalanobis2([0.0, 0.0, 0.0]) == 0.0
    assert UncertainPose2([0.0, 0.0, 0.0], np.zeros((3, 3))).mahalanobis2([1.0, 0.0, 0.0]) == np.inf
    C = np.array([[2.0, 0.5, 0.1], [0.5, 1.0, 0.2], [0.1, 0.2, 0.5]]) * 1e-3
    q = UncertainPose2([1.0, 2.0, 0.3], C)
    x = np.array([1.02, 1.97, 0.35])
    d = x - q.mean
    assert q.mahalanobis2(x) == pytest.approx(d @ np.linalg.solve(C, d), rel=1e-12)


def test_an_overflowing_relation_is_refused_where_it_is_made():
    """Exponential coordinates of 1e300 m gave a pose of NaNs (found later by a LinAlgError); a mean or
    covariance near 1e308 overflowed in the symmetry test."""
    from armguard.uncertainty import UncertainPose3

    with pytest.raises(UncertaintyError, match=r"xi: .* beyond 1e\+09"):
        UncertainPose3.from_exp_coords([0, 0, 0, 1e300, 0, 0], np.eye(6) * 1e-4)
    with pytest.raises(UncertaintyError, match="beyond"):
        UncertainPose2([1e308, 0.0, 0.0], np.eye(3) * 1e-4)
    with pytest.raises(UncertaintyError, match="beyond"):
        UncertainPose2([0.0, 0.0, 0.0], 1e308 * np.eye(3))


def test_operations_refuse_a_relation_of_another_kind():
    """A 2-D pose compounded with a 3-D one, a list or None, and sample's bad arguments, were raw
    TypeError / ValueError / AttributeError from numpy."""
    from armguard.uncertainty import UncertainPose3

    a = UncertainPose2([1.0, 2.0, 0.3], np.eye(3) * 1e-3)
    for call in (lambda: a.compound(UncertainPose3.identity()), lambda: a.compound([1, 2, 3]), lambda: a.merge(None),
                 lambda: UncertainPose3.identity().merge(a), lambda: UncertainPose3.chain(a),
                 lambda: UncertainPose2.chain(a, 5), lambda: UncertainPose2.chain(5, a)):
        with pytest.raises(UncertaintyError, match="expected another UncertainPose"):
            call()
    with pytest.raises(UncertaintyError, match="rng: expected a numpy Generator"):
        a.sample(3, None)
    with pytest.raises(UncertaintyError, match="n: expected an integer >= 0"):
        a.sample(-1, np.random.default_rng(0))
    assert UncertainPose2.chain(a) == a or np.array_equal(UncertainPose2.chain(a).mean, a.mean)


def test_messages_say_what_is_wrong():
    """A NaN cross-covariance said "expected a finite (3, 3) array, got shape (3, 3)"; a reflection passed
    as a rotation said "max |R^T R - I| = 0"."""
    from armguard.uncertainty import UncertainPose3

    a = UncertainPose2([1.0, 2.0, 0.3], np.eye(3) * 1e-3)
    with pytest.raises(UncertaintyError, match="cross_cov: contains NaN or infinity"):
        a.compound(a, cross_cov=np.full((3, 3), np.nan))
    with pytest.raises(UncertaintyError, match="rotation block is a reflection"):
        UncertainPose3(np.diag([1.0, 1.0, -1.0, 1.0]), np.eye(6) * 1e-4)


def test_confidence_helpers_refuse_what_is_no_number():
    from armguard.uncertainty import confidence_for_k2, k2_for_confidence

    assert k2_for_confidence(0.9, dim=2.0) == k2_for_confidence(0.9, 2)
    for call, said in ((lambda: k2_for_confidence(0.9, dim=float("nan")), "dim: expected an integer >= 1"),
                       (lambda: k2_for_confidence(0.9, dim="2"), "dim: expected an integer >= 1"),
                       (lambda: confidence_for_k2("x"), "k2: expected a finite number >= 0"),
                       (lambda: k2_for_confidence("abc"), r"confidence: expected a finite number in \(0, 1\)")):
        with pytest.raises(UncertaintyError, match=said):
            call()
