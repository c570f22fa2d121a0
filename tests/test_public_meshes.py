"""Dense meshes load in O(N log N) time and O(N) memory, and their hulls are Qhull's hulls of the raw vertices.

Before, the mesh-to-hull step ran a full SVD of the (N, 3) vertices (an N x N left factor):
example-robot-data's z1 (a 130 212-vertex mesh) and so101 died with ``MemoryError: Unable to
allocate 126 GiB``.  Here the memory a load allocates is measured (tracemalloc sees numpy's
arrays), and the hulls are compared with scipy's hull of every raw vertex (the slow reference).
"""

from __future__ import annotations

import sysconfig
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

import armguard
from armguard.model._hull import mesh_hull, unique_rows

ROBOTS = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share" / "example-robot-data" / "robots"


def _rows_in(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """For each row of ``a (n, 3)``: is it, bit for bit, a row of ``b (m, 3)``."""
    row = np.dtype((np.void, 24))
    return np.isin(np.ascontiguousarray(a, dtype=np.float64).view(row).ravel(),
                   np.ascontiguousarray(b, dtype=np.float64).view(row).ravel())


def _same_hull(hull_vertices: np.ndarray, raw: np.ndarray, seed: int = 0) -> None:
    """The hull of ``hull_vertices`` is scipy's hull of ``raw``: every hull vertex is a raw point,
    every vertex of scipy's hull is one of them, and the support functions agree along 500 directions."""
    from scipy.spatial import ConvexHull

    ref = raw[ConvexHull(raw).vertices]
    assert _rows_in(hull_vertices, raw).all()  # no point made up
    assert _rows_in(ref, hull_vertices).all()  # no extreme point lost
    d = np.random.default_rng(seed).normal(size=(500, 3))
    assert np.allclose((hull_vertices @ d.T).max(axis=0), (ref @ d.T).max(axis=0), rtol=0, atol=1e-12)


def _soup(n_inside: int, seed: int = 1):
    """A triangle soup: an icosphere (r = 0.1 m, 642 vertices) and random triangles inside it."""
    import trimesh

    rng = np.random.default_rng(seed)
    ball = trimesh.creation.icosphere(subdivisions=3, radius=0.1)
    inner = rng.uniform(-0.05, 0.05, size=(n_inside, 3))
    v = np.vstack([ball.vertices, inner])
    faces = np.vstack([ball.faces, len(ball.vertices) + rng.integers(0, n_inside, size=(n_inside // 3, 3))])
    return trimesh.Trimesh(v, faces, process=False), ball


def test_a_200k_vertex_mesh_loads_in_linear_memory(tmp_path, monkeypatch):
    import trimesh

    monkeypatch.setenv("ARMGUARD_HULL_CACHE", "0")  # the hull is computed in the measured load, not read

    mesh, ball = _soup(200_000)
    mesh.export(tmp_path / "dense.stl")  # STL repeats each vertex per triangle: ~200 k vertices in the file
    (tmp_path / "r.urdf").write_text(
        '<robot name="r"><link name="base"/><link name="l1"><collision><geometry><mesh filename="dense.stl"/>'
        '</geometry></collision></link><joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>'
        '<axis xyz="0 0 1"/><limit lower="-1" upper="1" velocity="1" effort="1"/></joint></robot>', encoding="utf-8")
    armguard.load_model(tmp_path / "r.urdf")  # imports and kernel caches, outside the measurement
    tracemalloc.start()
    try:
        model = armguard.load_model(tmp_path / "r.urdf")
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    # the vertices are 200 k x 24 B = 4.8 MB; an N x N factor would be 320 GB
    assert peak < 120e6, f"peak {peak / 1e6:.0f} MB"
    (poly,) = model.scene.robots["r"].link_shapes["l1"]
    raw = np.asarray(trimesh.load(tmp_path / "dense.stl", process=False).vertices, dtype=np.float64)
    assert len(raw) >= 199_998
    _same_hull(np.asarray(poly.vertices), raw)
    assert len(poly.vertices) == len(ball.vertices)  # the sphere's vertices: nothing inside is a corner


def test_a_million_points_hull_in_bounded_memory():
    rng = np.random.default_rng(2)
    p = rng.uniform(-0.5, 0.5, size=(1_000_000, 3))
    tracemalloc.start()
    try:
        hull = mesh_hull(p)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 400e6, f"peak {peak / 1e6:.0f} MB"  # the points: 24 MB
    assert not hull.flat and len(hull.triangles) > 0
    _same_hull(hull.vertices, p)


def test_unique_rows_drops_only_exact_repeats():
    rng = np.random.default_rng(3)
    base = rng.normal(size=(1000, 3))
    base[1] = np.nextafter(base[0], 1.0)  # one ulp apart: distinct
    rep = base[rng.integers(0, len(base), size=6000)]
    got = unique_rows(np.vstack([base, rep]))
    assert sorted(map(tuple, got.tolist())) == sorted(map(tuple, np.unique(base, axis=0).tolist()))


@pytest.mark.parametrize("points, flat", [(np.c_[np.random.default_rng(4).uniform(size=(500, 2)), np.full(500, 0.3)], True),
                                          (np.random.default_rng(5).uniform(size=(500, 3)), False)], ids=["coplanar", "solid"])
def test_mesh_hull_against_scipy(points, flat):
    from scipy.spatial import ConvexHull

    hull = mesh_hull(points)
    assert hull.flat is flat
    dims = slice(0, 2) if flat else slice(0, 3)
    ref = points[ConvexHull(points[:, dims]).vertices]
    assert sorted(map(tuple, hull.vertices.tolist())) == sorted(map(tuple, ref.tolist()))


def _mesh_objects(model):
    for go in model.collision_model.geometryObjects:
        if go.meshPath and Path(go.meshPath).is_file():
            yield go


@pytest.mark.skipif(not (ROBOTS / "z1_description").is_dir(), reason="example-robot-data is not installed")
@pytest.mark.parametrize("name, urdf, n_checked", [("z1", "z1_description/urdf/z1.urdf", None),
                                                   ("so101", "so_arm_description/urdf/so101.urdf", 3)])
def test_dense_public_robots_load_with_qhulls_hulls(name, urdf, n_checked):
    import trimesh

    model = armguard.load_model(ROBOTS / urdf)
    assert len(model.pairs) > 0
    meshes = sorted(_mesh_objects(model), key=lambda go: -Path(go.meshPath).stat().st_size)
    assert meshes
    for go in meshes[:n_checked]:  # so101: its three largest meshes (the reference takes seconds each)
        raw = np.asarray(trimesh.load(go.meshPath, force="mesh", process=False).vertices, dtype=np.float64) * go.meshScale
        _same_hull(np.asarray(go.geometry.points(), dtype=np.float64).reshape(-1, 3), raw)


# ---------------------------------------------------------------- coal's limit on a vertex's neighbours
def _ring(n: int, z: float = 0.0) -> np.ndarray:
    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return np.c_[np.cos(t), np.sin(t), np.full(n, z)]


@pytest.mark.parametrize("k", [3, 4, 5, 8, 301])
def test_strip_triangles_tile_the_polygon_in_its_order(k):
    from armguard.model._shapes import strip_triangles

    loop = np.random.default_rng(k).permutation(1000)[:k]
    tris = strip_triangles(loop)
    assert tris.shape == (k - 2, 3)
    pos = {v: i for i, v in enumerate(loop)}
    assert all(pos[a] < pos[b] < pos[c] for a, b, c in tris)  # the loop's order: the same orientation
    p = _ring(k)[[pos[v] for v in tris.ravel()]].reshape(-1, 3, 3)
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1).sum()
    assert area == pytest.approx(0.5 * k * np.sin(2 * np.pi / k), rel=1e-12)  # the regular k-gon's area
    e = {tuple(sorted(x)) for t in tris for x in ((t[0], t[1]), (t[1], t[2]), (t[0], t[2]))}
    assert max(np.bincount(np.array(list(e)).ravel() % 1000)) <= 4  # two sides and at most two diagonals


@pytest.mark.parametrize("shape", ["prism", "polygon"])
def test_a_face_of_300_vertices_makes_a_coal_convex_with_the_same_support(shape):
    """Qhull fans such a face out from one vertex (299 edges there): coal refuses more than 254, so
    its copy is cut in strips; the support function along any direction is the points' own."""
    from armguard.model._hull import mesh_polytope
    from armguard.model._shapes import convex_hull, convex_of_polytope

    pts = np.vstack([_ring(300), _ring(300, 0.5)]) if shape == "prism" else _ring(300)
    for conv in (convex_of_polytope(mesh_polytope(pts)), convex_hull(pts)):
        v = np.asarray(conv.points(), dtype=np.float64).reshape(-1, 3)
        d = np.random.default_rng(1).normal(size=(200, 3))
        assert np.allclose((v @ d.T).max(axis=0), (pts @ d.T).max(axis=0), atol=1e-12)
        import coal

        req, res = coal.DistanceRequest(), coal.DistanceResult()
        X = coal.Transform3s(np.eye(3), np.array([3.0, 0.0, 0.25]))
        coal.distance(conv, coal.Transform3s(), coal.Sphere(0.5), X, req, res)
        # the nearest point: the rim's vertex at (1, 0, z), z = 0.25 on the prism's side, 0 on the polygon
        assert res.min_distance == pytest.approx(2.0 - 0.5 if shape == "prism" else np.hypot(2.0, 0.25) - 0.5, abs=1e-6)


def test_a_cone_apex_with_300_edges_is_an_error_naming_the_limit():
    from armguard import GeometryError
    from armguard.model._hull import mesh_polytope
    from armguard.model._shapes import convex_of_polytope

    with pytest.raises(GeometryError, match="a vertex of the hull has 300 edges; coal's Convex holds at most 254"):
        convex_of_polytope(mesh_polytope(np.vstack([_ring(300), [[0.0, 0.0, 1.0]]])))
