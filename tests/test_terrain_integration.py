"""The terrain integrated with the robot system: TerrainGuard, the Detector's terrain category, the
certified terrain sweep, the rover's body hierarchy, coal's height field as the reference, the CLI."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

import armguard
from armguard.detect import DetectionReport, Status
from armguard.geometry import ConvexPolyhedron, Prism, Sphere, distance
from armguard.kinematics import Trajectory
from armguard.terrain import (
    BodyHierarchy,
    ElevationMap,
    TerrainGuard,
    attach_terrain,
    check_with_terrain,
    coal_checker,
    dilated,
    link_volume,
    load_terrain,
    sweep_terrain,
    verify_with_terrain,
)
from armguard.terrain.generate import make_terrain
from armguard.verify import VerificationStatus

ROCKY = "reference/terrain/rocky.npz"


@pytest.fixture(scope="module")
def model():
    return armguard.load_model("rover")


@pytest.fixture(scope="module")
def truth(model):
    """The rocky reference terrain's ground truth (fully known), centred under the arm's base."""
    with np.load(ROCKY) as z:
        h = np.asarray(z["heights"], dtype=np.float64)
    return ElevationMap.from_heights(h, 0.05, origin=(0.5 - 1.6, -1.6))


@pytest.fixture(scope="module")
def guard(model, truth):
    return TerrainGuard(model, truth)


def _traj(q_deg, T=4.0):
    W = np.deg2rad(np.asarray(q_deg, dtype=np.float64))
    return Trajectory("arm", ["azimuth", "elevation", "elbow", "wrist", "turret"],
                      np.linspace(0.0, T, len(W)), W)


# ------------------------------------------------------------------------------------------ guard
def test_rover_links_are_their_obps(model):
    sc = model.scene
    for it in sc.shapes_at(sc.flat_q(sc.default_q())):
        v = link_volume(it.shape)
        if isinstance(it.shape, ConvexPolyhedron):
            assert isinstance(v, Prism) and v.n_sides in (8, 16)  # the URDF's OBPs, recognised
            P = v.as_polyhedron()
            assert max(distance(Sphere(p, 0.0), P).distance for p in it.shape.core_points) <= 0.0


def test_guard_distances_equal_the_pyramid_exact_mode(model, guard):
    """The compiled per-link distances agree with TerrainPyramid.check(exact=True) on shape objects."""
    Q = model.scene_q(model.random_q(60, rng=4))
    R = 0.1
    seen = 0
    for q in Q:
        known, unknown, res, cell, wit = guard.distances(q, reach=R)
        vols, shapes = guard.posed(q)
        ref = guard.pyramid.check(vols, shapes=shapes, exact=True, clearance=R)
        want = np.where(ref.link_known <= R, ref.link_known, np.inf)
        np.testing.assert_allclose(known, want, atol=1e-9)
        assert np.all(np.isinf(unknown) | (unknown <= R))  # only the off-map slabs: the map is fully known
        seen += int(np.isfinite(known).sum())
        for k in np.flatnonzero(np.isfinite(known)):  # witness points: |p_WA - p_WB| = |d|
            assert abs(np.linalg.norm(wit[0, k, :3] - wit[0, k, 3:]) - abs(known[k])) < 1e-7
    assert seen > 20


def test_guard_status_rules(model, truth):
    g = TerrainGuard(model, truth)
    low = np.deg2rad([0, 30, 20, 30, 0])  # the turret in the ground in front of the wheels
    r = g.check(low)
    assert r.status is Status.COLLISION and r.distance < 0 and r.link == "arm/turret" and not r.unknown
    home = model.scene.flat_q(model.scene.default_q())
    assert g.check(home).status is Status.CLEAR
    # the same ground unseen: never CLEAR by omission, INCOMPLETE (a known contact would still be COLLISION)
    blind = ElevationMap(truth.heights, truth.origin, truth.cell, np.zeros(truth.shape, bool), truth.counts,
                         truth.floor)
    rb = TerrainGuard(model, blind).check(low)
    assert rb.status is Status.INCOMPLETE and rb.unknown and math.isinf(rb.known_distance)
    assert rb.pair().feature.kind == "unseen cell"


def test_off_the_map_is_unknown(model):
    """A small map in front of the rover: the arm reaching past its edge near the ground is INCOMPLETE."""
    m = ElevationMap.from_heights(np.zeros((4, 4)), 0.05, origin=(3.0, 3.0))  # far away, flat at z = 0
    g = TerrainGuard(model, m, unknown_margin=0.05)
    r = g.check(np.deg2rad([0, 30, 20, 30, 0]))  # turret below z = 0, far from the map
    assert r.status is Status.INCOMPLETE and r.cell is None and r.unknown


def test_collides_many_agrees_with_check(model, guard):
    Q = model.scene_q(model.random_q(80, rng=5))
    got = guard.collides_many(Q)
    want = np.array([guard.check(q).known_distance <= 1e-9 or guard.check(q).unknown_distance <= 1e-9 for q in Q])
    assert got.any() and np.array_equal(got, want)


# ------------------------------------------------------------------------------------------ detector
def test_detector_terrain_category(model, truth, guard):
    sc = model.scene
    plain = armguard.Detector(sc, threshold=0.05)
    assert plain.terrain is None and type(plain.check(sc.flat_q(sc.default_q()))) is DetectionReport
    assert "check" not in plain.__dict__  # nothing attached: the class's check, untouched
    det = armguard.Detector(sc, threshold=0.05, terrain=truth)
    low = np.deg2rad([0, 30, 20, 30, 0])
    rep = det.check(low)
    assert rep.status is Status.COLLISION and rep.detector_status is not None
    t = rep.by_category["terrain"]
    assert t.category == "terrain" and t.b == "terrain" and t.distance == rep.terrain.distance
    assert rep.nearest.distance <= t.distance and t in rep.within_threshold
    for cat in plain.check(low).by_category:  # the kernel's categories are all still there
        assert cat in rep.by_category
    d = json.loads(json.dumps(rep.to_dict()))
    assert d["terrain"]["status"] == "collision" and d["by_category"]["terrain"]["obstacle"] == "terrain"
    again = check_with_terrain(plain, guard, low)
    assert again.terrain.distance == pytest.approx(rep.terrain.distance, abs=1e-12)
    attach_terrain(det, None)
    assert type(det.check(low)) is DetectionReport


# ------------------------------------------------------------------------------------------ sweep
def _dense(guard, traj, n=300):
    ts = np.linspace(0.0, traj.duration, n)
    out = []
    for t in ts:
        known, unknown = guard.distances(np.asarray(traj.at(t)), reach=0.3)[:2]
        out.append((float(known.min()), float(unknown.min())))
    return ts, np.array(out)


def test_sweep_finds_the_first_contact_dense_sampling_confirms(model, guard):
    traj = model.scene.trajectories["place_instrument"]
    sw = sweep_terrain(guard, traj)
    assert sw.status is VerificationStatus.COLLISION
    c = sw.first_contact
    assert c.category == "terrain" and c.obstacle == "terrain" and c.feature.known
    assert c.distance <= guard.tol.verify_contact + 1e-12
    ts, d = _dense(guard, traj)
    before = ts < c.time - 1e-9
    assert np.all(d[before, 0] > -1e-9)  # no sample before the reported contact is inside the terrain
    assert np.any(d[~before, 0] <= 1e-6)  # and the contact is real


def test_sweep_safe_is_proven_dense_sampling_confirms(model, guard):
    traj = _traj([[0, 0, 0, 0, 0], [40, -20, 10, 0, 45], [-40, 0, 0, 0, 0]])  # sweeping high over the ground
    sw = sweep_terrain(guard, traj, stopping_distance=0.02)
    assert sw.status is VerificationStatus.SAFE and sw.first_contact is None and sw.intervals >= 2
    _, d = _dense(guard, traj)
    assert np.all(d[:, 0] >= sw.lower_bound - 1e-9) and sw.lower_bound > 0.02
    assert np.all(d[:, 1] > 0.02 + guard.unknown_margin)


def test_sweep_over_unseen_terrain_is_incomplete(model, truth):
    """Unseen cells under the arm's path: INCOMPLETE, never SAFE (and the time is reported)."""
    traj = _traj([[0, 0, 0, 0, 0], [0, 15, 10, 10, 0]])  # down towards the ground, stopping above it
    g = TerrainGuard(model, truth)
    assert sweep_terrain(g, traj).status is VerificationStatus.SAFE
    known = truth.known.copy()
    known[:, 36:46] = False  # the ground under the arm's reach, unseen
    blind = ElevationMap(truth.heights, truth.origin, truth.cell, known, truth.counts, truth.floor)
    sw = sweep_terrain(TerrainGuard(model, blind, unknown_margin=0.2), traj)
    assert sw.status is VerificationStatus.INCOMPLETE and sw.unknown_at is not None and "unseen" in sw.reason


