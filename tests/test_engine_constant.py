"""Pairs whose relative pose never changes (``armguard_analytic._engine._constant``): computed once per
build; a pair fixed in W copied bit for bit, a rigid pair (links joined by fixed joints) moved with its
link A to rounding; computed again when a scene edit moves them."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import armguard
from armguard_analytic._engine._layout import K


@pytest.fixture(autouse=True)
def _quiet():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the public robots' SRDF notes
        yield


def _rows(checker) -> tuple:
    """``(cst, frame)``: each pair's row of "cstv" (-1: none) and each row's frame (-1: W, else a link)."""
    H, MF, MI = checker._plan().args[:3]
    o, n = H[2 * K["cst"]], H[2 * K["cst"] + 1]
    cst = MI[o:o + n]
    ov = H[2 * K["cstv"]]
    frame = MF[ov:ov + 8 * H[2 * K["cstv"] + 1]].reshape(-1, 8)[:, 0]
    return cst, frame


@pytest.mark.parametrize("name, n_world, n_rigid", [("puma560", 9, 0), ("gmf_s480", 1, 0), ("kinova", 0, 6),
                                                    ("talos_left_arm", 0, 3), ("rover", 0, 0), ("panda", 0, 0)])
def test_the_pairs_found_constant_are_those_no_joint_moves(name, n_world, n_rigid):
    model = armguard.load_model(name)
    ana = armguard.checker(model, "analytic")
    cst, frame = _rows(ana)
    k = np.flatnonzero(cst >= 0)
    world = k[frame[cst[k]] < 0]
    rigid = k[frame[cst[k]] >= 0]
    assert (len(world), len(rigid)) == (n_world, n_rigid)
    rows = [ana.pair_distances(q) for q in model.random_q(20, 5)]
    for r in rows[1:]:  # their distances never change; the fixed ones' witness points neither
        np.testing.assert_array_equal(r.distance[k], rows[0].distance[k])
        np.testing.assert_array_equal(r.p_WA[world], rows[0].p_WA[world])
    if len(rigid):  # a rigid pair's witness points move with its links, the same distance apart
        assert np.ptp(np.array([r.p_WA[rigid] for r in rows]), axis=0).max() > 1e-3
        for r in rows:
            np.testing.assert_allclose(np.linalg.norm(r.p_WB[rigid] - r.p_WA[rigid], axis=1), np.abs(r.distance[rigid]),
                                       rtol=0, atol=1e-12)
    moving = np.flatnonzero(cst < 0)
    if len(moving):  # a pair said to move does move somewhere among the configurations
        assert np.ptp(np.array([r.distance[moving] for r in rows]), axis=0).max() > 0.0


@pytest.mark.parametrize("name, bits", [("puma560", True), ("gmf_s480", True), ("kinova", False),
                                        ("talos_left_arm", False)])
def test_copied_rows_are_the_rows_computed_at_every_check(name, bits):
    """The same checker with its constant rows switched off (every pair computed at every call): a pair
    fixed in W bit for bit, a rigid pair to rounding (the kernel recomputes its relative pose from two
    link poses at each check), and the coal reference within its tolerance."""
    model = armguard.load_model(name)
    fast = armguard.checker(model, "analytic")
    slow = armguard.checker(model, "analytic")
    cst, _ = _rows(slow)
    assert np.any(cst >= 0)
    cst[:] = -1  # this checker's own buffers: computed every time
    coal = armguard.checker(model, "coal")
    check = (np.testing.assert_array_equal if bits else
             lambda a, b: np.testing.assert_allclose(a, b, rtol=0, atol=1e-13))
    for q in model.random_q(30, 11):
        a, b = fast.pair_distances(q), slow.pair_distances(q)
        check(a.distance, b.distance)
        check(a.p_WA, b.p_WA)
        check(a.p_WB, b.p_WB)
        c = coal.pair_distances(q)
        np.testing.assert_allclose(a.distance, c.distance, atol=1e-9, rtol=0)
    Q = model.random_q(7, 2)
    many = fast.pair_distances_many(Q)
    for m, q in enumerate(Q):
        check(many.distance[m], slow.pair_distances(q).distance)


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
