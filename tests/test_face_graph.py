"""The support face over a hull's vertex graph (`face_span_graph`) equals the scan's (`face_span`), bit for bit.

On the public robots' mesh hulls (so101, z1, kinova, panda) and on prisms with many coplanar
vertices, in random directions and in the directions that make a face, an edge or a vertex the
support set (a hull facet's normal, the mean of two adjacent facets' normals, a vertex's own)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import ConvexHull
from scipy.spatial.transform import Rotation

import armguard
from armguard import DEFAULT_TOLERANCES
from armguard.backends._face_graph import MIN_GRAPH, face_span_graph, vertex_graph
from armguard.backends._jacobian import WitnessJacobian, face_span

TOL_FACE, TOL_PAR = DEFAULT_TOLERANCES.jacobian_face, DEFAULT_TOLERANCES.jacobian_parallel


def _rotation(rng):
    return Rotation.random(random_state=rng).as_matrix()


def _directions(P, rng, n_random=60):
    """Local directions: random, facet normals (a face), two adjacent facets' mean (an edge), vertices."""
    hull = ConvexHull(P)
    out = list(rng.normal(size=(n_random, 3)))
    eq = hull.equations[:, :3]
    out += list(eq[rng.choice(len(eq), min(30, len(eq)), replace=False)])
    for i in rng.choice(len(hull.neighbors), min(30, len(hull.neighbors)), replace=False):
        out.append(eq[i] + eq[hull.neighbors[i][0]])
    c = P.mean(axis=0)
    out += list(P[rng.choice(len(P), min(20, len(P)), replace=False)] - c)
    return [d / np.linalg.norm(d) for d in out if np.linalg.norm(d) > 0]


def _compare(V, vstart, disk_axis, disk_r, shapes, rng, rotate=True):
    adj, adj_start = vertex_graph(V, vstart, disk_r)
    N = max(len(V), 1)
    hbuf, fbuf = np.empty(N), np.empty(N, np.int64)
    mark, qbuf = np.zeros(N, np.bool_), np.empty(N, np.int64)
    dims_seen = set()
    graphs = 0
    for g in shapes:
        s, e = int(vstart[g]), int(vstart[g + 1])
        A = adj[adj_start[g]:adj_start[g + 1]]
        graphs += int(len(A) > 0)
        R = _rotation(rng) if rotate else np.eye(3)
        for uL in _directions(V[s:e], rng):
            u = R @ uL
            d_scan, d_graph = np.zeros(3), np.zeros(3)
            a = face_span(R, u, s, e, V, disk_axis[g], disk_r[g], TOL_FACE, TOL_PAR, d_scan, hbuf, fbuf)
            b = face_span_graph(R, u, s, e, V, disk_axis[g], disk_r[g], TOL_FACE, TOL_PAR, d_graph, hbuf, fbuf,
                                A, mark, qbuf)
            assert a == b, (g, uL)
            assert np.array_equal(d_scan, d_graph), (g, uL, d_scan, d_graph)
            assert not mark.any()  # the scratch is left clean
            dims_seen.add(int(a))
    return graphs, dims_seen


@pytest.mark.parametrize("name", ["so101", "z1", "kinova", "panda"])
def test_public_hulls_give_the_scans_faces(name):
    model = armguard.load_model(name)
    wj = WitnessJacobian(model)
    big = [g for g in range(len(wj._vstart) - 1) if wj._vstart[g + 1] - wj._vstart[g] > MIN_GRAPH]
    assert big, "the model has hulls large enough for the graph"
    graphs, dims = _compare(wj._V, wj._vstart, wj._disk_axis, wj._disk_r, big, np.random.default_rng(3))
    assert graphs == len(big)  # every such hull is a hull of its own vertices: each gets its graph
    assert dims == {0, 1, 2}  # vertices, edges and faces all met


@settings(max_examples=30, deadline=None)
@given(n_sides=st.integers(33, 200), half=st.floats(0.01, 0.5), r=st.floats(0.01, 0.5), seed=st.integers(0, 2**31))
def test_prisms_with_coplanar_caps(n_sides, half, r, seed):
    """A prism's caps hold ``n_sides`` coplanar vertices each, its sides are rectangles: 2-D faces everywhere."""
    t = np.arange(n_sides) * 2 * np.pi / n_sides
    ring = np.c_[r * np.cos(t), r * np.sin(t)]
    P = np.vstack([np.c_[ring, np.full(n_sides, -half)], np.c_[ring, np.full(n_sides, half)]])
    V = np.vstack([np.zeros((8, 3)), P])  # a small shape first: offsets into V are global
    vstart = np.array([0, 8, 8 + len(P)])
    graphs, dims = _compare(V, vstart, np.zeros((2, 3)), np.zeros(2), [1], np.random.default_rng(seed))
    assert graphs == 1 and 2 in dims


def test_shapes_kept_on_the_scan():
    """Small hulls, cylinders (a disk), flat point sets and points inside their hull keep the scan."""
    rng = np.random.default_rng(0)
    cube = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    flat = np.c_[rng.normal(size=(100, 2)), np.zeros(100)]
    inner = np.vstack([rng.normal(size=(100, 3)), [[0.0, 0.0, 0.0]]])
    big = rng.normal(size=(100, 3))
    big /= np.linalg.norm(big, axis=1)[:, None]
    V = np.vstack([cube, flat, inner, big, big])
    vstart = np.cumsum([0, 8, 100, 101, 100, 100])
    disk_r = np.array([0.0, 0.0, 0.0, 0.0, 0.3])
    _, adj_start = vertex_graph(V, vstart, disk_r)
    assert list(np.diff(adj_start) > 0) == [False, False, False, True, False]