def test_verify_with_terrain_merges_reports(model, truth):
    sc = model.scene
    rep = verify_with_terrain(sc, sc.trajectories["place_instrument"], truth)
    assert rep.status is VerificationStatus.COLLISION and rep.first_collision.category == "terrain"
    assert "terrain" in rep.profile.by_category and len(rep.profile.time) == len(rep.profile.overall)
    assert np.all(np.diff(rep.profile.time) >= 0)
    json.loads(rep.to_json())
    assert "terrain" in rep.summary()
    safe = verify_with_terrain(sc, _traj([[0, 0, 0, 0, 0], [30, -10, 0, 0, 0]]), truth)
    assert safe.status is VerificationStatus.SAFE and "proven" in safe.reason


# ------------------------------------------------------------------------------------------ body
def test_body_hierarchy_from_the_urdf(model):
    h = BodyHierarchy.from_model(model)
    names = [n.name for n in h.nodes]
    assert h.nodes[0].name == "vehicle" and {"mast", "wheels", "chassis_0"} <= set(names)
    mast = h.nodes[names.index("mast")]
    assert sorted(h.nodes[c].name for c in mast.children) == ["mast_0", "mast_1"]  # the pole and the camera head
    wheels = h.nodes[names.index("wheels")]
    sides = [h.nodes[c] for c in wheels.children]
    assert [s.name for s in sides] == ["wheels:y-", "wheels:y+"]  # the two suspension sides
    assert len(h.shapes) == 9 and h.depth == 4


