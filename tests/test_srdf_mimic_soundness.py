"""Certified collision matrices with mimic joints (a review's findings, each reproduced before the fix with coal as
ground truth): a follower that turns fast, and a certificate that must cover its leader's limits."""

from __future__ import annotations

import math

import numpy as np
import pytest

import armguard
from armguard.srdfgen import collision_matrix


def _robot(path, mult: float, hi: float, leader: str = "prismatic", post_y: float = 0.58):
    """j1 (``leader``, [0, hi]) carries link1, a post at y = ``post_y``; j2 follows j1 at ``mult`` and swings
    link3's sphere (0.5 m out) round through the post's place."""
    path.write_text(f'''<robot name="pg">
  <link name="base"><collision><origin xyz="0 0 -1"/><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <joint name="j1" type="{leader}"><parent link="base"/><child link="link1"/><axis xyz="0 0 1"/>
    <limit lower="0" upper="{hi}" effort="1" velocity="1"/></joint>
  <link name="link1"><collision><origin xyz="0 {post_y} 0"/><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <joint name="j2" type="revolute"><parent link="link1"/><child link="link2"/><axis xyz="0 0 1"/>
    <limit lower="-7" upper="7" effort="1" velocity="1"/><mimic joint="j1" multiplier="{mult!r}" offset="0"/></joint>
  <link name="link2"><collision><origin xyz="0 0 0.3"/><geometry><sphere radius="0.01"/></geometry></collision></link>
  <joint name="j3" type="fixed"><parent link="link2"/><child link="link3"/></joint>
  <link name="link3"><collision><origin xyz="0.5 0 0"/><geometry><sphere radius="0.05"/></geometry></collision></link>
</robot>''')
    return path


def _least_distance(model, hi: float) -> float:
    ch = armguard.checker(model, "coal")
    names = [tuple(sorted(x)) for x in ch.pair_distances(np.zeros(1)).pairs]
    k = names.index(("link1_0", "link3_0"))
    return min(float(ch.pair_distances(np.array([q])).distance[k]) for q in np.linspace(0.0, hi, 401))


@pytest.mark.parametrize("leader", ["prismatic", "revolute"])
def test_a_fast_mimic_follower_is_never_proved_apart_where_it_collides(tmp_path, leader):
    """j2 = 8 pi j1: the 0.25 probe turned it a whole 2 pi, read as no turn, so j1 was dropped from link1-link3's
    joints and one evaluation at home "proved" Never; coal finds the pair 2 cm deep at j1 = 1/16."""
    m = armguard.load_model(_robot(tmp_path / "pg.urdf", 8 * math.pi, 0.25, leader), srdf=False)
    assert _least_distance(m, 0.25) < -0.01
    e = next(e for e in collision_matrix(m).entries if {e.link1, e.link2} == {"link1", "link3"})
    assert e.reason != "Never", e


_LEADER = """<?xml version="1.0"?>
<robot name="r2">
  <link name="base"><collision><origin xyz="0 0 0.1"/><geometry><box size="0.3 0.3 0.2"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="link1"/><origin xyz="0 0 0.2"/><axis xyz="0 0 1"/>
    <limit lower="-LIM" upper="LIM" effort="1" velocity="1"/></joint>
  <link name="link1"><collision><origin xyz="0 0 0.15"/><geometry><cylinder radius="0.05" length="0.3"/></geometry></collision></link>
  <joint name="j2" type="revolute"><parent link="link1"/><child link="link2"/><origin xyz="0 0 0.3"/><axis xyz="0 1 0"/>
    <limit lower="-1.5" upper="1.5" effort="1" velocity="1"/></joint>
  <link name="link2"><collision><origin xyz="0.25 0 0"/><geometry><box size="0.5 0.08 0.08"/></geometry></collision></link>
  <joint name="j3" type="revolute"><parent link="link2"/><child link="link3"/><origin xyz="0.5 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-3.2" upper="3.2" effort="1" velocity="1"/><mimic joint="j1" multiplier="1.0" offset="0.0"/></joint>
  <link name="link3"><collision><origin xyz="0.3 0 0"/><geometry><sphere radius="0.05"/></geometry></collision></link>
</robot>
"""


