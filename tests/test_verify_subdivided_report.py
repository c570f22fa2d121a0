"""A trajectory verified as :class:`Subdivided` (``armguard verify --speed-dependent``) reports segment numbers and
the name of the trajectory as given: puma560's pick_and_place violated its stopping distance at t = 0.156 s, in
its segment 0 (knots 0, 1.247 s, ...), and the report said "segment 1" (the second eighth of segment 0) and named
the trajectory "trajectory"."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

import armguard
from armguard.cli import main
from armguard.verify import Subdivided


@pytest.fixture(scope="module")
def puma():
    return armguard.load_scene("puma560")


def test_a_subdivided_trajectorys_collision_names_the_given_segment_and_trajectory(puma):
    traj = puma.trajectories["pick_and_place"]
    whole = armguard.verify(puma, traj, stopping_distance=0.1)
    pieces = armguard.verify(puma, Subdivided(traj, 8), stopping_distance=0.1)
    c = pieces.first_collision
    knots = np.asarray(traj.times)
    assert c is not None and knots[c.segment] <= c.time <= knots[c.segment + 1], (c.segment, c.time, knots)
    assert c.segment == whole.first_collision.segment == 0
    assert pieces.trajectory == whole.trajectory == "pick_and_place"


def test_verify_speed_dependent_prints_the_given_segment(tmp_path, puma):
    r = CliRunner().invoke(main, ["-q", "verify", "puma560", "pick_and_place", "--stopping-distance", "0.1",
                                  "--speed-dependent", "--report", str(tmp_path / "sd.json")])
    assert r.exit_code == 1 and "(segment 0)" in r.output, r.output
    rep = json.loads((tmp_path / "sd.json").read_text())
    text = json.dumps(rep)
    assert '"segment": 0' in text and '"segment": 1' not in text
