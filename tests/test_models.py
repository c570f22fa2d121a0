"""The built-in seed systems: counts against their papers, loading, FK, limits, clearance at home.

Golden numbers: Hermes 8 convex polyhedra / 54 faces / 76 vertices (Sciomachen & Magnani, seed
001); Ranger's module make-up and ten canned tests (Bon & Seraji, seed 000); the PUMA 560
standard DH table and limits (Corke's puma560, as cited in the file).  Clearance at home is
measured with python-fcl, an independent library.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from armguard.geometry import Box, Capsule, ConvexPolyhedron, Polygon, Prism, Sphere
from armguard.harness import seed_data
from armguard.kinematics import task_coordinates
from armguard.models import builtin_names, builtin_path
from armguard.scene import PairCategory, compile_scene, load_scene

NAMES = builtin_names()
HERMES = seed_data("hermes")["model"]  # reference/seeds/hermes.yaml


@pytest.fixture(scope="module")
def scenes():
    return {n: load_scene(n) for n in NAMES}


def _counts(shape):
    p = shape.as_polyhedron() if isinstance(shape, (Box, Prism)) else shape
    return len(p.faces), len(p.vertices)


def test_hermes_is_8_polyhedra_54_faces_76_vertices(scenes):
    s = scenes["hermes"]
    shapes = [sh for b in s.bodies.values() for sh in b.shapes]
    assert len(shapes) == HERMES["polyhedra"]
    assert all(isinstance(sh, (Box, Prism, ConvexPolyhedron)) for sh in shapes)
    faces = sum(_counts(sh)[0] for sh in shapes)
    verts = sum(_counts(sh)[1] for sh in shapes)
    assert (faces, verts) == (HERMES["faces"], HERMES["vertices"])
    c = compile_scene(s)
    assert c.n_faces == HERMES["faces"]
    per_body = {b.name: [_counts(sh) for sh in b.shapes] for b in s.bodies.values()}
    assert per_body["tail"] == [(9, 14)]  # a prism with 7 base sides
    assert per_body["cockpit"] == [(9, 14)]
    assert per_body["cargo_bay"] == [(6, 8)] * 3  # three 4-sided prisms


def test_hermes_arm_and_pairs(scenes):
    s = scenes["hermes"]
    hera = s.robots["hera"]
    assert hera.n_joints == 6
    X = hera.forward_kinematics(np.zeros(6))
    # link 5 has zero length (seed 001) and no shape: its frame (URDF: at joint 5) is where link 4 ends
    (cap4,) = hera.link_shapes["link4"]
    end4_W = X[hera.link_index("link4")] @ np.append(cap4.p1, 1.0)
    assert np.linalg.norm(X[hera.link_index("link5"), :3, 3] - end4_W[:3]) == pytest.approx(0.0, abs=1e-9)
    assert not hera.link_shapes["link5"]
    # about 10 m stretched out: sum of the segment lengths from the base to the tool
    pts = X[:, :3, 3]
    assert 9.5 <= float(np.sum(np.linalg.norm(np.diff(pts, axis=0), axis=1))) <= 11.0
    arm_arm = s.allowed_pairs_by_category()[PairCategory.ARM_ARM]
    listed = {tuple(sorted((a.split("/")[1], b.split("/")[1]))) for a, b in arm_arm}
    assert listed == {("link1", "link3"), ("link1", "link4"), ("link1", "link6"), ("link2", "link4"),
                      ("link2", "link6"), ("link3", "link6")}
    assert "payload" in s.payloads
    assert len(s.trajectories) >= 2


def test_ranger_make_up(scenes):
    s = scenes["ranger"]
    assert set(s.robots) == {"left_arm", "right_arm", "camera_arm", "grapple_arm"}
    assert s.robots["left_arm"].n_joints == 7 and s.robots["right_arm"].n_joints == 7
    assert isinstance(s.bodies["manipulator_module"].shapes[0], Box)
    he = s.bodies["manipulator_module"].shapes[0].half_extents
    assert np.allclose(he, he[0])  # cubical
    assert len(s.bodies["propulsion_module"].shapes[0].faces) == 8 + 2  # octagonal prism (a convex mesh in URDF)
    assert len(s.bodies["electronics_module"].shapes[0].faces) == 6  # tapered square section
    assert all(isinstance(s.bodies[n].shapes[0], Polygon) for n in ("left_solar_array", "right_solar_array"))
    for arm in ("left_arm", "right_arm"):
        assert all(isinstance(sh, Capsule) for shs in s.robots[arm].link_shapes.values() for sh in shs)
    assert all(b.category == "vehicle" for b in s.bodies.values())
    assert s.workspace is not None
    # seed 000 section 2: "centered on the Ranger manipulator module" (the manipulator frame's origin)
    assert np.allclose(s.workspace.center, 0.0)
    assert len(s.canned_tests) == 10


def _box_clearance(scene, test) -> float:
    """The active arm's clearance to the workspace box at the end of a canned test, by the seed's own
    end-point rule (seed 000 section 3: each capsule end-point against each box limit, minus the radius)."""
    traj = test.trajectory(scene)
    rob = scene.robots[test.robot]
    X_WL = rob.forward_kinematics(np.asarray(traj.at(traj.duration)))
    lo, hi = scene.workspace.lo, scene.workspace.hi
    d = math.inf
    for ln, shapes in rob.link_shapes.items():
        X = X_WL[rob.link_names.index(ln)]
        for sh in shapes:
            for p_L in (sh.p0, sh.p1):
                p_W = X[:3, :3] @ p_L + X[:3, 3]
                d = min(d, float(np.min(hi - p_W)) - sh.radius, float(np.min(p_W - lo)) - sh.radius)
    return d


def test_ranger_box_clearances_in_the_descriptions(scenes):
    """The canned tests that name a distance to the centred workspace box end at that distance."""
    s = scenes["ranger"]
    named = {}
    for name, ct in s.canned_tests.items():
        words = ct.description.replace(";", " ").split()
        for i, w in enumerate(words[:-5]):
            if words[i + 1:i + 5] == ["m", "from", "the", "workspace"]:
                named[name] = float(w)
    assert set(named) == {"test3_left_forward_up", "test4_left_down"}
    for name, d in named.items():
        assert _box_clearance(s, s.canned_tests[name]) == pytest.approx(d, abs=0.005), name


def test_ranger_canned_tests_are_trapezoids_within_limits(scenes):
    """Seed 000 section 6: every Test button moves the active arm "in one or more of the six
    end-effector coordinates or the arm angle", from rest to rest, within the joint limits."""
    s = scenes["ranger"]
    modes = [ct.mode for ct in s.canned_tests.values()]
    assert "joint" not in modes and modes.count("arm_angle") == 3 and modes.count("end_effector") == 7
    for ct in s.canned_tests.values():
        assert set(ct.setup) == set(s.robots)
        traj = ct.trajectory(s)
        robot = s.robots[ct.robot]
        q = traj.waypoints
        assert np.all(q >= robot.lower - 1e-12) and np.all(q <= robot.upper + 1e-12)
        assert np.all(traj.peak_velocity() <= robot.max_velocity)
        assert np.array_equal(q[0], ct.setup[ct.robot])
        x0, x1 = task_coordinates(robot, q[0]), task_coordinates(robot, q[-1])
        delta = np.append(ct.end_effector, 0.0) if ct.mode == "end_effector" else np.r_[np.zeros(6), ct.arm_angle]
        np.testing.assert_allclose(x1 - x0, delta, atol=1e-9, err_msg=ct.name)
        speed = np.max(np.abs(np.diff(q, axis=0)) / np.diff(traj.times)[:, None], axis=1)
        assert speed[0] < 0.1 * speed.max() and speed[-1] < 0.1 * speed.max(), ct.name  # from rest to rest


