"""Trajectory verification: Hermes's numbers, the lever-arm bound, certified vs dense reference, outputs."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from armguard import DEFAULT_TOLERANCES, VerificationError
from armguard.geometry import Box, Capsule, Sphere
from armguard.kinematics import Trajectory
from armguard.scene import Scene
from armguard.verify import (
    ClearanceModel,
    StoppingDistance,
    VerificationStatus,
    discretisation_error,
    verify,
)
from armguard.verify._motion import chain_bounds

from _verify_fixtures import planar_arm, spatial_arm, thin_scene, thin_suite
from armguard.harness import seed_data

HERMES_ED = seed_data("hermes")["discretisation_error"]  # reference/seeds/hermes.yaml


# --------------------------------------------------------------------------- Hermes's numbers
@pytest.mark.parametrize(
    ("speed_mm_s", "ed_mm"),
    [(row["speed_mm_s"], row["ed_mm"]) for row in HERMES_ED["table"]],
    ids=[f"{row['speed_mm_s']}mm/s" for row in HERMES_ED["table"]],
)
def test_hermes_discretisation_error_table(speed_mm_s, ed_mm):
    # Hermes (001_…, §4, eq. 4-2): Ed = v / f at the 1.7 Hz its 18 kFLOPS allowed.
    ed = discretisation_error(speed_mm_s * 1e-3, HERMES_ED["frequency_hz"])
    assert round(float(ed) * 1e3) == ed_mm


def test_hermes_stopping_distance_ten_ranges_up_to_100_mm():
    sd = StoppingDistance.hermes(max_speed=0.2)  # 10 ranges, 100 mm at the top (Hermes §4)
    assert len(sd.table) == 10 and sd.max_distance == pytest.approx(0.1)
    speeds = np.linspace(0.0, 0.2, 2001)
    values = np.array([sd.at(v) for v in speeds])
    assert np.all(np.diff(values) >= 0)
    # the step function never under-estimates the linear law it steps, and errs by at most 10 mm
    linear = 0.1 * speeds / 0.2
    assert np.all(values >= linear - 1e-12)
    assert np.max(values - linear) <= 0.01 + 1e-12
    assert sd.at(0.02) == pytest.approx(0.01) and sd.at(0.0201) == pytest.approx(0.02)
    with pytest.raises(VerificationError):
        sd.at(0.25)


@pytest.mark.parametrize("top", [1.8166484431762606] + list(np.random.default_rng(0).uniform(0.01, 5.0, 200)))
def test_hermes_table_takes_the_speed_it_was_made_for(top):
    """The table's top edge is max_speed itself: vmax * n / n rounded a bit below it for ~6 % of speeds,
    and the table then refused the speed of the path it was made from."""
    sd = StoppingDistance.hermes(float(top), max_distance=0.05, n_ranges=10)
    assert sd.speed_edges[-1] == top and sd.at(float(top)) == pytest.approx(0.05)


def test_a_speed_over_the_tables_top_by_rounding_is_in_its_last_range():
    """``verify --speed-dependent`` makes the table from a plain verification's top speed and verifies
    the trajectory split finer: there the same speed came out one unit in the last place above it, and
    the check stopped with no verdict ("speed 0.41756353276537833 is above the table's last edge
    0.4175635327653783").  A speed above it by more than rounding is still refused."""
    top = 0.4175635327653783
    sd = StoppingDistance.hermes(top, max_distance=0.01)
    assert sd.at(0.41756353276537833) == sd.at(top) == pytest.approx(0.01)
    with pytest.raises(VerificationError, match="above the table"):
        sd.at(top * (1.0 + 1e-9))


def test_stopping_distance_by_speed_and_mass():
    sd = StoppingDistance((0.0, 0.1, 0.2), (0.0, 10.0, 100.0), ((0.02, 0.04), (0.05, 0.1)))
    assert sd.at(0.05, 5.0) == 0.02 and sd.at(0.05, 50.0) == 0.04 and sd.at(0.15, 50.0) == 0.1
    with pytest.raises(VerificationError):
        StoppingDistance((0.0, 0.1, 0.2), (0.0, 1.0), ((0.05,), (0.02,)))  # decreasing with speed
    with pytest.raises(VerificationError):
        sd.at(float("nan"))


# --------------------------------------------------------------------------- the lever-arm bound
@pytest.mark.parametrize("convention", ["standard", "modified"], ids=["dh-standard", "dh-modified"])
def test_lever_arm_bound_holds_along_random_joint_lines(convention):
    """|p(s) - p(0)| <= s * |dq| . lever for every core point of every link (coupled and prismatic joints included)."""
    robot = spatial_arm(convention)
    sc = Scene("lever")
    sc.add_robot(robot)
    model = ClearanceModel(sc, source="reference")
    rng = np.random.default_rng(7)
    lo, hi = robot.lower, robot.upper
    s = np.linspace(0.0, 1.0, 41)
    worst = 0.0
    for _ in range(25):
        q0 = rng.uniform(lo, hi)
        q1 = rng.uniform(lo, hi)
        dq = q1 - q0
        bound = model.lever[:-1] @ np.abs(dq)  # per part
        pts0 = _core_points_by_owner(sc, q0)
        for sk in s[1:]:
            pts = _core_points_by_owner(sc, q0 + sk * dq)
            for i, owner in enumerate(model.parts):
                disp = float(np.max(np.linalg.norm(pts[owner] - pts0[owner], axis=1)))
                assert disp <= sk * bound[i] + 1e-12, (owner, disp, sk * bound[i])
                worst = max(worst, disp / (sk * bound[i]))
    assert worst > 0.2  # the bound is not vacuous: it is within a small factor of real motion


def _core_points_by_owner(sc, q):
    out = {}
    for it in sc.shapes_at(q):
        out.setdefault(it.owner, []).append(np.asarray(it.shape.core_points))
    return {k: np.vstack(v) for k, v in out.items()}


def test_chain_bounds_of_planar_arm_closed_form():
    """Planar 3R arm: joint j's lever for link k is the reach from joint j's axis to link k's far end."""
    cb = chain_bounds(planar_arm())
    a = (0.5, 0.4, 0.3)
    for j in range(3):
        for k in range(j, 3):
            reach = sum(a[j : k + 1])  # the origin of link k+1 sits at the far end of link k
            assert cb.A[j, k + 1] == pytest.approx(reach, rel=1e-6)
    assert np.all(cb.P == 0.0)


# --------------------------------------------------------------------------- certified never misses
def _dense_first_collision(model, traj, n_per_segment=3000):
    """Very dense reference: the first knot-to-knot sample with distance <= 0 (returns its s along the whole path)."""
    segs = list(traj.segments())
    for si, (_, _, q0, q1) in enumerate(segs):
        for s in np.linspace(0.0, 1.0, n_per_segment + 1):
            d, _, _ = model.reference_distances(q0 + s * (q1 - q0))
            if d.min() <= 0.0:
                return si + s
    return None


def test_certified_never_misses_what_a_dense_reference_finds_and_sampled_does_miss():
    rng = np.random.default_rng(2024)
    misses_sampled = 0
    found_dense = 0
    for sc, traj in thin_suite(rng, 45, n_obstacles=6):
        model = ClearanceModel(sc, source="reference")
        cert = verify(sc, traj, method="certified")
        sampled = verify(sc, traj, method="sampled", joint_step=0.05)
        dense = _dense_first_collision(model, traj, n_per_segment=800) if cert.status is not VerificationStatus.SAFE or not sampled.safe else None
        if cert.safe:
            # proven safe: the dense reference agrees and so does the sampled check
            assert sampled.safe
            assert cert.min_clearance_lower_bound > 0.0
        else:
            assert cert.status is VerificationStatus.COLLISION
            c = cert.first_collision
            assert c.distance <= DEFAULT_TOLERANCES.verify_contact
            assert c.obstacle.startswith(("plate", "rod"))
            d_real, _, _ = model.reference_distances(np.concatenate([c.q]))
            assert d_real.min() <= DEFAULT_TOLERANCES.verify_contact + 1e-9  # a real contact, not a false alarm
        if dense is not None:
            found_dense += 1
            assert cert.status is VerificationStatus.COLLISION, "certified mode missed a collision"
            # the first collision is first: no later than the dense reference's first colliding sample
            assert cert.first_collision.time <= dense * traj.duration + 1e-9
            if sampled.safe:
                misses_sampled += 1
    assert found_dense >= 10
    assert misses_sampled >= 1, "the suite should contain collisions a 0.05 rad sampled check misses"


def test_certified_collision_is_real_and_first():
    """A thin plate (2 mm) crossed by the tip between two 0.05 rad samples."""
    sc = Scene("plate")
    robot = planar_arm(radius=0.005)
    sc.add_robot(robot)
    # the tip sweeps a circle of radius 1.2 m; the plate stands across it at angle 0.525 rad
    ang = 0.525
    c = 1.2 * np.array([np.cos(ang), np.sin(ang), 0.0])
    R = np.array([[np.cos(ang), -np.sin(ang), 0], [np.sin(ang), np.cos(ang), 0], [0, 0, 1.0]])
    sc.add_body("plate", [Box(c, [0.01, 0.001, 0.1], R)])  # 2 mm thick along the tip's motion
    traj = Trajectory.joint_interpolated(robot, [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]], profile="linear")
    sampled = verify(sc, traj, method="sampled", joint_step=0.05)
    assert sampled.safe  # the plate lies between the samples at 0.50 and 0.55 rad (24 mm clear of both)
    cert = verify(sc, traj, method="certified")
    assert cert.status is VerificationStatus.COLLISION
    c = cert.first_collision
    assert c.link == "link3" and c.obstacle == "plate" and c.check == "link-obstacle" and c.objects == ("arm", "obstacle")
    # closed form: the tip capsule (radius 0.02) first touches the plate's near face
    model = ClearanceModel(sc, source="reference")
    d, _, _ = model.reference_distances(c.q)
    assert abs(d.min()) <= 2e-6
    assert c.q[0] < ang  # before the plate's centre line
    assert c.feature is not None
    assert c.time == pytest.approx(c.q[0], abs=1e-9)  # linear profile at 1 rad/s


