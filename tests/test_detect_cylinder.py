"""The detector on exact cylinders (links, a payload-free arm, static bodies, the workspace walls).

Oracles: :func:`armguard.geometry.distance` per shape pair (GJK + EPA on support functions for a
cylinder side, ``_pair_cylinder``), the brute-force reference (``check_reference``: the scene's own
geometry, the walls through each shape's support function), the all-pairs batch
(``check_many_bruteforce``), and surface samples of the cylinders for the bounding volumes.  A
URDF ``<cylinder>`` (no capsule marking) is an exact Cylinder, compared with coal's.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

import armguard
from armguard.detect import CATEGORIES, Detector, check_reference
from armguard.geometry import Box, Capsule, ConvexPolyhedron, Cylinder, distance
from armguard.scene import Scene, compile_scene

sys.path.insert(0, str(Path(__file__).parent))
from _verify_fixtures import spatial_arm  # noqa: E402


def _rot(rng):
    q = rng.normal(size=4)
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _along(p0, p1, r):
    """The Cylinder whose axis runs from ``p0`` to ``p1`` (link frame), radius ``r``."""
    p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
    a = p1 - p0
    L = np.linalg.norm(a)
    z = a / L
    x = np.cross(z, [1.0, 0.0, 0.0] if abs(z[0]) < 0.9 else [0.0, 1.0, 0.0])
    x /= np.linalg.norm(x)
    return Cylinder(0.5 * (p0 + p1), np.column_stack([x, np.cross(z, x), z]), r, 0.5 * L)


def cylinder_scene() -> Scene:
    """The spatial arm with cylinder links (and a capsule inside one) among static cylinders, boxes,
    a capsule and a hull, in a workspace box."""
    rng = np.random.default_rng(5)
    arm = spatial_arm()
    shapes = dict(arm.link_shapes)
    shapes["link2"] = (_along([-0.4, 0, 0], [0, 0, 0], 0.05),)
    shapes["link3"] = (Cylinder([0.0, 0.0, 0.05], np.eye(3), 0.05, 0.08),)
    shapes["link4"] = (_along([0, 0, -0.2], [0, 0, 0], 0.035), Capsule([0, 0, -0.2], [0, 0, 0], 0.02))
    sc = Scene("cylinders")
    sc.add_robot(arm.with_link_shapes(shapes))
    for k in range(5):
        sc.add_body(f"post{k}", [Cylinder(rng.uniform([-0.7, -0.7, -0.2], [0.7, 0.7, 0.6]), _rot(rng),
                                          rng.uniform(0.03, 0.12), rng.uniform(0.05, 0.3))])
    for k in range(3):
        sc.add_body(f"box{k}", [Box(rng.uniform([-0.6, -0.6, -0.2], [0.6, 0.6, 0.6]), rng.uniform(0.03, 0.12, 3),
                                    _rot(rng))])
    sc.add_body("rod", [Capsule([0.3, -0.5, 0.1], [0.5, -0.2, 0.4], 0.03)])
    sc.add_body("rock", [ConvexPolyhedron(rng.normal(size=(20, 3)) * 0.08 + [-0.4, 0.4, 0.3])])
    sc.set_workspace([-0.9, -0.9, -0.5], [0.9, 0.9, 1.1])
    return sc


@pytest.fixture(scope="module")
def cyl_scene():
    return cylinder_scene()


def _limits(scene):
    lo = np.concatenate([scene.robots[r].lower for r in scene.robots])
    hi = np.concatenate([scene.robots[r].upper for r in scene.robots])
    return np.where(np.isfinite(lo), lo, -np.pi), np.where(np.isfinite(hi), hi, np.pi)


def _by_cat(report):
    return np.array([report.by_category[c].distance if c in report.by_category else np.inf for c in CATEGORIES])


def test_cylinders_compile_as_elements(cyl_scene):
    cs = compile_scene(cyl_scene)
    cyl = np.flatnonzero(cs.elem_core == 4)
    assert len(cyl) == 3 + 5
    for g in cyl:  # pose and size in the box slots, no faces or edges
        assert cs.elem_box_half[g][0] == cs.elem_box_half[g][1] > 0.0
        assert cs.elem_plane_start[g + 1] == cs.elem_plane_start[g]
        assert cs.elem_edge_start[g + 1] == cs.elem_edge_start[g]
        assert cs.elem_radius[g] == 0.0


def test_pair_distances_match_the_geometry_core(cyl_scene):
    """Every pair the detector evaluates, and the walls, against ``armguard.geometry.distance`` /
    the support-function wall distance on the scene's own world-frame shapes."""
    det = Detector(cyl_scene, threshold=0.05)
    cs = det._model.compiled
    lo, hi = _limits(cyl_scene)
    rng = np.random.default_rng(1)
    n_cyl = n_pen = 0
    ws = cyl_scene.workspace
    for q in rng.uniform(lo, hi, size=(30, len(lo))):
        pd = det.pair_distances(q)
        items = cyl_scene.shapes_at(q)
        shape_of = {}
        for it in items:
            shape_of.setdefault(it.owner, []).append(it.shape)
        start = cs.owner_elem_start

        def world(g):
            o = int(cs.elem_owner[g])
            return shape_of[cs.owner_names[o]][g - int(start[o])]

        m = det._model
        for k, p in enumerate(pd.pair_index):
            a, b = int(m.pair_a[p]), int(m.pair_b[p])
            sa = world(a)
            if b < 0:
                ref = min(min(ws.hi[i] - sa.support(np.eye(3)[i])[i], sa.support(-np.eye(3)[i])[i] - ws.lo[i])
                          for i in range(3))
                assert abs(pd.distance[k] - ref) <= 1e-12
                if isinstance(sa, Cylinder):  # the witness is the support point on the wall's side
                    assert abs(np.min(np.concatenate([ws.hi - pd.p_WA[k], pd.p_WA[k] - ws.lo])) - ref) <= 1e-12
                continue
            sb = world(b)
            ref = distance(sa, sb)
            has_cyl = isinstance(sa, Cylinder) or isinstance(sb, Cylinder)
            n_cyl += has_cyl
            if ref.distance > 0.0:
                assert abs(pd.distance[k] - ref.distance) <= 1e-9
                if has_cyl:  # witnesses on the shapes, their gap the distance
                    assert abs(np.linalg.norm(pd.p_WB[k] - pd.p_WA[k]) - pd.distance[k]) <= 1e-9
            else:
                n_pen += has_cyl
                assert pd.distance[k] <= 1e-9
                assert abs(pd.distance[k] - ref.distance) <= 1e-7
    assert n_cyl > 500 and n_pen >= 5


