"""Defects found by adversarial testing: unbounded work, solids far from the origin, a loader that
took ``true`` as a radius, a scene without robots, and the contact tolerance of ``intersects``."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
import pytest

import armguard
from armguard import DEFAULT_TOLERANCES, DetectionError, GeometryError, SceneFileError, VerificationError
from armguard.geometry import Box, Capsule, ConvexPolyhedron, Prism, Sphere, distance, intersects
from armguard.kinematics import Trajectory
from armguard.scene import Scene, load_scene_file, scene_from_dict

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _geometry_strategies import KINDS, random_shape  # noqa: E402
from _verify_fixtures import planar_arm  # noqa: E402

# ---------------------------------------------------------------- unbounded work


def _arm_scene():
    sc = Scene("arm")
    sc.add_robot(planar_arm(radius=0.005), self_pairs=[])
    sc.add_body("rod", [Capsule([0.9, 0.5, -0.2], [0.9, 0.5, 0.2], 0.003)])
    return sc


def _motion(sc):
    return Trajectory.joint_interpolated(sc.robots["arm"], np.array([[0.0, 0.0, 0.0], [1.0, 0.5, 0.0]]),
                                         profile="linear", times=[0.0, 2.0])


@pytest.mark.parametrize("kw", [{"joint_step": 1e-9}, {"joint_step": 1e-6}, {"frequency": 1e9}, {"frequency": 1e6}])
def test_sampled_verification_refuses_an_unbounded_request_at_once(kw):
    sc = _arm_scene()
    t0 = time.perf_counter()
    with pytest.raises(VerificationError) as info:
        armguard.verify(sc, _motion(sc), method="sampled", **kw)
    assert time.perf_counter() - t0 < 5.0
    assert "verify_max_evaluations" in str(info.value) and next(iter(kw)) in str(info.value)


def test_sampled_verification_within_the_bound_still_runs():
    sc = _arm_scene()
    for kw in ({"joint_step": 0.01}, {"frequency": 100.0}):
        rep = armguard.verify(sc, _motion(sc), method="sampled", **kw)
        assert rep.status.value in ("safe", "collision")


def test_a_prism_with_too_many_sides_is_refused_by_the_shape_and_the_loader(tmp_path):
    bound = DEFAULT_TOLERANCES.max_prism_sides
    Prism([0, 0, 0], np.eye(3), 0.05, 0.1, bound)  # the bound itself is allowed
    with pytest.raises(GeometryError, match="max_prism_sides"):
        Prism([0, 0, 0], np.eye(3), 0.05, 0.1, bound + 1)
    with pytest.raises(GeometryError):
        Prism([0, 0, 0], np.eye(3), 0.05, 0.1, True)
    t0 = time.perf_counter()
    for n in (100_000, 1_000_000):
        with pytest.raises(SceneFileError) as info:
            scene_from_dict(_one_shape(f"{{type: prism, n_sides: {n}, apothem: 0.1, length: 0.2}}", tmp_path))
        assert "bodies[0].shapes[0].n_sides" in str(info.value)
    assert time.perf_counter() - t0 < 5.0


# ---------------------------------------------------------------- far from the origin


def _cube(o, h):
    return ConvexPolyhedron(np.asarray(o) + h * np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]))


@pytest.mark.parametrize("big", [1e4, 1e5, 1e6])
def test_valid_solids_far_from_the_origin_are_solids(big):
    o = np.array([big] * 3)
    cube = _cube(o, 0.01)  # a 2 cm cube
    assert len(cube.faces) == 6
    r = distance(Prism(o, np.eye(3), 0.05, 0.1, 8), Sphere(o + [1.0, 0.0, 0.0], 0.1))
    assert r.distance == pytest.approx(0.85, abs=1e-6)
    with pytest.raises(GeometryError, match="coplanar"):  # a flat set is still refused
        ConvexPolyhedron(o + np.array([[0, 0, 0], [0.01, 0, 0], [0, 0.01, 0], [0.01, 0.01, 0]]))


@pytest.mark.parametrize("make", [lambda: Sphere([0.0, 0.0, 0.0], 1e154), lambda: Sphere([1e154, 0.0, 0.0], 1.0),
                                  lambda: Box([0.0, 2e9, 0.0], [1.0, 1.0, 1.0]),
                                  lambda: Capsule([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 1e10)])
def test_a_shape_beyond_the_largest_magnitude_is_refused_not_apart_by_overflow(make):
    """Two spheres of radius 1e154 overlapping by half were `distance` inf and `intersects` False: the
    squared lengths overflowed.  Shapes take Tolerances.max_magnitude (1e9 m), as the files do."""
    with pytest.raises(GeometryError, match="beyond the largest magnitude"):
        make()


def test_the_batched_obb_test_refuses_boxes_that_pass_every_axis():
    """Two coincident boxes with half extents -1 were 'no overlap' (every separating-axis test passes),
    and so was a box with a zero matrix for its rotation."""
    from armguard.geometry import batch

    with pytest.raises(GeometryError, match="half_extents_A must be > 0"):
        batch.box_box_overlap([0, 0, 0], [-1, -1, -1], np.eye(3), [0, 0, 0], [-1, -1, -1], np.eye(3))
    with pytest.raises(GeometryError, match=r"rotation_B\[1\] is no rotation"):
        batch.box_box_overlap(np.zeros((2, 3)), np.ones((2, 3)), np.stack([np.eye(3)] * 2), np.zeros((2, 3)),
                              np.ones((2, 3)), np.stack([np.eye(3), np.diag([1.0, 1.0, -1.0])]))
    assert batch.box_box_overlap([0, 0, 0], [1, 1, 1], np.eye(3), [0, 1.5, 0], [1, 1, 1], np.eye(3))


def test_a_continuous_joints_cos_sin_off_the_unit_circle_is_refused_by_scene_q():
    """(cos, sin) = (0, 0) was read as the angle 0, (-0, -0) as -pi, and a NaN passed: a Detector would
    judge an angle the caller never gave (the Checkers refuse them)."""
    m = armguard.load_model("kinova")
    k = int(m.continuous_q[0])
    for c, s_ in ((0.0, 0.0), (-0.0, -0.0), (np.nan, 1.0), (0.6, 0.6)):
        q = m.neutral().copy()
        q[k], q[k + 1] = c, s_
        with pytest.raises(DetectionError, match="not on the unit circle"):
            m.scene_q(q)
        with pytest.raises(DetectionError, match=r"q \(row 1\)"):
            m.scene_q(np.stack([m.neutral(), q]))
    assert np.isfinite(m.scene_q(m.neutral())).all()


def test_a_terrain_fill_that_would_make_pits_or_no_fill_is_refused():
    from armguard import TerrainError
    from armguard.terrain import ElevationMap

    rng = np.random.default_rng(0)
    pts = np.column_stack([rng.uniform(0, 1, 400), rng.uniform(0, 1, 400), rng.uniform(0.0, 0.2, 400)])
    with pytest.raises(TerrainError, match="ceiling -1.0 m is below the highest point seen"):
        ElevationMap.from_points(pts, 0.1, fill="ceiling", ceiling=-1.0)
    for bad in (-1, 1.5, np.nan, True):
        with pytest.raises(TerrainError, match=r"fill_radius \(cells\): expected an integer >= 0"):
            ElevationMap.from_points(pts, 0.1, fill_radius=bad)
    with pytest.raises(TerrainError, match="points_W: expected"):
        ElevationMap.from_points([["a", "b", "c"]], 0.1)


def test_a_scene_whose_site_is_20_km_away_loads_and_checks(tmp_path):
    text = """armguard_scene: 1
