"""Every Detector query rebuilds its model when the scene changed after it was built.

Closed-form geometry: the planar arm of ``_verify_fixtures`` reaches x = 1.2 m at q = 0, so a
sphere of radius 5 cm centred at (1.2, 0, 0) encloses its tip; a sphere at (5, 5, 5) is far.
"""

from __future__ import annotations

import numpy as np
import pytest

import armguard
from armguard.geometry import Sphere
from armguard.scene import Scene

from _verify_fixtures import planar_arm


def _scene() -> Scene:
    sc = Scene("stale")
    sc.add_robot(planar_arm(), self_pairs=[])
    sc.add_body("far", [Sphere([5.0, 5.0, 5.0], 0.1)])
    return sc


def _check(det, q):
    return det.check(q).status.value == "collision"


def _check_many(det, q):
    return bool(det.check_many(q[None, :]).collision[0])


def _collides_many(det, q):
    return bool(det.collides_many(q[None, :])[0])


def _pair_distances(det, q):
    return bool(np.min(det.pair_distances(q).distance) <= 0.0)


@pytest.mark.parametrize("backend", ["analytic", "coal"])  # the fused Detector; Ranger's over a Checker
@pytest.mark.parametrize("query", [_check, _check_many, _collides_many, _pair_distances],
                         ids=["check", "check_many", "collides_many", "pair_distances"])
def test_query_after_add_body_sees_the_new_body(query, backend):
    sc = _scene()
    det = armguard.Detector(sc, threshold=0.05, backend=backend)
    q = np.zeros(3)
    assert not query(det, q)
    n0 = det.n_pairs
    sc.add_body("post", [Sphere([1.2, 0.0, 0.0], 0.05)])
    assert query(det, q)
    assert det.n_pairs > n0


def test_disable_pair_after_build_is_honoured():
    sc = _scene()
    sc.add_body("post", [Sphere([1.2, 0.0, 0.0], 0.05)])
    det = armguard.Detector(sc, threshold=0.05)
    q = np.zeros(3)
    assert det.check(q).status.value == "collision"
    sc.disable_pair("arm", "post")
    assert det.check(q).status.value != "collision"
    assert "post" not in det.obstacle_list(det.link_names[-1])


@pytest.mark.parametrize("backend", ["analytic", "coal"])
def test_settings_changed_after_an_edit_still_see_the_edit(backend):
    """``set_active`` or a larger threshold rebuilds on the Model the Detector holds; the scene's
    edit before it is still seen by the next query."""
    sc = _scene()
    det = armguard.Detector(sc, threshold=0.05, backend=backend)
    q = np.zeros(3)
    assert not _check(det, q)
    sc.add_body("post", [Sphere([1.2, 0.0, 0.0], 0.05)])
    det.set_active("arm")
    det.set_threshold(0.5)
    assert _check(det, q)
