"""The fast convex-convex kernel (GJK on vertex graphs + EPA depth) against the exhaustive SAT.

``armguard.geometry._pair_sat.convex_convex`` (GJK, then SAT over every face normal and every
edge-edge cross product) is the slow, obviously exact reference; ``_pair_epa.convex_convex_fast``
must give the same signed distance to within ``TOL`` (relative to the hulls' size), the same
status and sign, and witnesses with ``p_WB - p_WA == distance * nhat``, on random hull pairs
placed deep, shallow, touching and apart.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from armguard.geometry import ConvexPolyhedron
from armguard.geometry._pack import hull_graph
from armguard.geometry._pair_epa import EPA_WORK_SIZE, convex_convex_fast, sat_depth_graph
from armguard.geometry._pair_gjk import GJK_WORK_SIZE
from armguard.geometry._pair_sat import convex_convex, sat_depth

TOL = 1e-9  # depth agreement, relative to the hulls' size (EPA stops within gjk_epsilon = 1e-12 m)
EPS = dict(eps_len=1e-12, eps_par=1e-12, gjk_eps=1e-12, max_iter=128, offset=1e-3)
SETTINGS = settings(max_examples=60, deadline=None, derandomize=True)


def _hull(seed: int, n: int, scale, center) -> ConvexPolyhedron:
    rng = np.random.default_rng(seed)
    p = rng.normal(size=(n, 3))
    p /= np.linalg.norm(p, axis=1)[:, None]
    p *= rng.uniform(0.3, 1.0, size=(n, 1))
    return ConvexPolyhedron(p * np.asarray(scale) + np.asarray(center))


def _reference(A, B, ra=0.0, rb=0.0):
    pa, fa, ea, _ = A._sat
    pb, fb, eb, _ = B._sat
    out = np.zeros(9)
    d, status = convex_convex(pa, fa, ea, ra, pb, fb, eb, rb, out, np.zeros(GJK_WORK_SIZE), *EPS.values())
    return d, status, out


def _fast(A, B, ra=0.0, rb=0.0, *, graph_only=True, level=-math.inf, work=EPA_WORK_SIZE):
    """The fast kernel; ``graph_only``: the hulls carry only their graph and triangles (as in the
    detector), else their face normals and edge directions as well."""
    pa, fa, ea, _ = A._sat
    pb, fb, eb, _ = B._sat
    aa, ta = hull_graph(pa)
    ab, tb = hull_graph(pb)
    if graph_only:
        fa, ea, fb, eb = fa[:0], ea[:0], fb[:0], eb[:0]
    out = np.zeros(9)
    d, status = convex_convex_fast(pa, fa, ea, aa, ta, ra, pb, fb, eb, ab, tb, rb, out, np.zeros(work), *EPS.values(),
                                   level)
    return d, status, out


def _size(A, B) -> float:
    return float(max(np.ptp(A.vertices, axis=0).max(), np.ptp(B.vertices, axis=0).max()))


def _check_witness(d, out):
    assert np.all(np.isfinite(out))
    if abs(d) > 1e-6:  # a normal from GJK's witnesses at a nanometre gap carries their rounding
        assert abs(np.linalg.norm(out[6:9]) - 1.0) < 1e-9
    assert np.allclose(out[3:6] - out[0:3], d * out[6:9], atol=1e-9)


pair = st.tuples(
    st.integers(0, 10_000), st.integers(4, 90), st.integers(4, 90),
    st.floats(0.2, 3.0), st.floats(0.2, 3.0), st.floats(0.2, 3.0),
    st.floats(-1.0, 1.0), st.floats(-1.0, 1.0), st.floats(-1.0, 1.0), st.floats(0.0, 2.5),
)


@SETTINGS
@given(pair, st.booleans())
def test_fast_matches_exhaustive_sat(p, graph_only):
    seed, na, nb, sx, sy, sz, dx, dy, dz, reach = p
    A = _hull(seed, na, (sx, sy, sz), (0.0, 0.0, 0.0))
    c = np.array([dx, dy, dz])
    c = reach * c / max(np.linalg.norm(c), 1e-9)  # from deep (reach 0) to apart
    B = _hull(seed + 1, nb, (sz, sx, sy), c)
    d0, s0, _ = _reference(A, B)
    d1, s1, out = _fast(A, B, graph_only=graph_only)
    assert s1 == s0
    assert (d1 < 0.0) == (d0 < 0.0)
    assert abs(d1 - d0) <= TOL * _size(A, B)
    _check_witness(d1, out)


@SETTINGS
@given(st.integers(0, 10_000), st.integers(8, 90), st.sampled_from([0.0, 1e-9, -1e-9, 1e-6, -1e-6, 0.3]))
def test_touching_and_shallow(seed, n, eps):
    """B moved out along the reference's depth direction by the depth plus ``eps`` times the size:
    touching (0), barely apart or barely penetrating, and shallow."""
    A = _hull(seed, n, (1.0, 0.7, 0.5), (0.0, 0.0, 0.0))
    B = _hull(seed + 7, n, (0.6, 1.0, 0.8), A.vertices.mean(axis=0) + (0.03, -0.02, 0.01))
    d0, _, o0 = _reference(A, B)
    assert d0 < 0.0
    shift = (-d0 + eps) * o0[6:9]
    B2 = ConvexPolyhedron(B.vertices + shift)
    r0 = _reference(A, B2)
    r1 = _fast(A, B2)
    assert abs(r1[0] - r0[0]) <= TOL * _size(A, B2)
    if abs(r0[0]) > 1e-10:  # beyond rounding of the construction: the sign is certain
        assert (r1[0] < 0.0) == (r0[0] < 0.0)
        assert r1[1] == r0[1]
    _check_witness(r1[0], r1[2])


@SETTINGS
@given(st.integers(0, 10_000), st.integers(4, 60), st.integers(4, 60), st.floats(0.0, 1.5))
def test_graph_axes_are_the_sat_axes(seed, na, nb, off):
    """``sat_depth_graph`` with the triangles and graphs of the hulls gives ``sat_depth``'s depth."""
    A = _hull(seed, na, (1.0, 0.5, 0.8), (0.0, 0.0, 0.0))
    B = _hull(seed + 3, nb, (0.4, 0.9, 0.6), (off, 0.2, -0.1))
    pa, fa, ea, _ = A._sat
    pb, fb, eb, _ = B._sat
    aa, ta = hull_graph(pa)
    ab, tb = hull_graph(pb)
    ref = sat_depth(pa, fa, ea, pb, fb, eb, 1e-12)
    got = sat_depth_graph(pa, fa[:0], ea[:0], aa, ta, pb, fb[:0], eb[:0], ab, tb, 1e-12)
    assert abs(got[0] - ref[0]) <= 1e-12 * _size(A, B)