# --------------------------------------------------------------------------- the four checks
def _hermes_like_scene():
    sc = Scene("four")
    robot = planar_arm()
    sc.add_robot(robot, self_pairs=[("link1", "link3")])
    sc.add_body("wall", [Box([0.0, -0.6, 0.0], [1.5, 0.01, 0.3])])
    sc.attach_payload("cargo", "arm", "link3", [Capsule([0, 0, 0], [0.0, 0.0, 0.0], 0.05)])
    return sc, robot


def test_payload_obstacle_collision_reported_as_payload():
    sc, robot = _hermes_like_scene()
    traj = Trajectory.joint_interpolated(robot, [[0.0, 0.0, 0.0], [-1.2, 0.0, 0.0]], profile="linear")
    r = verify(sc, traj)
    assert r.status is VerificationStatus.COLLISION
    c = r.first_collision
    # the payload (5 cm ball at the tip) reaches the wall before the tip's 2 cm capsule
    assert c.check == "payload-obstacle" and c.payload == "cargo" and c.obstacle == "wall"
    assert c.objects == ("payload", "obstacle") and c.category == "payload"


def test_link_link_only_listed_pairs_and_stopping_distance_growth():
    sc, robot = _hermes_like_scene()
    sc.remove_body("wall")
    # fold link3 back onto link1 (listed pair 1-3)
    traj = Trajectory.joint_interpolated(robot, [[0.0, 0.5, 0.0], [0.0, 2.6, 2.9]], profile="linear")
    r = verify(sc, traj)
    assert r.status is VerificationStatus.COLLISION
    assert r.first_collision.check in ("link-link", "payload-link")
    assert {r.first_collision.a, r.first_collision.b} & {"arm/link1", "arm/link3", "cargo"}


