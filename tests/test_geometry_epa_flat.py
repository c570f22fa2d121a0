"""The polytope EPA (hulls of 48+ vertices) against an exact separating-axis depth, flat contacts included.

For two convex polytopes in contact the penetration depth is the least overlap over the
candidate axes of their Minkowski difference: both hulls' face normals and the cross products of
their edges (the separating axis theorem). Slow, obviously correct, computed here with SciPy's
ConvexHull. The cylinder kernel once placed witness points off the surfaces on flat contacts;
this holds the polytope kernel to the exact depth and to witnesses on both surfaces.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull
from scipy.spatial.transform import Rotation

import armguard.geometry as g


def _prism(r: float, h: float, n: int) -> np.ndarray:
    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    ring = np.c_[r * np.cos(t), r * np.sin(t)]
    return np.r_[np.c_[ring, -h * np.ones(n)], np.c_[ring, h * np.ones(n)]]


def _axes(P: np.ndarray):
    H = ConvexHull(P)
    edges = {tuple(sorted((s[i], s[(i + 1) % 3]))) for s in H.simplices for i in range(3)}
    E = np.array([P[b] - P[a] for a, b in edges])
    return H, E / np.linalg.norm(E, axis=1)[:, None]


def _sat_depth(PA, PB) -> float:
    HA, EA = _axes(PA)
    HB, EB = _axes(PB)
    C = np.cross(EA[:, None, :], EB[None, :, :]).reshape(-1, 3)
    nc = np.linalg.norm(C, axis=1)
    U = np.r_[HA.equations[:, :3], HB.equations[:, :3], C[nc > 1e-9] / nc[nc > 1e-9][:, None]]
    a, b = PA @ U.T, PB @ U.T
    return float(np.minimum(a.max(0) - b.min(0), b.max(0) - a.min(0)).min())


def _off_surface(P, p) -> float:
    H = ConvexHull(P)
    return abs(float(np.max(H.equations[:, :3] @ p + H.equations[:, 3])))


def test_epa_depth_and_witnesses_match_the_separating_axis_depth():
    rng = np.random.default_rng(5)
    PA = _prism(0.2, 0.1, 32)  # 64 vertices: the vertex-graph GJK + EPA path
    assert "EPA" in g.kernel_name(g.ConvexPolyhedron(PA), g.ConvexPolyhedron(PA))
    flat = tilted = 0
    for trial in range(300):
        if trial % 3 == 0:  # flat: B's bottom face pressed into A's top face, 1-20 mm deep
            PB = _prism(0.15, 0.2, 30) + np.array([rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1),
                                                   0.3 - rng.uniform(0.001, 0.02)])
        else:
            PB = _prism(0.15, 0.2, 30) @ Rotation.random(random_state=rng).as_matrix().T + rng.normal(size=3) * 0.15
        r = g.distance(g.ConvexPolyhedron(PA), g.ConvexPolyhedron(PB))
        if r.distance >= 0.0:
            continue
        flat, tilted = flat + (trial % 3 == 0), tilted + (trial % 3 != 0)
        assert abs(-r.distance - _sat_depth(PA, PB)) <= 1e-9, trial
        assert _off_surface(PA, r.p_WA) <= 1e-9 and _off_surface(PB, r.p_WB) <= 1e-9, trial
        np.testing.assert_allclose(r.p_WB - r.p_WA, r.distance * r.nhat_AB_W, atol=1e-12)
    assert flat >= 90 and tilted >= 100


def test_an_edge_flat_on_a_face_keeps_its_witness_on_the_edge():
    """Rover, link 3's hull lying with an edge flat on the chassis box: the facet of the Minkowski difference is
    a polygon split into coplanar triangles, and EPA's closest one did not hold the origin's projection; its
    barycentric weights extrapolated the hull's witness 5.85 mm past the edge's end (coal and python-fcl: on the
    edge).  The triangle of that facet which holds the projection gives it."""
    import armguard
    from armguard.testing._surface import surface_residuals

    m = armguard.load_model("rover")
    q = np.array([2.759174136325586, -0.30901891641118473, -1.1436276588745256, 1.4535033759874043,
                  -2.3595853210018447])
    k = [tuple(p) for p in m.pairs.names].index(("arm_link3_0", "chassis_0"))
    r = armguard.checker(m, "analytic").pair_distances(q)
    ref = armguard.checker(m, "coal").pair_distances(q)
    assert r.distance[k] < -0.07 and abs(r.distance[k] - ref.distance[k]) < 1e-9
    for side, p in ((0, r.p_WA), (1, r.p_WB)):
        res, _, _ = surface_residuals(m, q, m.pairs.names[k:k + 1, side], p[k:k + 1])
        assert abs(res[0]) < 1e-9, (side, res)
    assert abs(np.linalg.norm(r.p_WA[k] - r.p_WB[k]) - abs(r.distance[k])) < 1e-12