@pytest.mark.parametrize("ra, rb", [(0.0, 0.0), (0.05, 0.1)])
def test_yes_no_level_and_radii(ra, rb):
    """With a level, an overlap returns a value <= the level (no depth); apart, a value above the
    level and no less than the exact distance (GJK stops once a support plane proves it apart;
    test_geometry_hull_distance holds the verdicts at levels on both sides of the distance)."""
    rng = np.random.default_rng(5)
    n_over = 0
    for k in range(40):
        A = _hull(k, 40, (1.0, 0.6, 0.8), (0.0, 0.0, 0.0))
        B = _hull(k + 100, 50, (0.7, 0.9, 0.5), rng.uniform(-1.2, 1.2, 3))
        d0, s0, _ = _reference(A, B, ra, rb)
        d1, s1, out = _fast(A, B, ra, rb, level=0.0)
        _check_witness(d1, out)
        if d0 <= 0.0:
            assert d1 <= 0.0 and d1 >= d0 - 1e-12
            n_over += 1
        else:
            assert s1 == s0 and d1 > 0.0 and d1 >= d0 - TOL
        d2, _, _ = _fast(A, B, ra, rb)  # no level: exact again
        assert abs(d2 - d0) <= TOL * _size(A, B)
    assert 5 <= n_over <= 35  # both branches exercised


def test_short_work_takes_the_sat_path():
    """Without room for EPA the kernel is the exhaustive SAT itself (same answer)."""
    A = _hull(1, 30, (1.0, 1.0, 1.0), (0.0, 0.0, 0.0))
    B = _hull(2, 30, (1.0, 1.0, 1.0), (0.5, 0.2, 0.0))
    d0, s0, _ = _reference(A, B)
    d1, s1, out = _fast(A, B, work=GJK_WORK_SIZE)
    assert d0 < 0.0 and s1 == s0 and abs(d1 - d0) <= 1e-12
    _check_witness(d1, out)