@pytest.mark.parametrize(("sd", "safe"), [(0.03, True), (0.07, False)], ids=["sd30mm-safe", "sd70mm-collision"])
def test_stopping_distance_grows_obstacles(sd, safe):
    sc = Scene("pass")
    robot = planar_arm()
    sc.add_robot(robot)
    # a rod 50 mm outside the tip's circle (tip capsule radius 0.02 m): clearance 50 mm
    sc.add_body("rod", [Capsule([1.2 + 0.02 + 0.05 + 0.005, 0, -0.1], [1.275, 0, 0.1], 0.005)])
    traj = Trajectory.joint_interpolated(robot, [[-0.5, 0.0, 0.0], [0.5, 0.0, 0.0]], profile="linear")
    r = verify(sc, traj, stopping_distance=sd)
    assert r.safe is safe
    if safe:  # the true minimum (50 mm, at q = 0) lies between the proven lower bound and the sampled minimum
        assert r.min_clearance_lower_bound - 1e-9 <= 0.05 <= r.min_clearance + 1e-9
        assert r.min_clearance_lower_bound > sd
    if not safe:
        assert r.first_collision.distance <= sd + DEFAULT_TOLERANCES.verify_contact
        assert r.stopping_distance == sd


def test_step_function_stopping_distance_follows_speed():
    sc = Scene("pass")
    robot = planar_arm()
    sc.add_robot(robot)
    sc.add_body("rod", [Capsule([1.275, 0, -0.1], [1.275, 0, 0.1], 0.005)])  # 50 mm clearance
    sd = StoppingDistance.hermes(max_speed=2.0, max_distance=0.1)
    slow = Trajectory.joint_interpolated(robot, [[-0.5, 0, 0], [0.5, 0, 0]], profile="linear", times=[0.0, 10.0])
    fast = Trajectory.joint_interpolated(robot, [[-0.5, 0, 0], [0.5, 0, 0]], profile="linear", times=[0.0, 1.0])
    assert verify(sc, slow, stopping_distance=sd).safe
    r = verify(sc, fast, stopping_distance=sd)
    assert not r.safe and r.stopping_distance > 0.05


