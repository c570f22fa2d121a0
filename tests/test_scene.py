"""The Scene model, scene files (errors, units, round trip), pair filters, payloads, compile."""

from __future__ import annotations

import math
import textwrap
from pathlib import Path

import numpy as np
import pytest

from armguard import SceneError, SceneFileError
from armguard.geometry import Box, Capsule, Sphere
from armguard.kinematics import DHRow, Robot
from armguard.scene import (
    PairCategory,
    Scene,
    compile_scene,
    load_scene,
    save_scene,
    scene_from_dict,
)

BASE = {
    "armguard_scene": 1,
    "name": "t",
    "units": {"angle": "deg", "length": "m"},
    "bodies": [{"name": "table", "shapes": [{"type": "box", "size": [1, 1, 0.1], "xyz": [1, 0, 0]}]}],
    "robots": [{
        "name": "arm",
        "joints": [
            {"a": 0.5, "alpha": 0, "d": 0.0, "limits": [-90, 90]},
            {"a": 0.5, "alpha": 0, "d": 0.0, "limits": [-90, 90]},
            {"a": 0.3, "alpha": 0, "d": 0.0, "limits": [-90, 90]},
        ],
        "link_shapes": {"link1": [{"type": "link_capsule", "radius": 0.05}],
                        "link2": [{"type": "link_capsule", "radius": 0.05}],
                        "link3": [{"type": "link_capsule", "radius": 0.05}]},
        "mount": {"xyz": [0, 0, 1]},
    }],
}


def _copy(d):
    import copy

    return copy.deepcopy(d)


def _error(data) -> SceneFileError:
    with pytest.raises(SceneFileError) as ei:
        scene_from_dict(data, "cell.yaml")
    return ei.value


# ------------------------------------------------------------------ errors name file, place, expectation
def _set(d, path, value):
    node = d
    for k in path[:-1]:
        node = node[k]
    node[path[-1]] = value
    return d