def test_body_hierarchy_never_misses_what_the_flat_check_finds(model, guard):
    h = BodyHierarchy.from_model(model)
    rng = np.random.default_rng(8)
    Q = model.scene_q(model.random_q(120, rng=9))
    fewer = 0
    for q in Q:
        vols, shapes = guard.posed(q)
        c = float(rng.uniform(0.0, 0.1))
        for exact in (False, True):
            r = h.check(vols, shapes=shapes, exact=exact, clearance=c)
            f = h.check_flat(vols, shapes=shapes, exact=exact, clearance=c)
            assert r.hits == f.hits
            if exact and f.hits:
                assert r.min_distance == pytest.approx(f.min_distance, abs=1e-12)
        fewer += r.tests < f.tests
    assert fewer > len(Q) // 2


def test_body_hierarchy_distance_is_the_detectors(model, guard):
    h = BodyHierarchy.from_model(model)
    det = armguard.Detector(model.scene, threshold=0.05)
    Q = model.scene_q(model.random_q(60, rng=10))
    for q in Q:
        vols, shapes = guard.posed(q)
        r = h.check(vols, shapes=shapes, exact=True, clearance=0.05)
        env = det.check(q).by_category["environment"].distance
        assert r.hit == (env <= 0.05)
        if r.hit:
            assert r.min_distance == pytest.approx(env, abs=1e-7)


def test_body_against_terrain_top_down(model, truth):
    h = BodyHierarchy.from_model(model)
    r = h.check_terrain(guard_pyramid(truth))
    assert r.hit and all(name.startswith("wheels_") for _, name in r.hits)  # the wheels stand on the ground


def guard_pyramid(m):
    from armguard.terrain import TerrainPyramid

    return TerrainPyramid(m)