# --------------------------------------------------------------------------- incomplete, errors
def test_budget_exhausted_is_incomplete_never_safe():
    rng = np.random.default_rng(3)
    sc = thin_scene(rng)
    robot = sc.robots["arm"]
    traj = Trajectory.joint_interpolated(robot, [[0.0, 0.0, 0.0], [2.0, 1.0, 1.0]], profile="linear")
    from dataclasses import replace

    r = verify(sc, traj, tol=replace(DEFAULT_TOLERANCES, verify_max_evaluations=3))
    assert r.status is VerificationStatus.INCOMPLETE and not r.safe
    assert "budget" in r.reason and r.first_collision is None


@pytest.mark.parametrize(
    "kwargs",
    [
        {"stopping_distance": float("nan")},
        {"stopping_distance": -0.1},
        {"method": "exact"},
        {"method": "sampled", "frequency": 0.0},
        {"method": "sampled", "joint_step": float("inf")},
        {"threshold": float("nan")},
        {"robot": "nobody"},
    ],
    ids=["sd-nan", "sd-negative", "bad-method", "zero-frequency", "inf-step", "nan-threshold", "unknown-robot"],
)
def test_bad_arguments_raise(kwargs):
    sc = Scene("x")
    robot = planar_arm()
    sc.add_robot(robot)
    sc.add_body("ball", [Sphere([0.0, 2.0, 0.0], 0.1)])
    traj = Trajectory.joint_interpolated(robot, [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0]])
    with pytest.raises(VerificationError):
        verify(sc, traj, **kwargs)


