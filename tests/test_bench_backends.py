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
