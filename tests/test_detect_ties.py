"""A Detector's answer does not depend on what it checked before, down to which pair it names nearest.

On hermes, links 3 and 4 are exactly as far from the payload at some configurations; the analytic
kernel evaluates last check's nearest pairs first and kept the first of two equal distances, so a
Detector that had checked another configuration named link 4 where a fresh one named link 3 (status
and distances equal).  A tie now goes to the lower pair number, as the coal Detector's does.
"""

from __future__ import annotations

import numpy as np
import pytest

import armguard


def _summary(r):
    return r.status.value, sorted((k, v.distance, v.a, v.b) for k, v in r.by_category.items())


@pytest.mark.parametrize("backend", ["analytic", "coal"])
def test_the_pair_named_in_a_tie_does_not_depend_on_earlier_checks(backend):
    model = armguard.load_model("hermes")
    scene = model.scene_for()
    lo = np.concatenate([r.lower for r in scene.robots.values()])
    hi = np.concatenate([r.upper for r in scene.robots.values()])
    Q = np.random.default_rng(5).uniform(lo, hi, (60, len(lo)))
    q = Q[16]
    fresh = _summary(armguard.Detector(model, threshold=0.05, backend=backend).check(q))
    payload = dict((k, (d, a, b)) for k, d, a, b in fresh[1])["payload"]
    assert payload[1:] == ("hera/link3", "payload")  # the lower pair number of the two at equal distance
    det = armguard.Detector(model, threshold=0.05, backend=backend)
    for i in range(0, 60, 3):
        det.check(Q[i])
        assert _summary(det.check(q)) == fresh, f"after Q[{i}]"