def test_check_matches_brute_force_reference(cyl_scene):
    det = Detector(cyl_scene, threshold=0.05)
    lo, hi = _limits(cyl_scene)
    rng = np.random.default_rng(2)
    statuses = set()
    for q in rng.uniform(lo, hi, size=(40, len(lo))):
        rep = det.check(q)
        ref = check_reference(cyl_scene, q, 0.05)
        got = _by_cat(rep)
        fin = np.isfinite(ref.min_distance)
        assert np.array_equal(np.isfinite(got), fin)
        assert np.max(np.abs(got[fin] - ref.min_distance[fin])) <= 1e-7
        assert rep.status.value == ("clear", "warning", "collision")[ref.status]
        statuses.add(ref.status)
        # the pruned path never drops a pair within the threshold
        within = sorted(d for *_, d in ref.pairs if d <= 0.05)
        assert np.allclose(sorted(r.distance for r in rep.within_threshold), within, atol=1e-7)
        lazy = det.check(q, lazy=True)
        assert lazy.status is rep.status
        assert [r.distance for r in lazy.within_threshold] == [r.distance for r in rep.within_threshold]
    assert 2 in statuses and len(statuses) >= 2


def test_pruned_and_yes_no_batches_agree_with_all_pairs(cyl_scene):
    det = Detector(cyl_scene, threshold=0.05)
    lo, hi = _limits(cyl_scene)
    Q = np.random.default_rng(3).uniform(lo, hi, size=(3000, len(lo)))
    brute = det.check_many_bruteforce(Q)
    exact = det.check_many(Q)
    fin = np.isfinite(brute.min_distance)
    assert np.array_equal(np.isfinite(exact.min_distance), fin)
    assert np.max(np.abs(exact.min_distance[fin] - brute.min_distance[fin])) <= 1e-12
    assert 0.05 < brute.collision.mean() < 0.95
    np.testing.assert_array_equal(exact.collision, brute.collision)
    np.testing.assert_array_equal(det.collides_many(Q), brute.collision)
    stop = Detector(cyl_scene, threshold=0.05, stopping_distance=0.03)
    np.testing.assert_array_equal(stop.collides_many(Q), stop.check_many_bruteforce(Q).collision)
    # a single check's nearest distances are the batch's
    for k in range(0, 3000, 300):
        assert np.array_equal(_by_cat(det.check(Q[k])), exact.min_distance[k])


