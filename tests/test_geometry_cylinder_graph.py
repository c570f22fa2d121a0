"""A cylinder against a mesh hull: supports climbed over the hull's vertex graph equal a scan.

The detector's narrow phase gives the support-function kernel (``_pair_cylinder``) a hull's
vertex graph (``_pack.hull_graph``) so that each support point is a climb of a few dozen dot
products instead of a scan of every vertex (the z1 gripper hulls have 3,193 and 6,877).  The
climb finds a true support vertex, so the distance must be the scan's; the slow reference here
is the same kernel with no graph (every point scanned), and a brute-force support-function
minimum for a few pairs.  The point sets hold points inside the hull too (the graph leaves them
without neighbours: a climb never visits them).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from _geometry_strategies import random_rotation
from armguard._tolerance import DEFAULT_TOLERANCES as TOL
from armguard.geometry import Cylinder
from armguard.geometry._dispatch import _support_core
from armguard.geometry._pack import hull_graph, support_table
from armguard.geometry._pair_gjk import ADJ_HEAD
from armguard.geometry._pair_cylinder import SUPPORT_WORK_SIZE, support_pair, support_pair_graph, support_point
from armguard.geometry._pair_cylinder_support import _WA, _warm_point
from armguard.geometry._support_reference import reference_signed_distance


def _cloud(rng, n: int) -> np.ndarray:
    """``n`` points on a random ellipsoid (all hull vertices) and ``n // 4`` inside it, shuffled."""
    u = rng.normal(size=(n, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    inner = rng.normal(size=(n // 4, 3)) * 0.2
    p = np.concatenate([u, inner]) * rng.uniform(0.05, 0.3, 3)
    p = p @ random_rotation(rng).T + rng.uniform(-0.2, 0.2, 3)
    return np.ascontiguousarray(p[rng.permutation(len(p))])


def _both(p, adj, cyl_core, graph_first: bool):
    """The distance and witnesses with the hull as side A (``graph_first``) or B, with and without its graph."""
    pc, cc, rc = cyl_core
    none = np.zeros(0, np.int64)
    args = dict(eps_len=TOL.length, gjk_eps=TOL.gjk_epsilon, max_iter=TOL.gjk_max_iterations, level=-np.inf)
    out_g, out_s = np.empty(9), np.empty(9)
    if graph_first:
        dg, sg = support_pair_graph(p, adj, np.zeros(0), 0.0, pc, none, cc, rc, out_g, np.empty(SUPPORT_WORK_SIZE),
                                    *args.values())
        ds, ss = support_pair(p, np.zeros(0), 0.0, pc, cc, rc, out_s, np.empty(SUPPORT_WORK_SIZE), *args.values())
    else:
        dg, sg = support_pair_graph(pc, none, cc, rc, p, adj, np.zeros(0), 0.0, out_g, np.empty(SUPPORT_WORK_SIZE),
                                    *args.values())
        ds, ss = support_pair(pc, cc, rc, p, np.zeros(0), 0.0, out_s, np.empty(SUPPORT_WORK_SIZE), *args.values())
    return (dg, sg, out_g), (ds, ss, out_s)


def _with_table(p, adj, cyl_core, graph_first: bool):
    """:func:`_both`'s graph call with the hull's support table as well (the detector's call)."""
    pc, cc, rc = cyl_core
    none = np.zeros(0, np.int64)
    tab = support_table(p)
    args = (TOL.length, TOL.gjk_epsilon, TOL.gjk_max_iterations, -np.inf)
    out, work = np.empty(9), np.empty(SUPPORT_WORK_SIZE)
    if graph_first:
        return support_pair_graph(p, adj, np.zeros(0), 0.0, pc, none, cc, rc, out, work, *args, tab, none)
    return support_pair_graph(pc, none, cc, rc, p, adj, np.zeros(0), 0.0, out, work, *args, none, tab)


@pytest.mark.parametrize("graph_first", [True, False])
def test_climbed_supports_give_the_scans_distance(graph_first):
    rng = np.random.default_rng(7)
    n_sep = n_pen = 0
    for _ in range(150):
        p = _cloud(rng, int(rng.integers(60, 600)))
        adj, _tri = hull_graph(p)
        cyl = Cylinder(rng.uniform(-0.3, 0.3, 3), random_rotation(rng), rng.uniform(0.02, 0.2), rng.uniform(0.02, 0.3))
        (dg, sg, og), (ds, ss, os_) = _both(p, adj, _support_core(cyl), graph_first)
        assert sg == ss
        assert abs(dg - ds) <= 1e-9, (dg, ds)
        dt, st_ = _with_table(p, adj, _support_core(cyl), graph_first)  # climbs warm-started from the table
        assert st_ == ss and abs(dt - ds) <= 1e-9, (dt, ds)
        # the contract: |p_WB - p_WA| = |d|, the witnesses within the scan's by the same tolerance
        assert abs(np.linalg.norm(og[3:6] - og[0:3]) - abs(dg)) <= 1e-9
        n_sep += ds > 0.0
        n_pen += ds < 0.0
    assert n_sep >= 20 and n_pen >= 20  # both regimes covered (separated: GJK; penetrating: EPA)


def test_climbed_supports_match_the_support_function_minimum():
    rng = np.random.default_rng(11)
    for _ in range(6):
        p = _cloud(rng, 300)
        adj, _tri = hull_graph(p)
        cyl = Cylinder(rng.uniform(-0.3, 0.3, 3), random_rotation(rng), rng.uniform(0.02, 0.2), rng.uniform(0.02, 0.3))
        (dg, _, _), _ = _both(p, adj, _support_core(cyl), True)
        ref = reference_signed_distance(_Points(p), cyl)
        assert abs(dg - ref) <= 1e-7, (dg, ref)


class _Points:
    """The hull of a point set as the reference reads a shape (``core_points``, ``core_radius``)."""

    def __init__(self, p):
        self.core_points, self.core_radius = p, 0.0


@settings(max_examples=40, deadline=None, derandomize=True)
@given(st.integers(0, 2**31 - 1), st.integers(48, 900), st.floats(0.01, 1.0))
def test_warm_climbs_return_true_support_vertices(seed, n, step):
    """GJK and EPA climb a hull from the previous support vertex (``work[_WA]`` / ``work[_WB]``) and,
    cold, from the stored extreme vertex farthest along ``d``.  The detector builds a hull's graph
    in its link frame and moves the points to W, so the stored extremes are not W's: the points
    here are rotated after the graph is built.  Along a random walk of directions (GJK's are
    close, EPA's jump) every climb reaches a vertex as extreme as a scan's, whatever the slot held
    before: a hull vertex (a climb only ever leaves one there), -1 (cold), or an index past the points (a buffer never reset)."""
    rng = np.random.default_rng(seed)
    p = _cloud(rng, n)
    adj, _tri = hull_graph(p)
    p = np.ascontiguousarray(p @ random_rotation(rng).T + rng.uniform(-1.0, 1.0, 3))
    tab = support_table(p)
    work = np.empty(SUPPORT_WORK_SIZE)
    on_hull = np.flatnonzero(np.diff(adj[ADJ_HEAD:ADJ_HEAD + len(p) + 1]) > 0)  # inner points have no neighbours
    work[_WA] = rng.choice([-1.0, float(rng.choice(on_hull)), float(len(p) + rng.integers(0, 10**6))])
    d = rng.normal(size=3)
    for _ in range(30):
        d = d + step * rng.normal(size=3)
        x, y, z = _warm_point(p, adj, np.zeros(0), d[0], d[1], d[2], work, _WA)
        i = int(work[_WA])
        s = p[:, 0] * d[0] + p[:, 1] * d[1] + p[:, 2] * d[2]  # the kernels' dot products, rounded alike
        assert 0 <= i < len(p) and (x, y, z) == tuple(p[i])
        assert s[i] == s.max()  # the scan's value: a true support vertex
        x, y, z = support_point(p, adj, np.zeros(0), *d)  # the cold climb, from the best stored extreme
        assert x * d[0] + y * d[1] + z * d[2] == s.max()
        x, y, z = _warm_point(p, adj, np.zeros(0), d[0], d[1], d[2], work, _WA, tab)  # from the table's entry too
        assert x * d[0] + y * d[1] + z * d[2] == s.max() and s[int(work[_WA])] == s.max()
