"""Pairs whose elements never move (``armguard_analytic._engine._constant``): computed once per build,
the same bits as computing them at every check, and computed again when a scene edit moves them."""

from __future__ import annotations

import numpy as np
import pytest

import armguard
from armguard_analytic._engine._layout import K


def _cst(checker) -> np.ndarray:
    H, MF, MI = checker._plan().args[:3]
    o, n = H[2 * K["cst"]], H[2 * K["cst"] + 1]
    return MI[o:o + n]


@pytest.mark.parametrize("name, n_constant", [("puma560", 9), ("gmf_s480", 1), ("rover", 0), ("panda", 0)])
def test_the_pairs_found_constant_are_those_no_joint_moves(name, n_constant):
    model = armguard.load_model(name)
    ana = armguard.checker(model, "analytic")
    cst = _cst(ana)
    assert int(np.count_nonzero(cst >= 0)) == n_constant
    # the rows of those pairs are the same at every configuration (and their witnesses in W)
    Q = model.random_q(20, 5)
    rows = [ana.pair_distances(q) for q in Q]
    k = np.flatnonzero(cst >= 0)
    moving = np.flatnonzero(cst < 0)
    for r in rows[1:]:
        np.testing.assert_array_equal(r.distance[k], rows[0].distance[k])
        np.testing.assert_array_equal(r.p_WA[k], rows[0].p_WA[k])
    if len(moving):  # a pair said to move does move somewhere among the configurations
        assert np.ptp(np.array([r.distance[moving] for r in rows]), axis=0).max() > 0.0


@pytest.mark.parametrize("name", ["puma560", "gmf_s480"])
def test_copied_rows_are_the_bits_computed_at_every_check(name):
    """The same checker with its constant rows switched off (every pair computed at every call):
    distances and witness points bit for bit, and the coal reference within its tolerance."""
    model = armguard.load_model(name)
    fast = armguard.checker(model, "analytic")
    slow = armguard.checker(model, "analytic")
    cst = _cst(slow)
    assert np.any(cst >= 0)
    cst[:] = -1  # this checker's own buffers: computed every time
    coal = armguard.checker(model, "coal")
    for q in model.random_q(30, 11):
        a, b = fast.pair_distances(q), slow.pair_distances(q)
        np.testing.assert_array_equal(a.distance, b.distance)
        np.testing.assert_array_equal(a.p_WA, b.p_WA)
        np.testing.assert_array_equal(a.p_WB, b.p_WB)
        c = coal.pair_distances(q)
        np.testing.assert_allclose(a.distance, c.distance, atol=1e-9, rtol=0)
    Q = model.random_q(7, 2)
    many = fast.pair_distances_many(Q)
    for m, q in enumerate(Q):
        np.testing.assert_array_equal(many.distance[m], slow.pair_distances(q).distance)


def test_a_moved_base_computes_the_constant_rows_again():
    """puma560's base pairs are constant until the robot's base is placed elsewhere: the Detector on the
    scene rebuilds and its rows follow the new mount (against coal's)."""
    scene = armguard.load_scene("puma560")
    det = armguard.Detector(scene)
    q = scene.flat_q(scene.default_q())
    before = det.pair_distances(q)
    r = next(iter(scene.robots))
    X = scene.robots[r].X_WB.copy()
    X[:3, 3] += [0.05, 0.02, 0.0]
    scene.set_robot_base(r, X)
    after = det.pair_distances(q)
    fresh = armguard.Detector(scene).pair_distances(q)  # built on the moved scene from the start
    np.testing.assert_array_equal(after.distance, fresh.distance)
    np.testing.assert_array_equal(after.p_WB, fresh.p_WB)
    ref = armguard.Detector(scene, backend="coal").pair_distances(q)  # its own pair numbering: compared sorted
    assert np.max(np.abs(np.sort(after.distance) - np.sort(ref.distance))) <= 1e-9
    assert np.max(np.abs(after.distance - before.distance)) > 1e-3  # the base's pairs moved with it
