"""check-urdf findings and load warnings. A revolute joint whose ``<limit>`` has no lower/upper is read as [0, 0] (urdfdom's default): a
joint that cannot move, so a smaller model than meant.  Loading warns, naming the joint and line,
and ``armguard check-urdf`` reports it (both said nothing)."""

from __future__ import annotations

import warnings

import pytest
from click.testing import CliRunner

import armguard
from armguard.cli import main

_URDF = """<robot name="two">
  <link name="base"><collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <link name="l1"><collision><origin xyz="0.3 0 0"/><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <link name="l2"><collision><origin xyz="0.3 0 0"/><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>
    LIMIT</joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0.6 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>"""


def test_a_limit_without_lower_and_upper_is_warned_of_and_linted(tmp_path):
    p = tmp_path / "two.urdf"
    p.write_text(_URDF.replace("LIMIT", '<limit effort="1" velocity="1"/>'))
    with pytest.warns(armguard.ArmguardWarning, match=r"joint\[j1\]\.limit \(line 6\): no lower or upper: read as "
                                                      r"\[0 \(unset\), 0 \(unset\)\].*can move nowhere"):
        m = armguard.load_model(p, srdf=False)
    assert list(m.scene.robots["two"].lower) == [0.0, -1.0] and list(m.scene.robots["two"].upper) == [0.0, 1.0]
    r = CliRunner().invoke(main, ["-q", "check-urdf", str(p), "--json"])
    assert '"frozen-joint"' in r.output and "joint[j1].limit" in r.output, r.output


def test_a_limit_with_both_bounds_says_nothing(tmp_path):
    p = tmp_path / "two.urdf"
    p.write_text(_URDF.replace("LIMIT", '<limit lower="-2" upper="2" effort="1" velocity="1"/>'))
    with warnings.catch_warnings():
        warnings.simplefilter("error", armguard.ArmguardWarning)
        armguard.load_model(p, srdf=False)
    r = CliRunner().invoke(main, ["-q", "check-urdf", str(p), "--json"])
    assert "frozen-joint" not in r.output


def test_check_urdf_checks_the_srdf_load_model_finds_and_its_end_effectors(tmp_path):
    """The SRDF in ``../srdf/`` (example-robot-data's layout) was not checked ("clean", "srdf": null),
    nor an ``<end_effector parent_link>``."""
    import json

    (tmp_path / "urdf").mkdir()
    (tmp_path / "srdf").mkdir()
    p = tmp_path / "urdf" / "two.urdf"
    p.write_text(_URDF.replace("LIMIT", '<limit lower="-2" upper="2" effort="1" velocity="1"/>'))
    (tmp_path / "srdf" / "two.srdf").write_text(
        '<robot name="two"><group name="arm"><chain base_link="base" tip_link="l2"/></group>'
        '<end_effector name="tool" parent_link="l2_tcp" group="arm"/></robot>')
    r = CliRunner().invoke(main, ["-q", "check-urdf", str(p), "--json"])
    d = json.loads(r.output)
    assert d["srdf"] == str(tmp_path / "srdf" / "two.srdf")
    assert [(f["check"], f["severity"]) for f in d["findings"] if "end_effector[tool].parent_link" in f["where"]] == [
        ("srdf-name", "error")], d["findings"]


def test_a_misspelt_or_repeated_element_is_reported():
    """``<orgin>`` in a collision (the box then sat at the link's origin) and a second ``<limit>`` (the
    first wins) passed check-urdf as "clean"."""
    import json
    import tempfile
    from pathlib import Path

    text = _URDF.replace("LIMIT", '<limit lower="-2" upper="2" effort="1" velocity="1"/><limit lower="-1" upper="1" '
                                  'effort="1" velocity="1"/>').replace('<collision><origin xyz="0.3 0 0"/>',
                                                                       '<collision><orgin xyz="0.3 0 0"/>', 1)
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "two.urdf"
        p.write_text(text)
        r = CliRunner().invoke(main, ["-q", "check-urdf", str(p), "--json"])
    found = {(f["where"].split(": ", 1)[1], f["message"]) for f in json.loads(r.output)["findings"] if f["check"] == "unread-element"}
    assert found == {("link[l1].collision[0].orgin (line 3)", "<orgin> is read by nothing: did you mean <origin>? (it changes what "
                                                     "is checked)"),
                     ("joint[j1].limit", "2 <limit> elements: only the first is read")}, found


