"""SRDF files: where they are found, how leniently they are read, what their groups and homes mean.

Synthetic arms (primitive shapes, loaded in well under a second) test the rules; the public
robots of example-robot-data that load quickly (Panda, Panda collision, UR5, UR10, Talos's left
arm) test the discovery and the homes, differentially against coal.
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import armguard
from armguard import ArmguardWarning, DetectionError, SceneFileError
from armguard.cli import main
from armguard.detect import Detector
from armguard.model._load import _srdf_for

from test_backends import ROBOTS


def arm_urdf(name: str = "arm", robot: str | None = None) -> str:
    """A 3-joint arm on a fixed base beside a post: base -j1(z)- l1 -j2(y)- l2 -j3(y)- l3 -fixed- tool."""
    return f"""<robot name="{robot or name}">
  <link name="world"/>
  <link name="base"><collision><origin xyz="0 0 0.05"/><geometry><box size="0.2 0.2 0.1"/></geometry></collision></link>
  <link name="l1"><collision><origin xyz="0 0 0.15"/><geometry><cylinder radius="0.05" length="0.2"/></geometry></collision></link>
  <link name="l2"><collision><origin xyz="0.2 0 0"/><geometry><box size="0.4 0.06 0.06"/></geometry></collision></link>
  <link name="l3"><collision><origin xyz="0.15 0 0"/><geometry><box size="0.3 0.05 0.05"/></geometry></collision></link>
  <link name="tool"><collision><geometry><sphere radius="0.04"/></geometry></collision></link>
  <link name="post"><collision><origin xyz="0.45 0 0.3"/><geometry><box size="0.1 0.1 0.6"/></geometry></collision></link>
  <joint name="fix" type="fixed"><parent link="world"/><child link="base"/></joint>
  <joint name="fix_post" type="fixed"><parent link="world"/><child link="post"/></joint>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0 0 0.25"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
  <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/><origin xyz="0.4 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-2.5" upper="2.5" effort="1" velocity="1"/></joint>
  <joint name="j_tool" type="fixed"><parent link="l3"/><child link="tool"/><origin xyz="0.3 0 0"/></joint>
