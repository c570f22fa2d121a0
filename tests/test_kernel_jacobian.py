"""The analytic backend's in-kernel distance Jacobians against the slow reference.

``armguard.checker(model, "analytic").pair_distances(q, jacobian=True)`` differentiates every pair
inside a numba kernel from the kernel's own forward kinematics
(:mod:`armguard_analytic._engine._pair_jacobian`); the reference is the same formula with Pinocchio's joint
Jacobians at the same witness points (:meth:`CheckerBase.witness_jacobian`).  They agree to 1e-10
(m/rad) on every built-in model and on public robots with continuous joints (kinova), prismatic
mimic fingers (Panda), a parallelogram coupling (GMF S-480, a mimic of coefficient -1), several
robots in one scene (Ranger), and ``smooth`` is the same flag.  The finite-difference tests
(``tests/test_distance_jacobian.py``) check both against the distances themselves.
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import armguard
from armguard.backends import CheckerBase

ATOL = 1e-10
BUILT_IN = ["ranger", "hermes", "puma560", "rover", "gmf_s480"]
PUBLIC = ["panda", "ur5", "kinova", "z1", "talos_left_arm", "so101"]


@pytest.fixture(scope="module")
def models():
    cache = {}

    def get(name):
        if name not in cache:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # kinova's SRDF home state: read, with a warning
                cache[name] = armguard.load_model(name)
        return cache[name]

    return get


def _compare(c, q, idx=None):
    r = c.pair_distances(q, pairs=idx, jacobian=True)
    J, smooth = CheckerBase.witness_jacobian(c, q, r, idx)
    np.testing.assert_allclose(r.jacobian, J, rtol=0, atol=ATOL)
    np.testing.assert_array_equal(r.smooth, smooth)
    return r


@pytest.mark.parametrize("name", BUILT_IN + PUBLIC)
def test_kernel_jacobian_equals_pinocchio_reference(models, name):
    m = models(name)
    c = armguard.checker(m, "analytic")
    n_smooth = 0
    for q in [m.neutral(), *m.random_q(6, rng=17)]:
        r = _compare(c, q)
        assert r.jacobian.shape == (len(m.pairs), m.pin_model.nv) and r.smooth.dtype == bool
        np.testing.assert_array_equal(r.distance, c.pair_distances(q).distance)
        n_smooth += int(r.smooth.sum())
        assert np.abs(r.jacobian).max() > 0.0
    assert n_smooth > len(m.pairs)  # the rows compared are mostly differentiable ones


@pytest.mark.parametrize("name", ["ranger", "panda", "kinova"])
def test_subsets_and_given_results(models, name):
    """A subset of rows (repeated rows included) equals the full result's rows; distance_jacobian
    of a result computed earlier (another configuration checked in between) equals the direct answer."""
    m = models(name)
    c = armguard.checker(m, "analytic")
    Q = m.random_q(3, rng=5)
    full = c.pair_distances(Q[0], jacobian=True)
    rows = np.array([len(m.pairs) - 1, 0, 3, 3])
    sub = _compare(c, Q[0], rows)
    np.testing.assert_array_equal(sub.jacobian, full.jacobian[rows])
    np.testing.assert_array_equal(sub.smooth, full.smooth[rows])
    r1 = c.pair_distances(Q[1], jacobian=True)
    c.pair_distances(Q[2])  # the scratch now holds another configuration's link poses
    J, s = c.distance_jacobian(Q[1], r1.take(rows), rows)
    np.testing.assert_array_equal(J, r1.jacobian[rows])
    np.testing.assert_array_equal(s, r1.smooth[rows])
    many = np.tile(np.arange(len(m.pairs)), 2)  # more rows than the model has: the full result's rows
    np.testing.assert_array_equal(c.pair_distances(Q[1], pairs=many, jacobian=True).jacobian, r1.jacobian[many])


def test_touching_rows_are_refined_like_the_reference(models):
    """With a contact tolerance of 5 cm many of Ranger's pairs count as touching: both paths give
    them the same forward-difference rows and ``smooth`` False."""
    m = armguard.load_model("ranger")
    m.tol = dataclasses.replace(m.tol, length=0.05)
    c = armguard.checker(m, "analytic")
    q = m.random_q(2, rng=2)[1]  # 7 pairs within 5 cm
    r = _compare(c, q)
    touching = np.abs(r.distance) <= 0.05
    assert touching.sum() >= 3 and not r.smooth[touching].any()
    assert np.abs(r.jacobian[touching]).max() > 0.0


def test_two_threads_share_a_checker(models):
    """Each thread's scratch holds its own link poses: answers equal the single-threaded ones."""
    from concurrent.futures import ThreadPoolExecutor

    m = models("ranger")
    c = armguard.checker(m, "analytic")
    Q = m.random_q(40, rng=9)
    ref = [c.pair_distances(q, jacobian=True).jacobian for q in Q]
    with ThreadPoolExecutor(2) as ex:
        got = list(ex.map(lambda q: c.pair_distances(q, jacobian=True).jacobian, Q))
    for a, b in zip(ref, got):
        np.testing.assert_array_equal(a, b)


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.lists(st.floats(0.0, 1.0), min_size=24, max_size=24), st.sampled_from(["ranger", "gmf_s480", "panda"]))
def test_kernel_jacobian_property(models, u, name):
    """Hypothesis: at any in-limit configuration (the limits themselves included) the kernel's
    rows equal the reference's."""
    m = models(name)
    c = armguard.checker(m, "analytic")
    robots = list(m.scene.robots.values())
    lo = np.concatenate([r.lower for r in robots])
    hi = np.concatenate([r.upper for r in robots])
    lo, hi = np.where(np.isfinite(lo), lo, -np.pi), np.where(np.isfinite(hi), hi, np.pi)
    q = m.pin_q(lo + (hi - lo) * np.asarray(u[:len(lo)]))
    _compare(c, q)
