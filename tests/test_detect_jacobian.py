"""``Detector.check(q, jacobian=True)``: each category's nearest pair's ``d(distance)/dq``.

The reference is central differences of the same Detector's category minimum
(``check(q).by_category[c].distance``) along each of ``pin_model``'s velocity columns, at step
``Tolerances.jacobian_step``; points where the differences at that step and at ten times it disagree
(a switch of the nearest pair or of its features nearby) are not compared, as in
``tests/test_distance_jacobian.py``.  Elsewhere, where the report says ``smooth``, the relative error
stays below 1e-6 (row norms, floored at 1 cm/rad).
"""

from __future__ import annotations

import numpy as np
import pytest

import armguard
from armguard import DEFAULT_TOLERANCES as TOL
from armguard.detect import Detector, RangerDetector

REL = 1e-6
FLOOR = 1e-2


@pytest.fixture(scope="module")
def ranger():
    m = armguard.load_model("ranger")
    assert m.pin_model.nq == m.pin_model.nv  # revolute joints: a velocity column is a q column
    return m


def _category_fd(det, m, q_scene, cat, h):
    """Central differences of the category minimum along each pin velocity column."""
    q_pin = m.pin_q(q_scene)
    out = np.zeros(m.pin_model.nv)
    for j in range(m.pin_model.nv):
        dq = np.zeros(m.pin_model.nq)
        dq[j] = h
        up = det.check(m.scene_q(q_pin + dq)).by_category[cat].distance
        dn = det.check(m.scene_q(q_pin - dq)).by_category[cat].distance
        out[j] = (up - dn) / (2 * h)
    return out


def _compare(det, m, n_q, rng):
    compared = 0
    for q_pin in m.random_q(n_q, rng=rng):
        q = m.scene_q(q_pin)
        rep = det.check(q, jacobian=True)
        assert set(rep.jacobian) == set(rep.by_category)
        for cat, cj in rep.jacobian.items():
            assert cj.jacobian.shape == (m.pin_model.nv,) and np.all(np.isfinite(cj.jacobian))
            assert cj.distance == pytest.approx(rep.by_category[cat].distance, abs=1e-9)
            fd = _category_fd(det, m, q, cat, TOL.jacobian_step)
            fd10 = _category_fd(det, m, q, cat, 10 * TOL.jacobian_step)
            scale = max(np.linalg.norm(fd), FLOOR)
            if not cj.smooth or np.linalg.norm(fd - fd10) / scale > REL:
                continue
            err = np.linalg.norm(cj.jacobian - fd) / scale
            assert err < REL, (cat, err, cj.row)
            compared += 1
    return compared


def test_analytic_detector_jacobian_matches_central_differences(ranger):
    det = Detector(ranger.scene, threshold=0.05)
    assert _compare(det, ranger, 4, 11) >= 6  # most categories of 4 configurations are compared


def test_ranger_detector_jacobian_matches_central_differences(ranger):
    det = RangerDetector(ranger.scene, threshold=0.05, backend="analytic")
    assert _compare(det, ranger, 3, 12) >= 4


def test_both_detectors_differentiate_the_same_pair(ranger):
    a = Detector(ranger.scene, threshold=0.05)
    b = RangerDetector(ranger.scene, threshold=0.05, backend="analytic")
    for q_pin in ranger.random_q(5, rng=13):
        q = ranger.scene_q(q_pin)
        ja, jb = a.check(q, jacobian=True).jacobian, b.check(q, jacobian=True).jacobian
        assert set(ja) == set(jb)
        for cat in ja:
            if ja[cat].smooth and jb[cat].smooth:
                assert ja[cat].row == jb[cat].row
                np.testing.assert_allclose(ja[cat].jacobian, jb[cat].jacobian, atol=1e-9)


def test_default_check_has_no_jacobian(ranger):
    for det in (Detector(ranger.scene), RangerDetector(ranger.scene, backend="analytic")):
        q = ranger.scene_q(ranger.neutral())
        rep = det.check(q)
        assert rep.jacobian is None and "jacobian" not in rep.__dict__ and "jacobian" not in rep.to_dict()
        assert det.check(q, budget_us=1e6).jacobian is None
        with_j = det.check(q, jacobian=True)
        assert with_j.jacobian is not None and "jacobian" in with_j.to_dict()
        assert with_j.status == rep.status and with_j.nearest.distance == rep.nearest.distance


@pytest.mark.parametrize("backend", ["analytic", "coal"])
def test_warm_up_runs_every_mode_and_changes_no_answer(backend):
    """``Detector.warm_up(q)`` before a control loop: afterwards each mode answers as on a Detector never warmed
    (budgeted checks included: its anytime memory is of true distances)."""
    model = armguard.load_model("ranger")
    Q = model.scene_q(model.random_q(6, 21))
    warmed = armguard.Detector(model, threshold=0.1, backend=backend)
    warmed.warm_up(Q[0])
    fresh = armguard.Detector(model, threshold=0.1, backend=backend)
    for q in Q[1:]:
        a, b = warmed.check(q, jacobian=True), fresh.check(q, jacobian=True)
        assert a.status == b.status and a.by_category.keys() == b.by_category.keys()
        for c in a.by_category:
            assert a.by_category[c].distance == b.by_category[c].distance
            np.testing.assert_array_equal(a.jacobian[c].jacobian, b.jacobian[c].jacobian)
        assert warmed.check(q, lazy=True).status == fresh.check(q, lazy=True).status
        big = warmed.check(q, budget_us=1e9)  # time enough for every pair: the exact status
        assert big.status == b.status