def _surface(cyl: Cylinder, n: int, rng) -> np.ndarray:
    """Points on the cylinder's side, rims and caps (W)."""
    t = rng.uniform(0, 2 * np.pi, n)
    s = rng.choice([-1.0, 1.0], n) * np.where(rng.random(n) < 0.5, 1.0, rng.random(n))
    rr = np.where(np.abs(s) == 1.0, cyl.radius * np.sqrt(rng.random(n)), cyl.radius)
    rr[::7] = cyl.radius
    s[::7] = rng.choice([-1.0, 1.0], len(s[::7]))
    R = cyl.rotation
    return (cyl.center + (rr * np.cos(t))[:, None] * R[:, 0] + (rr * np.sin(t))[:, None] * R[:, 1]
            + (s * cyl.half_length)[:, None] * R[:, 2])


def test_bounding_volumes_contain_the_cylinders(cyl_scene):
    """Static AABBs, bounding spheres and the yes/no cull's link boxes contain every cylinder."""
    det = Detector(cyl_scene, threshold=0.05)
    m = det._model
    cs = m.compiled
    rng = np.random.default_rng(4)
    obb = det._layout.view(det._MF, "obb_L").reshape(-1, 16)
    n_obb = 0
    for g in np.flatnonzero(cs.elem_core == 4):
        cyl = Cylinder(cs.elem_box_center[g], cs.elem_box_axes[g], cs.elem_box_half[g][0], cs.elem_box_half[g][2])
        p = _surface(cyl, 2000, rng)
        c, r = cs.elem_sphere[g, :3], cs.elem_sphere[g, 3]
        assert np.all(np.linalg.norm(p - c, axis=1) <= r + 1e-12)
        if m.st_idx[g] >= 0:
            s = m.st_idx[g]
            assert np.all(p >= m.static_lo[s]) and np.all(p <= m.static_hi[s])
            lo, hi = cyl.aabb()
            assert np.all(m.static_lo[s] <= lo) and np.all(m.static_hi[s] >= hi)
        else:
            assert obb[g, 15] == 1.0
            cb, h, R = obb[g, 0:3], obb[g, 3:6], obb[g, 6:15].reshape(3, 3)
            assert np.all(np.abs((p - cb) @ R) <= h)
            n_obb += 1
    assert n_obb == 3


def test_wall_distance_of_a_tilted_cylinder_is_its_support():
    """One link cylinder against the walls only: the kernel's distance and witness are the exact
    support along each wall normal (oracle: ``Cylinder.support``), at random poses."""
    arm = spatial_arm()
    shapes = {ln: () for ln in arm.link_names}
    shapes["link6"] = (_along([0, 0, 0], [0.1, 0.05, 0.08], 0.04),)
    sc = Scene("walls")
    sc.add_robot(arm.with_link_shapes(shapes))
    sc.set_workspace([-0.5, -0.6, -0.2], [0.6, 0.5, 0.9])
    det = Detector(sc, threshold=0.05)
    assert det.n_pairs == 1
    lo, hi = _limits(sc)
    for q in np.random.default_rng(6).uniform(lo, hi, size=(200, len(lo))):
        (cyl,) = [it.shape for it in sc.shapes_at(q)]
        gaps = [(sc.workspace.hi[i] - cyl.support(np.eye(3)[i])[i], cyl.support(np.eye(3)[i]), i, 1.0)
                for i in range(3)]
        gaps += [(cyl.support(-np.eye(3)[i])[i] - sc.workspace.lo[i], cyl.support(-np.eye(3)[i]), i, -1.0)
                 for i in range(3)]
        d, p, i, sgn = min(gaps, key=lambda g: g[0])
        pd = det.pair_distances(q)
        assert abs(pd.distance[0] - d) <= 1e-12
        np.testing.assert_allclose(pd.p_WA[0], p, atol=1e-12)
        wall = p.copy()
        wall[i] = sc.workspace.hi[i] if sgn > 0 else sc.workspace.lo[i]
        np.testing.assert_allclose(pd.p_WB[0], wall, atol=1e-12)


_URDF = """<robot name="cyl">
  <link name="base"><collision><origin xyz="0 0 0.05"/><geometry><box size="0.3 0.3 0.1"/></geometry></collision></link>
  <link name="post"><collision><origin xyz="0.45 0.1 0.3" rpy="0.3 0.2 0"/>
    <geometry><cylinder radius="0.06" length="0.5"/></geometry></collision></link>
  <link name="upper"><collision><origin xyz="0.2 0 0" rpy="0 1.5707963267948966 0"/>
    <geometry><cylinder radius="0.05" length="0.4"/></geometry></collision></link>
  <link name="fore"><collision><origin xyz="0.15 0 0" rpy="0 1.5707963267948966 0"/>
    <geometry><cylinder radius="0.04" length="0.3"/></geometry></collision></link>
  <joint name="fix" type="fixed"><parent link="base"/><child link="post"/></joint>
  <joint name="j1" type="revolute"><parent link="base"/><child link="upper"/><origin xyz="0 0 0.15"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="upper"/><child link="fore"/><origin xyz="0.4 0 0"/>
    <axis xyz="0 1 0"/><limit lower="-2.5" upper="2.5" effort="1" velocity="1"/></joint>
</robot>"""


