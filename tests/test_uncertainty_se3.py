"""armguard.uncertainty on SE(3): exponential coordinates, adjoint propagation, and pytransform3d's
uncertainty module as the oracle (its covariances are (ω, v), ours (ρ, φ): mapped by a block swap)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from armguard import UncertaintyError
from armguard.uncertainty import UncertainPose3, agreement, monte_carlo_chain3, se3

pt = pytest.importorskip("pytransform3d.transformations")
pu = pytest.importorskip("pytransform3d.uncertainty")


def random_pose(rng, sd_rho=0.01, sd_phi=0.01, angle=None):
    xi = np.concatenate((rng.uniform(-1, 1, 3), rng.normal(size=3)))
    if angle is not None:
        xi[3:] *= angle / np.linalg.norm(xi[3:])
    s = np.diag([sd_rho] * 3 + [sd_phi] * 3)
    a = rng.normal(size=(6, 6)) / math.sqrt(12.0)
    cov = s @ (a @ a.T + 0.5 * np.eye(6)) @ s
    return UncertainPose3.from_exp_coords(xi, cov)


@pytest.mark.parametrize("theta", [1e-7, 9.9e-6, 1.01e-5, 2e-5, 1e-4, 9.99e-4, 1.001e-3, 0.5, 3.0])
def test_exp_and_log_are_accurate_at_every_angle(theta):
    """Against scipy's matrix exponential of the twist, and log(exp(xi)) == xi, to round-off: just
    above the series' switch, 1 - cos θ cancelled (log(exp(xi)) was off by 1e-6 m per metre at
    θ = 1.01e-5 rad)."""
    from scipy.linalg import expm

    rng = np.random.default_rng(7)
    for _ in range(20):
        axis = rng.normal(size=3)
        rho, phi = rng.normal(size=3), theta * axis / np.linalg.norm(axis)
        twist = np.zeros((4, 4))
        twist[:3, :3] = [[0, -phi[2], phi[1]], [phi[2], 0, -phi[0]], [-phi[1], phi[0], 0]]
        twist[:3, 3] = rho
        xi = np.r_[rho, phi]
        np.testing.assert_allclose(se3.exp(xi), expm(twist), rtol=0, atol=1e-14)
        np.testing.assert_allclose(se3.log(se3.exp(xi)), xi, rtol=0, atol=1e-14)


def test_exp_log_round_trip_and_pytransform3d_agree():
    rng = np.random.default_rng(0)
    for angle in (0.0, 1e-7, 0.3, 2.0, math.pi - 1e-4):
        xi = np.concatenate((rng.normal(size=3), rng.normal(size=3)))
        n = np.linalg.norm(xi[3:])
        xi[3:] = xi[3:] / n * angle
        T = se3.exp(xi)
        # pytransform3d: exponential coordinates (ω θ, v θ), rotation first
        Tp = pt.transform_from_exponential_coordinates(np.concatenate((xi[3:], xi[:3])))
        np.testing.assert_allclose(T, Tp, atol=1e-12)
        np.testing.assert_allclose(se3.log(T), xi, atol=1e-9)


def test_adjoint_conjugates_twists():
    rng = np.random.default_rng(1)
    T = random_pose(rng).mean
    xi = rng.normal(size=6) * 0.1
    np.testing.assert_allclose(T @ se3.exp(xi) @ se3.invert_transform(T), se3.exp(se3.adjoint(T) @ xi), atol=1e-12)
    # the same block swap P A P^T that maps covariances maps the adjoint
    np.testing.assert_allclose(se3.to_pytransform3d_cov(se3.adjoint(T)), pt.adjoint_from_transform(T), atol=1e-15)


def test_compound_matches_pytransform3d_to_its_fourth_order_terms():
    rng = np.random.default_rng(2)
    for sd in (1e-3, 1e-2):
        a, b = random_pose(rng, sd, sd), random_pose(rng, sd, sd)
        c = a.compound(b)
        ta, ca = a.to_pytransform3d()
        tb, cb = b.to_pytransform3d()
        # ours: T_AC = T_AB T_BC; theirs: B2C left-multiplied onto A2B -> pass (T_BC, T_AB)
        tm, cm = pu.concat_globally_uncertain_transforms(tb, cb, ta, ca)
        np.testing.assert_allclose(c.mean, tm, atol=1e-12)
        # identical second-order part; theirs adds Barfoot & Furgale's fourth-order terms,
        # relatively O(sd²) smaller
        rel = np.max(np.abs(se3.to_pytransform3d_cov(c.cov) - cm)) / np.max(np.abs(cm))
        assert rel < 10 * sd**2


def test_inverse_matches_pytransform3d_exactly():
    rng = np.random.default_rng(3)
    a = random_pose(rng, 0.05, 0.05)
    inv = a.inverse()
    tm, cm = pu.invert_uncertain_transform(*a.to_pytransform3d())
    np.testing.assert_allclose(inv.mean, tm, atol=1e-12)
    np.testing.assert_allclose(se3.to_pytransform3d_cov(inv.cov), cm, atol=1e-15)
    back = UncertainPose3.from_pytransform3d(tm, cm)
    np.testing.assert_allclose(back.cov, inv.cov, atol=1e-15)
    np.testing.assert_allclose(inv.inverse().mean, a.mean, atol=1e-12)
    np.testing.assert_allclose(inv.inverse().cov, a.cov, atol=1e-15)


def test_merge_matches_pytransform3d_pose_fusion_for_close_estimates():
    rng = np.random.default_rng(4)
    a = random_pose(rng, 0.02, 0.02)
    b = UncertainPose3(se3.exp(rng.normal(size=6) * 1e-3) @ a.mean, random_pose(rng, 0.03, 0.01).cov)
    m = a.merge(b)
    fm, fc, _ = pu.pose_fusion([a.mean, b.mean], [se3.to_pytransform3d_cov(a.cov), se3.to_pytransform3d_cov(b.cov)])
    np.testing.assert_allclose(m.mean, fm, atol=1e-6)  # first order in the 1e-3 innovation
    np.testing.assert_allclose(se3.to_pytransform3d_cov(m.cov), fc, atol=1e-2 * np.max(np.abs(fc)))
    np.testing.assert_allclose(b.merge(a).mean, m.mean, atol=1e-6)


def test_no_poles_at_the_euler_singularity():
    # pitch of 90° is the Z-Y-X Euler pole; exponential coordinates propagate through it unchanged
    rng = np.random.default_rng(5)
    pole = UncertainPose3.from_exp_coords([0.5, 0, 0, 0, math.pi / 2, 0], np.diag([1e-4] * 3 + [1e-4] * 3))
    after = UncertainPose3.from_exp_coords([1.0, 0.2, 0, 0.1, 0, 0.3], np.diag([1e-4] * 3 + [1e-4] * 3))
    chain = [pole, after]
    lin = UncertainPose3.chain(*chain)
    mc = monte_carlo_chain3(chain, 20_000, rng, moment_match=True)
    a = agreement(np.zeros(6), lin.cov, mc, position=slice(0, 3), angle_index=())
    assert a.cov < 0.01 and np.all(np.isfinite(lin.cov))


def test_invalid_transforms_raise():
    with pytest.raises(UncertaintyError, match="rotation"):
        UncertainPose3(np.diag([1.0, 1.0, 2.0, 1.0]), np.eye(6))
    with pytest.raises(UncertaintyError, match="last row"):
        UncertainPose3(np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 1, 1.0]]), np.eye(6))
    with pytest.raises(UncertaintyError, match="NaN"):
        UncertainPose3(np.full((4, 4), np.nan), np.eye(6))
    with pytest.raises(UncertaintyError, match="semi-definite"):
        UncertainPose3(np.eye(4), -np.eye(6))
    with pytest.raises(UncertaintyError, match="singular"):
        UncertainPose3.identity().merge(UncertainPose3.identity())


def test_monte_carlo_chain3_refuses_a_reference_that_is_no_rigid_transform():
    chain = [UncertainPose3(np.eye(4), np.diag([1e-4] * 3 + [1e-5] * 3))]
    with pytest.raises(UncertaintyError, match="reference"):  # made rigid inside the logarithm, unseen
        monte_carlo_chain3(chain, 100, np.random.default_rng(0), reference=np.diag([2.0, 2.0, 2.0, 1.0]))
    monte_carlo_chain3(chain, 100, np.random.default_rng(0), reference=np.eye(4))