# ------------------------------------------------------------------------------------------ coal
def test_coal_heightfield_sandwiches_the_pyramid(model):
    m = make_terrain(n=48, cell=0.05, sigma=0.05, rocks=6, seed=12)
    m = ElevationMap.from_heights(m.heights, m.cell, origin=(0.5 - 1.2, -1.2))
    ck = coal_checker(model, m)
    g, gd = TerrainGuard(model, m, unknown_margin=0.0), TerrainGuard(model, dilated(m), unknown_margin=0.0)
    Qp = model.random_q(60, rng=11)
    R, n_sep, n_hit = 0.1, 0, 0
    base = armguard.checker(model, "coal")
    for qp, q in zip(Qp, model.scene_q(Qp)):
        np.testing.assert_allclose(ck.pair_distances(qp).distance, base.pair_distances(qp).distance)  # unchanged
        dc = ck.terrain_distances(qp, reach=R, tol=1e-8)
        dp = np.minimum(*g.distances(q, reach=R)[:2])
        dd = np.minimum(*gd.distances(q, reach=R)[:2])
        for lo, c, hi in zip(dd, dc, dp):
            if hi > 0.0:  # separated from the columns: dilated <= coal <= columns
                n_sep += math.isfinite(c)
                assert lo <= c + 1e-7 and (c <= hi + 1e-7 or math.isinf(hi))
            else:  # a pyramid contact is always a coal contact
                n_hit += 1
                assert c <= 1e-7
    assert n_sep > 10 and n_hit > 5


# ------------------------------------------------------------------------------------------ files, CLI
def test_load_terrain_centres_the_sensed_map_under_the_arm(model):
    m = load_terrain(ROCKY, model.scene, robot="arm")
    centre = m.origin + 0.5 * m.cell * np.array(m.shape[::-1])
    np.testing.assert_allclose(centre, [0.5, 0.0], atol=1e-12)
    assert 0.3 < m.known.mean() < 0.7  # the stereo points: holes, filled conservatively


def test_cli_check_and_verify_with_terrain():
    from armguard.cli import main

    run = CliRunner()
    r = run.invoke(main, ["check", "rover", "--q", "0,30,20,30,0", "--deg", "--terrain", ROCKY, "--json"])
    assert r.exit_code == 1, r.output
    d = json.loads(r.output)
    assert d["status"] == "collision" and d["terrain"]["status"] == "collision"
    r = run.invoke(main, ["check", "rover", "--terrain", ROCKY])
    assert r.exit_code == 0, r.output
    r = run.invoke(main, ["verify", "rover", "place_instrument", "--terrain", ROCKY])
    assert r.exit_code == 1 and "terrain" in r.output


def test_a_collision_names_the_seen_cell_that_decided_it(model):
    """rocky's map, the turret low: a seen cell 36 mm deep makes the COLLISION, beside an unseen cell whose
    filled column is 60 mm deep.  The report (and the CLI's terrain row) named only the unseen cell, as
    if the collision were with ground nobody saw; it now names the seen one, and ``unknown_distance``
    keeps the other."""
    g = TerrainGuard(model, load_terrain("rocky", model))  # as the CLI's --terrain rocky (a Model raised AttributeError)
    r = g.check(np.deg2rad([0, 30, 20, 30, 0]))
    assert r.status is Status.COLLISION and r.unknown_distance < r.known_distance < 0  # the unseen one deeper
    assert not r.unknown and r.distance == r.known_distance and r.pair().feature.kind == "cell"
    assert abs(np.linalg.norm(r.p_WA - r.p_WB) - abs(r.distance)) < 1e-7
    out = CliRunner().invoke(armguard.cli.main, ["-q", "check", "rover", "--q", "0,30,20,30,0", "--deg", "--terrain",
                                                 "rocky", "--json"])
    d = json.loads(out.output)
    rows = [p for p in d["within_threshold"] if p["category"] == "terrain"]
    assert rows and all("unseen" not in json.dumps(p) for p in rows), rows


