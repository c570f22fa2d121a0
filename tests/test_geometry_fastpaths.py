"""The fast capsule-polytope path (GJK on registers + Minkowski-facet depth) agrees with the
generic GJK + exhaustive-SAT kernel (itself checked against the feature-enumeration reference
in test_geometry_distance.py), on separated, grazing and deeply penetrating pairs, for every
polytope kind and for sphere cores; and the single-call fast path of ``distance()``.  Hill-climbing
support queries on a polytope's vertex graph agree with a scan of its vertices."""

from __future__ import annotations

import numpy as np
import pytest

from _geometry_strategies import random_rotation
from armguard import DEFAULT_TOLERANCES as TOL
from armguard.geometry import Box, Capsule, ConvexPolyhedron, Polygon, Prism, Sphere, batch, distance
from armguard.geometry._pack import polytope_adjacency, polytope_data
from armguard.geometry._pair_gjk import ADJ_HEAD, CLIMB_MIN_VERTICES, GJK_WORK_SIZE, _support
from armguard.geometry._pair_sat import convex_convex
from armguard.geometry._pair_segment_polytope import segment_polytope_depth


def _generic(cap, hull):
    """Signed distance by the generic kernel: GJK, then SAT over every candidate axis."""
    pa, fa, ea, ra = cap._sat
    pb, fb, eb, rb = hull._sat
    out = np.empty(9)
    d, _status = convex_convex(
        pa, fa, ea, ra, pb, fb, eb, rb, out, np.empty(GJK_WORK_SIZE), TOL.length, TOL.parallel,
        TOL.gjk_epsilon, TOL.gjk_max_iterations, TOL.penetration_witness_offset,
    )
    return d


def _hulls():
    rng = np.random.default_rng(11)
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0.0]]) - 0.5
    return {
        "polyhedron-20": ConvexPolyhedron(rng.normal(size=(20, 3)) * 0.5),
        "polyhedron-6": ConvexPolyhedron(rng.normal(size=(6, 3)) * 0.5),
        "box": Box([0.1, 0.2, 0.0], [0.4, 0.3, 0.2], random_rotation(rng)),
        "prism-8": Prism([0, 0, 0.1], random_rotation(rng), 0.3, 0.4, 8),
        "prism-3": Prism([0, 0.1, 0], random_rotation(rng), 0.3, 0.2, 3),
        "polygon": Polygon(square @ random_rotation(rng).T),
    }


HULLS = _hulls()


@pytest.mark.parametrize("name", list(HULLS), ids=list(HULLS))
def test_batch_capsule_convex_matches_generic_sat(name):
    hull = HULLS[name]
    rng = np.random.default_rng(12)
    n = 400
    c = rng.uniform(-0.8, 0.8, (n, 3))
    d = rng.normal(size=(n, 3)) * 0.4
    d[:40] = 0.0  # sphere cores
    a0, a1 = c - d, c + d
    ra = rng.uniform(0.0, 0.1, n)
    res = batch.capsule_convex(a0, a1, ra, hull)
    want = np.array([_generic(Capsule(a0[i], a1[i], ra[i]), hull) for i in range(n)])
    assert np.sum(want < -0.05) > 20 and np.sum(want > 0.05) > 20  # both regimes are exercised
    np.testing.assert_allclose(res.distance, want, rtol=0, atol=1e-12)
    gap = res.p_WB - res.p_WA
    np.testing.assert_allclose(np.linalg.norm(gap, axis=1), np.abs(res.distance), rtol=0, atol=1e-9)
    np.testing.assert_allclose(gap, res.distance[:, None] * res.nhat_AB_W, rtol=0, atol=1e-9)
    for i in range(0, n, 37):  # the single call is the same kernel (a box has its own: capsule_box)
        one = distance(Capsule(a0[i], a1[i], ra[i]), hull)
        if name == "box":
            assert one.distance == pytest.approx(res.distance[i], abs=1e-12)
        else:
            assert one.distance == res.distance[i]
            np.testing.assert_array_equal(one.p_WA, res.p_WA[i])
        back = distance(hull, Capsule(a0[i], a1[i], ra[i]))
        assert back.distance == one.distance
        np.testing.assert_array_equal(back.p_WA, one.p_WB)


