"""Uncertain placements in the checks: sigmas against Monte Carlo, the conservative bound, and
verification at a confidence (``armguard.uncertainty._checks``)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

import armguard
from armguard._errors import UncertaintyError
from armguard.geometry import Box, Capsule, ConvexPolyhedron, Cylinder, Polygon, Prism, Sphere, distance
from armguard.uncertainty import (
    ClearanceStatus,
    UncertainPlacement,
    UncertainPose2,
    UncertainPose3,
    clearance_sigmas,
    grow_shape,
    verify_with_confidence,
)

SIGMA_RTOL = 0.05
"""The linearised sigma against the standard deviation of 4000 seeded Monte Carlo distances:
the sampling error of a standard deviation is about 1/sqrt(2n) = 1.1 %, the linearisation's
(a sphere beside a box face, rotations of a fraction of a degree) far below it."""

BALL = np.array([0.923, -0.15, 0.8865])  # 5 cm beside the PUMA's tool box at home


def _ball_scene(radius=0.03):
    scene = armguard.load_scene("puma560")
    for b in list(scene.bodies):
        scene.remove_body(b)
    scene.add_body("ball", Sphere(BALL, radius))
    return scene


def _pose3(sd_t, sd_r_deg, origin=(0.0, 0.0, 0.0)):
    T = np.eye(4)
    T[:3, 3] = origin
    return UncertainPose3(T, np.diag([sd_t**2] * 3 + [math.radians(sd_r_deg) ** 2] * 3))


def _pair(report, a, b):
    return next(p for p in report.pairs if (p.a, p.b) == (a, b))


@pytest.mark.parametrize("origin,sd_t,sd_r", [(BALL, 0.008, 0.0), ((0.0, 0.0, 0.0), 0.004, 0.3)],
                         ids=["translation", "lever-arm"])
def test_sigma_matches_monte_carlo(origin, sd_t, sd_r):
    scene = _ball_scene()
    det = armguard.Detector(scene, threshold=0.0)
    q = scene.flat_q(scene.default_q())
    place = UncertainPlacement("ball", _pose3(sd_t, sd_r, origin))
    r = _pair(clearance_sigmas(det, q, place, samples=0), "puma560/tool", "ball")
    tool = next(it.shape for it in scene.shapes_at(q) if it.owner == "puma560/tool")
    D = place.sample_displacements(4000, np.random.default_rng(1))
    d = np.array([distance(tool, scene.bodies["ball"].shapes[0].transformed(X)).distance for X in D])
    assert r.distance == pytest.approx(0.0501342, abs=1e-6)
    assert np.std(d) == pytest.approx(r.sigma, rel=SIGMA_RTOL)
    assert np.mean(d) == pytest.approx(r.distance, abs=3 * r.sigma / math.sqrt(len(d)) + 1e-4)
    # closed form for isotropic covariances: var = sd_t^2 + sd_r^2 |n x (p - o)|^2, the lever arm
    # from the placement's origin o to the witness point p on the ball
    n = (r.p_WA - r.p_WB) / r.distance
    lever = np.linalg.norm(np.cross(n, r.p_WB - np.asarray(origin)))
    assert r.sigma == pytest.approx(math.hypot(sd_t, math.radians(sd_r) * lever), rel=1e-9)
    assert r.sigmas == pytest.approx(r.distance / r.sigma)
    if sd_r:
        assert lever > 0.8  # about the W origin the rotation matters: 0.3 deg at ~0.9 m


CASES = {
    "translation 3-D": lambda: [UncertainPlacement("ball", _pose3(0.02, 0.0, BALL))],
    "SE(3) about W": lambda: [UncertainPlacement("ball", _pose3(0.02, 1.0))],
    "planar": lambda: [UncertainPlacement("ball", UncertainPose2([0.3, 0.1, 0.2], np.diag([4e-4, 4e-4, 2e-4])))],
    "base and ball": lambda: [UncertainPlacement("puma560", _pose3(0.01, 0.3)),
                              UncertainPlacement("ball", _pose3(0.01, 0.0, BALL))],
}


@pytest.mark.parametrize("name", list(CASES))
def test_bound_covers_monte_carlo(name):
    scene = _ball_scene()
    det = armguard.Detector(scene, threshold=0.0)
    q = scene.flat_q(scene.default_q())
    rep = clearance_sigmas(det, q, CASES[name](), samples=3000, seed=4)
    assert rep.pairs and rep.overall is not None
    assert rep.overall.p_monte_carlo > 0.0  # these cases do collide sometimes: the test can fail
    for p in rep.pairs:
        assert p.p_monte_carlo <= p.p_bound
        assert p.sigma <= p.sigma_max * (1 + 1e-12)  # the bound's extent is the worst direction's
    for g in [*rep.by_category.values(), rep.overall]:
        assert g.p_monte_carlo <= g.p_bound
    assert rep.overall.status is ClearanceStatus.AT_RISK
    dofs = {"translation 3-D": 3, "SE(3) about W": 6, "planar": 3, "base and ball": 12}
    nearest = rep.overall.nearest
    ratio = nearest.distance / nearest.sigma_max
    assert rep.overall.p_bound <= stats.chi2.sf(ratio**2, dofs[name]) * (1 + 1e-9)


def test_detector_and_checker_agree():
    model = armguard.load_model("puma560")
    place = [UncertainPlacement("cylinder_a", _pose3(0.01, 1.0, (0.55, 0.15, 0.6)))]
    by_checker = clearance_sigmas(armguard.checker(model, "analytic"), model.neutral(), place, samples=0)
    det = armguard.Detector(model.scene, threshold=0.0)
    by_detector = clearance_sigmas(det, model.scene_q(model.neutral()), place, samples=0)
    a, b = by_checker.pairs[0], by_detector.pairs[0]
    assert (a.a, a.b) == (b.a, b.b) and a.sigmas == pytest.approx(b.sigmas, rel=1e-6)
    assert a.status is ClearanceStatus.CONFIDENT and by_checker.overall.p_bound < 1e-6


def test_placements_are_checked():
    scene = _ball_scene()
    det = armguard.Detector(scene, threshold=0.0)
    q = scene.flat_q(scene.default_q())
    with pytest.raises(UncertaintyError, match="not a body or robot"):
        clearance_sigmas(det, q, UncertainPlacement("nowhere", _pose3(0.01, 0.0)))
    with pytest.raises(UncertaintyError, match="given twice"):
        clearance_sigmas(det, q, [UncertainPlacement("ball", _pose3(0.01, 0.0))] * 2)
    with pytest.raises(UncertaintyError, match="UncertainPose3 or UncertainPose2"):
        UncertainPlacement("ball", np.eye(4))
    assert UncertainPlacement("ball", _pose3(0.01, 0.0)).rank == 3
    assert UncertainPlacement("ball", _pose3(0.01, 1.0)).rank == 6


def test_verify_with_confidence():
    scene = armguard.load_scene("puma560")
    traj = scene.trajectories["pick_and_place"]
    nominal = armguard.verify(scene, traj)
    assert nominal.safe and 0.04 < nominal.min_clearance < 0.06  # 50 mm from cylinder_a
    k = math.sqrt(stats.chi2.ppf(0.999, 3))
    wide = verify_with_confidence(scene, traj, [UncertainPlacement("cylinder_a", _pose3(0.02, 0.0, (0.55, 0.15, 0.6)))])
    assert not wide.safe  # k * 20 mm = 81 mm reaches the arm
    assert wide.k == pytest.approx(k) and wide.growth["cylinder_a"] == pytest.approx(k * 0.02)
    assert wide.report.first_collision.obstacle == "cylinder_a"
    narrow = verify_with_confidence(scene, traj, [UncertainPlacement("cylinder_a", _pose3(0.002, 0.0, (0.55, 0.15, 0.6)))])
    assert narrow.safe and narrow.report.min_clearance < nominal.min_clearance
    # a base placed by an uncertain planar relation grows every body
    base = verify_with_confidence(scene, traj, [UncertainPlacement("puma560", UncertainPose2([0, 0, 0], np.diag([4e-4, 4e-4, 1e-4])))])
    assert not base.safe and set(base.growth) == set(scene.bodies)
    assert verify_with_confidence(scene, traj, [UncertainPlacement("puma560", UncertainPose2([0, 0, 0], np.diag([1e-6, 1e-6, 1e-8])))]).safe
    assert scene.bodies["cylinder_a"].shapes is not wide.scene.bodies["cylinder_a"].shapes  # the scene is not changed


@pytest.mark.parametrize("shape", [
    Box([0.1, 0.2, 0.3], [0.1, 0.2, 0.05]),
    Prism([0, 0, 0], np.eye(3), 0.1, 0.2, 6),
    ConvexPolyhedron(np.random.default_rng(0).normal(size=(20, 3))),
    Polygon([[0, 0, 0], [1, 0, 0], [0, 1, 0.2]]),
    Capsule([0, 0, 0], [0.3, 0, 0], 0.05),
    Cylinder([0.1, 0, 0.2], np.array([[0, 0, 1.0], [0, 1.0, 0], [-1.0, 0, 0]]), 0.05, 0.2),
], ids=lambda s: type(s).__name__)
def test_grown_shape_contains_the_minkowski_sum(shape):
    g = 0.07
    grown = grow_shape(shape, g)
    rng = np.random.default_rng(3)
    if isinstance(shape, Cylinder):  # its core points circumscribe it: take points on its surface
        th = rng.uniform(0.0, 2 * np.pi, 300)
        rho = np.where(rng.random(300) < 0.5, shape.radius, shape.radius * np.sqrt(rng.random(300)))
        z = np.where(rho == shape.radius, rng.uniform(-1, 1, 300), rng.choice([-1.0, 1.0], 300)) * shape.half_length
        pts = shape.center + np.column_stack([rho * np.cos(th), rho * np.sin(th), z]) @ shape.rotation.T
    else:
        pts = shape.core_points[rng.integers(len(shape.core_points), size=300)]
    u = rng.normal(size=(300, 3))
    far = pts + (shape.core_radius + g * 0.999) * u / np.linalg.norm(u, axis=1)[:, None]  # within g of the shape
    assert all(distance(Sphere(p, 0.0), grown).distance <= 1e-12 for p in far)
    outside = pts + (shape.core_radius + 3 * g) * u / np.linalg.norm(u, axis=1)[:, None]
    assert any(distance(Sphere(p, 0.0), grown).distance > 0 for p in outside)  # it is not everything


@pytest.mark.parametrize("kw, said", [
    (dict(samples=-5), "samples: expected an integer >= 0"), (dict(samples=2.5), "samples: expected an integer"),
    (dict(samples="10"), "samples: expected an integer"), (dict(seed="x"), "seed: expected an integer"),
    (dict(confidence="abc"), r"confidence: expected a finite number in \(0, 1\)"), (dict(confidence=1.0), r"confidence: expected a finite number in"),
])
def test_clearance_sigmas_refuses_bad_arguments_by_name(kw, said):
    """samples=-5 was accepted; 2.5, "10" and seed="x" were raw TypeErrors, confidence="abc" a ValueError."""
    scene = _ball_scene()
    det = armguard.Detector(scene, threshold=0.0)
    q = scene.flat_q(scene.default_q())
    place = [UncertainPlacement("ball", _pose3(0.005, 1.0))]
    with pytest.raises(UncertaintyError, match=said):
        clearance_sigmas(det, q, place, **kw)


def test_a_pairs_bound_reads_its_nearest_shapes_not_its_fewest_sigmas():
    """PUMA link3 (a capsule and a sphere) 1 mm beside a probe placed by a frame 1 m away on the far side
    (0.95° of turn): the capsule's nearest direction is along the lever arm (sigma 0, infinite sigmas), so the
    pair's row with the fewest sigmas was the sphere's, 155 mm away, and the pair was CONFIDENT at 0.999 --
    Monte Carlo collides in 0.6 % of draws.  The bound and the status now read the nearest distance."""
    import math

    import armguard
    from armguard.geometry import Sphere
    from armguard.uncertainty import ClearanceStatus, UncertainPlacement, UncertainPose2, clearance_sigmas

    scene = armguard.load_scene("puma560")
    for b in list(scene.bodies):
        scene.remove_body(b)
    scene.add_body("probe", [Sphere([0.51, -0.15 + 0.06 + 0.001 + 0.03, 0.957], 0.03)])
    place = UncertainPlacement("probe", UncertainPose2([0.51, -1.059, 0.0],
                                                       np.diag([5e-5 ** 2, 5e-5 ** 2, math.radians(0.95) ** 2])))
    det = armguard.Detector(scene, threshold=0.0)
    rep = clearance_sigmas(det, scene.flat_q(scene.default_q()), place, confidence=0.999, samples=4000, seed=0)
    p = next(p for p in rep.pairs if (p.a, p.b) == ("puma560/link3", "probe"))
    assert p.distance < 0.002 and p.p_monte_carlo > 0.001  # 1 mm apart; it does collide now and then
    assert p.p_bound >= p.p_monte_carlo and p.status is not ClearanceStatus.CONFIDENT
    assert rep.status is not ClearanceStatus.CONFIDENT


def test_a_merge_stays_a_covariance_armguard_accepts():
    """A 1 m^2 prior merged with a 1e-8 m^2 sensor that knows one rotated direction exactly: C1 - K C1 came out
    with eigenvalues of -1e-14, refused when the result was rebuilt (50 of 200).  Joseph's form keeps it PSD."""
    from scipy.spatial.transform import Rotation

    from armguard.uncertainty import UncertainPose2

    base = np.array([[200.0, 60.0, 5.0], [60.0, 50.0, 2.0], [5.0, 2.0, 0.5]]) / 200
    for i in range(200):
        R = Rotation.from_rotvec(np.random.default_rng(i).normal(size=3)).as_matrix()
        c2 = R @ np.diag([0.0, 1e-8, 4e-8]) @ R.T
        m = UncertainPose2([3.0, 1.0, 0.4], base).merge(UncertainPose2([3.0, 1.0, 0.4], c2))
        UncertainPose2(m.mean, m.cov)  # validated again: no refusal
        assert np.linalg.eigvalsh(m.cov).min() >= -1e-18