name: far
frames: [{name: site, xyz: [20000.0, 0.0, 0.0]}]
bodies:
  - {name: post, frame: site, xyz: [0.5, 0, 0], shapes: [{type: prism, n_sides: 8, apothem: 0.01, length: 0.02},
                                                     {type: polyhedron, vertices: [[0,0,0],[0.02,0,0],[0,0.02,0],[0,0,0.02]]}]}
robots:
  - name: arm
    mount: {frame: site}
    joints: [{a: 0.3, limits: [-3, 3]}, {a: 0.2, limits: [-3, 3]}]
    link_shapes: {link2: [{type: capsule, p0: [-0.2, 0, 0], p1: [0, 0, 0], radius: 0.02}]}
"""
    p = tmp_path / "far.yaml"
    p.write_text(text, encoding="utf-8")
    sc = load_scene_file(p)
    det = armguard.Detector(sc, threshold=0.05)
    q = sc.flat_q(sc.default_q())
    from armguard.detect import check_reference

    ref = check_reference(sc, q, 0.05)
    assert det.check(q).nearest.distance == pytest.approx(float(np.min(ref.min_distance)), abs=1e-9)
    assert np.isfinite(ref.min_distance).any()


def test_the_witness_relation_holds_to_the_documented_bound_far_from_the_origin():
    """docs/notation.md: |p_WA - p_WB| == |distance| and p_WB - p_WA == distance * nhat to 1e-9 m + 4e-15 R."""
    rng = np.random.default_rng(3)
    for big in (1e3, 1e5, 1e6):
        worst = 0.0
        for k in range(72):
            a, b = random_shape(KINDS[k % 6], rng), random_shape(KINDS[(k // 6) % 6], rng)
            T = np.eye(4)
            T[:3, 3] = big * rng.normal(size=3) / np.sqrt(3.0)
            a, b = a.transformed(T), b.transformed(T)
            R = max(float(np.max(np.abs(a.core_points))), float(np.max(np.abs(b.core_points))))
            r = distance(a, b)
            bound = 1e-9 + 4e-15 * R
            assert abs(np.linalg.norm(r.p_WA - r.p_WB) - abs(r.distance)) <= bound
            e = float(np.linalg.norm(r.p_WB - r.p_WA - r.distance * r.nhat_AB_W))
            assert e <= bound
            worst = max(worst, e)
        assert worst > 0.0 or big < 1e4  # the test sees the round-off it bounds


# ---------------------------------------------------------------- the loader's numbers and keys


def _one_shape(shape: str, tmp_path) -> dict:
    import yaml

    from armguard._yaml import _SceneLoader

    text = f"armguard_scene: 1\nname: t\nbodies:\n  - name: b\n    shapes:\n      - {shape}\n"
    return yaml.load(text, Loader=_SceneLoader)


def _load(text: str, tmp_path):
    p = tmp_path / "s.yaml"
    p.write_text("armguard_scene: 1\nname: t\nbodies:\n  - name: b\n    shapes:\n" + text, encoding="utf-8")
    return p, lambda: load_scene_file(p)


@pytest.mark.parametrize("shape,where", [
    ('{type: sphere, radius: true, xyz: [1, 0, 0]}', "bodies[0].shapes[0].radius"),
    ('{type: sphere, radius: 0.1, xyz: ["1e3", 0, 0]}', "bodies[0].shapes[0].xyz[0]"),
    ('{type: sphere, radius: 0.1, xyz: [1, false, 0]}', "bodies[0].shapes[0].xyz[1]"),
    ('{type: sphere, radius: "1", xyz: [1, 0, 0]}', "bodies[0].shapes[0].radius"),
    ('{type: prism, n_sides: 8.0, apothem: 0.1, length: 0.2}', "bodies[0].shapes[0].n_sides"),
    ('{type: sphere, radius: 0.1, xyz: [1e300, 0, 0]}', "bodies[0].shapes[0].xyz[0]"),
    ('{type: sphere, radius: 1.0e10}', "bodies[0].shapes[0].radius"),
])
def test_the_loader_refuses_non_numbers_and_huge_numbers_naming_the_place(shape, where, tmp_path):
    p, load = _load(f"      - {shape}\n", tmp_path)
    with pytest.raises(SceneFileError) as info:
        load()
    assert info.value.where == where and str(p) in str(info.value)


def test_the_issue_example_is_refused_not_coerced(tmp_path):
    _, load = _load('      - {type: sphere, radius: true, xyz: ["1e3", false, "0"]}\n', tmp_path)
    with pytest.raises(SceneFileError, match="not numbers"):
        load()


def test_yaml_1_2_numbers_are_numbers(tmp_path):
    _, load = _load("      - {type: sphere, radius: 1e-1, xyz: [1e3, 2.5E-1, -1.0e0]}\n", tmp_path)
    s = load().bodies["b"].shapes[0]
    assert s.radius == 0.1 and s.center.tolist() == [1000.0, 0.25, -1.0]


@pytest.mark.parametrize("number, said", [("010", "leading zero"), ("-045", "leading zero"), ("0x10", "hexadecimal"),
                                          ("0b11", "binary")])
def test_numbers_yaml_1_1_and_1_2_read_differently_are_refused_where_they_stand(tmp_path, number, said):
    """YAML 1.1 reads 010 as 8 (1.2: 10) and 0b11 as 3 (1.2: text): refused at their line and column, never
    read as one or the other (a joint limit of -060 deg was -48)."""
    _, load = _load(f"      - {{type: sphere, radius: 0.1, xyz: [0, 0, {number}]}}\n", tmp_path)
    with pytest.raises(SceneFileError) as info:
        load()
    assert info.value.where == "line 6, column 49" and said in str(info.value) and repr(number) in str(info.value)
    assert "quote it if it is a name" in str(info.value)
    _, load = _load("      - {type: sphere, radius: 0.1, xyz: [0, +10, -0]}\n", tmp_path)
    assert load().bodies["b"].shapes[0].center.tolist() == [0.0, 10.0, 0.0]


@pytest.mark.parametrize("text", ["1:30", "1__0", "1:30.5", "1_0.5", "090"])
def test_yaml_1_1_numbers_that_are_text_in_yaml_1_2_are_text(tmp_path, text):
    """1:30 (YAML 1.1: 90), 1__0 (10), 090 (no octal): text, as YAML 1.2 reads them; a number field refuses them
    by its name, and a name keeps them (a body named 1_2, a joint named 08)."""
    _, load = _load(f"      - {{type: sphere, radius: 0.1, xyz: [0, 0, {text}]}}\n", tmp_path)
    with pytest.raises(SceneFileError) as info:
        load()
    assert "bodies[0].shapes[0].xyz" in info.value.where, info.value
    if ":" in text:
        return  # not a name's character
    p = tmp_path / "named.yaml"
    p.write_text(f"armguard_scene: 1\nname: {text}\nbodies:\n  - name: {text}\n    shapes:\n"
                 "      - {type: sphere, radius: 0.1, xyz: [0, 0, 0]}\n", encoding="utf-8")
    sc = load_scene_file(p)
    assert sc.name == text and list(sc.bodies) == [text]


def test_a_duplicate_key_is_an_error_naming_both_lines(tmp_path):
    _, load = _load("      - type: sphere\n        radius: 0.1\n        xyz: [0, 0, 0]\n        radius: 0.2\n", tmp_path)
    with pytest.raises(SceneFileError) as info:
        load()
    assert info.value.where == "line 9" and "'radius'" in str(info.value) and "line 7" in str(info.value)
    p = tmp_path / "top.yaml"
    p.write_text("armguard_scene: 1\nname: a\nname: b\n", encoding="utf-8")
    with pytest.raises(SceneFileError, match="duplicate key 'name'"):
        load_scene_file(p)


def test_aliases_are_refused(tmp_path):
    p = tmp_path / "alias.yaml"
    p.write_text("armguard_scene: 1\nname: t\nbodies:\n  - name: b\n    shapes: &s [{type: sphere, radius: 0.1}]\n"
                 "  - name: c\n    shapes: *s\n", encoding="utf-8")
    with pytest.raises(SceneFileError, match="alias"):
        load_scene_file(p)


def test_the_format_version_must_be_the_integer_1(tmp_path):
    p = tmp_path / "v.yaml"
    p.write_text("armguard_scene: true\nname: t\n", encoding="utf-8")
    with pytest.raises(SceneFileError) as info:
        load_scene_file(p)
    assert info.value.where == "armguard_scene"


@pytest.mark.parametrize("value", ["true", "1.0"])
def test_every_files_format_version_must_be_the_integer_1(tmp_path, value):
    """A program's, a cell's, a calibration's and a trajectory's version key took ``true`` and ``1.0`` for 1
    (a scene file's already refused them)."""
    import armguard
    from armguard.program import load_cell, load_program, read_calibration
    from armguard.verify import load_trajectory

    puma = armguard.load_scene("puma560")

    cases = ((load_program, f"armguard_program: {value}\nname: p\ntasks: []\n", "armguard_program"),
             (load_cell, f"armguard_cell: {value}\nmodel: puma560\n", "armguard_cell"),
             (read_calibration, f"armguard_calibration: {value}\n", "armguard_calibration"),
             (lambda p: load_trajectory(puma, p), f"format: armguard.trajectory\nversion: {value}\nrobot: puma560\n"
              "joint_names: [j1]\ntimes: [0, 1]\nwaypoints: [[0], [1]]\n", "version"))
    for load, text, key in cases:
        p = tmp_path / "f.yaml"
        p.write_text(text, encoding="utf-8")
        with pytest.raises(SceneFileError) as info:
            load(p)
        assert info.value.where.startswith(key) or f"{key} (line" in info.value.message, (key, info.value)


# ---------------------------------------------------------------- smaller ones


def test_a_scene_without_robots_has_nothing_to_check():
    sc = Scene("bodies only")
    sc.add_body("b", [Sphere([0, 0, 0], 0.1)])
    # nothing to check is never CLEAR: the Detector refuses the scene and says why
    with pytest.raises(DetectionError, match="has no pair to check"):
        armguard.Detector(sc)


def test_intersects_and_the_detector_share_one_contact_tolerance():
    tol = DEFAULT_TOLERANCES.length
    a = Sphere([0.0, 0.0, 0.0], 0.5)
    for gap, expect in ((0.5 * tol, True), (0.0, True), (-1e-3, True), (1e-9, False)):
        b = Box([1.0 + gap, 0.0, 0.0], [0.5, 0.5, 0.5])
        assert intersects(a, b) is expect
        assert (distance(a, b).distance <= tol) is expect
    # two boxes: the JPL test's slack only errs towards overlap; the distance confirms it
    for gap, expect in ((0.5 * tol, True), (1e-11, False), (1e-9, False), (-1e-6, True)):
        A = Box([0.0, 0.0, 0.0], [50.0, 50.0, 50.0])
        B = Box([100.0 + gap, 0.0, 0.0], [50.0, 50.0, 50.0])
        assert intersects(A, B) is expect, gap


@pytest.mark.parametrize("field, value", [("length", float("nan")), ("length", 0.0), ("verify_contact", -1.0),
                                          ("gjk_epsilon", float("inf")), ("verify_max_evaluations", -5),
                                          ("gjk_max_iterations", 2.5), ("edge_max_evaluations", 1), ("length", True),
                                          ("joint_limit", "1e-9")])
def test_a_tolerance_that_is_no_tolerance_is_refused_when_made(field, value):
    """``Tolerances(length=nan)`` once gave a Detector's WARNING at -0.7 m and a verifier's bare
    ZeroDivisionError: a field NaN, infinite, zero or negative (a count below its least) is refused by name."""
    from dataclasses import replace

    from armguard import DEFAULT_TOLERANCES, Tolerances, ToleranceError

    with pytest.raises(ToleranceError, match=f"Tolerances.{field}: expected"):
        Tolerances(**{field: value})
    with pytest.raises(ToleranceError):
        replace(DEFAULT_TOLERANCES, **{field: value})
    assert Tolerances(ik_restarts=0, cspace_max_depth=0, length=np.float64(1e-9), gjk_max_iterations=np.int64(9)).length == 1e-9