def test_a_certificate_covers_the_limits_of_a_mimic_joints_leader(tmp_path):
    """j3 mimics j1, which lies above link1-link3's common ancestor: the pair was certified Never with j1 in
    [-0.5, 0.5], and widening j1 to [-3, 3] (coal: -0.09 m at q = [2.81, 1.12]) left its certificate whole, the pair
    disabled without a word.  The print now holds the leader's limits: loading warns of link1-link3."""
    import shutil
    import warnings

    a = tmp_path / "a" / "r2.urdf"
    a.parent.mkdir()
    a.write_text(_LEADER.replace("LIM", "0.5"))
    cm = collision_matrix(armguard.load_model(a, srdf=False), max_evaluations=20000)
    never = {frozenset((e.link1, e.link2)) for e in cm.entries if e.reason == "Never"}
    assert frozenset(("link1", "link3")) in never
    cm.write_srdf(a.with_suffix(".srdf"))
    b = tmp_path / "b" / "r2.urdf"
    b.parent.mkdir()
    b.write_text(_LEADER.replace("LIM", "3.0"))
    shutil.copy(a.with_suffix(".srdf"), b.with_suffix(".srdf"))
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        armguard.load_model(b)
    said = " ".join(str(x.message) for x in w)
    assert "may now collide" in said and "link1-link3" in said, said


def test_a_scene_files_link_shapes_undo_the_srdfs_verdicts_on_that_link(tmp_path):
    """A scene file giving link3 a 0.3 m sphere (``link_shapes``) kept the SRDF's certified Never of link1-link3,
    proved for the URDF's 5 cm sphere: unchecked, though coal finds it 0.14 m deep.  Its pairs but the adjacent
    one are checked again, and the scene file warns."""
    import warnings

    urdf = tmp_path / "r2.urdf"
    urdf.write_text(_LEADER.replace("LIM", "0.5"))
    collision_matrix(armguard.load_model(urdf, srdf=False), max_evaluations=20000).write_srdf(tmp_path / "r2.srdf")
    scene = tmp_path / "cell.yaml"
    scene.write_text("armguard_scene: 1\nname: cell\nunits: {angle: rad, length: m}\nrobots:\n  - name: arm\n"
                     "    urdf: r2.urdf\n    srdf: r2.srdf\n    link_shapes:\n"
                     "      link3: [{type: sphere, radius: 0.3, xyz: [0.3, 0, 0]}]\n")
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        sc = armguard.load_scene(scene)
    said = " ".join(str(x.message) for x in w)
    assert "link_shapes" in said and "link1-link3" in said, said
    disabled = {frozenset(p) for p in sc.disabled_pairs}
    assert frozenset(("arm/link1", "arm/link3")) not in disabled
    assert frozenset(("arm/link2", "arm/link3")) in disabled  # adjacent: whatever the shapes


def test_a_pair_added_by_hand_to_a_certified_srdf_is_warned_of(tmp_path):
    """A ``<disable_collisions ... reason="Never"/>`` added by hand, without a certificate, to an SRDF armguard wrote
    (base-link2, which collides) loaded without a word: only check-srdf would have found it."""
    import warnings

    urdf = tmp_path / "r2.urdf"
    urdf.write_text(_LEADER.replace("LIM", "0.5"))
    srdf = tmp_path / "r2.srdf"
    collision_matrix(armguard.load_model(urdf, srdf=False), max_evaluations=20000).write_srdf(srdf)
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        armguard.load_model(urdf)
    assert not [x for x in w if "without a certificate" in str(x.message)]
    srdf.write_text(srdf.read_text().replace("</robot>", '<disable_collisions link1="base" link2="link2" reason="Never"/>'
                                                         "</robot>"))
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        armguard.load_model(urdf)
    said = " ".join(str(x.message) for x in w)
    assert "1 disabled pair without a certificate" in said and "base-link2 (Never)" in said, said