</robot>"""


ADJACENT = [("base", "l1"), ("l1", "l2"), ("l2", "l3"), ("l3", "tool"), ("base", "post")]


def srdf_text(body: str = "", robot: str = "arm", disabled=ADJACENT) -> str:
    dis = "".join(f'<disable_collisions link1="{a}" link2="{b}" reason="Adjacent"/>' for a, b in disabled)
    return f'<?xml version="1.0"?><robot name="{robot}">{body}{dis}</robot>'


def package(tmp_path: Path, stem: str = "arm", robot: str | None = None) -> Path:
    """``tmp/arm_description/urdf/<stem>.urdf`` (robots keep SRDFs in ``../srdf/``); returns the URDF."""
    d = tmp_path / "arm_description"
    (d / "urdf").mkdir(parents=True)
    (d / "srdf").mkdir()
    urdf = d / "urdf" / f"{stem}.urdf"
    urdf.write_text(arm_urdf(stem, robot))
    return urdf


# ------------------------------------------------------------------------------ discovery
def test_srdf_found_in_the_package_srdf_folder_beside_wins_and_explicit_wins(tmp_path):
    urdf = package(tmp_path)
    bare = armguard.load_model(urdf)
    assert bare.srdf is None
    (urdf.parent.parent / "srdf" / "arm.srdf").write_text(srdf_text(disabled=ADJACENT + [("l1", "l3"), ("tool", "post")]))
    m = armguard.load_model(urdf)
    assert Path(m.srdf.file) == (urdf.parent.parent / "srdf" / "arm.srdf").resolve()
    assert "../srdf/" in m.srdf.found and not m.srdf.partial

    def owners(model):
        return {frozenset(p) for p in zip(model.pairs.owner_a, model.pairs.owner_b)}

    assert owners(bare) - owners(m) == {frozenset(("arm/l1", "arm/l3")), frozenset(("arm/tool", "post")),
                                        frozenset(("arm/base", "post"))}
    assert owners(m) < owners(bare)
    assert Path(m.srdf.file) in m.files
    beside = urdf.with_suffix(".srdf")
    beside.write_text(srdf_text(disabled=ADJACENT[:1]))
    assert Path(armguard.load_model(urdf).srdf.file) == beside.resolve()
    given = tmp_path / "given.srdf"
    given.write_text(srdf_text(disabled=()))
    assert Path(armguard.load_model(urdf, srdf=given).srdf.file) == given
    assert armguard.load_model(urdf, srdf=False).srdf is None


def test_srdf_found_under_the_robot_name_may_describe_a_larger_robot(tmp_path):
    urdf = package(tmp_path, stem="arm_collision", robot="arm")
    body = ('<group name="leg"><chain base_link="hip" tip_link="foot"/></group>'
            '<group_state name="home" group="all"><joint name="j2" value="0.5"/><joint name="knee" value="1"/>'
            '<joint name="root_joint" value="0 0 1 0 0 0 1"/></group_state>')
    (urdf.parent.parent / "srdf" / "arm.srdf").write_text(srdf_text(body, disabled=ADJACENT + [("hip", "l1")]))
    with pytest.warns(ArmguardWarning) as rec:
        m = armguard.load_model(urdf)
    assert m.srdf.partial and "robot's name 'arm'" in m.srdf.found
    text = " ".join(str(w.message) for w in rec)
    assert "disable_collisions[5] (hip)" in text and "leg" in text and "knee" not in m.scene.joint_names
    np.testing.assert_allclose(m.scene.home("arm"), [0.0, 0.5, 0.0])
    # the same file given under the URDF's own name must match it: the unknown link is an error
    with pytest.raises(SceneFileError) as exc:
        armguard.load_model(urdf, srdf=urdf.parent.parent / "srdf" / "arm.srdf")
    assert exc.value.file.endswith("arm.srdf")


@pytest.mark.parametrize("urdf, srdf", [
    ("panda_description/urdf/panda.urdf", "panda_description/srdf/panda.srdf"),
    ("panda_description/urdf/panda_collision.urdf", "panda_description/srdf/panda.srdf"),
    ("ur_description/urdf/ur5_robot.urdf", "ur_description/srdf/ur5.srdf"),
    ("ur_description/urdf/ur5_gripper.urdf", "ur_description/srdf/ur5_gripper.srdf"),
    ("kinova_description/robots/kinova.urdf", "kinova_description/srdf/kinova.srdf"),
    ("xarm_description/urdf/xarm7.urdf", "xarm_description/srdf/xarm7.srdf"),
    ("z1_description/urdf/z1.urdf", "z1_description/srdf/z1.srdf"),
    ("talos_data/robots/talos_left_arm.urdf", "talos_data/srdf/talos.srdf"),
    ("ur_description/urdf/ur10_robot.urdf", None),  # example-robot-data has no ur10.srdf
    ("so_arm_description/urdf/so101.urdf", None),
])
def test_public_robots_find_their_srdf(urdf, srdf):
    found = _srdf_for((ROBOTS / urdf).resolve(), None)  # the choice alone (no mesh is read)
    assert (found and Path(found.file)) == (srdf and (ROBOTS / srdf).resolve())


@pytest.mark.parametrize("name, srdf, partial", [
    ("panda_collision", "panda_description/srdf/panda.srdf", False),  # the table's
    ("kinova", "kinova_description/srdf/kinova.srdf", False),  # found by the search (read leniently)
    ("talos_left_arm", "talos_data/srdf/talos.srdf", True),  # the humanoid's, under the robot's name
    ("ur10", None, None),
])
def test_public_robot_srdf_is_the_one_load_model_reads(name, srdf, partial):
    from armguard.model._public import public_robot_files, public_robot_srdf

    found = public_robot_srdf(name)
    assert (found and (found[0], found[1])) == (srdf and ((ROBOTS / srdf).resolve(), partial))
    urdf, table = public_robot_files(name)
    chosen = _srdf_for(urdf.resolve(), table)
    assert (chosen and (Path(chosen.file).resolve(), chosen.partial)) == found


# ------------------------------------------------------------------------------ lenient reading, homes
def test_group_state_without_group_is_a_warning_and_the_first_state_is_home(tmp_path):
    urdf = package(tmp_path)
    body = ('<group_state name="arm_up"><joint name="j2" value="-0.5"/><joint name="j3" value="1.25"/></group_state>'
            '<group_state name="other"><joint name="j2" value="0.3"/></group_state>')
    urdf.with_suffix(".srdf").write_text(srdf_text(body))
    with pytest.warns(ArmguardWarning, match=r"group_state\[0\] \(arm_up\): no attribute 'group'"):
        m = armguard.load_model(urdf)
    np.testing.assert_allclose(m.scene.home("arm"), [0.0, -0.5, 1.25])
    assert any("group_state[0]" in w for w in m.srdf.warnings)
    np.testing.assert_allclose(m.scene_q(m.neutral()), [0.0, -0.5, 1.25])


@pytest.mark.parametrize("joint, value, where, words", [
    ("j9", "0.1", "group_state[0] (home).joint[1] (j9)", "names joint 'j9', which is not a movable joint"),
    ("j3", "2.9", "group_state[0] (home).joint[1] (j3)", "outside the limits"),
    ("j3", "0.1 0.2", "group_state[0] (home).joint[1] (j3)", "expected one value"),
])
def test_a_bad_home_is_an_error_naming_the_srdf_element(tmp_path, joint, value, where, words):
    urdf = package(tmp_path)
    srdf = urdf.with_suffix(".srdf")
    srdf.write_text(srdf_text(f'<group_state name="home" group="arm"><joint name="j2" value="0.5"/>'
                              f'<joint name="{joint}" value="{value}"/></group_state>'))
    with pytest.raises(SceneFileError) as exc:
        armguard.load_model(urdf)
    assert Path(exc.value.file) == srdf.resolve() and exc.value.where == where and words in exc.value.message


def test_a_home_a_whole_turn_out_is_that_angle(tmp_path):
    urdf = package(tmp_path)
    urdf.with_suffix(".srdf").write_text(srdf_text('<group_state name="home" group="arm">'
                                                   '<joint name="j3" value="5.78318530718"/></group_state>'))
    with pytest.warns(ArmguardWarning, match=r"group_state\[0\] \(home\).joint\[0\] \(j3\): value 5.783185307 is outside"):
        m = armguard.load_model(urdf)
    np.testing.assert_allclose(m.scene.home("arm"), [0.0, 0.0, -0.5], atol=1e-10)


@pytest.mark.parametrize("chain, words", [
    ('base_link="base0" tip_link="tool"', "names link 'base0'"),  # z1.srdf: a link z1.urdf lacks
    # icub.srdf's legs run from the chest to a sole
    ('base_link="l2" tip_link="l1"', "tip link 'l1' is not below base link 'l2'"),
    ('base_link="l1" tip_link="tool"', "base link 'l1' is moved by a joint"),  # icub's arms: from the turning chest
], ids=["missing link", "tip not below", "base moved"])
def test_a_chain_armguard_cannot_take_as_an_arm_is_not_one_with_a_warning(tmp_path, chain, words):
    """Pinocchio reads no groups: the model is the URDF's tree, with a warning naming the element."""
    urdf = package(tmp_path)
    urdf.with_suffix(".srdf").write_text(srdf_text(f'<group name="g"><chain {chain}/></group>'))
    with pytest.warns(ArmguardWarning, match=r"group\[0\] \(g\).chain: " + re.escape(words)):
        m = armguard.load_model(urdf)
    assert list(m.scene.robots) == ["arm"] and m.scene.robots["arm"].joint_names == ("j1", "j2", "j3")


