"""``armguard srdf --update`` keeps the file's margin and method unless given (it searched an SRDF
made at 2 cm again at 0 without a word, disabling pairs witnessed within 2 cm), and drops, naming them,
the disable_collisions of a link the URDF no longer has (kept, they made a file load_model refuses)."""

from __future__ import annotations

import warnings

import pytest
from click.testing import CliRunner

import armguard
from armguard.cli import main

_URDF = """<robot name="two">
  <link name="base"><collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <link name="l1"><collision><origin xyz="0.3 0 0"/><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <link name="L2"><collision><origin xyz="0.3 0 0"/><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>
    <limit lower="-0.5" upper="0.5" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="L2"/><origin xyz="0.6 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-0.5" upper="0.5" effort="1" velocity="1"/></joint>
</robot>"""


@pytest.fixture()
def two(tmp_path):
    p = tmp_path / "two.urdf"
    p.write_text(_URDF.replace("L2", "l2"))
    return p, tmp_path / "two.srdf"


def test_update_keeps_the_files_margin_and_method(two):
    urdf, srdf = two
    r = CliRunner().invoke(main, ["-q", "srdf", str(urdf), "--out", str(srdf), "--margin", "0.02"])
    assert r.exit_code == 0, r.output
    r = CliRunner().invoke(main, ["-q", "srdf", str(urdf), "--out", str(srdf), "--update"])
    assert r.exit_code == 0 and "--update: margin 0.02 m and method certified from" in r.output, r.output
    assert 'armguard_margin="0.02"' in srdf.read_text()
    r = CliRunner().invoke(main, ["-q", "srdf", str(urdf), "--out", str(srdf), "--update", "--margin", "0"])
    assert "margin 0.02" not in r.output and 'armguard_margin="0.0"' in srdf.read_text()


def test_update_drops_the_pairs_of_a_renamed_link_and_says_so(two):
    urdf, srdf = two
    assert CliRunner().invoke(main, ["-q", "srdf", str(urdf), "--out", str(srdf)]).exit_code == 0
    srdf.write_text(srdf.read_text().replace("</robot>", '<disable_collisions link1="l2" link2="base" reason="Never"/></robot>'))
    urdf.write_text(_URDF.replace("L2", "l2_renamed"))
    r = CliRunner().invoke(main, ["-q", "srdf", str(urdf), "--out", str(srdf), "--update"])
    assert r.exit_code == 0 and "dropped the disable_collisions of l2 - base: the URDF has no such link" in r.output, r.output
    assert 'link1="l2"' not in srdf.read_text() and 'link2="l2"' not in srdf.read_text()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        armguard.load_model(urdf)  # the file it wrote loads


def test_update_keeps_a_hand_written_files_comments_once(two):
    """A vendor's header comment before ``<robot>`` was dropped (ElementTree keeps no comment outside the
    root); a comment inside it was kept.  Both are kept, and a second update does not repeat them."""
    urdf, srdf = two
    srdf.write_text('<?xml version="1.0"?>\n<!-- TWO SRDF\n  by hand -->\n<robot name="two">\n'
                    '  <!-- the base and l2 cannot meet -->\n'
                    '  <group name="arm"><chain base_link="base" tip_link="l2"/></group>\n</robot>\n')
    for _ in range(2):
        r = CliRunner().invoke(main, ["-q", "srdf", str(urdf), "--out", str(srdf), "--update"])
        assert r.exit_code == 0, r.output
        text = srdf.read_text()
        assert text.count("TWO SRDF\n  by hand") == 1 and text.count("the base and l2 cannot meet") == 1, text
        assert text.count('<group name="arm">') == 1
    m = armguard.load_model(urdf, srdf=srdf)
    assert m.srdf.groups["arm"].chains == (("base", "l2"),)


def test_update_refuses_a_urdf_and_another_robots_srdf_before_writing(two):
    """``--out`` naming the robot's own URDF was rewritten in place with --update (disable_collisions and
    certificates added to the URDF, "wrote", exit 0); another robot's SRDF kept its groups and states in
    this robot's file, which every command then refused.  Both are refused naming the place, unchanged."""
    urdf, srdf = two
    before = urdf.read_text()
    r = CliRunner().invoke(main, ["-q", "srdf", str(urdf), "--out", str(urdf), "--update"])
    assert r.exit_code == 2 and "this is a URDF, not an SRDF" in r.output, r.output
    assert urdf.read_text() == before
    r = CliRunner().invoke(main, ["-q", "srdf", str(urdf), "--out", str(urdf)])
    assert r.exit_code == 2 and "this is a URDF, not an SRDF" in r.output and "--update keeps" not in r.output, r.output
    other = ('<robot name="arm"><group name="arm"><chain base_link="panda_link0" tip_link="panda_link8"/></group>'
             '<group_state name="home" group="arm"><joint name="panda_joint1" value="0"/></group_state></robot>')
    srdf.write_text(other)
    r = CliRunner().invoke(main, ["-q", "srdf", str(urdf), "--out", str(srdf), "--update"])
    assert r.exit_code == 2 and "group[0] (arm): none of its links and joints" in r.output and "panda_link0" in r.output, r.output
    assert srdf.read_text() == other
    srdf.write_text(other.replace('<group name="arm"><chain base_link="panda_link0" tip_link="panda_link8"/></group>',
                                  '<group name="arm"><chain base_link="base" tip_link="l2"/></group>'))
    r = CliRunner().invoke(main, ["-q", "srdf", str(urdf), "--out", str(srdf), "--update"])
    assert r.exit_code == 2 and "sets joint 'panda_joint1'" in r.output, r.output