@pytest.mark.parametrize(
    "p0,p1,depth",
    [
        ([0.0, 0.0, 0.3], [0.0, 0.0, 0.3], 0.2),  # point 0.3 above centre of a unit cube: out the top
        ([-2.0, 0.0, 0.4], [2.0, 0.0, 0.4], 0.1),  # through the cube near its top face
        ([-2.0, 0.45, 0.45], [2.0, 0.45, 0.45], 0.05),  # along an edge: out through either face
        ([-2.0, -2.0, 0.0], [2.0, 2.0, 0.0], 0.5),  # diagonal in the mid-plane: out through top/bottom
    ],
    ids=["point-face", "segment-face", "segment-near-edge", "segment-diagonal"],
)
def test_segment_polytope_depth_closed_forms(p0, p1, depth):
    cube = ConvexPolyhedron(np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)]))
    v, pl, ed, bi, _cen = polytope_data(cube)
    got, qx, qy, qz = segment_polytope_depth(*p0, *p1, v, pl, ed, bi, TOL.length, TOL.parallel)
    assert got == pytest.approx(depth, abs=1e-12)
    assert np.linalg.norm([qx, qy, qz]) == pytest.approx(1.0, abs=1e-12)
    # the full kernel: witnesses read off the facet, or (a segment lying along a face, whose
    # end point is off the face) solved by GJK after the move; either way on both surfaces
    r = distance(Capsule(p0, p1, 0.0), cube)
    assert r.distance == pytest.approx(-depth, abs=1e-12)
    assert np.max(pl[:, :3] @ r.p_WB - pl[:, 3]) == pytest.approx(0.0, abs=1e-9)  # on the cube
    seg = np.array(p1) - np.array(p0)
    off = r.p_WA - np.array(p0)
    assert np.linalg.norm(np.cross(off, seg)) <= 1e-9 * max(1.0, np.linalg.norm(seg))  # on the segment line


def test_edge_facet_is_found():
    # a long segment in the plane y = 0 along (1, 0, -1), cutting the corner of the cube's
    # cross-section at x + z = 0.9: leaving through a face takes ~2 m, through the top-front
    # edge (a Minkowski facet of edge x segment, normal (1, 0, 1)/sqrt2) only (1 - 0.9)/sqrt2
    cube = ConvexPolyhedron(np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)]))
    v, pl, ed, bi, _cen = polytope_data(cube)
    p0 = np.array([0.45, 0.0, 0.45]) - 2.0 * np.array([1.0, 0.0, -1.0])
    p1 = np.array([0.45, 0.0, 0.45]) + 2.0 * np.array([1.0, 0.0, -1.0])
    got, qx, qy, qz = segment_polytope_depth(*p0, *p1, v, pl, ed, bi, TOL.length, TOL.parallel)
    assert got == pytest.approx(0.1 / np.sqrt(2.0), abs=1e-12)
    np.testing.assert_allclose([qx, qy, qz], np.array([1.0, 0.0, 1.0]) / np.sqrt(2.0), atol=1e-12)
    r = distance(Capsule(p0, p1, 0.02), cube)
    assert r.distance == pytest.approx(-0.1 / np.sqrt(2.0) - 0.02, abs=1e-12)
    np.testing.assert_allclose(r.nhat_AB_W, -np.array([1.0, 0.0, 1.0]) / np.sqrt(2.0), atol=1e-12)
    assert r.distance == pytest.approx(_generic(Capsule(p0, p1, 0.02), cube), abs=1e-12)


def test_polytope_data_describes_the_hull():
    hull = HULLS["polyhedron-20"]
    v, pl, ed, bi, cen = polytope_data(hull)
    assert np.all(v @ pl[:, :3].T <= pl[:, 3] + 1e-12)  # every vertex inside every face plane
    for a, b, f1, f2 in ed:  # both end points of an edge lie on both of its faces
        for f in (f1, f2):
            assert abs(v[a] @ pl[f, :3] - pl[f, 3]) < 1e-9 and abs(v[b] @ pl[f, :3] - pl[f, 3]) < 1e-9
    assert len(ed) == len(hull.edges)
    np.testing.assert_allclose(cen, hull.vertices.mean(axis=0))
    box = HULLS["box"]
    assert polytope_data(box) is polytope_data(box)  # built once, on first use


@pytest.mark.parametrize("kind", ["capsule", "sphere"], ids=["capsule", "sphere"])
def test_single_call_fast_path_keeps_the_contract(kind):
    a = Capsule([0, 0, 0], [1, 0, 0], 0.1) if kind == "capsule" else Sphere([0.5, 0, 0], 0.1)
    b = Capsule([0.5, 1, -0.5], [0.5, 1, 0.5], 0.1)
    r = distance(a, b)
    assert r.distance == pytest.approx(0.8, abs=1e-15)
    np.testing.assert_allclose(r.p_WB - r.p_WA, r.distance * r.nhat_AB_W, atol=1e-15)
    with pytest.raises(ValueError):
        r.p_WA[0] = 1.0  # read-only
    with pytest.raises(AttributeError):
        r._d = 0.0  # immutable


def _sphere_hull(n, seed):
    v = np.random.default_rng(seed).normal(size=(n, 3))
    return ConvexPolyhedron(0.5 * v / np.linalg.norm(v, axis=1)[:, None])


def _large_hulls():
    rng = np.random.default_rng(21)
    # a mesh-like hull: a flattened cylinder sampled on rings, many nearly coplanar faces
    t = np.linspace(0.0, 2.0 * np.pi, 24, endpoint=False)
    rings = [np.stack([0.3 * np.cos(t), 0.1 * np.sin(t), np.full_like(t, z)], axis=1) for z in (-0.4, 0.0, 0.4)]
    mesh = np.vstack(rings + [[[0, 0, -0.45]], [[0, 0, 0.45]]]) + rng.normal(size=(74, 3)) * 1e-7
    return {
        "sphere-60": _sphere_hull(60, 22),
        "sphere-200": _sphere_hull(200, 23),
        "mesh-cylinder": ConvexPolyhedron(mesh),
        "prism-32": Prism([0.1, 0, 0], random_rotation(rng), 0.3, 0.4, 32),
        "box": HULLS["box"],
        "polygon-6": Polygon(0.4 * np.stack([np.cos(t[::4]), np.sin(t[::4]), np.zeros(6)], axis=1)),
    }