@pytest.mark.parametrize("entry, why", [
    # the legged robots' SRDFs (a1, anymal, go2, ...): the virtual joint Pinocchio's free-flyer is named after
    ('<joint name="root_joint" value="0 0 0.3 0 0 0 1"/>', "a floating base"),
    # solo.srdf, talos.srdf: the same 7 values without a <virtual_joint>
    ('<joint name="free" value="0 0 0.3 0 0 0 1"/>', "a floating base"),
    # finger_edu.srdf, the flying arms' SRDFs: a value for a joint the URDF has as fixed
    ('<joint name="j_tool" value="0.7"/>', "a fixed joint of the URDF"),
])
def test_a_home_value_no_joint_takes_is_skipped_with_a_warning(tmp_path, entry, why):
    urdf = package(tmp_path)
    urdf.with_suffix(".srdf").write_text(srdf_text(
        '<virtual_joint name="root_joint" type="floating" parent_frame="world_frame" child_link="base"/>'
        f'<group_state name="home" group="arm">{entry}<joint name="j2" value="0.5"/></group_state>'))
    with pytest.warns(ArmguardWarning, match=r"group_state\[0\] \(home\).joint\[0\] \(\w+\): value not read, .*" + why):
        m = armguard.load_model(urdf)
    np.testing.assert_allclose(m.scene.home("arm"), [0.0, 0.5, 0.0])
    ref = armguard.checker(m, "coal").pair_distances(m.neutral())
    assert np.allclose(armguard.checker(m, "analytic").pair_distances(m.neutral()).distance, ref.distance, atol=1e-9)