def test_clearance_sigmas_reads_the_scene_of_its_rows_while_another_thread_edits_it():
    """Another thread's edit between the Detector's query and the reads of the shapes (simulated: the
    query adds a body): the rows and the shapes come from one revision, read again after a change;
    an edit on every try is an error, never a report of a scene that no row describes."""
    scene = _ball_scene()
    det = armguard.Detector(scene, threshold=0.0)
    q = scene.flat_q(scene.default_q())
    place = UncertainPlacement("ball", _pose3(0.008, 0.0, BALL))
    query, edits, calls = det.pair_distances, [], []

    def edited_once(*a, **k):
        r = query(*a, **k)
        calls.append(1)
        if not edits:
            edits.append(1)
            scene.add_body("late_ball", Sphere((2.0, 2.0, 2.0), 0.05))
        return r

    det.pair_distances = edited_once
    rep = clearance_sigmas(det, q, place, samples=0)
    assert len(calls) == 2  # the rows read again, of the edited scene
    assert [(p.a, p.b) for p in rep.pairs] == [(p.a, p.b) for p in clearance_sigmas(det, q, place, samples=0).pairs]

    def edited_always(*a, **k):
        r = query(*a, **k)
        scene.add_body(f"ball_{len(edits)}", Sphere((2.0, -2.0, 2.0), 0.05))
        edits.append(1)
        return r

    det.pair_distances = edited_always
    with pytest.raises(UncertaintyError, match="changed"):
        clearance_sigmas(det, q, place, samples=0)