ERRORS = [
    ("limits_length", ["robots", 0, "joints", 2, "limits"], [1, 2, 3], "robots[0].joints[2].limits", "at most 2"),
    ("unknown_key", ["robots", 0, "jionts"], [], "robots[0].jionts", "unknown key"),
    ("nan", ["bodies", 0, "shapes", 0, "size"], [1, float("nan"), 1], "bodies[0].shapes[0].size[1]", "finite"),
    ("unknown_shape", ["bodies", 0, "shapes", 0], {"type": "cube", "size": 1}, "bodies[0].shapes[0]", "box, sphere"),
    ("version", ["armguard_scene"], 2, "armguard_scene", "armguard_scene: 1"),
    ("bad_unit", ["units", "angle"], "grad", "units.angle", "deg"),
    ("missing", ["bodies", 0, "shapes", 0], {"type": "sphere"}, "bodies[0].shapes[0].radius", "missing"),
    ("lower_gt_upper", ["robots", 0, "joints", 1, "limits"], [10, -10], "robots[0].joints[1].limits", "lower <= upper"),
    ("unknown_link", ["robots", 0, "link_shapes", "link9"], [{"type": "sphere", "radius": 1}], "robots[0].link_shapes.link9", "unknown link"),
    ("unknown_frame", ["robots", 0, "mount"], {"frame": "nowhere"}, "robots[0].mount.frame", "unknown frame"),
    ("bad_home", ["robots", 0, "home"], [0, 0], "robots[0].home", "expected 3 joint values"),
    ("capsule_both", ["bodies", 0, "shapes", 0], {"type": "capsule", "radius": 0.1, "length": 1, "p0": [0, 0, 0], "p1": [1, 0, 0]}, "bodies[0].shapes[0]", "either"),
    ("degenerate_poly", ["bodies", 0, "shapes", 0], {"type": "polyhedron", "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]}, "bodies[0].shapes[0]", "coplanar"),
]


@pytest.mark.parametrize("path,value,where,expect", [e[1:] for e in ERRORS], ids=[e[0] for e in ERRORS])
def test_file_errors_name_file_place_and_expectation(path, value, where, expect):
    err = _error(_set(_copy(BASE), path, value))
    assert err.file == "cell.yaml"
    assert err.where == where
    assert expect in err.message
    assert str(err).startswith(f"cell.yaml: {where}: ")


def test_yaml_syntax_error_has_line(tmp_path):
    p = tmp_path / "bad.yaml"
    p.write_text("armguard_scene: 1\nname: x\nbodies: [\n  {name: a\n")
    with pytest.raises(SceneFileError) as ei:
        load_scene(p)
    assert ei.value.where.startswith("line ") and "YAML syntax" in ei.value.message


def test_unknown_builtin_lists_the_valid_ones():
    with pytest.raises(SceneError, match="hermes"):
        load_scene("hermez")


# ------------------------------------------------------------------ units and frames
def test_units_mm_deg_equal_m_rad():
    d_mm = _copy(BASE)
    d_mm["units"] = {"angle": "rad", "length": "mm"}
    d_mm["bodies"][0]["shapes"][0] = {"type": "box", "size": [1000, 1000, 100], "xyz": [1000, 0, 0]}
    d_mm["robots"][0]["mount"] = {"xyz": [0, 0, 1000]}
    for j in d_mm["robots"][0]["joints"]:
        j["a"] *= 1000
        j["limits"] = [-math.pi / 2, math.pi / 2]
    for shapes in d_mm["robots"][0]["link_shapes"].values():
        shapes[0]["radius"] *= 1000
    a, b = scene_from_dict(BASE), scene_from_dict(d_mm)
    q = {"arm": np.array([0.3, -0.2, 0.5])}
    assert np.allclose(a.robots["arm"].forward_kinematics(q["arm"]), b.robots["arm"].forward_kinematics(q["arm"]))
    assert np.allclose(a.robots["arm"].upper, b.robots["arm"].upper)
    for x, y in zip(a.shapes_at(q), b.shapes_at(q)):
        assert np.allclose(x.shape.aabb()[0], y.shape.aabb()[0]) and np.allclose(x.shape.aabb()[1], y.shape.aabb()[1])


def test_frames_compose_as_workmate_trans_rotz_roty_rotx():
    d = _copy(BASE)
    d["frames"] = [{"name": "f", "xyz": [1, 2, 3], "rpy": [10, 20, 30]}, {"name": "g", "parent": "f", "xyz": [0.5, 0, 0]}]
    d["bodies"][0] = {"name": "ball", "frame": "g", "shapes": [{"type": "sphere", "radius": 0.1}]}
    s = scene_from_dict(d)
    r, p, y = np.radians([10, 20, 30])
    Rz = np.array([[math.cos(y), -math.sin(y), 0], [math.sin(y), math.cos(y), 0], [0, 0, 1]])
    Ry = np.array([[math.cos(p), 0, math.sin(p)], [0, 1, 0], [-math.sin(p), 0, math.cos(p)]])
    Rx = np.array([[1, 0, 0], [0, math.cos(r), -math.sin(r)], [0, math.sin(r), math.cos(r)]])
    expect = np.array([1, 2, 3]) + Rz @ Ry @ Rx @ np.array([0.5, 0, 0])
    assert np.allclose(s.bodies["ball"].shapes[0].center, expect, atol=1e-12)


def test_frame_cycle_is_an_error():
    d = _copy(BASE)
    d["frames"] = [{"name": "a", "parent": "b"}, {"name": "b", "parent": "a"}]
    assert "cycle" in _error(d).message


# ------------------------------------------------------------------ scene API
def _scene() -> Scene:
    return scene_from_dict(_copy(BASE))


def test_joint_names_split_q_and_contract():
    s = _scene()
    assert s.joint_names == ("arm/joint1", "arm/joint2", "arm/joint3")
    parts = s.split_q(np.zeros((4, 3)))
    assert parts["arm"].shape == (4, 3)
    with pytest.raises(SceneError):
        s.split_q(np.zeros(2))
    with pytest.raises(SceneError):
        s.split_q({"other": np.zeros(3)})
    with pytest.raises(Exception, match="NaN"):
        s.split_q([0.0, float("nan"), 0.0])
    items = s.shapes_at(np.array([0.1, 0.2, 0.3]))
    assert [it.owner for it in items] == ["table", "arm/link1", "arm/link2", "arm/link3"]
    assert [it.kind for it in items] == ["body", "link", "link", "link"]
    # the link capsule follows FK: its distal end is at the link origin
    X = s.robots["arm"].forward_kinematics(np.array([0.1, 0.2, 0.3]))
    assert np.allclose(items[3].shape.p1, X[3, :3, 3])


def test_add_body_and_failed_calls_change_nothing():
    s = _scene()
    before = s.owners()
    with pytest.raises(SceneError):
        s.add_body("table", [Sphere([0, 0, 0], 1.0)])  # duplicate
    with pytest.raises(SceneError):
        s.add_body("x", ["not a shape"])
    with pytest.raises(SceneError):
        s.add_body("y", [Sphere([0, 0, 0], 1.0)], category="moon")
    assert s.owners() == before
    s.add_body("wall", [Box([0, 2, 1], [1, 0.1, 1])], category="vehicle")
    cats = s.allowed_pairs_by_category()
    assert ("arm/link1", "wall") in cats[PairCategory.ARM_VEHICLE]
    assert ("arm/link1", "table") in cats[PairCategory.ARM_ENVIRONMENT]


def test_failed_file_load_changes_nothing(tmp_path):
    s = _scene()
    p = tmp_path / "bad.yaml"
    p.write_text("armguard_scene: 1\nname: bad\nbodies: [{name: b, shapes: [{type: box, size: [1, 1]}]}]\n")
    with pytest.raises(SceneFileError):
        load_scene(p)
    assert s.owners() == ("table", "arm/link1", "arm/link2", "arm/link3")


def test_pairs_adjacent_listed_and_disabled():
    s = _scene()
    arm_arm = s.allowed_pairs_by_category()[PairCategory.ARM_ARM]
    assert arm_arm == (("arm/link1", "arm/link3"),)  # 1-2 and 2-3 are adjacent
    s.exclude_adjacent = False
    assert len(s.allowed_pairs_by_category()[PairCategory.ARM_ARM]) == 3
    s.exclude_adjacent = True
    s.set_self_pairs("arm", [("link1", "link2")])
    assert s.allowed_pairs_by_category()[PairCategory.ARM_ARM] == (("arm/link1", "arm/link2"),)
    s.set_self_pairs("arm", None)
    s.disable_pair("arm/link1", "arm/link3")
    assert s.allowed_pairs_by_category()[PairCategory.ARM_ARM] == ()
    s.disable_pair("arm", "table")  # a robot name stands for all its links
    assert s.allowed_pairs_by_category()[PairCategory.ARM_ENVIRONMENT] == ()
    with pytest.raises(SceneError):
        s.disable_pair("arm/link9", "table")


def test_shapeless_link_between_capsules_counts_as_adjacent():
    rows = [DHRow(0, 0, 0.5), DHRow(0, 0, 0.0), DHRow(0, 0, 0.5)]  # link2 has zero length
    r = Robot.from_dh("z", rows)
    r = r.with_link_shapes({"link1": [Capsule([0, 0, -0.5], [0, 0, 0], 0.05)], "link3": [Capsule([0, 0, -0.5], [0, 0, 0], 0.05)]})
    s = Scene()
    s.add_robot(r)
    assert s.allowed_pairs() == ()


def test_payload_attach_release_grasp():
    s = _scene()
    q = np.array([0.2, -0.1, 0.3])
    s.attach_payload("can", "arm", "link3", [Sphere([0, 0, 0], 0.05)], np.array(
        [[1, 0, 0, 0.1], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]]))
    X = s.robots["arm"].forward_kinematics(q)[3]
    item = [it for it in s.shapes_at(q) if it.kind == "payload"][0]
    assert np.allclose(item.shape.center, X[:3, :3] @ [0.1, 0, 0] + X[:3, 3])
    cats = s.allowed_pairs_by_category()
    assert ("arm/link1", "can") in cats[PairCategory.ARM_PAYLOAD]
    assert ("arm/link3", "can") not in cats[PairCategory.ARM_PAYLOAD]  # the holding link
    assert ("can", "table") in cats[PairCategory.PAYLOAD_ENVIRONMENT]
    body = s.release_payload("can", q)
    assert np.allclose(body.shapes[0].center, item.shape.center) and "can" not in s.payloads
    q2 = np.array([-0.3, 0.2, 0.1])
    s.grasp("can", "arm", "link2", q2)
    again = [it for it in s.shapes_at(q2) if it.kind == "payload"][0]
    assert np.allclose(again.shape.center, item.shape.center)  # grasped where it lay


# ------------------------------------------------------------------ save / load round trip
@pytest.mark.parametrize("name", ["hermes", "puma560", "gmf_s480"], ids=["hermes", "puma560", "gmf_s480"])
def test_save_load_round_trip(tmp_path, name):
    a = load_scene(name)
    b = load_scene(save_scene(a, tmp_path / f"{name}.yaml"))
    assert a.joint_names == b.joint_names
    assert [(p.a, p.b, p.category) for p in a.allowed_pairs()] == [(p.a, p.b, p.category) for p in b.allowed_pairs()]
    rng = np.random.default_rng(3)
    for r in a.robots:
        lo, hi = a.robots[r].lower, a.robots[r].upper
        q = rng.uniform(lo, hi)
        assert np.allclose(a.robots[r].forward_kinematics(q), b.robots[r].forward_kinematics(q), atol=1e-12)
        assert np.allclose(a.home(r), b.home(r))
    qa = a.default_q()
    for x, y in zip(a.shapes_at(qa), b.shapes_at(qa)):
        assert x.owner == y.owner and type(x.shape) is type(y.shape)
        assert np.allclose(x.shape.core_points, y.shape.core_points, atol=1e-12)
    assert set(a.trajectories) == set(b.trajectories)
    for t in a.trajectories:
        assert np.allclose(a.trajectories[t].waypoints, b.trajectories[t].waypoints)
        assert a.trajectories[t].duration == pytest.approx(b.trajectories[t].duration)


# ------------------------------------------------------------------ compile
def test_compile_layout_matches_the_scene():
    s = load_scene("hermes")
    c = compile_scene(s)
    items = s.shapes_at()  # home: same order as the elements
    assert c.n_elements == len(items)
    assert c.owner_names == s.owners()
    X = {r: s.robots[r].forward_kinematics(s.home(r)) for r in s.robots}
    for e, it in enumerate(items):
        v = c.verts[c.elem_vert_start[e]:c.elem_vert_start[e + 1]]
        if c.elem_kind[e] != 0:  # link/payload element: in the link frame
            Xl = X[c.robot_names[c.elem_robot[e]]][c.elem_link[e]]
            v = v @ Xl[:3, :3].T + Xl[:3, 3]
        assert np.allclose(np.sort(v, axis=0), np.sort(it.shape.core_points, axis=0), atol=1e-9)
        assert c.elem_radius[e] == pytest.approx(it.shape.core_radius)
        # every face's vertices lie on its plane
        for f in range(c.elem_face_start[e], c.elem_face_start[e + 1]):
            plane = c.planes[c.elem_plane_start[e] + f - c.elem_face_start[e]]
            pts = c.verts[c.face_verts[c.face_vert_start[f]:c.face_vert_start[f + 1]]]
            assert np.allclose(pts @ plane[:3], plane[3], atol=1e-9)
    assert len(c.pair_a) == len(s.allowed_pairs())
    assert c.nbytes > 0 and not c.verts.flags.writeable


# ------------------------------------------------------------------ URDF
URDF = """<robot name="two">
  <link name="base"><collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision></link>
  <link name="l1"><collision><origin xyz="0 0 0.25"/><geometry><sphere radius="0.05"/></geometry></collision></link>
  <link name="l2"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><origin xyz="0 0 0.1"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="j2" type="prismatic"><parent link="l1"/><child link="l2"/><origin xyz="0 0 0.5"/>
    <axis xyz="1 0 0"/><limit lower="0" upper="0.3" effort="1" velocity="1"/></joint>
</robot>
"""


def test_load_urdf_gives_one_robot_and_no_bodies(tmp_path):
    p = tmp_path / "two.urdf"
    p.write_text(URDF)
    s = load_scene(p)
    assert list(s.robots) == ["two"] and not s.bodies
    assert s.joint_names == ("two/j1", "two/j2")
    owners = [it.owner for it in s.shapes_at(np.array([0.5, 0.1]))]
    assert owners == ["two/base", "two/l1"]
    b = load_scene(save_scene(s, tmp_path / "two.yaml"))  # URDF robots save as a path to the file
    assert b.joint_names == s.joint_names


def test_srdf_disable_collisions(tmp_path):
    d = _copy(BASE)
    srdf = tmp_path / "arm.srdf"
    srdf.write_text(textwrap.dedent("""\
        <robot name="arm"><disable_collisions link1="link1" link2="link3" reason="Never"/></robot>"""))
    d["robots"][0]["srdf"] = str(srdf)
    s = scene_from_dict(d)
    assert s.allowed_pairs_by_category()[PairCategory.ARM_ARM] == ()
    srdf.write_text('<robot><disable_collisions link1="link1" link2="nope"/></robot>')
    err = _error(d)
    assert err.where == "robots[0].srdf" and "nope" in err.message


def test_docs_example_loads(tmp_path):
    doc = (Path(__file__).resolve().parent.parent / "docs" / "scene-format.md").read_text()
    block = doc.split("```yaml\n", 1)[1].split("```", 1)[0]
    p = tmp_path / "cell.yaml"
    p.write_text(block)
    s = load_scene(p)
    assert s.joint_names == ("arm/j1", "arm/j2", "arm/j3")
    assert [it.kind for it in s.shapes_at(s.default_q())] == ["body", "body", "link", "link", "payload"]
    assert s.canned_tests["reach"].trajectory(s).duration > 0
