"""The on-line guard never puts a NaN in its decision.

Found in review: ``Guard.step(q, target=...)`` (automatic mode without a commanded speed) with
the arm already within the stopping distance answered STOP with ``time_to_collision = nan``
(0 x inf), and a predicted contact further along the segment read "in inf s".  Closed-form
geometry: the planar arm of ``_verify_fixtures`` reaches x = 1.2 m at q = 0 and a sphere of
radius 5 cm sits there.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from armguard.geometry import Sphere
from armguard.scene import Scene
from armguard.verify import Guard

from _verify_fixtures import planar_arm


def _guard() -> Guard:
    sc = Scene("guard")
    sc.add_robot(planar_arm(), self_pairs=[])
    sc.add_body("post", [Sphere([1.2, 0.0, 0.0], 0.05)])
    return Guard(sc, horizon_s=0.5, period_s=0.01)


@pytest.mark.parametrize("q0", [0.0, 0.5], ids=["in-contact-now", "contact-ahead"])
def test_target_without_speed_gives_a_finite_time_to_collision(q0):
    d = _guard().step(np.array([q0, 0.0, 0.0]), target=[-1.0, 0.0, 0.0])
    assert not d.ok and d.pair == ("arm/link3", "post")
    assert d.time_to_collision == 0.0  # no speed given: the arm may get there at once
    assert "inf" not in d.reason
    assert all(math.isfinite(x) for x in (d.clearance, d.predicted_clearance, d.time_to_collision))


def test_target_with_speed_gives_the_time_along_the_segment():
    # from q1 = 0.5 rad towards -1 at 1 rad/s: contact a little before q1 = 0, i.e. before t = 0.5 s
    d = _guard().step(np.array([0.5, 0.0, 0.0]), target=[-1.0, 0.0, 0.0], qdot=[1.0, 0.0, 0.0])
    assert not d.ok and 0.3 < d.time_to_collision < 0.5