def test_a_one_value_home_for_a_joint_the_urdf_lacks_is_still_an_error(tmp_path):
    urdf = package(tmp_path)
    srdf = urdf.with_suffix(".srdf")
    srdf.write_text(srdf_text('<virtual_joint name="root_joint" type="floating" parent_frame="w" child_link="base"/>'
                              '<group_state name="home" group="arm"><joint name="j9" value="0.1"/></group_state>'))
    with pytest.raises(SceneFileError, match="names joint 'j9', which is not a movable joint"):
        armguard.load_model(urdf)


def test_srdf_that_is_a_directory_is_an_error_naming_it(tmp_path):
    urdf = package(tmp_path)
    with pytest.raises(SceneFileError, match="directory"):
        armguard.load_model(urdf, srdf=tmp_path)


def two_arm_urdf() -> str:
    """Two 1-joint arms, each on its own mount fixed to the world: ``<side>_mount -<s>j(z)- <side>``."""
    def arm(side: str, y: float) -> str:
        return (f'<link name="{side}_mount"><collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>'
                f'<joint name="{side}_fix" type="fixed"><parent link="world"/><child link="{side}_mount"/>'
                f'<origin xyz="0 {y} 0"/></joint>'
                f'<link name="{side}"><collision><origin xyz="0.15 0 0"/><geometry><box size="0.3 0.05 0.05"/>'
                f'</geometry></collision></link><joint name="{side[0]}j" type="revolute"><parent link="{side}_mount"/>'
                f'<child link="{side}"/><origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>'
                '<limit lower="-3" upper="3" effort="1" velocity="1"/></joint>')
    return '<robot name="duo"><link name="world"/>' + arm("left", 0.3) + arm("right", -0.3) + "</robot>"


def test_a_movable_link_no_chain_group_reaches_is_an_error_naming_the_srdf(tmp_path):
    """A dual-arm SRDF naming only the left arm: the right arm's link lies in no arm.  The SRDF's
    groups are at fault, so the error names the SRDF file and its chain group, not the URDF."""
    urdf = tmp_path / "duo.urdf"
    urdf.write_text(two_arm_urdf())
    srdf = tmp_path / "duo.srdf"
    srdf.write_text('<robot name="duo"><group name="left_arm"><chain base_link="left_mount" tip_link="left"/></group>'
                    '<group name="right_arm"><chain base_link="nowhere" tip_link="right"/></group></robot>')
    with pytest.warns(ArmguardWarning, match="nowhere"), pytest.raises(SceneFileError) as exc:
        armguard.load_model(urdf)
    assert Path(exc.value.file) == srdf.resolve() and exc.value.where == "group[0] (left_arm).chain"
    assert "'right' is moved by joint 'rj'" in exc.value.message and "['left_arm']" in exc.value.message
    # both chain groups: two arms, each link moving with its own joint
    srdf.write_text(srdf.read_text().replace("nowhere", "right_mount"))
    m = armguard.load_model(urdf)
    assert m.scene.joint_names == ("left_arm/lj", "right_arm/rj")
    assert m.scene.moves("left_arm/left") and m.scene.moves("right_arm/right") and not m.scene.moves("right_arm/right_mount")


