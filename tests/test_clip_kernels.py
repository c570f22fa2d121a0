"""armguard.clip kernels: Cyrus–Beck and Sutherland–Hodgman against slow, obviously-correct
references (a linear program for the kept segment interval; brute-force vertex enumeration of
the clipped polygon in its own plane)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import linprog
from scipy.spatial import ConvexHull

from armguard.clip import cyrus_beck, sutherland_hodgman
from armguard.geometry import ConvexPolyhedron


def _random_planes(rng, k=None):
    """A random bounded convex volume as outward planes ``(K, 4)`` (the hull of random points)."""
    pts = rng.normal(size=(int(k or rng.integers(4, 14)), 3)) * rng.uniform(0.2, 1.0)
    return np.array(ConvexPolyhedron(pts).planes)


def _lp_interval(planes, p0, p1):
    """Reference: the kept parameter interval of p0 + t (p1 - p0) by two linear programs."""
    d = p1 - p0
    A = (planes[:, :3] @ d)[:, None]
    b = planes[:, 3] - planes[:, :3] @ p0
    lo = linprog([1.0], A_ub=A, b_ub=b, bounds=[(0.0, 1.0)])
    if lo.status == 2:
        return None
    hi = linprog([-1.0], A_ub=A, b_ub=b, bounds=[(0.0, 1.0)])
    return float(lo.x[0]), float(hi.x[0])


@settings(max_examples=150, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_cyrus_beck_matches_linear_program(seed):
    rng = np.random.default_rng(seed)
    planes = _random_planes(rng)
    p0, p1 = rng.normal(size=3) * 1.2, rng.normal(size=3) * 1.2
    hit, t_in, t_out = cyrus_beck(planes, p0, p1, 0.0)
    ref = _lp_interval(planes, p0, p1)
    if ref is None:
        # the LP says empty: Cyrus–Beck must agree unless the segment grazes the volume
        if hit:
            assert t_out - t_in < 1e-7
        return
    if ref[1] - ref[0] > 1e-7:
        assert hit
        assert t_in == pytest.approx(ref[0], abs=1e-7) and t_out == pytest.approx(ref[1], abs=1e-7)


def test_cyrus_beck_parallel_and_degenerate():
    cube = np.array(ConvexPolyhedron(np.array(list(itertools.product([-1.0, 1.0], repeat=3)))).planes)
    # parallel to x faces, outside in y: rejected; inside: the x range clipped to [-1, 1]
    assert not cyrus_beck(cube, np.array([-3.0, 1.5, 0.0]), np.array([3.0, 1.5, 0.0]), 0.0)[0]
    hit, a, b = cyrus_beck(cube, np.array([-3.0, 0.5, 0.0]), np.array([3.0, 0.5, 0.0]), 0.0)
    assert hit and a == pytest.approx(1 / 3) and b == pytest.approx(2 / 3)
    # a point (zero-length segment) inside and outside
    assert cyrus_beck(cube, np.zeros(3), np.zeros(3), 0.0)[0]
    assert not cyrus_beck(cube, np.full(3, 2.0), np.full(3, 2.0), 0.0)[0]
    # touching a face counts (closed sets)
    assert cyrus_beck(cube, np.array([1.0, 0.0, 0.0]), np.array([2.0, 0.0, 0.0]), 0.0)[0]


def _plane_frame(poly):
    n = np.cross(poly[1] - poly[0], poly[2] - poly[0])
    n /= np.linalg.norm(n)
    e1 = (poly[1] - poly[0]) / np.linalg.norm(poly[1] - poly[0])
    return poly[0], e1, np.cross(n, e1), n


def _reference_clip_area(planes, poly):
    """Brute force: every vertex of (polygon ∩ volume) is where two of its boundary lines meet
    in the polygon's plane; keep the feasible intersections, area of their hull."""
    o, e1, e2, n = _plane_frame(poly)
    q = (poly - o) @ np.stack([e1, e2]).T
    lines = []  # a . u <= b in the plane's 2-D coordinates
    m = len(q)
    for i in range(m):
        a, b = q[i], q[(i + 1) % m]
        normal = np.array([b[1] - a[1], a[0] - b[0]])
        if normal @ (q.mean(axis=0) - a) > 0:
            normal = -normal
        lines.append((normal, float(normal @ a)))
    for nn, d in zip(planes[:, :3], planes[:, 3]):
        a2 = np.array([nn @ e1, nn @ e2])
        lines.append((a2, float(d - nn @ o)))
    pts = []
    for (a1, b1), (a2, b2) in itertools.combinations(lines, 2):
        M = np.stack([a1, a2])
        if abs(np.linalg.det(M)) < 1e-12:
            continue
        u = np.linalg.solve(M, [b1, b2])
        if all(a @ u <= b + 1e-9 * max(1.0, np.linalg.norm(a)) for a, b in lines):
            pts.append(u)
    if len(pts) < 3:
        return 0.0, pts
    pts = np.array(pts)
    try:
        return float(ConvexHull(pts).volume), pts
    except Exception:  # collinear feasible set: no area
        return 0.0, pts


def _area3(loop):
    if len(loop) < 3:
        return 0.0
    s = np.zeros(3)
    for i in range(len(loop)):
        s += np.cross(loop[i], loop[(i + 1) % len(loop)])
    return 0.5 * float(np.linalg.norm(s))


@settings(max_examples=150, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_sutherland_hodgman_matches_vertex_enumeration(seed):
    rng = np.random.default_rng(seed)
    planes = _random_planes(rng)
    m = int(rng.integers(3, 9))
    ang = np.linspace(0, 2 * np.pi, m, endpoint=False) + rng.uniform(0, 0.5, m)
    R = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    poly = (np.stack([np.cos(ang), np.sin(ang), np.zeros(m)], 1) * rng.uniform(0.3, 1.5)) @ R.T + rng.normal(size=3) * 0.5
    K = len(planes)
    ba, bb = np.empty((m + K + 1, 3)), np.empty((m + K + 1, 3))
    count, which = sutherland_hodgman(planes, poly, m, ba, bb, 0.0)
    out = (ba if which == 0 else bb)[:count]
    ref_area, _ = _reference_clip_area(planes, poly)
    assert _area3(out) == pytest.approx(ref_area, abs=1e-9)
    if ref_area > 1e-9:
        assert count >= 3
    # every output vertex is inside every plane and on the polygon's plane
    if count:
        assert np.all(out @ planes[:, :3].T - planes[:, 3] <= 1e-9)
        _, _, _, n = _plane_frame(poly)
        assert np.allclose((out - poly[0]) @ n, 0.0, atol=1e-9)
