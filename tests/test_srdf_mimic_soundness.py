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