def test_a_terrain_collisions_headline_is_the_contact_not_the_unseen_cell_before_it(model):
    """rover's place_instrument on rocky: the headline read "COLLISION -- terrain: arm/link3 within 50 mm of
    unseen cell (32, 42) at t = 0.8198 s", the unknown-terrain note, while the contact (with a seen cell)
    is at 1.1244 s: an operator was told of the wrong time and ground."""
    rep = verify_with_terrain(model, model.trajectories["place_instrument"], load_terrain("rocky", model))
    c = rep.first_collision
    assert rep.status is VerificationStatus.COLLISION and c.feature.known
    assert rep.reason.startswith(f"contact with seen terrain at t = {c.time:.4f} s (before it, ") and "unseen cell" in rep.reason
    t_note = float(rep.reason.split(" at t = ")[2].split(" s;")[0])
    assert t_note < c.time


def test_an_incomplete_report_keeps_seen_ground_within_the_threshold(model):
    """INCOMPLETE (an unseen column 60 mm away) with seen ground 27 mm away, inside the 50 mm threshold: the
    seen pair stays the one named and in ``within_threshold`` (naming the unseen one dropped it from both)."""
    sc = model.scene
    det = armguard.Detector(sc, threshold=0.05, terrain=load_terrain("rocky", sc))
    r = det.check(np.array([-1.2148, -0.7106, 2.2112, 0.5489, 2.4902]))
    t = r.terrain
    assert t.status is Status.INCOMPLETE and t.known_distance < 0.05 < t.unknown_distance
    assert t.distance == t.known_distance and not t.unknown
    assert ("terrain", t.known_distance) in [(p.category, p.distance) for p in r.within_threshold]


def test_a_detector_with_terrain_answers_for_it_in_batches():
    """``Detector(scene, terrain=...)``: ``check`` said collision with the ground where ``collides_many`` said
    False and ``check_many`` clear (the kernel's alone).  ``check_many`` now gives ``check``'s status on every row,
    and ``collides_many`` says yes wherever ``check`` says collision (and where it reaches unknown ground)."""
    import armguard
    from armguard.terrain import load_terrain

    model = armguard.load_model("rover")
    det = armguard.Detector(model.scene, threshold=0.05, terrain=load_terrain("rocky", model.scene))
    low = np.deg2rad([0, 30, 20, 30, 0])  # the turret in the ground
    Q = np.vstack([low[None], model.scene_q(model.random_q(12, 3))])
    want = [det.check(q).status for q in Q]
    assert want[0].value == "collision"
    batch = det.check_many(Q)
    assert [s.value for s in batch.statuses()] == [s.value for s in want]
    said = det.collides_many(Q).tolist()  # yes/no: a collision, and (conservatively) unknown ground reached
    assert all(said[i] for i, s in enumerate(want) if s.value == "collision")
    assert all(s.value in ("collision", "incomplete") for s, yes in zip(want, said) if yes)
    armguard.terrain.attach_terrain(det, None)  # detached: the kernel's batches again
    assert not det.collides_many(Q[:1])[0]


@pytest.mark.parametrize("backend", ["analytic", "coal"])
def test_the_terrain_guard_follows_the_active_arm(backend):
    """``set_active`` left the guard on the old arm: a terrain collision of the new one read WARNING (ranger, flat
    ground between where the two arms reach down).  A map's guard and a guard given for one arm both follow it."""
    from armguard.terrain import ElevationMap, TerrainGuard

    m = armguard.load_model("ranger")
    Q = [m.scene_q(q) for q in m.random_q(200, 0)]
    flat = ElevationMap.from_heights(np.zeros((80, 80)), 0.1, origin=(-4.0, -4.0))
    dr = np.array([TerrainGuard(m, flat, robot="right_arm", reach=10.0).check(q).known_distance for q in Q])
    dl = np.array([TerrainGuard(m, flat, robot="left_arm", reach=10.0).check(q).known_distance for q in Q])
    i = int(np.argmax(dl - dr))
    assert dl[i] - dr[i] > 0.02  # 26 mm above the ground and 26 mm into it
    ground = ElevationMap.from_heights(np.full((80, 80), 0.5 * (dr[i] + dl[i])), 0.1, origin=(-4.0, -4.0))
    given = TerrainGuard(m, ground, robot="left_arm")
    for terrain in (ground, given):
        d = armguard.Detector(m, threshold=0.05, active="left_arm", terrain=terrain, backend=backend)
        assert d.check(Q[i]).terrain.status is not armguard.Status.COLLISION  # the left arm is above the ground
        d.set_active("right_arm")
        fresh = armguard.Detector(m, threshold=0.05, active="right_arm", terrain=ground, backend=backend)
        a, b = d.check(Q[i]), fresh.check(Q[i])
        assert d.terrain.robot == "right_arm"
        assert b.terrain.status is armguard.Status.COLLISION and a.status is b.status is armguard.Status.COLLISION
        assert a.terrain.known_distance == b.terrain.known_distance
        assert d.collides_many(np.array([Q[i]]))[0] and d.check_many(np.array([Q[i]])).collision[0]
        d.set_active("left_arm")
        assert d.terrain.robot == "left_arm" and d.check(Q[i]).terrain.status is not armguard.Status.COLLISION
        d.set_active(None)  # every arm: a guard over every robot (the given one covered one arm: kept, it read WARNING)
        assert d.terrain.robot is None
        every = armguard.Detector(m, threshold=0.05, terrain=ground, backend=backend)
        assert d.check(Q[i]).terrain.status is every.check(Q[i]).terrain.status is armguard.Status.COLLISION