def test_puma560_published_dh_and_limits(scenes):
    s = scenes["puma560"]
    r = s.robots["puma560"]
    # the URDF (written by tools/dh_to_urdf) reproduces the published standard DH table's frames
    a = [0.0, 0.4318, 0.0203, 0.0, 0.0, 0.0]
    d = [0.0, 0.0, 0.15005, 0.4318, 0.0, 0.0]
    alpha = np.radians([90, 0, -90, 90, -90, 0])
    rng = np.random.default_rng(7)
    for q in rng.uniform(r.lower, r.upper, size=(20, 6)):
        T = r.X_WB.copy()
        for i in range(6):
            c, sn, ca, sa = np.cos(q[i]), np.sin(q[i]), np.cos(alpha[i]), np.sin(alpha[i])
            T = T @ np.array([[c, -sn * ca, sn * sa, a[i] * c], [sn, c * ca, -c * sa, a[i] * sn],
                              [0, sa, ca, d[i]], [0, 0, 0, 1]])
        X_last = r.forward_kinematics(q)[r.link_index("link6")]
        X_tool = r.forward_kinematics(q)[r.link_index("tool")]
        # the DH frame 6 is link6's URDF frame moved by the last row's (a, alpha) = (0, 0): link6 itself
        np.testing.assert_allclose(X_last[:3, 3], T[:3, 3], atol=1e-9)
        np.testing.assert_allclose(X_last[:3, :3], T[:3, :3], atol=1e-9)
        assert np.all(np.isfinite(X_tool))
    assert np.allclose(np.degrees(r.lower), [-160, -45, -225, -110, -100, -266])
    assert np.allclose(np.degrees(r.upper), [160, 225, 45, 170, 100, 266])
    assert {"table", "block_a", "block_b", "cylinder_a", "cylinder_b"} <= set(s.bodies)


