"""A scene file's ``urdf:`` robot takes its SRDF's disabled pairs as :func:`armguard.load_model` does.

Without ``srdf:`` the SRDF found beside the URDF (or the public robot's) disables the same pairs as
in ``load_model`` (before, only its home was read and panda's found SRDF left 108 shape pairs checked
against load_model's 44: false collisions at the hand); ``srdf: none`` none; and a save/load round
trip keeps the pairs the saved scene checked (a Model loaded with ``srdf=False`` saves ``srdf: none``).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest
import yaml

import armguard
from armguard.model._public import public_robot_files
from armguard.scene import load_scene, save_scene


def _owner_pairs(scene) -> set:
    return {frozenset(p) for pairs in scene.allowed_pairs_by_category().values() for p in pairs}


def _scene_file(tmp_path, robot: dict):
    p = tmp_path / "cell.yaml"
    p.write_text(yaml.safe_dump({"armguard_scene": 1, "name": "cell", "robots": [robot]}))
    return p


@pytest.fixture(scope="module")
def panda():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return armguard.load_model("panda")


def test_a_urdf_robot_without_srdf_key_checks_the_pairs_load_model_checks(tmp_path, panda):
    urdf, _ = public_robot_files("panda")  # its SRDF is found in the package's srdf/ folder
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = load_scene(_scene_file(tmp_path, {"name": "panda", "urdf": str(urdf)}))
        alone = load_scene(_scene_file(tmp_path, {"name": "panda", "urdf": str(urdf), "srdf": "none"}))
    assert _owner_pairs(scene) == _owner_pairs(panda.scene)
    assert scene.disabled_pairs == panda.scene.disabled_pairs and len(scene.disabled_pairs) == 35
    assert len(_owner_pairs(alone)) > len(_owner_pairs(scene))  # srdf: none keeps every pair
    assert not alone.disabled_pairs


def test_a_partial_srdf_found_for_a_smaller_urdf_applies_its_own_links_pairs(tmp_path):
    """talos_left_arm finds the whole humanoid's talos.srdf: its pairs of links the arm lacks are
    skipped (as load_model skips them), the arm's own pairs hold."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = armguard.load_model("talos_left_arm")
        urdf, _ = public_robot_files("talos_left_arm")
        scene = load_scene(_scene_file(tmp_path, {"name": next(iter(model.scene.robots)), "urdf": str(urdf)}))
    assert model.scene.disabled_pairs and scene.disabled_pairs == model.scene.disabled_pairs
    assert _owner_pairs(scene) == _owner_pairs(model.scene)


def test_a_found_srdf_pair_of_one_link_is_skipped_as_load_model_skips_it(tmp_path):
    urdf = tmp_path / "two.urdf"
    urdf.write_text("""<robot name="two">
  <link name="base"><collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <link name="l1"><collision><origin xyz="0.3 0 0"/><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <link name="l2"><collision><origin xyz="0.3 0 0"/><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0.6 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>""")
    (tmp_path / "two.srdf").write_text('<robot name="two"><disable_collisions link1="l1" link2="l1" reason="x"/>'
                                       '<disable_collisions link1="base" link2="l2" reason="Never"/></robot>')
    model = armguard.load_model(urdf)
    scene = load_scene(_scene_file(tmp_path, {"name": "two", "urdf": str(urdf)}))
    assert scene.disabled_pairs == model.scene.disabled_pairs == {frozenset(("two/base", "two/l2"))}
    back = load_scene(save_scene(scene, tmp_path / "again.yaml"))
    assert back.disabled_pairs == scene.disabled_pairs and _owner_pairs(back) == _owner_pairs(scene)


def test_a_model_loaded_without_its_srdf_saves_srdf_none_and_loads_back_with_its_pairs(tmp_path, panda):
    urdf, srdf = public_robot_files("panda")  # the SRDF is found on a reload, unless the saved file says none
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        bare = armguard.load_model(urdf, srdf=False)
        saved = save_scene(bare.scene, tmp_path / "bare.yaml")
        assert yaml.safe_load(saved.read_text())["robots"][0]["srdf"] == "none"
        back = load_scene(saved)
        assert _owner_pairs(back) == _owner_pairs(bare.scene) and not back.disabled_pairs
        named = armguard.load_model(urdf, srdf=srdf)
        again = load_scene(save_scene(named.scene, tmp_path / "named.yaml"))
    assert yaml.safe_load((tmp_path / "named.yaml").read_text())["robots"][0]["srdf"] == str(srdf.resolve())
    assert _owner_pairs(again) == _owner_pairs(named.scene) == _owner_pairs(panda.scene)