def test_a_misspelt_collision_is_an_error_of_load_model_and_check_urdf(tmp_path):
    """A link's ``<colision>`` left the link without geometry: load_model said nothing (its pairs were simply
    not checked) and check-urdf gave a warning with exit 0; then load_model warned, and ``check`` said CLEAR
    of the smaller model.  load_model refuses it, naming the place; check-urdf reports it once."""
    import json

    import armguard
    from armguard._errors import SceneFileError

    text = _URDF.replace("LIMIT", '<limit lower="-2" upper="2" effort="1" velocity="1"/>')
    i = text.index("<collision>", text.index('<link name="l2"'))
    bad = text[:i] + text[i:].replace("<collision>", "<colision>", 1).replace("</collision>", "</colision>", 1)
    bad = bad.replace("</robot>", '<link name="l3"><collision><origin xyz="0.3 0 0"/><geometry><box size="0.1 0.1 0.1"/>'
                      '</geometry></collision></link><joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/>'
                      '<origin xyz="0.6 0 0"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/>'
                      '</joint></robot>')  # pairs left to check: base - l3, l1 - l3
    p = tmp_path / "two.urdf"
    p.write_text(bad)
    line = bad[:bad.index("<colision>")].count("\n") + 1
    with pytest.raises(SceneFileError, match=rf"two.urdf: link\[l2\].colision \(line {line}\): <colision> is read by nothing: "
                                             r"did you mean <collision>\? \(the link has no geometry from it: its pairs are not checked\)"):
        armguard.load_model(p, srdf=False)
    r = CliRunner().invoke(main, ["-q", "check-urdf", str(p), "--json"])
    assert r.exit_code == 1, r.output
    findings = json.loads(r.output)["findings"]
    found = [(f["severity"], f["message"]) for f in findings if f["check"] == "unread-element"]
    assert found == [("error", "<colision> is read by nothing: did you mean <collision>? (it changes what is checked)")], found
    assert not [f for f in findings if f["check"] == "load"], findings  # said once


def test_info_says_no_hull_was_stored_when_the_cache_cannot_be_written(tmp_path):
    """It warned that the cache could not be written, then said "1 computed and stored" (a new process:
    this one may hold the hulls already)."""
    import os
    import subprocess
    import sys

    blocker = tmp_path / "a_file"
    blocker.write_text("not a folder")
    env = {**os.environ, "ARMGUARD_CACHE_DIR": str(blocker / "cache"), "COLUMNS": "300"}
    r = subprocess.run([sys.executable, "-m", "armguard.cli", "info", "ur5"], capture_output=True, text=True, env=env,
                       timeout=300)
    assert r.returncode == 0 and "could not be written" in r.stderr, r.stderr
    line = next(ln for ln in r.stdout.splitlines() if ln.startswith("Mesh hulls"))
    assert "0 stored: the cache could not be written" in line and "and stored" not in line, line


def _units(report) -> list:
    from armguard.harness._lint import Check

    return report.by_check(Check.UNITS)


def test_degrees_in_rpy_and_in_a_revolute_limit_are_warned_of_with_the_radians(tmp_path):
    """``rpy="0 0 90"`` turns the shape 90 rad (about 77 degrees), not 90 degrees, without a word."""
    from armguard.harness import check_model_files

    p = tmp_path / "two.urdf"
    p.write_text(_URDF.replace("LIMIT", '<limit lower="-170" upper="170" effort="1" velocity="1"/>')
                 .replace('<origin xyz="0.6 0 0"/>', '<origin xyz="0.6 0 0" rpy="0 0 90"/>'))
    found = {f.where: f for f in _units(check_model_files(p, n_configs=1))}
    assert set(found) == {"two.urdf: joint[j2].origin", "two.urdf: joint[j1].limit"}, found
    assert 'rpy="0 0 1.5708"' in found["two.urdf: joint[j2].origin"].suggestion
    assert 'lower="-2.96706" upper="2.96706"' in found["two.urdf: joint[j1].limit"].suggestion
    r = CliRunner().invoke(main, ["-q", "check-urdf", str(p), "--json"])
    assert '"units"' in r.output and r.exit_code == 0, r.output  # warnings: exit 0


