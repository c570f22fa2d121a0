"""Public robots by name (``armguard.model._public``): every name resolves to its package's files, loads
through ``load_model``/``load_scene``/the CLI, and an unknown name lists the known ones.

Name resolution is checked for every robot without loading it; one robot is loaded for real.
"""

from __future__ import annotations

import importlib.metadata
import importlib.util
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from click.testing import CliRunner

import armguard
from armguard import SceneError
from armguard.cli import main
from armguard.model import _load, _public
from armguard.model._public import (EXAMPLE_ROBOT_DATA, PUBLIC_ROBOTS, PYBULLET_DATA, known_models, package_root,
                                    public_robot, public_robot_files, public_robot_names)

HAS_PYBULLET = importlib.util.find_spec("pybullet_data") is not None
# what issue 20 names: every arm of example-robot-data and three of pybullet_data
ISSUE_NAMES = ("panda", "panda_collision", "ur3", "ur5", "ur10", "ur5_gripper", "kinova", "xarm7", "z1", "so100", "so101",
               "talos_left_arm", "franka_panda", "kuka_iiwa", "xarm6", "iiwa")


def _needs(robot):
    if robot.package == PYBULLET_DATA and not HAS_PYBULLET:
        pytest.skip("pybullet (a test extra) is not installed")


def test_every_name_of_the_issue_is_known():
    assert set(ISSUE_NAMES) <= set(public_robot_names(aliases=True))
    assert public_robot("iiwa") is public_robot("kuka_iiwa")
    assert public_robot("no_such_robot") is None


@pytest.mark.parametrize("robot", PUBLIC_ROBOTS, ids=[r.name for r in PUBLIC_ROBOTS])
def test_files_resolve_where_the_package_installed_them(robot):
    _needs(robot)
    urdf, srdf = public_robot_files(robot.name)
    assert urdf.is_file() and urdf.suffix == ".urdf"
    assert urdf == package_root(robot.package) / robot.urdf
    assert (srdf is None) == (robot.srdf is None)
    if srdf is not None:
        assert srdf.is_file() and srdf.suffix == ".srdf"
        # the SRDF read strictly (given as srdf=) may name only links of this URDF
        links = {el.get("name") for el in ET.parse(urdf).getroot().iter("link")}
        named = {el.get(k) for el in ET.parse(srdf).getroot().iter("disable_collisions") for k in ("link1", "link2")}
        assert named <= links, sorted(named - links)


@pytest.mark.parametrize("name", ISSUE_NAMES)
def test_load_model_by_name_loads_the_registry_files(name, monkeypatch):
    """The name branch hands the registry's URDF and SRDF to ``model_from_urdf`` (not loaded here: see below)."""
    robot = public_robot(name)
    _needs(robot)
    calls = []
    monkeypatch.setattr(_load, "model_from_urdf", lambda path, **kw: calls.append((path, kw)) or "model")
    assert armguard.load_model(name) == "model"
    urdf, srdf = public_robot_files(name)
    assert calls == [(urdf, {"srdf": srdf, "package_dirs": ()} if srdf is None else
                      {"srdf": srdf, "package_dirs": (), "srdf_found": f"the SRDF of public robot {name!r} (docs/models.md)"})]
    calls.clear()
    armguard.load_model(name, srdf="other.srdf")  # srdf= wins over the registry's
    assert calls[0][1]["srdf"] == "other.srdf"


def test_builtins_come_before_public_robots(monkeypatch):
    monkeypatch.setattr(_load, "model_from_urdf", lambda *a, **kw: pytest.fail("a built-in name loaded as a URDF"))
    monkeypatch.setattr(_load, "model_from_yaml", lambda path, srdf=None: path)
    assert armguard.load_model("hermes") == _load.builtin_model_path("hermes")


def test_panda_loads_by_name_with_its_srdf():
    urdf, srdf = public_robot_files("panda")
    m = armguard.load_model("panda")
    assert m.name == "panda" and m.nq == 8
    files = [Path(f) for f in m.files]
    assert files[:2] == [urdf.resolve(), srdf]  # then the meshes the geometry came from
    assert files[2:] and all(f.suffix.lower() in (".stl", ".dae", ".obj") and f.is_file() for f in files[2:])
    disabled = {frozenset((el.get("link1"), el.get("link2"))) for el in ET.parse(srdf).getroot().iter("disable_collisions")}
    checked = {frozenset(o.split("/", 1)[1] for o in pair) for pair in zip(m.pairs.owner_a, m.pairs.owner_b)}
    assert checked and not checked & disabled  # the SRDF was applied: none of its disabled pairs is checked


def test_unknown_name_lists_the_known_ones():
    with pytest.raises(SceneError) as err:
        armguard.load_model("ur11")
    for n in ("hermes", "ranger", "ur10", "xarm7", "talos_left_arm", "kuka_iiwa"):
        assert repr(n) in str(err.value)
    with pytest.raises(SceneError, match="'z1'"):
        armguard.load_scene("ur11")
    res = CliRunner().invoke(main, ["check", "ur11"])
    assert res.exit_code == 3 and res.output.startswith("error:") and "'xarm7'" in res.output, res.output
    assert res.output.strip().count("\n") == 0


def test_a_missing_package_is_named(monkeypatch):
    monkeypatch.setattr(_public, "package_root", lambda package: None)
    with pytest.raises(SceneError, match="pybullet_data, which is not installed"):
        public_robot_files("xarm6")
    with pytest.raises(SceneError, match="example-robot-data, which is not installed"):
        armguard.load_model("ur10")
    avail = {m.name: m.available for m in known_models()}
    assert avail["hermes"] and not avail["ur10"] and not avail["xarm6"]


def test_example_robot_data_found_without_its_record(monkeypatch):
    """No distribution record (a copied environment): its cmeel prefix is found on ``sys.path``."""
    expected = package_root(EXAMPLE_ROBOT_DATA)

    def no_record(name):
        raise importlib.metadata.PackageNotFoundError(name)

    monkeypatch.setattr(importlib.metadata, "distribution", no_record)
    assert package_root(EXAMPLE_ROBOT_DATA) == expected


def test_info_without_a_name_lists_every_known_model():
    res = CliRunner().invoke(main, ["info"], terminal_width=250)
    assert res.exit_code == 0, res.output
    rows = {line.split("│")[1].split()[0]: line for line in res.output.splitlines() if line.startswith("│")}
    for m in known_models():
        assert m.name in rows, m.name
        assert ("│ yes" in rows[m.name]) == m.available
    assert set(rows) >= {"ranger", "hermes", "puma560", "gmf_s480", "rover", *public_robot_names()}
    assert "(iiwa)" in rows["kuka_iiwa"]