@pytest.mark.parametrize("case", ["srdf: none", "srdf: one pair", "srdf=False"])
def test_a_sidecar_models_srdf_choice_survives_a_save_and_reload(tmp_path, case):
    """A sidecar naming no SRDF or another one, or loaded with ``srdf=False``: the saved scene names
    that choice, so the reload does not take the SRDF found beside the URDF (25 pairs fewer on panda)."""
    urdf, _ = public_robot_files("panda")
    (tmp_path / "one_pair.srdf").write_text('<robot name="panda"><disable_collisions link1="panda_link0" '
                                            'link2="panda_link1" reason="Adjacent"/></robot>')
    model = {"urdf": str(urdf)}
    if case != "srdf=False":
        model["srdf"] = "none" if case == "srdf: none" else "one_pair.srdf"
    side = tmp_path / "cell.yaml"
    side.write_text(yaml.safe_dump({"armguard_scene": 1, "name": "cell", "model": model}))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = armguard.load_model(side, srdf=False if case == "srdf=False" else None)
        back = load_scene(save_scene(m.scene, tmp_path / "saved.yaml"))
    assert _owner_pairs(back) == _owner_pairs(m.scene)
    assert len(m.scene.disabled_pairs) == (1 if case == "srdf: one pair" else 0)


@pytest.mark.parametrize("how", ["load_model", "scene file"])
def test_an_srdf_pair_checked_again_stays_checked_after_a_save_and_reload(tmp_path, how):
    """``Scene.enable_pair`` on a pair the SRDF disables: the saved file lists it under
    ``pairs.enable`` (its SRDF, read again, disables it; before, the reload did so silently)."""
    urdf, _ = public_robot_files("panda")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = (armguard.load_model("panda").scene if how == "load_model"
                 else load_scene(_scene_file(tmp_path, {"name": "panda", "urdf": str(urdf)})))
        pair = frozenset(("panda/panda_link5", "panda/panda_hand"))
        assert pair in scene.disabled_pairs
        scene.enable_pair(*pair)
        saved = save_scene(scene, tmp_path / "saved.yaml")
        assert yaml.safe_load(saved.read_text())["pairs"]["enable"] == [sorted(pair)]
        back = load_scene(saved)
    assert pair not in back.disabled_pairs and _owner_pairs(back) == _owner_pairs(scene)


def test_pairs_enable_checks_a_pair_the_srdf_disables_and_names_an_unknown_owner(tmp_path):
    urdf, _ = public_robot_files("panda")
    p = tmp_path / "cell.yaml"
    p.write_text(yaml.safe_dump({"armguard_scene": 1, "name": "cell", "robots": [{"name": "panda", "urdf": str(urdf)}],
                                 "pairs": {"enable": [["panda/panda_link5", "panda/panda_hand"]]}}))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = load_scene(p)
        assert frozenset(("panda/panda_link5", "panda/panda_hand")) in _owner_pairs(s)
        p.write_text(yaml.safe_dump({"armguard_scene": 1, "name": "cell", "robots": [{"name": "panda", "urdf": str(urdf)}],
                                     "pairs": {"enable": [["panda/panda_link5", "panda/hand"]]}}))
        with pytest.raises(armguard.SceneFileError) as err:
            load_scene(p)
    assert err.value.where.startswith("pairs.enable[0]") and "hand" in err.value.message


