"""An SRDF certificate (``armguard_fingerprint``) depends on a mimic joint's coupling and on an
unaligned joint axis: Pinocchio's generic JointModel shows neither, so a multiplier of 1 -> -2 (the
fingers then cross) or a tilted axis kept the certificate, and the stale "Never" hid a collision."""

from __future__ import annotations

import pinocchio as pin
import pytest

from armguard.model._certificate import pair_fingerprint

_URDF = """<robot name="g">
  <link name="palm"><collision><geometry><box size="0.1 0.1 0.02"/></geometry></collision></link>
  <link name="finger_l"><collision><geometry><box size="0.01 0.01 0.05"/></geometry></collision></link>
  <link name="finger_r"><collision><geometry><box size="0.01 0.01 0.05"/></geometry></collision></link>
  <joint name="jl" type="prismatic"><parent link="palm"/><child link="finger_l"/><origin xyz="0 0.03 0.04"/>
    <axis xyz="0 -1 0"/><limit lower="0" upper="0.04" effort="1" velocity="1"/></joint>
  <joint name="jr" type="prismatic"><parent link="palm"/><child link="finger_r"/><origin xyz="0 -0.03 0.04"/>
    <axis xyz="AXIS"/><limit lower="-0.1" upper="0.1" effort="1" velocity="1"/>
    <mimic joint="jl" multiplier="MULT" offset="OFF"/></joint>
</robot>"""


def _print(axis="0 1 0", mult="1", off="0"):
    xml = _URDF.replace("AXIS", axis).replace("MULT", mult).replace("OFF", off)
    m = pin.buildModelFromXML(xml, mimic=True)
    g = pin.buildGeomFromUrdfString(m, xml, pin.COLLISION)
    return pair_fingerprint(m, g, "finger_l", "finger_r", margin=0.0, method="certified", verdict="Never")


def test_the_same_model_gives_the_same_print():
    assert _print() == _print()


@pytest.mark.parametrize("edit", [{"mult": "-2"}, {"off": "0.05"}, {"axis": "0 0 1"}, {"axis": "0 0.6 0.8"}])
def test_a_coupling_or_axis_edit_voids_the_print(edit):
    assert _print(**edit) != _print()


def test_two_tilted_axes_differ():
    assert _print(axis="0 0.6 0.8") != _print(axis="0 -0.6 0.8")


_CHAIN = """<robot name="c">
  <link name="a"><collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <link name="mid">MID</link>
  <link name="b"><collision><origin xyz="0.3 0 0"/><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="a"/><child link="mid"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="mid"/><child link="b"/><origin xyz="0.3 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>"""


def test_an_adjacent_certificate_goes_stale_when_the_link_between_gets_geometry(tmp_path):
    """a and b are *Adjacent* through ``mid`` while ``mid`` has no geometry (MoveIt's rule); once it
    has some, the certificate no longer holds (a restored forearm mesh left UR5's upper arm and
    wrist 1, 18.5 mm into each other, unchecked without a word)."""
    from armguard.model._certificate import stale_certificates

    srdf = tmp_path / "c.srdf"
    srdf.write_text('<robot name="c"><disable_collisions link1="a" link2="b" reason="Adjacent" '
                    'armguard_fingerprint="0123456789abcdef"/></robot>')
    for mid, stale in (("", False), ('<collision><geometry><box size="0.05 0.05 0.05"/></geometry></collision>', True)):
        xml = _CHAIN.replace("MID", mid)
        m = pin.buildModelFromXML(xml)
        g = pin.buildGeomFromUrdfString(m, xml, pin.COLLISION)
        found = stale_certificates(m, g, srdf)
        assert (len(found) == 1 and (found[0].link1, found[0].link2) == ("a", "b")) == stale, found