# ------------------------------------------------------------------------------ overlapping groups
def _agree_with_coal(model, Q):
    """Analytic and coal: the same signed distance on every pair at every row of ``Q``."""
    a, c = armguard.checker(model, "analytic"), armguard.checker(model, "coal")
    for q in Q:
        da, dc = a.pair_distances(q).distance, c.pair_distances(q).distance
        np.testing.assert_allclose(da, dc, atol=1e-6)
    return a, c


@pytest.mark.parametrize("groups", [
    '<group name="short"><chain base_link="base" tip_link="l2"/></group>'
    '<group name="long"><chain base_link="base" tip_link="tool"/></group>',
    '<group name="wrist"><chain base_link="l2" tip_link="tool"/></group>'
    '<group name="short"><chain base_link="base" tip_link="l2"/></group>',
])
def test_overlapping_chain_groups_are_one_arm(tmp_path, groups):
    urdf = package(tmp_path)
    urdf.with_suffix(".srdf").write_text(srdf_text(groups, disabled=ADJACENT))
    m = armguard.load_model(urdf)
    assert list(m.scene.robots) == ["short"]
    assert m.scene.robots["short"].joint_names == ("j1", "j2", "j3")
    assert len(m.q_index) == m.nq == 3
    Q = m.random_q(40, 3)
    a, c = _agree_with_coal(m, Q)
    hits = c.collides(Q)
    assert hits.any() and (a.collides(Q) == hits).all()  # the far links move with j3: collisions are seen


def test_panda_arm_and_panda_arm_hand_groups_check_the_arm(tmp_path):
    """MoveIt's panda_arm (link0 -> link8) beside panda_arm_hand (link0 -> hand): one arm, every
    shape moving with its own joints; the colliding configuration of the report is seen."""
    src = (ROBOTS / "panda_description/srdf/panda.srdf").read_text()
    dis = src[src.index("<disable_collisions"):src.rindex("</robot>")]
    srdf = tmp_path / "panda_moveit.srdf"
    srdf.write_text('<robot name="panda">'
                    '<group name="panda_arm"><chain base_link="panda_link0" tip_link="panda_link8"/></group>'
                    '<group name="panda_arm_hand"><chain base_link="panda_link0" tip_link="panda_hand"/></group>'
                    + dis + "</robot>")
    m = armguard.load_model(ROBOTS / "panda_description/urdf/panda.urdf", srdf=srdf)
    assert list(m.scene.robots) == ["panda_arm"] and len(m.scene.joint_names) == m.nq
    q7 = [-0.6235, -0.0246, 1.0238, -2.8893, 0.3222, 1.0059, 2.1999]
    q = m.pin_q(np.r_[q7, m.scene_q(m.neutral())[7:]])
    Q = np.vstack([q, m.random_q(16, 27)])
    a, c = _agree_with_coal(m, Q)
    assert a.pair_distances(q).distance.min() < -0.02  # coal: -0.031 m (reported CLEAR +0.135 m before)
    assert (a.collides(Q) == c.collides(Q)).all()


# ------------------------------------------------------------------------------ empty models
def test_a_model_with_no_pair_is_refused_not_clear(tmp_path):
    urdf = package(tmp_path)
    links = ["base", "l1", "l2", "l3", "tool", "post"]
    every = [(x, y) for i, x in enumerate(links) for y in links[i + 1:]]
    urdf.with_suffix(".srdf").write_text(srdf_text(disabled=every))
    m = armguard.load_model(urdf)
    assert len(m.pairs) == 0
    for backend in ("analytic", "coal"):
        with pytest.raises(DetectionError, match="no pair to check"):
            armguard.checker(m, backend)
    with pytest.raises(DetectionError, match="no pair to check"):
        Detector(m.scene)
    run = CliRunner().invoke(main, ["check", str(urdf), "--q", "0,0,0"])
    assert run.exit_code == 3 and "no pair to check" in run.output, run.output
    # one pair left: a verdict again
    urdf.with_suffix(".srdf").write_text(srdf_text(disabled=[p for p in every if p != ("l3", "post")]))
    m = armguard.load_model(urdf)
    assert len(m.pairs) == 1 and Detector(m.scene).check(m.scene_q(m.neutral())) is not None