def test_radians_up_to_two_turns_and_unbounded_limits_pass(tmp_path):
    """UR's +-2 pi limits, an rpy of pi, and pybullet's 1e16 'unbounded' rotor limits are radians."""
    from armguard.harness import check_model_files

    p = tmp_path / "two.urdf"
    p.write_text(_URDF.replace("LIMIT", '<limit lower="-1e16" upper="1e16" effort="1" velocity="1"/>')
                 .replace('<origin xyz="0.6 0 0"/>', '<origin xyz="0.6 0 0" rpy="3.14159 0 -6.2832"/>')
                 .replace('<limit lower="-1" upper="1"', '<limit lower="-12.5664" upper="12.5664"'))
    assert _units(check_model_files(p, n_configs=1)) == []  # 2 pi and 4 pi written to 4 places


def test_a_large_or_small_primitive_is_no_mesh_in_other_units(tmp_path):
    """A 40 m floor box and a 20 m cylinder were told 'a mesh in other units than its scale assumes', with a
    scale= for an element that has none (Pinocchio's meshPath of a primitive is "BOX", "CYLINDER")."""
    from armguard.harness import check_model_files

    p = tmp_path / "two.urdf"
    p.write_text(_URDF.replace("LIMIT", '<limit lower="-2" upper="2" effort="1" velocity="1"/>')
                 .replace('<box size="0.1 0.1 0.1"/></geometry></collision></link>\n  <link name="l1">',
                          '<box size="40 40 0.1"/></geometry></collision></link>\n  <link name="l1">', 1))
    assert "40 40 0.1" in p.read_text()
    assert _units(check_model_files(p, n_configs=1)) == []


@pytest.mark.parametrize("scale, stored, flagged", [("1 1 1", 1.0, False), ("1 1 1", 1000.0, True),
                                                     ("0.001 0.001 0.001", 1.0, True),
                                                     ("0.001 0.001 0.001", 1000.0, False)])
def test_a_mesh_a_thousand_times_off_the_chain_is_warned_of(tmp_path, scale, stored, flagged):
    """A 10 cm box stored in metres or in millimetres, read with scale 1 or 0.001, on a 0.9 m chain."""
    import trimesh

    from armguard.harness import check_model_files

    trimesh.creation.box([0.1 * stored, 0.1 * stored, 0.1 * stored]).export(tmp_path / "box.stl")
    p = tmp_path / "two.urdf"
    p.write_text(_URDF.replace("LIMIT", '<limit lower="-2" upper="2" effort="1" velocity="1"/>')
                 .replace('<box size="0.1 0.1 0.1"/></geometry></collision></link>\n  <link name="l2">',
                          f'<mesh filename="box.stl" scale="{scale}"/></geometry></collision></link>\n  <link name="l2">', 1))
    found = _units(check_model_files(p, n_configs=1))
    assert bool(found) == flagged, found
    if flagged:
        (f,) = found
        assert f.where.startswith("two.urdf: link[l1] mesh ") and "box.stl" in f.message, f.where
        assert f.suggestion == ('scale="0.001 0.001 0.001" if the mesh is in millimetres' if stored == 1000.0
                                else 'scale="1 1 1" if the mesh is already in metres')


def test_a_mimic_joint_driven_outside_its_own_limits_is_a_finding(tmp_path):
    import json

    text = _URDF.replace("LIMIT", '<limit lower="-2" upper="2" effort="1" velocity="1"/>')
    coupled = text.replace('<child link="l2"/>', '<child link="l2"/><mimic joint="j1" multiplier="-2" offset="0.3"/>')
    assert coupled != text
    for urdf, want in ((text, []), (coupled, [("joint[j2].mimic", "warning")])):
        p = tmp_path / "two.urdf"
        p.write_text(urdf)
        r = CliRunner().invoke(main, ["-q", "check-urdf", str(p), "--json"])
        found = [f for f in json.loads(r.output)["findings"] if f["check"] == "mimic-range"]
        assert [(f["where"].split(": ", 1)[1], f["severity"]) for f in found] == want, r.output
    assert "follows 'j1' as 0.3 + -2 x its value: over its limits [-2, 2] it reaches [-3.7, 4.3], outside its own " \
           "limits [-1, 1]" in found[0]["message"]


