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
    assert found == {("link[l1].collision[0].orgin", "<orgin> is read by nothing: did you mean <origin>?"),
                     ("joint[j1].limit", "2 <limit> elements: only the first is read")}, found


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