LARGE = _large_hulls()


@pytest.mark.parametrize("name", list(LARGE), ids=list(LARGE))
def test_vertex_graph_climb_finds_the_support(name):
    """Hill climbing on the vertex graph, cold (from the stored extreme vertex) and warm (from
    a random vertex), reaches a vertex as extreme as a scan's along 2000 random directions."""
    hull = LARGE[name]
    v = polytope_data(hull)[0]
    adj = polytope_adjacency(hull)
    assert polytope_adjacency(hull) is adj  # built once
    nv = len(v)
    assert adj[ADJ_HEAD + nv] == len(adj)  # the offsets close the array
    nbr = {i: set(adj[adj[ADJ_HEAD + i]:adj[ADJ_HEAD + i + 1]].tolist()) for i in range(nv)}
    assert all(i in nbr[j] for i in nbr for j in nbr[i])  # symmetric
    for a, b, _f1, _f2 in polytope_data(hull)[2]:  # every polytope edge is a graph edge
        assert b in nbr[a]
    axes = np.vstack([np.eye(3), -np.eye(3)])[[0, 3, 1, 4, 2, 5]]
    np.testing.assert_array_equal((v @ axes.T)[adj[:ADJ_HEAD], np.arange(6)], np.max(v @ axes.T, axis=0))
    rng = np.random.default_rng(24)
    d = rng.normal(size=(2000, 3))
    d[:20] = axes[rng.integers(0, 6, 20)]  # axis directions: ties between extreme vertices
    start = rng.integers(-1, nv, 2000)
    for k in range(len(d)):
        scan = _support(v, None, -1, *d[k])
        climb = _support(v, adj, int(start[k]), *d[k])
        assert v[climb] @ d[k] == v[scan] @ d[k], (k, scan, climb)


@pytest.mark.parametrize("name", ["sphere-60", "sphere-200", "mesh-cylinder", "prism-32"])
def test_batch_capsule_convex_large_hull_matches_generic_sat(name):
    """Hulls of at least CLIMB_MIN_VERTICES vertices take the climbing supports in the batch
    and the single call: same distances as the generic scan-GJK + exhaustive SAT kernel."""
    hull = LARGE[name]
    assert len(polytope_data(hull)[0]) >= CLIMB_MIN_VERTICES
    rng = np.random.default_rng(25)
    n = 300
    c = rng.uniform(-0.8, 0.8, (n, 3))
    d = rng.normal(size=(n, 3)) * 0.3
    d[:30] = 0.0  # sphere cores
    a0, a1 = c - d, c + d
    ra = rng.uniform(0.0, 0.1, n)
    res = batch.capsule_convex(a0, a1, ra, hull)
    want = np.array([_generic(Capsule(a0[i], a1[i], ra[i]), hull) for i in range(n)])
    assert np.sum(want < -0.05) > 20 and np.sum(want > 0.05) > 20
    np.testing.assert_allclose(res.distance, want, rtol=0, atol=1e-9)
    gap = res.p_WB - res.p_WA
    np.testing.assert_allclose(gap, res.distance[:, None] * res.nhat_AB_W, rtol=0, atol=1e-9)
    for i in range(0, n, 29):
        one = distance(Capsule(a0[i], a1[i], ra[i]), hull)
        assert one.distance == res.distance[i]


@pytest.mark.parametrize("name", ["sphere-60", "sphere-200", "mesh-cylinder", "prism-32"])
def test_gjk_start_points_lie_inside_the_hulls(name):
    """convex_convex_fast starts GJK along a point inside A minus one inside B: with a vertex graph,
    the mean of its six stored extreme vertices (six reads instead of a scan), rotated and moved as
    the detector moves a hull after building its graph in the link frame; without one, the centroid."""
    from scipy.spatial import Delaunay

    from armguard.geometry._pair_gjk import inner_difference

    hull = LARGE[name]
    v = polytope_data(hull)[0]
    adj = polytope_adjacency(hull)
    rng = np.random.default_rng(26)
    for _ in range(20):
        p = np.ascontiguousarray(v @ random_rotation(rng).T + rng.uniform(-1.0, 1.0, 3))
        tess = Delaunay(p)
        zero = np.zeros((1, 3))
        for graph in (adj, np.zeros(0, np.int64)):
            g = np.array(inner_difference(p, graph, zero, np.zeros(0, np.int64)))
            assert tess.find_simplex(g) >= 0, g
        np.testing.assert_allclose(inner_difference(p, np.zeros(0, np.int64), zero, np.zeros(0, np.int64)), p.mean(axis=0),
                                   atol=1e-15)
