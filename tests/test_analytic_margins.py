"""``collides(Q, margin=m)`` on the analytic backend: any number of margins on one detector.

A margin used to build and keep a fused detector of its own (32 ms and 5.4 MB each on panda, 1.1 s
and 35 MB on so101, never freed): a planner trying clearances grew without bound.  The detector keeps
every pair (``reach_margin`` inf), so the margin is only the kernel's stopping-distance parameter.
"""

from __future__ import annotations

import tracemalloc

import numpy as np

import armguard


def test_many_margins_cost_no_memory_and_answer_as_the_distances():
    model = armguard.load_model("panda")
    c = armguard.checker(model, "analytic")
    Q = model.random_q(40, 3)
    dmin = np.array([c.pair_distances(q).distance.min() for q in Q])
    c.collides(Q, margin=0.001)  # the detector built, the kernel loaded
    margins = np.linspace(0.002, 0.2, 25)
    tracemalloc.start()
    try:
        base = tracemalloc.get_traced_memory()[0]
        for m in margins:
            hit = c.collides(Q, margin=float(m))
            far = np.abs(dmin - m) > 1e-9
            assert np.array_equal(hit[far], (dmin <= m)[far]), m
        grown = tracemalloc.get_traced_memory()[0] - base
    finally:
        tracemalloc.stop()
    assert grown < 1_000_000, f"{grown} bytes kept over {len(margins)} margins"  # was ~5.4 MB per margin
    assert c.detector() is c.detector()