def test_a_scene_loaded_by_a_relative_path_saves_elsewhere_and_loads_back(tmp_path, monkeypatch):
    """The URDF path of a scene file read by a relative path was saved relative to the working
    directory and read back relative to the saved file: "URDF file not found"."""
    urdf, _ = public_robot_files("ur5")
    cell = tmp_path / "cell"
    cell.mkdir()
    (cell / "ur5.urdf").symlink_to(urdf)
    (cell / "cell.yaml").write_text(yaml.safe_dump({"armguard_scene": 1, "name": "cell",
                                                     "robots": [{"name": "ur5", "urdf": "ur5.urdf", "srdf": "none"}]}))
    monkeypatch.chdir(tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = load_scene(Path("cell") / "cell.yaml")
        (tmp_path / "out").mkdir()
        back = load_scene(save_scene(s, tmp_path / "out" / "saved.yaml"))
    assert back.joint_names == s.joint_names and _owner_pairs(back) == _owner_pairs(s)


def test_two_robots_from_one_urdf_save_and_load_back(tmp_path):
    """Two arms of a scene file from the same one-arm URDF are two robots, not one URDF's two arms:
    they save (before: "its URDF holds the arms ['left', 'right']")."""
    urdf, _ = public_robot_files("ur5")
    p = tmp_path / "two.yaml"
    p.write_text(yaml.safe_dump({"armguard_scene": 1, "name": "two", "robots": [
        {"name": "left", "urdf": str(urdf)}, {"name": "right", "urdf": str(urdf), "mount": {"xyz": [1.0, 0, 0]}}]}))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = load_scene(p)
        back = load_scene(save_scene(s, tmp_path / "saved.yaml"))
    assert back.joint_names == s.joint_names and _owner_pairs(back) == _owner_pairs(s)
    assert back.disabled_pairs == s.disabled_pairs


@pytest.mark.parametrize("srdf", [False, "pairs only"])
def test_a_built_in_loaded_without_its_pairs_saves_its_groups_and_loads_back_alike(tmp_path, srdf):
    """hermes with ``srdf=False`` or an SRDF of pairs only keeps its sidecar SRDF's groups (the arm
    ``hera``, its payload on ``link6``): the saved file names that SRDF and lists its pairs this Model
    checks under ``pairs.enable`` (``srdf: none`` had lost the groups: "robot 'hera' has no link 'link6'")."""
    if srdf == "pairs only":
        srdf = tmp_path / "pairs.srdf"
        srdf.write_text('<robot name="hermes"><disable_collisions link1="hera_link1" link2="hera_link2" reason="Adjacent"/>'
                        "</robot>")
    m = armguard.load_model("hermes", srdf=srdf)
    back = load_scene(save_scene(m.scene, tmp_path / "h.yaml"))
    assert back.joint_names == m.scene.joint_names and list(back.payloads) == list(m.scene.payloads)
    assert _owner_pairs(back) == _owner_pairs(m.scene)


def test_a_file_pair_enabled_under_a_robot_wide_disable_is_refused(tmp_path):
    """``disable: [[panda, table]]`` with ``enable: [[panda/panda_link1, table]]`` left the link unchecked."""
    urdf, _ = public_robot_files("panda")
    p = tmp_path / "cell.yaml"
    p.write_text(yaml.safe_dump({"armguard_scene": 1, "name": "cell",
                                 "bodies": [{"name": "table", "shapes": [{"type": "box", "size": [1, 1, 0.1], "xyz": [0, 0, -0.1]}]}],
                                 "robots": [{"name": "panda", "urdf": str(urdf)}],
                                 "pairs": {"disable": [["panda", "table"]], "enable": [["panda/panda_link1", "table"]]}}))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(armguard.SceneFileError) as err:
            load_scene(p)
    assert err.value.where.startswith("pairs.enable[0]") and "stays disabled by ['panda', 'table']" in err.value.message


def test_self_pairs_a_file_lists_are_checked_though_the_found_srdf_disables_one(tmp_path):
    urdf, _ = public_robot_files("panda")
    want = [["panda_link3", "panda_hand"], ["panda_link1", "panda_link5"]]  # the SRDF disables link3-hand
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = load_scene(_scene_file(tmp_path, {"name": "panda", "urdf": str(urdf), "self_pairs": want}))
    assert sorted(tuple(sorted((p.a, p.b))) for p in s.allowed_pairs()) == sorted(
        tuple(sorted((f"panda/{a}", f"panda/{b}"))) for a, b in want)


def test_save_lists_no_enabled_pair_of_a_removed_body(tmp_path):
    srdf = tmp_path / "base_table.srdf"
    srdf.write_text('<robot name="puma560"><disable_collisions link1="puma560_base" link2="table" reason="Static"/>'
                    '<disable_collisions link1="puma560_link1" link2="block_a" reason="Never"/></robot>')
    urdf = next(f for f in armguard.load_model("puma560").files if f.suffix == ".urdf")
    s = armguard.load_model(urdf, srdf=srdf).scene.copy()
    s.remove_body("table")
    back = load_scene(save_scene(s, tmp_path / "rb.yaml"))
    assert "table" not in back.bodies and _owner_pairs(back) == _owner_pairs(s)


def test_a_project_folder_saved_and_moved_whole_loads_back(tmp_path):
    """URDF and SRDF paths were saved absolute: a cell folder copied to another machine or renamed failed
    with "URDF file not found".  Files inside the saved file's folder are now relative to it; a
    package's URDF outside it stays absolute."""
    import shutil

    urdf, srdf = public_robot_files("ur5")
    cell = tmp_path / "cell"
    (cell / "robots").mkdir(parents=True)
    (cell / "robots" / "ur5.urdf").write_text(urdf.read_text().replace(
        "package://example-robot-data/robots/ur_description/", f"{urdf.parent.parent.as_posix()}/"))
    shutil.copy(srdf, cell / "robots" / "ur5.srdf")
    (cell / "cell.yaml").write_text(yaml.safe_dump({"armguard_scene": 1, "name": "cell", "robots": [
        {"name": "ur5", "urdf": "robots/ur5.urdf", "srdf": "robots/ur5.srdf"},
        {"name": "other", "urdf": str(urdf), "srdf": "none", "mount": {"xyz": [1.5, 0, 0]}}]}))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = load_scene(cell / "cell.yaml")
        saved = yaml.safe_load(save_scene(s, cell / "saved.yaml").read_text())
        assert [(r["urdf"], r.get("srdf")) for r in saved["robots"]] == [("robots/ur5.urdf", "robots/ur5.srdf"),
                                                                         (str(urdf), "none")]
        moved = tmp_path / "moved"
        shutil.move(cell, moved)
        back = load_scene(moved / "saved.yaml")
    assert back.joint_names == s.joint_names and _owner_pairs(back) == _owner_pairs(s)