def test_a_model_whose_pairs_never_move_is_refused_not_clear(tmp_path):
    """Every pair disabled but one between two fixed shapes (the arm's base and the post): the
    check would give the same verdict at every configuration without looking at the arm."""
    urdf = package(tmp_path)
    links = ["base", "l1", "l2", "l3", "tool", "post"]
    every = [(x, y) for i, x in enumerate(links) for y in links[i + 1:]]
    urdf.with_suffix(".srdf").write_text(srdf_text(disabled=[p for p in every if p != ("base", "post")]))
    m = armguard.load_model(urdf)
    assert set(zip(m.pairs.owner_a, m.pairs.owner_b)) in ({("post", "arm/base")}, {("arm/base", "post")})
    for backend in ("analytic", "coal"):
        with pytest.raises(DetectionError, match="no pair to check with a shape the configuration moves"):
            armguard.checker(m, backend)
    with pytest.raises(DetectionError, match="no pair to check with a shape the configuration moves"):
        Detector(m.scene)
    run = CliRunner().invoke(main, ["check", str(urdf), "--q", "0,0,0"])
    assert run.exit_code == 3 and "no pair to check" in run.output and "CLEAR" not in run.output, run.output
    # why: neither owner moves, and the pair's distance (coal on pinocchio's placements, the
    # ground truth) is the same at every configuration
    import coal
    import pinocchio as pin

    assert not m.scene.moves("arm/base") and not m.scene.moves("post")
    assert m.scene.moves("arm/l1") and m.scene.moves("arm/tool")  # below j1 (tool through a fixed joint)
    ia, ib = (m.geometry_index(n) for n in (m.pairs.a[0], m.pairs.b[0]))
    gos, gd, dist = m.collision_model.geometryObjects, pin.GeometryData(m.collision_model), []
    for q in m.random_q(5, 11):
        pin.updateGeometryPlacements(m.pin_model, m.pin_model.createData(), m.collision_model, gd, q)
        res = coal.DistanceResult()
        X = [coal.Transform3s(gd.oMg[i].rotation, gd.oMg[i].translation) for i in (ia, ib)]
        coal.distance(gos[ia].geometry, X[0], gos[ib].geometry, X[1], coal.DistanceRequest(), res)
        dist.append(res.min_distance)
    assert dist[0] > 0.0 and np.ptp(dist) < 1e-12
    # one moving pair added: a verdict again
    urdf.with_suffix(".srdf").write_text(srdf_text(disabled=[p for p in every if p not in (("base", "post"), ("l3", "post"))]))
    m = armguard.load_model(urdf)
    assert len(m.pairs) == 2 and Detector(m.scene).check(m.scene_q(m.neutral())) is not None


# ------------------------------------------------------------------------------ public robots at home
PUBLIC = {  # the robots that load in seconds today; z1, so100, so101, ur3, kinova, xarm7 wait for faster meshes
    "panda": "panda_description/urdf/panda.urdf",
    "panda_collision": "panda_description/urdf/panda_collision.urdf",
    "ur5": "ur_description/urdf/ur5_robot.urdf",
    "ur10": "ur_description/urdf/ur10_robot.urdf",
    "talos_left_arm": "talos_data/robots/talos_left_arm.urdf",
}


@pytest.mark.parametrize("name", list(PUBLIC))
def test_public_robot_is_clear_at_its_srdf_home(name):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ArmguardWarning)  # talos.srdf is the whole humanoid's
        m = armguard.load_model(ROBOTS / PUBLIC[name])
    q = m.neutral()
    a, c = _agree_with_coal(m, [q])
    d = c.pair_distances(q)
    near = d.nearest()
    assert d.distance.min() > 0.0, f"{name} at home: {[(n.a, n.b, n.distance) for n in near.values()]}"


def test_info_says_which_srdf_was_used(tmp_path):
    urdf = package(tmp_path)
    found = urdf.parent.parent / "srdf" / "arm.srdf"
    found.write_text(srdf_text('<group_state name="up"><joint name="j2" value="0.5"/></group_state>'))
    out = CliRunner().invoke(main, ["info", str(urdf)])
    assert out.exit_code == 0, out.output
    assert f"SRDF: {found.resolve()} (in ../srdf/, under the URDF's name)" in out.output
    assert "warning: group_state[0] (up): no attribute 'group'" in out.output
    given = tmp_path / "given.srdf"
    given.write_text(srdf_text())
    out = CliRunner().invoke(main, ["info", str(urdf), "--srdf", str(given)])
    assert out.exit_code == 0 and f"SRDF: {given} (given (srdf=))" in out.output, out.output
    found.unlink()
    out = CliRunner().invoke(main, ["info", str(urdf)])
    assert out.exit_code == 0 and "SRDF: none found" in out.output, out.output


