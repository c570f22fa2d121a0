"""armguard.clip: curved obstacles as short segments and ruled strips (Smith §IV).

A Cylinder / Sphere / Capsule obstacle is clipped as its circumscribed polytope within the chord
tolerance; the oracle is the exact signed distance to the *true* curved shape
(``armguard.geometry.distance``: GJK + EPA on the cylinder's support function).  Conservative:
every true contact is answered INTERSECTED or MAYBE; a false alarm (INTERSECTED while the shape
is clear) only where the shape is within ``Obstacle.band <= chord_tol`` of the guard.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

import armguard
from armguard.clip import ClipModel, ClipStatus, Guard, Obstacle, check, chord_sides, circumscribed_band, curved_polytopes
from armguard.geometry import Box, Capsule, Cylinder, Sphere, distance
from _geometry_strategies import random_shape

ROUND = 1e-6  # the exact distance's own round-off allowance (GJK/EPA on the support function)


def _random_pose(rng, spread=0.3):
    X = np.eye(4)
    X[:3, :3] = Rotation.random(random_state=int(rng.integers(2**31))).as_matrix()
    X[:3, 3] = rng.uniform(-spread, spread, 3)
    return X


def _point_distance(p, shape) -> float:
    return distance(Sphere(p, 0.0), shape).distance


def test_a_cylinder_obstacle_is_accepted_where_it_raised_clip_error():
    cyl = Cylinder([0.2, 0.0, 0.0], np.eye(3), 0.1, 0.3)
    ob = Obstacle.from_shape(cyl)  # raised ClipError ("a Cylinder is curved") before §IV's approximation
    assert ob.shape is cyl and 0.0 < ob.band <= armguard.DEFAULT_TOLERANCES.clip_chord
    n = chord_sides(0.1, armguard.DEFAULT_TOLERANCES.clip_chord)
    assert ob.n_vertices == 2 * n
    g = Guard.from_shape(Capsule([0, 0, 0], [0.4, 0, 0], 0.05))
    X = np.eye(4)
    X[:3, 3] = [0.0, 0.0, 0.34]  # the capsule's underside 1 cm below the top cap (z = 0.3)
    assert check(g, ob, X).status is ClipStatus.INTERSECTED
    X[:3, 3] = [0.0, 0.0, 0.36]  # 1 cm above it
    assert check(g, ob, X).status is ClipStatus.CLEAR
    X[:3, 3] = [0.0, 0.25, 0.0]  # beside the curved side: 0.25 - 0.05 - 0.1 = 0.1 m clear
    assert check(g, ob, X).status is ClipStatus.CLEAR
    X[:3, 3] = [0.0, 0.14, 0.0]  # 1 cm into it
    assert check(g, ob, X).status is ClipStatus.INTERSECTED
    # the lower-level model with a cylinder among its statics (ClipError before)
    model = ClipModel([("link", Capsule([0, 0, 0], [0.4, 0, 0], 0.05))], [("post", cyl), ("ball", Sphere([1, 0, 0], 0.1))])
    assert model.check(np.eye(4)[None]).status is ClipStatus.INTERSECTED


@pytest.mark.parametrize("r", [0.01, 0.1, 0.5, 2.0])
@pytest.mark.parametrize("tol", [1e-4, 1e-3, 1e-2])
def test_chord_sides_is_the_fewest_within_the_tolerance(r, tol):
    n = chord_sides(r, tol)
    assert circumscribed_band(r, n) <= tol
    assert n == 3 or circumscribed_band(r, n - 1) > tol
    # reference: the circumscribed n-gon's vertex radius, r / cos(pi / n), minus r
    assert circumscribed_band(r, n) == pytest.approx(r / math.cos(math.pi / n) - r, rel=1e-12)


def test_chord_sides_refuses_what_it_cannot_meet():
    with pytest.raises(armguard.ClipError, match="max_prism_sides"):
        chord_sides(1.0, 1e-9)
    with pytest.raises(armguard.ClipError):
        chord_sides(0.0, 1e-3)
    with pytest.raises(armguard.ClipError):
        Obstacle.from_shape(Cylinder([0, 0, 0], np.eye(3), 0.1, 0.1), chord_tol=-1.0)


@pytest.mark.parametrize("seed", range(4))
def test_cylinder_polytopes_bracket_the_cylinder_within_the_band(seed):
    rng = np.random.default_rng(seed)
    R = Rotation.random(random_state=seed).as_matrix()
    cyl = Cylinder(rng.uniform(-1, 1, 3), R, rng.uniform(0.02, 0.6), rng.uniform(0.05, 0.8))
    tol = float(rng.choice([1e-4, 1e-3, 5e-3]))
    outer, inner, band = curved_polytopes(cyl, tol)
    n = len(outer.vertices) // 2
    assert band == pytest.approx(circumscribed_band(cyl.radius, n), rel=1e-12) and band <= tol
    # outer: every vertex within the band of the cylinder, the farthest exactly at it
    d_out = np.array([_point_distance(v, cyl) for v in outer.vertices])
    assert np.all(d_out <= band + 1e-9) and d_out.max() == pytest.approx(band, abs=1e-9)
    # outer contains the cylinder: its support along any direction reaches the cylinder's
    for u in rng.normal(size=(50, 3)):
        u /= np.linalg.norm(u)
        assert float(np.max(outer.vertices @ u)) >= float(cyl.support(u) @ u) - 1e-12
    # inner: vertices on the cylinder, its faces' chords the sagitta r (1 - cos(pi/n)) inside
    assert np.all(np.abs([_point_distance(v, cyl) for v in inner.vertices]) <= 1e-9)
    ax = cyl.rotation[:, 2]
    side = np.abs(inner.planes[:, :3] @ ax) < 1e-9
    depth = cyl.radius - (inner.planes[side, 3] - inner.planes[side, :3] @ cyl.center)
    assert np.allclose(depth, cyl.radius * (1.0 - math.cos(math.pi / n)), atol=1e-12)


@pytest.mark.parametrize("shape", [Sphere([0.1, -0.2, 0.3], 0.1), Capsule([0, 0, 0], [0.3, 0.1, -0.2], 0.08)])
def test_round_obstacles_are_circumscribed_within_the_tolerance(shape):
    tol = 2e-3
    outer, inner, band = curved_polytopes(shape, tol)
    d = np.array([_point_distance(v, shape) for v in outer.vertices])
    assert band <= tol and np.all(d <= band + 1e-9) and d.max() == pytest.approx(band, abs=1e-9)
    rng = np.random.default_rng(3)
    for u in rng.normal(size=(200, 3)):
        u /= np.linalg.norm(u)
        assert float(np.max(outer.vertices @ u)) >= float(shape.support(u) @ u) - 1e-12
    assert np.all(np.array([_point_distance(v, shape) for v in inner.vertices]) <= 1e-9)
    ob = Obstacle.from_shape(shape, chord_tol=tol)
    assert ob.band == band


def _verdict_ok(status, d, band):
    """Conservative with respect to the true shape: no contact answered CLEAR; INTERSECTED only
    within ``band`` of contact."""
    if d <= 0.0 and status is ClipStatus.CLEAR:
        return False
    if status is ClipStatus.INTERSECTED and d > band + ROUND:
        return False
    return True


def test_differential_against_exact_distances():
    """Random guards (each kind) against random cylinders, sphere and capsule obstacles."""
    rng = np.random.default_rng(26)
    guards = []
    for kind in ["capsule", "sphere", "box", "prism", "polyhedron"]:
        while True:
            s = random_shape(kind, rng, spread=0.0)
            if kind not in ("sphere", "capsule") or s.radius >= 0.05:
                break
        guards.append(Guard.from_shape(s))
    obstacles = []
    for i in range(8):
        R = Rotation.random(random_state=i).as_matrix()
        obstacles.append(Cylinder(rng.uniform(-0.3, 0.3, 3), R, rng.uniform(0.03, 0.3), rng.uniform(0.05, 0.5)))
    obstacles += [Sphere([0.1, 0.0, 0.0], 0.15), Capsule([-0.2, 0.1, 0.0], [0.2, -0.1, 0.1], 0.1)]
    tol = 5e-3  # coarse, so the band is wide enough to show up
    obs = [Obstacle.from_shape(s, chord_tol=tol) for s in obstacles]
    counts = {s: 0 for s in ClipStatus}
    false_alarms = misses = 0
    for k in range(1500):
        g, ob = guards[k % len(guards)], obs[k % len(obs)]
        X = _random_pose(rng, 0.6)
        r = check(g, ob, X)
        d = distance(g.shape.transformed(X), ob.shape).distance
        counts[r.status] += 1
        assert _verdict_ok(r.status, d, ob.band), (k, r, d, ob.band)
        misses += d <= 0.0 and r.status is ClipStatus.CLEAR
        false_alarms += d > ROUND and r.status is ClipStatus.INTERSECTED
    assert misses == 0
    assert counts[ClipStatus.INTERSECTED] > 200 and counts[ClipStatus.CLEAR] > 200  # both answers exercised


def test_false_alarm_only_inside_the_band():
    """A guard slid toward the cylinder's curved side through a polygon vertex: INTERSECTED
    starts no later than true contact and no earlier than ``band`` before it."""
    cyl = Cylinder([0, 0, 0], np.eye(3), 0.2, 0.3)
    ob = Obstacle.from_shape(cyl, chord_tol=1e-2)
    n = ob.n_vertices // 2
    g = Guard.from_shape(Sphere([0, 0, 0], 0.05), max_depth=4)
    # the prism's vertices sit at the angles of Prism's polygon: find the farthest vertex direction
    v = ob.geom[0][np.argmax(ob.geom[0][:, 0])]
    u = np.array([v[0], v[1], 0.0]) / np.hypot(v[0], v[1])
    onset_true, onset_clip = None, None
    for gap in np.linspace(0.03, -0.01, 401):  # true gap between sphere and cylinder
        X = np.eye(4)
        X[:3, 3] = u * (0.2 + 0.05 + gap)
        s = check(g, ob, X).status
        if s is ClipStatus.INTERSECTED and onset_clip is None:
            onset_clip = gap
        if gap <= 0.0 and onset_true is None:
            onset_true = gap
        assert _verdict_ok(s, gap, ob.band)
    assert onset_clip is not None and onset_clip >= onset_true
    assert onset_clip <= ob.band + 1e-4 and ob.band == pytest.approx(circumscribed_band(0.2, n))
    assert onset_clip > 0.5 * ob.band  # through a vertex the band is (nearly) all used: the false-alarm band is real


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    r=st.floats(0.02, 0.4),
    h=st.floats(0.02, 0.5),
    tol=st.sampled_from([1e-3, 4e-3, 1e-2]),
    guard_r=st.floats(0.03, 0.2),
    guard_len=st.floats(0.0, 0.5),
    rot=st.integers(0, 2**31 - 1),
    t=st.tuples(st.floats(-0.8, 0.8), st.floats(-0.8, 0.8), st.floats(-0.8, 0.8)),
)
def test_property_cylinder_verdict_is_conservative(r, h, tol, guard_r, guard_len, rot, t):
    cyl = Cylinder([0.0, 0.0, 0.0], Rotation.random(random_state=rot).as_matrix(), r, h)
    ob = Obstacle.from_shape(cyl, chord_tol=tol)
    assert 0.0 < ob.band <= tol
    g = _capsule_guard(guard_r, guard_len)
    X = np.eye(4)
    X[:3, :3] = Rotation.random(random_state=rot + 1).as_matrix()
    X[:3, 3] = t
    s = check(g, ob, X).status
    d = distance(g.shape.transformed(X), cyl).distance
    assert _verdict_ok(s, d, ob.band), (s, d, ob.band)


_GUARDS: dict = {}


def _capsule_guard(radius, length):
    key = (round(radius, 2), round(length, 2))  # a small cache: guards are built once per size
    if key not in _GUARDS:
        _GUARDS[key] = Guard.from_shape(Capsule([0, 0, 0], [key[1], 0, 0], key[0]) if key[1] > 0 else Sphere([0, 0, 0], key[0]))
    return _GUARDS[key]


def test_polyline_is_its_segments():
    ang = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    ring = np.stack([0.3 * np.cos(ang), 0.3 * np.sin(ang), np.zeros_like(ang)], 1)
    wire = Obstacle.polyline(ring, closed=True)
    assert wire.geom[1].shape == (24, 2)
    g = Guard.from_shape(Sphere([0, 0, 0], 0.05))
    rng = np.random.default_rng(5)
    for _ in range(200):
        X = np.eye(4)
        X[:3, 3] = rng.uniform(-0.4, 0.4, 3) * [1, 1, 0.2]
        s = check(g, wire, X).status
        d = min(distance(g.shape.transformed(X), Capsule(ring[i], ring[(i + 1) % 24], 0.0)).distance for i in range(24))
        assert not (s is ClipStatus.CLEAR and d <= 0.0) and not (s is ClipStatus.INTERSECTED and d > ROUND)
    with pytest.raises(armguard.ClipError):
        Obstacle.polyline([[0, 0, 0]])


def test_clip_backend_with_cylinders_is_never_wrong_against_coal():
    from armguard.kinematics import Robot
    from armguard.model import model_from_scene
    from armguard.scene import Scene

    arm = Robot.from_dh("arm", [(0.5, 0.0, 0.0), (0.4, 0.0, 0.0)], lower=[-3, -3], upper=[3, 3],
                        link_shapes={"link1": [Capsule([-0.5, 0, 0], [0, 0, 0], 0.05)],
                                     "link2": [Cylinder([-0.2, 0, 0], Rotation.from_euler("y", 90, degrees=True).as_matrix(), 0.04, 0.2)]})
    scene = Scene("cell")
    scene.add_robot(arm)
    scene.add_body("post", [Cylinder([0.3, 0.4, 0.0], np.eye(3), 0.1, 0.5)])
    scene.add_body("crate", [Box([-0.5, -0.5, 0.0], [0.1, 0.1, 0.3])])
    model = model_from_scene(scene)
    clip = armguard.checker(model, "clip")  # BackendError ("a Cylinder is curved") before
    coal = armguard.checker(model, "coal")
    kinds = {(g, o): k for k, g, o in clip.plans}
    assert "bracket" in kinds.values()
    Q = model.random_q(400, 11)
    batch = clip.check_pairs(Q)
    D = np.array([coal.pair_distances(q).distance for q in Q])
    wrong = ((batch.pair_codes == 0) & (D <= 0.0)) | ((batch.pair_codes == 1) & (D > 0.0))
    assert not wrong.any()
    assert np.any(batch.pair_codes == 1) and np.any(batch.pair_codes == 0)


@pytest.mark.parametrize("seed", range(3))
def test_cylinder_guard_is_never_wrong(seed):
    """A Cylinder as the guarded test object (the backend's cylinder-against-cylinder pairs):
    ``PI ⊂ cylinder ⊂ PO`` and every definite answer right against the exact distance."""
    rng = np.random.default_rng(100 + seed)
    cyl = Cylinder([0.0, 0.0, 0.0], Rotation.random(random_state=seed).as_matrix(), rng.uniform(0.05, 0.3), rng.uniform(0.05, 0.4))
    g = Guard.from_shape(cyl)
    assert np.all(np.array([_point_distance(v, cyl) for v in g.inner.vertices]) <= 1e-9)
    for u in rng.normal(size=(50, 3)):
        u /= np.linalg.norm(u)
        assert float(np.max(g.outer.vertices @ u)) >= float(cyl.support(u) @ u) - 1e-12
    maybe = 0
    for k in range(150):
        sh = random_shape(["box", "capsule", "polyhedron", "prism", "polygon"][k % 5], rng, spread=0.5)
        ob = Obstacle.from_shape(sh)
        X = _random_pose(rng, 0.3)
        s = check(g, ob, X).status
        d = distance(cyl.transformed(X), sh).distance
        assert _verdict_ok(s, d, ob.band), (k, s, d)
        maybe += s is ClipStatus.MAYBE
    assert maybe < 30
