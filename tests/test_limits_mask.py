"""``Model.within_pin_limits(Q)``: the rows a batch may be answered for, exactly those
``check_pin_limits`` lets through; a batch refused for a row outside says how many and how to mask."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import armguard
from armguard import JointLimitError, KinematicsError

TOL = armguard.DEFAULT_TOLERANCES.joint_limit


@pytest.fixture(scope="module", params=["ur5", "kinova", "ranger"])
def model(request):
    return armguard.load_model(request.param)


def _passes(model, q) -> bool:
    try:
        model.check_pin_limits(q)
    except KinematicsError:
        return False
    return True


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), push=st.sampled_from([0.0, 0.5 * TOL, 2 * TOL, 0.1]))
def test_rows_within_are_the_rows_check_pin_limits_passes(seed, push):
    model = armguard.load_model("ur5")
    rng = np.random.default_rng(seed)
    Q = model.random_q(20, seed)
    lo, hi = model.pin_model.lowerPositionLimit, model.pin_model.upperPositionLimit
    rows, cols = rng.integers(0, 20, 6), rng.integers(0, model.nq, 6)
    for r, c, up in zip(rows, cols, rng.random(6) < 0.5):
        Q[r, c] = hi[c] + push if up else lo[c] - push  # on a limit, within the allowance, past it
    ok = model.within_pin_limits(Q)
    assert ok.dtype == bool and ok.shape == (20,)
    assert [bool(x) for x in ok] == [_passes(model, q) for q in Q]


def test_nan_rows_and_continuous_joints(model):
    Q = model.random_q(5, 1)
    Q[2, 0] = np.nan
    ok = model.within_pin_limits(Q)
    assert not ok[2] and ok[[0, 1, 3, 4]].all()
    assert bool(model.within_pin_limits(Q[0])) is True
    if len(model.continuous_q):  # kinova: a (cos, sin) off the unit circle, or infinite, is no row to ask
        k = int(model.continuous_q[0])
        Q[3, k] = Q[3, k + 1] = 0.5
        Q[4, k] = np.inf
        ok = model.within_pin_limits(Q)
        assert list(ok) == [True, True, False, False, False]
        c = armguard.checker(model)
        for i in (3, 4):
            with pytest.raises(armguard.BackendError):
                c.collides(Q[[i]])
        assert c.collides(Q[ok]).shape == (2,)
    with pytest.raises(KinematicsError, match="Q: expected numbers, not booleans|bool"):
        model.within_pin_limits(np.ones((2, model.nq), dtype=bool))
    with pytest.raises(KinematicsError, match=r"expected shape \(\d+,\) or \(M, \d+\)"):
        model.within_pin_limits(Q[:, :2])


def test_a_refused_batch_says_how_many_rows_and_how_to_mask(model):
    Q = model.random_q(50, 2)
    free = np.zeros(model.nq, dtype=bool)
    free[model.continuous_q], free[np.asarray(model.continuous_q, dtype=int) + 1] = True, True  # (cos, sin): no limits
    j = int(np.flatnonzero(~free & (model.pin_model.upperPositionLimit < 1e10))[0])
    Q[[4, 9, 30], j] = model.pin_model.upperPositionLimit[j] + 0.5
    c = armguard.checker(model)
    with pytest.raises(JointLimitError) as info:
        c.collides(Q)
    assert str(info.value).startswith("Q row 4 (3 of 50 rows outside their limits; model.within_pin_limits(Q) masks them): joint")
    ok = model.within_pin_limits(Q)
    assert list(np.flatnonzero(~ok)) == [4, 9, 30]
    assert c.collides(Q[ok]).shape == (47,)