# --------------------------------------------------------------------------- outputs
def test_report_outputs_json_summary_plot(tmp_path):
    sc = Scene("out")
    robot = planar_arm()
    sc.add_robot(robot)
    sc.add_body("ball", [Sphere([1.0, 0.5, 0.0], 0.1)])
    traj = Trajectory.joint_interpolated(robot, [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    r = verify(sc, traj, stopping_distance=0.02, threshold=0.1, name="sweep")
    assert r.status is VerificationStatus.COLLISION
    d = json.loads(r.to_json())
    assert d["status"] == "collision" and d["safe"] is False and d["trajectory"] == "sweep"
    assert d["first_collision"]["obstacle"] == "ball" and len(d["first_collision"]["p_W"]) == 3
    assert d["details"]["method"] == "certified"
    p = r.save_json(tmp_path / "r.json")
    assert json.loads(p.read_text())["first_collision"]["link"] == r.first_collision.link
    text = r.summary()
    assert "Hermes's rule" in text and "ball" in text and "first stopping-distance violation" in text  # 20 mm apart, 20 mm to brake
    png = r.plot(tmp_path / "r.png")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert set(r.profile.by_category) == {"arm", "environment"}
    assert np.all(np.diff(r.profile.time) >= 0)


def test_sampled_at_frequency_reports_ed():
    sc = Scene("ed")
    robot = planar_arm()
    sc.add_robot(robot)
    sc.add_body("ball", [Sphere([0.0, -2.0, 0.0], 0.1)])
    traj = Trajectory.joint_interpolated(robot, [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]], profile="linear", times=[0.0, 2.0])
    r = verify(sc, traj, method="sampled", frequency=1.7)
    # fastest point: the bound is the chain's reach to link3's origin (1.2 m) plus link3's radius
    # about that origin (0.3 m + 0.02 m capsule radius), at 0.5 rad/s; the true tip speed is 0.5 * 1.22
    assert r.details.max_speed == pytest.approx(0.5 * 1.52, rel=1e-6)
    assert r.details.max_speed >= 0.5 * 1.22
    assert r.details.discretisation_error == pytest.approx(r.details.max_speed / 1.7)
    assert r.safe and r.details.samples_evaluated >= 4
    assert math.isinf(r.min_clearance_lower_bound) and r.min_clearance_lower_bound < 0


def test_detector_and_reference_sources_agree():
    rng = np.random.default_rng(11)
    sc = thin_scene(rng, n_obstacles=4)
    fast = ClearanceModel(sc, source="auto")
    ref = ClearanceModel(sc, source="reference")
    if fast.source != "detector":
        pytest.skip("the detector offers no pair_distances")
    for _ in range(200):
        q = rng.uniform(-2.9, 2.9, 3)
        d1, a1, b1 = fast.distances(q)
        d2, a2, b2 = ref.distances(q)
        np.testing.assert_allclose(d1, d2, atol=1e-9)


def test_top_level_verify_is_callable_even_after_the_subpackage_import():
    import subprocess
    import sys

    code = (
        "import armguard.verify, armguard, numpy as np\n"
        "from armguard.geometry import Sphere\n"
        "import sys; sys.path.insert(0, 'tests')\n"
        "from _verify_fixtures import planar_arm\n"
        "from armguard.scene import Scene\n"
        "sc = Scene('x'); r = planar_arm(); sc.add_robot(r); sc.add_body('b', [Sphere([0, 2, 0], 0.1)])\n"
        "t = armguard.Trajectory.joint_interpolated(r, [[0, 0, 0], [0.2, 0, 0]], max_velocity=[1, 1, 1])\n"
        "rep = armguard.verify(sc, t, stopping_distance=0.0, method='certified')\n"
        "print(rep.safe, rep.first_collision, rep.min_clearance > 0)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=str(__import__("pathlib").Path(__file__).parent.parent))
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["True", "None", "True"]


def test_pieces_keep_the_segments_peak_speed():
    """``Subdivided`` sampled each piece's speed strictly inside it: an accelerating piece peaks at its end,
    so a triangle profile seen in 2 pieces had a fastest point 2.9 % slow, and a stopping-distance table
    stepping up just below the true top speed read SAFE where the whole segment reads UNSAFE."""
    import armguard
    from armguard.verify import Subdivided

    m = armguard.load_model("ur5")
    J = list(m.scene.robots["ur5"].joint_names)
    q0 = np.array([np.pi, -1.57, 0.0, -1.57, 0.0, 0.0])
    tr = Trajectory("ur5", J, [0.0, 2.0], [q0, q0 + [0.5, 0.3, 0.4, 0.0, 0.0, 0.0]], blend_times=[1.0])
    top = armguard.verify(m, tr).details.max_speed
    for n in (2, 3, 8):
        assert armguard.verify(m, Subdivided(tr, n)).details.max_speed == pytest.approx(top, rel=1e-12)
    sd = StoppingDistance((0.0, 0.995 * top, 1.5 * top), (0.0, 1e300), ((0.0,), (0.1,)))
    assert armguard.verify(m, tr, stopping_distance=sd).verdict() == "unsafe (stopping distance)"
    assert armguard.verify(m, Subdivided(tr, 8), stopping_distance=sd).verdict() == "unsafe (stopping distance)"


def test_robot_argument_never_moves_another_arm_than_the_trajectorys():
    """Two alike arms: a trajectory for ``arm2`` verified with ``robot="ur5"`` was checked on ur5 and said
    SAFE, where arm2 collides; now refused, naming both."""
    import armguard
    from armguard.verify import Verifier

    m = armguard.load_model("ur5")
    X = np.eye(4)
    X[:3, 3] = [0.9, 0.0, 0.0]
    two = m.with_robot(m.robots["ur5"].with_name("arm2").with_base(X))
    q0 = np.array([np.pi, -1.57, 0.0, -1.57, 0.0, 0.0])
    tr = Trajectory("arm2", m.robots["ur5"].joint_names, [0.0, 2.0], [q0, q0 + [0.0, 1.57, 0.0, 0.0, 0.0, 0.0]])
    assert armguard.verify(two, tr).status is VerificationStatus.COLLISION
    assert armguard.verify(two, tr, robot="arm2").status is VerificationStatus.COLLISION
    for call in (lambda: armguard.verify(two, tr, robot="ur5"), lambda: Verifier(two, robot="ur5").verify(tr)):
        with pytest.raises(VerificationError, match="the trajectory is for robot 'arm2'"):
            call()


# --------------------------------------------------------------------------- per-pair rates
def _pair_rate_ratio(model, q0, q1, n=41):
    """The largest ``|d_p(s) - d_p(0)| / (s * rate_p)`` over the pairs and ``s`` along ``q0 -> q1``
    (the pair rate must bound every pair's change: at most 1), with the rates of the relative
    joints and those of the old per-part sum (lever_a + lever_b over every joint)."""
    dq = q1 - q0
    rates = model.pair_rates(dq)
    part = model.lever @ np.abs(dq)
    old = part[model.index_a] + part[model.index_b]
    assert np.all(rates <= old + 1e-15)
    d0 = model.distances(q0)[0]
    worst = 0.0
    for s in np.linspace(0.0, 1.0, n)[1:]:
        d = model.distances(q0 + s * dq)[0]
        change = np.abs(d - d0)
        assert np.all(change <= s * rates + 1e-9), (np.argmax(change - s * rates), change, s * rates)
        moving = rates > 0.0
        if np.any(moving):
            worst = max(worst, float(np.max(change[moving] / (s * rates[moving]))))
    return worst, float(np.sum(rates)) / float(np.sum(old))


def test_pair_rates_drop_the_joints_that_move_both_links_rigidly_and_still_bound_the_change():
    """A pair's clearance can change only through the joints between the two links' common ancestor and
    either link; the rate over those joints bounds the change along random joint lines (the spatial arm's
    coupled and prismatic joints included), and is well below the old per-part sum."""
    robot = spatial_arm()
    sc = Scene("rates")
    sc.add_robot(robot)
    model = ClearanceModel(sc, source="reference")
    assert len(model.owner_a) >= 5
    rng = np.random.default_rng(11)
    worst, share = 0.0, []
    for _ in range(15):
        q0, q1 = rng.uniform(robot.lower, robot.upper), rng.uniform(robot.lower, robot.upper)
        w, sh = _pair_rate_ratio(model, q0, q1, n=21)
        worst, share = max(worst, w), share + [sh]
    assert worst > 0.1  # not vacuous
    assert np.median(share) < 0.9  # and tighter than the old sum
    # the coupled joint j5 = -j3 + 0.5 j2 + 0.1 moves link5 against link3: j2 and j3 stay in that pair's row
    i = next(k for k, (a, b) in enumerate(zip(model.owner_a, model.owner_b)) if {a, b} == {"spatial/link3", "spatial/link5"})
    assert model.pair_lever[i, 1] > 0.0 and model.pair_lever[i, 2] > 0.0
    assert model.pair_lever[i, 0] == 0.0  # j1 turns link3 and link5 together


@pytest.mark.parametrize("name", ["ur5", "panda"])
def test_pair_rates_bound_public_robots_self_pairs(name):
    import armguard

    m = armguard.load_model(name)
    model = ClearanceModel(m.scene)
    rng = np.random.default_rng(5)
    worst, share = 0.0, []
    for k in range(6):
        Q = m.scene_q(m.random_q(2, int(rng.integers(1 << 30))))
        w, sh = _pair_rate_ratio(model, Q[0], Q[1], n=31)
        worst, share = max(worst, w), share + [sh]
    assert worst > 0.1
    assert np.median(share) < 0.8


def test_certified_verification_refuses_a_backend_whose_distances_may_run_long():
    """python-fcl's GJK stops early (``distances_may_run_long``): at a Hermes configuration whose nearest
    clearance is 0.330 m it says 0.331 m, and a margin of 0.3305 m was verified SAFE, the "proven" lower bound
    0.3310 m above the true minimum.  Such distances bound no clearance from below: refused, naming it."""
    pytest.importorskip("fcl")
    import armguard
    from armguard.verify import Verifier

    scene = armguard.load_scene("hermes")
    with pytest.raises(VerificationError, match="backend 'fcl': its distances may run long"):
        Verifier(scene, backend="fcl")
    Verifier(scene, backend="coal")  # exact to its tolerance: taken


def test_a_speed_table_refuses_a_time_law_whose_peak_speed_is_only_sampled():
    """A Trajectory subclass with its own time law: each segment's peak speed came from 17 samples of its
    velocity, no bound (a 3 ms spike read 1.43 m/s where it reached 192 m/s, and the table's 0 m range was
    taken where Hermes's rule wanted 5 m).  A constant stopping distance needs no speed: still verified."""
    import armguard
    from armguard.kinematics import Trajectory
    from armguard.verify import Verifier

    class Spiky(Trajectory):  # its own velocity (a narrow bump at u = 0.03): what the verifier reads the speeds from
        def velocity(self, t):
            t, seg = self._locate(t)
            T = self.times[seg + 1] - self.times[seg]
            u = (t - self.times[seg]) / T
            ds = (1.0 + 0.02 / 0.003 / np.cosh((np.asarray(u) - 0.03) / 0.003) ** 2) / T
            return np.asarray(ds)[..., None] * (self.waypoints[seg + 1] - self.waypoints[seg])

    scene = armguard.load_scene("puma560")
    rob = scene.robots["puma560"]
    tr = Spiky("puma560", list(rob.joint_names), [0.0, 1.0], scene.trajectories["pick_and_place"].waypoints[:2])
    v = Verifier(scene)
    table = StoppingDistance((0.0, 0.5, 1000.0), (0.0, 1e300), ((0.0,), (5.0,)))
    with pytest.raises(VerificationError, match="needs each segment's peak speed, which a Spiky gives in no closed form"):
        v.verify(tr, stopping_distance=table)
    assert v.verify(tr, stopping_distance=0.01).status.value in ("safe", "collision")  # a verdict, not a refusal