def test_a_missing_mesh_is_reported_once_and_every_other_one_too(tmp_path):
    """The mesh load_model stops at was reported twice (``load`` and ``unparsed`` at the same place); a second
    missing mesh, which load_model never reaches, must still be reported."""
    p = tmp_path / "two.urdf"
    p.write_text(_URDF.replace("LIMIT", '<limit lower="-1" upper="1" effort="1" velocity="1"/>')
                 .replace('<box size="0.1 0.1 0.1"/></geometry></collision></link>\n  <link name="l1">',
                          '<mesh filename="gone_a.stl"/></geometry></collision></link>\n  <link name="l1">', 1)
                 .replace('<origin xyz="0.3 0 0"/><geometry><box size="0.1 0.1 0.1"/>',
                          '<origin xyz="0.3 0 0"/><geometry><mesh filename="gone_b.stl"/>', 1))
    report = armguard.harness.check_model_files(p)
    said = [(f.check.value, f.where) for f in report.findings if "gone_a.stl" in f.message]
    assert [c for c, _ in said] == ["load"], said
    said_b = [(f.check.value, f.where) for f in report.findings if "gone_b.stl" in f.message]
    assert said_b == [("unparsed", "two.urdf: link[l1].collision[0]")], said_b


@pytest.mark.parametrize("attr, meant", [('ryp="0 0 1.5"', "rpy"), ('xzy="0.6 0 0"', "xyz")])
def test_a_misspelt_origin_attribute_is_refused_not_read_as_zero(tmp_path, attr, meant):
    """``<origin ryp="0 0 1.5">`` was read as no rotation (urdfdom ignores an unknown attribute) and check-urdf said
    "clean"; an extension that contains the attribute's name (ANYmal's ``gear_velocity``) is no misspelling."""
    p = tmp_path / "two.urdf"
    text = _URDF.replace("LIMIT", '<limit lower="-1" upper="1" effort="1" velocity="1" gear_velocity="10"/>')
    p.write_text(text.replace('<origin xyz="0.6 0 0"/>', f"<origin {attr}/>"))
    with pytest.raises(armguard.SceneFileError, match=rf'joint\[j2\]\.origin.*is read by nothing: did you mean {meant}='):
        armguard.load_model(p, srdf=False)
    r = CliRunner().invoke(main, ["-q", "check-urdf", str(p), "--json"])
    assert r.exit_code == 1 and f"did you mean {meant}=" in r.output, r.output
    p.write_text(text)
    armguard.load_model(p, srdf=False)


def test_every_misspelling_load_model_refuses_is_reported_beside_the_others(tmp_path):
    """With a ``<colision>`` (an unread-element finding) and a ``ryp=`` in one URDF, the refusal (which names both)
    was dropped as said already: the attribute went unreported."""
    p = tmp_path / "two.urdf"
    text = _URDF.replace("LIMIT", '<limit lower="-1" upper="1" effort="1" velocity="1"/>')
    text = text.replace('<origin xyz="0.6 0 0"/>', '<origin xyz="0.6 0 0" ryp="0 0 1"/>')
    text = text.replace('<link name="l2"><collision>', '<link name="l2"><colision>', 1).replace(
        '</collision></link>\n  <joint name="j1"', '</colision></link>\n  <joint name="j1"', 1)
    assert "<colision>" in text
    p.write_text(text)
    r = CliRunner().invoke(main, ["-q", "check-urdf", str(p), "--json"])
    assert r.exit_code == 1 and "did you mean rpy=" in r.output and "did you mean <collision>" in r.output, r.output


def test_a_floating_bases_joint_in_the_srdf_is_a_warning(tmp_path):
    """check-urdf erred (exit 1) on ``root_joint`` in a1's, go2's and bolt's SRDFs, which load_model reads with a
    warning."""
    p = tmp_path / "two.urdf"
    p.write_text(_URDF.replace("LIMIT", '<limit lower="-1" upper="1" effort="1" velocity="1"/>'))
    p.with_suffix(".srdf").write_text(
        '<robot name="two"><virtual_joint name="root_joint" type="floating" parent_frame="world" child_link="base"/>'
        '<group name="all"><joint name="root_joint"/><joint name="j1"/></group>'
        '<group_state name="home" group="all"><joint name="root_joint" value="0 0 0 0 0 0 1"/><joint name="j1" '
        'value="0"/></group_state></robot>')
    report = armguard.harness.check_model_files(p, n_configs=5)
    floating = [f for f in report.findings if "root_joint" in f.message]
    assert len(floating) == 2 and all(f.severity.value == "warning" for f in floating), report.findings