def test_urdf_cylinders_are_exact_and_agree_with_coal(tmp_path):
    urdf = tmp_path / "cyl.urdf"
    urdf.write_text(_URDF)
    model = armguard.load_model(urdf)
    assert dict(model.notes) == {}
    shapes = [it.shape for it in model.scene.shapes_at(np.zeros(len(model.scene.joint_names)))]
    assert sum(isinstance(s, Cylinder) for s in shapes) == 3
    a = armguard.checker(model, "analytic")
    c = armguard.checker(model, "coal")
    rng = np.random.default_rng(7)
    lo = model.pin_model.lowerPositionLimit
    hi = model.pin_model.upperPositionLimit
    n_sep = n_pen = 0
    for q in rng.uniform(lo, hi, size=(300, model.nq)):
        da, dc = a.pair_distances(q), c.pair_distances(q)
        assert np.array_equal(da.pairs, dc.pairs)
        sep = (da.distance > 1e-6) & (dc.distance > 1e-6)
        np.testing.assert_allclose(da.distance[sep], dc.distance[sep], atol=1e-6)
        pen = ~sep
        assert np.array_equal(da.distance[pen] <= 1e-6, dc.distance[pen] <= 1e-6)  # verdicts only
        n_sep += int(sep.sum())
        n_pen += int((da.distance < -1e-3).sum())
    assert n_sep > 300 and n_pen > 5


def test_scene_file_cylinder_loads_saves_and_checks(tmp_path):
    """``type: cylinder`` (radius, full length, local pose; mm and deg converted) in a body and on a
    link: an exact Cylinder, saved and loaded back unchanged, checked by the detector."""
    from armguard.scene import load_scene, save_scene, scene_from_dict

    data = {
        "armguard_scene": 1, "name": "c", "units": {"angle": "deg", "length": "mm"},
        "bodies": [{"name": "post", "xyz": [600, 0, 0], "shapes": [
            {"type": "cylinder", "radius": 50, "length": 800, "xyz": [0, 0, 400], "rpy": [10, 0, 30]}]}],
        "robots": [{"name": "arm", "joints": [{"a": 500, "alpha": 0, "d": 0, "limits": [-90, 90]},
                                               {"a": 400, "alpha": 0, "d": 0, "limits": [-90, 90]}],
                    "link_shapes": {"link1": [{"type": "cylinder", "radius": 40, "length": 500, "xyz": [-250, 0, 0],
                                               "rpy": [0, 90, 0]}],
                                    "link2": [{"type": "link_capsule", "radius": 30}]},
                    "mount": {"xyz": [0, 0, 300]}}],
    }
    sc = scene_from_dict(data, "c.yaml")
    (post,) = sc.bodies["post"].shapes
    assert isinstance(post, Cylinder) and post.radius == pytest.approx(0.05) and post.half_length == pytest.approx(0.4)
    np.testing.assert_allclose(post.center, [0.6, 0.0, 0.4], atol=1e-15)
    back = load_scene(save_scene(sc, tmp_path / "c.yaml"))
    (post2,) = back.bodies["post"].shapes
    assert isinstance(post2, Cylinder)
    np.testing.assert_allclose(post2.center, post.center, atol=1e-12)
    np.testing.assert_allclose(post2.rotation, post.rotation, atol=1e-12)
    assert (post2.radius, post2.half_length) == (post.radius, post.half_length)
    det, det2 = Detector(sc, threshold=0.05), Detector(back, threshold=0.05)
    for q in np.random.default_rng(8).uniform(-1.5, 1.5, size=(20, 2)):
        ref = check_reference(sc, q, 0.05)
        got = _by_cat(det.check(q))
        fin = np.isfinite(ref.min_distance)
        assert np.max(np.abs(got[fin] - ref.min_distance[fin])) <= 1e-7
        np.testing.assert_allclose(_by_cat(det2.check(q)), got, atol=1e-9)
    bad = {**data, "bodies": [{"name": "p", "shapes": [{"type": "cylinder", "radius": 0, "length": 1}]}]}
    from armguard import SceneFileError

    with pytest.raises(SceneFileError, match="radius"):
        scene_from_dict(bad, "c.yaml")