def test_puma560_pick_and_place_reaches_the_cylinders(scenes):
    s = scenes["puma560"]
    r = s.robots["puma560"]
    traj = s.trajectories["pick_and_place"]
    X = r.forward_kinematics(traj.waypoints)[:, r.link_index("tool")]
    a = s.bodies["cylinder_a"].shapes[0].vertices.mean(axis=0)  # a prism's vertices: symmetric about its centre
    b = s.bodies["cylinder_b"].shapes[0].vertices.mean(axis=0)
    grasp, place = X[2, :3, 3], X[5, :3, 3]
    assert np.linalg.norm(grasp[:2] - a[:2]) < 2e-3  # above the centre of cylinder_a (rounded joint values)
    assert np.linalg.norm(place[:2] - b[:2]) < 2e-3
    assert np.allclose(X[2, :3, 2], [0, 0, -1], atol=1e-3)  # the hand points down


def test_gmf_parallelogram_keeps_the_flange_level(scenes):
    s = scenes["gmf_s480"]
    r = s.robots["gmf_s480"]
    # the parallelogram as URDF mimic joints: a virtual joint j4_j2 = -j2 in series with j3 (elbow = j3 - j2),
    # and the wrist pitch j4 = -j3 that keeps the flange level
    assert r.joint_names == ("j1", "j2", "j3", "j5") and len(r.couplings) == 2
    rng = np.random.default_rng(1)
    q = rng.uniform(r.lower, r.upper, size=(50, 4))
    z = r.forward_kinematics(q)[:, -1, :3, 2]
    assert np.allclose(z, [0.0, 0.0, -1.0], atol=1e-12)


def test_rover_make_up(scenes):
    s = scenes["rover"]
    assert s.robots["arm"].n_joints == 5
    assert len(s.bodies["wheels"].shapes) == 6 and set(s.bodies) >= {"chassis", "mast"}


@pytest.mark.parametrize("name", NAMES, ids=NAMES)
def test_each_scene_loads_fk_runs_and_trajectories_within_limits(scenes, name):
    s = scenes[name]
    q = s.default_q()
    items = s.shapes_at(q)
    assert items and all(np.all(np.isfinite(it.shape.aabb()[0])) for it in items)
    for rname, robot in s.robots.items():
        X = robot.forward_kinematics(np.stack([q[rname]] * 3))
        assert X.shape == (3, len(robot.link_names), 4, 4)
    for tname, traj in s.trajectories.items():
        robot = s.robots[traj.robot_name]
        _, qs = traj.sample(frequency=10.0)
        assert np.all(qs >= robot.lower - 1e-12) and np.all(qs <= robot.upper + 1e-12), tname
    assert "assumed" in builtin_path(name).read_text()


@pytest.mark.parametrize("name", NAMES, ids=NAMES)
def test_home_is_clear_by_python_fcl(scenes, name):
    fcl = pytest.importorskip("fcl")
    s = scenes[name]
    by = {}
    for it in s.shapes_at():
        by.setdefault(it.owner, []).append(_fcl_object(fcl, it.shape))
    req = fcl.DistanceRequest(enable_signed_distance=True)
    worst = math.inf
    for p in s.allowed_pairs():
        for a in by[p.a]:
            for b in by[p.b]:
                worst = min(worst, fcl.distance(a, b, req, fcl.DistanceResult()))
    assert worst > 0.0


def _fcl_object(fcl, shape):
    if isinstance(shape, Sphere):
        return fcl.CollisionObject(fcl.Sphere(shape.radius), fcl.Transform(shape.center))
    if isinstance(shape, Capsule):
        d = shape.p1 - shape.p0
        L = float(np.linalg.norm(d))
        z = d / L
        x = np.cross(z, [1.0, 0.0, 0.0] if abs(z[0]) < 0.9 else [0.0, 1.0, 0.0])
        x /= np.linalg.norm(x)
        R = np.column_stack([x, np.cross(z, x), z])
        return fcl.CollisionObject(fcl.Capsule(shape.radius, L), fcl.Transform(R, 0.5 * (shape.p0 + shape.p1)))
    if isinstance(shape, Box):
        return fcl.CollisionObject(fcl.Box(*(2 * shape.half_extents)), fcl.Transform(shape.rotation, shape.center))
    if isinstance(shape, Polygon):
        m = fcl.BVHModel()
        v = np.asarray(shape.vertices)
        tris = np.array([[0, i, i + 1] for i in range(1, len(v) - 1)])
        m.beginModel(len(v), len(tris))
        m.addSubModel(v, tris)
        m.endModel()
        return fcl.CollisionObject(m, fcl.Transform())
    poly = shape.as_polyhedron() if isinstance(shape, Prism) else shape
    faces = []
    for f in poly.faces:
        faces.extend([len(f), *map(int, f)])
    return fcl.CollisionObject(fcl.Convex(np.asarray(poly.vertices), len(poly.faces), np.array(faces)), fcl.Transform())
