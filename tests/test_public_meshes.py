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
