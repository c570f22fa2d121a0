"""``armguard.geometry.distance`` on polytope pairs: GJK climbing the hulls' vertex graphs + EPA.

The public one-shot call answers a polytope pair with a hull of ``CLIMB_MIN_VERTICES`` or more
vertices by ``_pair_epa.convex_convex_fast`` (supports climb the hull's vertex graph from
``polytope_adjacency``; EPA for the penetration depth), smaller ones by GJK + SAT.  Oracle: the exhaustive GJK + SAT kernel
``_pair_sat.convex_convex`` on the same shapes (every face normal and edge-edge axis), and the
witness relation of the result itself.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from armguard.geometry import Box, ConvexPolyhedron, distance, kernel_name
from armguard.geometry._dispatch import _climb_graph
from armguard.geometry._pair_gjk import CLIMB_MIN_VERTICES, GJK_WORK_SIZE
from armguard.geometry._pair_sat import convex_convex


def _hull(rng, n: int, center) -> ConvexPolyhedron:
    p = rng.normal(size=(n, 3))
    p /= np.linalg.norm(p, axis=1)[:, None]
    return ConvexPolyhedron(p * rng.uniform([0.2, 0.2, 0.2], [0.6, 0.6, 0.6]) + np.asarray(center))


def _sat(a, b) -> float:
    pa, fa, ea, ra = a._sat
    pb, fb, eb, rb = b._sat
    d, status = convex_convex(pa, fa, ea, ra, pb, fb, eb, rb, np.empty(9), np.empty(GJK_WORK_SIZE),
                              1e-12, 1e-9, 1e-12, 64, 1e-6)
    assert status != 2
    return d


@settings(max_examples=40, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**31), dx=st.floats(0.0, 1.2))
def test_hull_pairs_agree_with_the_exhaustive_sat(seed, dx):
    rng = np.random.default_rng(seed)
    a = _hull(rng, 70, [0.0, 0.0, 0.0])
    b = _hull(rng, 60, [dx, 0.1, -0.05])
    assert len(_climb_graph(a)) > 0 and len(_climb_graph(b)) > 0  # the climbing path is the one tested
    p = distance(a, b)
    ref = _sat(a, b)
    assert abs(p.distance - ref) <= 1e-9
    assert np.allclose(p.p_WB - p.p_WA, p.distance * p.nhat_AB_W, atol=1e-9)
    q = distance(b, a)  # swapped: same distance, witnesses exchanged
    assert abs(q.distance - p.distance) <= 1e-9


def test_small_polytopes_scan_and_boxes_agree_with_the_sat():
    rng = np.random.default_rng(5)
    small = _hull(rng, 12, [0.1, 0.0, 0.0])
    assert len(small._sat[0]) < CLIMB_MIN_VERTICES and len(_climb_graph(small)) == 0
    box = Box([0.0, 0.0, 0.0], [0.3, 0.2, 0.1])
    for other in (small, _hull(rng, 80, [0.2, 0.1, 0.0]), Box([0.35, 0.1, 0.0], [0.1, 0.1, 0.1])):
        assert abs(distance(box, other).distance - _sat(box, other)) <= 1e-9
    assert "EPA" in kernel_name(box, small) and "SAT" in kernel_name(box, small)


@settings(max_examples=40, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**31), dx=st.floats(0.3, 1.6), r=st.floats(0.01, 0.1))
def test_yes_no_early_out_keeps_the_verdict(seed, dx, r):
    """With ``level > -inf`` (the detector's yes/no mode) convex_convex_fast stops GJK once a support
    plane proves the signed distance above ``level``: the value it returns may then be any upper
    bound, but it is > ``level`` exactly when the exhaustive SAT's distance is (levels on both sides
    of the distance, near it and far)."""
    from armguard.geometry._pair_epa import EPA_WORK_SIZE, convex_convex_fast

    rng = np.random.default_rng(seed)
    a = _hull(rng, 70, [0.0, 0.0, 0.0])
    b = _hull(rng, 60, [dx, 0.1, -0.05])
    pa, fa, ea, _ = a._sat
    pb, fb, eb, _ = b._sat
    ga, gb = _climb_graph(a), _climb_graph(b)
    tri = np.zeros((0, 3), np.int64)
    ref = _sat(a, b) - 2 * r
    args = (np.empty(9), np.empty(EPA_WORK_SIZE), 1e-12, 1e-9, 1e-12, 64, 1e-6)
    d_ex, _ = convex_convex_fast(pa, fa, ea, ga, tri, r, pb, fb, eb, gb, tri, r, *args, -np.inf)
    assert abs(d_ex - ref) <= 1e-9
    steps = np.array([1e-6, 1e-4, 1e-3, 0.01, 0.03, 0.1, 0.3])
    levels = np.concatenate([max(ref, 0.0) + steps, ref - steps])
    for level in levels[levels >= 0.0]:  # the detector's levels: max(length, stopping distance)
        d_yn, _ = convex_convex_fast(pa, fa, ea, ga, tri, r, pb, fb, eb, gb, tri, r, *args, level)
        assert (d_yn > level) == (ref > level), (d_yn, ref, level)
        assert d_yn >= d_ex - 1e-9  # a bound from above (or the distance)