def test_info_on_public_robots_says_how_their_srdf_came():
    """ur5's SRDF comes from armguard's table of public robots, not from the user ("given (srdf=)" was
    printed); a public robot without one says so (ur3 printed no SRDF line at all)."""
    out = CliRunner().invoke(main, ["info", "ur5"])
    assert out.exit_code == 0 and "(the SRDF of public robot 'ur5' (docs/models.md))" in out.output, out.output
    assert "given (srdf=)" not in out.output
    out = CliRunner().invoke(main, ["info", "ur3"])
    assert out.exit_code == 0 and "SRDF: none found" in out.output, out.output


def test_limbs_from_one_base_are_the_robot_named_as_the_urdf_names_it(tmp_path):
    """a1's four leg groups (and talos's legs, pr2's arms) start at one trunk: one robot, named after
    the URDF, not after its first leg (the whole quadruped was ``lf_leg``, its rear legs' links
    ``lf_leg/RR_thigh``).  A group inside another's chain (a hand's beside its arm's) still names the
    arm, as before."""
    trunk = '<link name="trunk"><collision><geometry><box size="0.4 0.2 0.1"/></geometry></collision></link>'

    def leg(side: str, y: float) -> str:
        return (f'<link name="{side}"><collision><origin xyz="0 0 -0.1"/><geometry><box size="0.05 0.05 0.2"/>'
                f'</geometry></collision></link><joint name="{side}_hip" type="revolute"><parent link="trunk"/>'
                f'<child link="{side}"/><origin xyz="0 {y} -0.05"/><axis xyz="0 1 0"/>'
                '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>')

    urdf = tmp_path / "quad.urdf"
    urdf.write_text('<robot name="quad"><link name="world"/>' + trunk + '<joint name="fix" type="fixed"><parent '
                    'link="world"/><child link="trunk"/></joint>' + leg("left", 0.15) + leg("right", -0.15) + "</robot>")
    srdf = tmp_path / "quad.srdf"
    groups = ('<group name="left_leg"><chain base_link="trunk" tip_link="left"/></group>'
              '<group name="right_leg"><chain base_link="trunk" tip_link="right"/></group>')
    srdf.write_text(f'<robot name="quad">{groups}</robot>')
    m = armguard.load_model(urdf)
    assert list(m.scene.robots) == ["quad"] and m.scene.robots["quad"].joint_names == ("left_hip", "right_hip")
    srdf.write_text('<robot name="quad"><group name="left_leg"><chain base_link="trunk" tip_link="left"/></group>'
                    '<group name="hip"><chain base_link="trunk" tip_link="left"/></group></robot>')
    assert list(armguard.load_model(urdf).scene.robots) == ["left_leg"]  # one branch: the first group names it


def test_an_end_effectors_group_does_not_name_the_arm(tmp_path):
    """kinova.srdf's one group, a chain from the base to the hand, is the group of its <end_effector>:
    the arm was named 'end_effector' (a trajectory's 'robot: kinova' refused, every link 'end_effector/...').
    Named as the URDF names the robot; a group that is no end effector's still names its arm."""
    urdf = package(tmp_path)
    group = '<group name="hand_group"><chain base_link="base" tip_link="tool"/></group>'
    ee = '<end_effector name="hand" parent_link="tool" group="hand_group"/>'
    urdf.with_suffix(".srdf").write_text(srdf_text(group + ee, disabled=ADJACENT))
    m = armguard.load_model(urdf)
    assert list(m.scene.robots) == [m.name] and m.name != "hand_group"
    urdf.with_suffix(".srdf").write_text(srdf_text(group, disabled=ADJACENT))
    assert list(armguard.load_model(urdf).scene.robots) == ["hand_group"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert list(armguard.load_model("kinova").scene.robots) == ["kinova"]
