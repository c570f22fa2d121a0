"""verify_with_confidence's radii: one per placement, k_i^2 = chi2_{r_i}.ppf(confidence^(1/n)), so that
every placement stays within its radius with probability >= confidence whatever the placements'
correlation (the Gaussian correlation inequality) -- held to Monte Carlo draws, independent and
through one shared error (two objects found by one camera whose pose is uncertain)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

import armguard
from armguard.uncertainty import UncertainPlacement, UncertainPose3, verify_with_confidence

CONFIDENCE = 0.99


def _pose(xyz, cov):
    T = np.eye(4)
    T[:3, 3] = xyz
    return UncertainPose3(T, cov)


def _mahalanobis(xi, cov):
    return np.sqrt(np.einsum("ij,ij->i", xi, np.linalg.solve(cov, xi.T).T))


def test_each_placement_gets_the_radius_of_its_own_rank_and_the_split_confidence():
    scene = armguard.load_scene("puma560")
    traj = scene.trajectories["pick_and_place"]
    cov3 = np.diag([1e-6, 1e-6, 1e-6, 0.0, 0.0, 0.0])
    cov6 = np.diag([1e-6, 1e-6, 1e-6, 1e-5, 1e-5, 1e-5])
    places = [UncertainPlacement("cylinder_a", _pose((0.55, 0.15, 0.6), cov3)),
              UncertainPlacement("cylinder_b", _pose((0.55, -0.15, 0.6), cov6))]
    out = verify_with_confidence(scene, traj, places, CONFIDENCE)
    each = CONFIDENCE ** 0.5
    assert out.radii["cylinder_a"] == pytest.approx(math.sqrt(stats.chi2.ppf(each, 3)), rel=1e-12)
    assert out.radii["cylinder_b"] == pytest.approx(math.sqrt(stats.chi2.ppf(each, 6)), rel=1e-12)
    assert out.k == max(out.radii.values()) and out.dof == 9
    for p in places:
        assert out.growth[p.name] == pytest.approx(out.radii[p.name] * p.sigma_max(scene.bodies[p.name].shapes), rel=1e-12)
    # narrower than one radius of the summed rank for all (the former rule, valid but wider)
    assert out.k < math.sqrt(stats.chi2.ppf(CONFIDENCE, 9))
    alone = verify_with_confidence(scene, traj, places[:1], CONFIDENCE)
    assert alone.radii["cylinder_a"] == pytest.approx(math.sqrt(stats.chi2.ppf(CONFIDENCE, 3)), rel=1e-12)


@pytest.mark.parametrize("shared", [0.0, 0.6, 1.0])
def test_every_placement_stays_within_its_radius_with_the_confidence_asked(shared):
    """Two 3-dof placements whose displacements share a fraction ``shared`` of one common error (a
    camera's): the share of draws with both within their radii is at least the confidence (exactly
    it when independent: the split is tight), 200000 draws, 4 standard errors."""
    rng = np.random.default_rng(7)
    n = 200_000
    C = np.diag([4e-6, 1e-6, 9e-6])
    common = rng.multivariate_normal(np.zeros(3), C, n)
    xi = [math.sqrt(shared) * common + math.sqrt(1.0 - shared) * rng.multivariate_normal(np.zeros(3), C, n)
          for _ in range(2)]
    cov6 = np.zeros((6, 6))
    cov6[:3, :3] = C
    scene = armguard.load_scene("puma560")
    places = [UncertainPlacement(b, _pose(xyz, cov6)) for b, xyz in (("cylinder_a", (0.55, 0.15, 0.6)),
                                                                        ("cylinder_b", (0.55, -0.15, 0.6)))]
    radii = verify_with_confidence(scene, scene.trajectories["pick_and_place"], places, CONFIDENCE).radii
    inside = (_mahalanobis(xi[0], C) <= radii["cylinder_a"]) & (_mahalanobis(xi[1], C) <= radii["cylinder_b"])
    se = math.sqrt(CONFIDENCE * (1 - CONFIDENCE) / n)
    assert inside.mean() >= CONFIDENCE - 4 * se
    if shared == 0.0:
        assert inside.mean() <= CONFIDENCE + 4 * se


def test_a_body_added_by_another_thread_meanwhile_is_never_checked_ungrown(monkeypatch):
    """An edit of the scene while verify_with_confidence reads it (simulated: at its first sigma_max) was
    in the grown copy without growth (a body the check saw at its own size)."""
    from armguard.geometry import Sphere

    scene = armguard.load_scene("puma560")
    traj = scene.trajectories["pick_and_place"]
    place = UncertainPlacement("cylinder_a", _pose((0.55, 0.15, 0.6), np.diag([1e-6] * 3 + [1e-5] * 3)))
    sigma_max = UncertainPlacement.sigma_max

    def edited(self, shapes):
        if "late_ball" not in scene.bodies:
            scene.add_body("late_ball", Sphere((0.55, 0.15, 0.9), 0.05))
        return sigma_max(self, shapes)

    monkeypatch.setattr(UncertainPlacement, "sigma_max", edited)
    out = verify_with_confidence(scene, traj, [place], CONFIDENCE)
    # the check is of the scene as the call found it: the body added meanwhile is in neither its growth nor its copy
    assert "late_ball" in scene.bodies and "late_ball" not in out.scene.bodies and "late_ball" not in out.growth
