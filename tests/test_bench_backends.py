"""``bench backends`` times the Python around the analytic kernels by swapping a kernel for a no-op:
it reaches into the Checker's call plan and the Detector's per-thread scratch, so a change there
can break it (a refactor of the Detector's scratch once did: the bench stopped with an
AttributeError after every test had passed).  Each figure must come out a small positive time."""

from __future__ import annotations

import math

import numpy as np

import armguard
from bench.backends import _collides_python_seconds, _wrapper_seconds


def test_the_python_per_call_figures_run_on_a_fresh_checker():
    m = armguard.load_model("gmf_s480")
    a = armguard.checker(m, "analytic")
    Q = np.ascontiguousarray(m.random_q(1, 3))
    a.pair_distances(Q[0])  # makes the call plan
    wrapper = _wrapper_seconds(a, a._plan(), Q[0])
    a2 = armguard.checker(m, "analytic")  # no call yet on this thread: the bench must make the scratch
    coll = _collides_python_seconds(a2, Q)
    for t in (wrapper, coll):
        assert math.isfinite(t) and 0.0 <= t < 1e-3  # seconds per call: a few µs, never a millisecond
    np.testing.assert_array_equal(a2.collides(Q), armguard.checker(m, "coal").collides(Q))  # kernel restored


def test_coal_core_computes_what_the_checker_reads():
    """``coal_core`` (the bench's "coal's C++ core" column) runs the coal Checker's own computeDistances: after it,
    the Checker's per-thread results hold the distances its ``pair_distances`` reports for that q."""
    from bench.backends import coal_core

    m = armguard.load_model("puma560")
    c = armguard.checker(m, "coal")
    core = coal_core(c)
    q = m.random_q(1, 4)[0]
    core(q)
    _, gdata = c._thread_data()
    d = np.array([r.min_distance for r in gdata.distanceResults])
    np.testing.assert_array_equal(np.sort(d), np.sort(c.pair_distances(q).distance))


def test_the_detector_peers_pose_only_the_arm_that_moves():
    """The Ranger cycle's peers posed all four arms in Python every call (most of their time); now the arm whose
    joints vary, the others once: each element's pose equals armguard's at every q."""
    from bench.detector import _peer_groups, _poser
    from armguard.scene import load_scene

    scene = load_scene("ranger")
    det = armguard.Detector(scene, threshold=0.05, active="left_arm")
    m = det._model
    q0 = scene.flat_q(scene.default_q())
    Q = np.tile(q0, (5, 1))
    left = list(scene.joint_names).index("left_arm/" + scene.robots["left_arm"].joint_names[0])
    Q[:, left] += np.linspace(0.0, 0.5, 5)
    active, arm_b, env_b, moving = _peer_groups(m)
    pose_elements, mine = _poser(scene, m, Q, moving)
    assert set(mine) == set(active) and not set(mine) & set(arm_b)
    got = {}
    pose_elements(Q[3], lambda g, X: got.__setitem__(g, X.copy()), moving)
    names = list(scene.robots)
    X_all = np.concatenate([scene.robots[r].forward_kinematics(scene.split_q(Q[3])[r]) for r in names])
    for g in moving:
        np.testing.assert_allclose(got[g], X_all[m.elem_glink[g]], atol=1e-12)
