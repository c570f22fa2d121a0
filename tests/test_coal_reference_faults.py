"""coal's faults that armguard's coal Checker must not pass on as answers."""

from __future__ import annotations

import sysconfig
from pathlib import Path

import numpy as np
import pytest

import armguard
from armguard import BackendError

TIAGO = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share" / "example-robot-data" / "robots" / \
    "tiago_description" / "robots" / "tiago.urdf"


@pytest.mark.skipif(not TIAGO.is_file(), reason="example-robot-data's tiago is not installed")
def test_nan_witness_points_from_coal_are_refused_not_handed_back():
    """On tiago a 1 mm sphere whose centre lies on a box's face (hand_index_link against hand_safety_box, distance
    exactly -1 mm) comes back from coal with NaN witness points: pair_distances handed them back, and compare
    stopped on them.  Retried with looser EPA tolerances, and where none settles them, a BackendError naming the pair."""
    m = armguard.load_model(TIAGO)
    q = m.random_q(12, 0)[0]
    with pytest.raises(BackendError, match="hand_index_link_0 / hand_safety_box_0 .*no finite witness points"):
        armguard.checker(m, "coal").pair_distances(q)
    r = armguard.checker(m, "analytic").pair_distances(q)  # the analytic backend answers it, finite
    assert np.isfinite(r.p_WA).all() and np.isfinite(r.p_WB).all()