def test_the_terrain_part_uses_the_settings_its_check_used(monkeypatch):
    """The guard read the detector's threshold after the kernel's check: another thread's change in between gave a
    report of two settings (144 of ~6k under a toggling thread)."""
    from armguard.terrain import ElevationMap

    m = armguard.load_model("ranger")
    ground = ElevationMap.from_heights(np.full((80, 80), -0.1), 0.1, origin=(-4.0, -4.0))
    d = armguard.Detector(m, threshold=0.05, stopping_distance=0.01, terrain=ground, backend="coal")
    kernel_check, kernel_many = type(d).check, type(d).check_many

    def check_then_change(self, q, **kw):
        r = kernel_check(self, q, **kw)
        self.set_threshold(0.3)
        self.set_stopping_distance(0.1)
        return r

    def many_then_change(self, Q):
        r = kernel_many(self, Q)
        self.set_threshold(0.3)
        self.set_stopping_distance(0.1)
        return r

    monkeypatch.setattr(type(d), "check", check_then_change)
    monkeypatch.setattr(type(d), "check_many", many_then_change)
    q = m.scene_q(m.random_q(1, 0)[0])
    r = d.check(q)
    assert r.threshold == r.terrain.threshold == 0.05 and r.stopping_distance == r.terrain.stopping_distance == 0.01
    d.set_threshold(0.05)
    d.set_stopping_distance(0.01)
    b = d.check_many(np.array([q]))
    monkeypatch.undo()
    d.set_threshold(0.05)
    d.set_stopping_distance(0.01)
    assert b.threshold == 0.05 and b.status[0] == d.check_many(np.array([q])).status[0]



def test_checks_during_set_active_use_the_kernel_and_guard_of_one_arm():
    """A thread toggling set_active while another checked: 3,112 of 8,708 reports had the kernel of one arm and the
    terrain guard of the other (the guard was built and installed after the kernel's new build)."""
    import threading
    import time

    from armguard.terrain import ElevationMap

    m = armguard.load_model("ranger")
    q = m.scene_q(m.random_q(1, 3)[0])
    ground = ElevationMap.from_heights(np.full((80, 80), -5.0), 0.1, origin=(-4.0, -4.0))  # far below: CLEAR
    d = armguard.Detector(m, threshold=0.05, active="left_arm", terrain=ground)
    d.check(q)
    stop = threading.Event()

    def toggle():
        k = 0
        while not stop.is_set():
            d.set_active("right_arm" if k % 2 == 0 else "left_arm")
            k += 1

    t = threading.Thread(target=toggle)
    t.start()
    mixed = total = 0
    try:
        t0 = time.perf_counter()
        while time.perf_counter() - t0 < 3.0:
            r = d.check(q)
            total += 1
            kernel_arm = r.by_category["workspace"].link.split("/")[0]  # the kernel's active arm's link
            terrain_arms = {n.split("/")[0] for n in r.terrain.link_distance}
            mixed += bool(terrain_arms) and kernel_arm not in terrain_arms
    finally:
        stop.set()
        t.join()
    assert total > 50 and mixed == 0, (mixed, total)
