"""The fast planar-face merge gives exactly the faces of the plain-Python reference.

``armguard.geometry._hull_faces`` replaced a scalar flood over Python lists (3.5 s of so101's
load, ``tests/_hull_faces_reference.py``) by a compiled flood and one sort for the face loops.
Both take the same Qhull hull, so the vertex set, every face loop, every plane and the oriented
triangles must be equal, bit for bit: on random clouds, on solids with large planar faces (boxes,
prisms), on surfaces whose triangles are coplanar only to within the merge tolerance (where the
seed order decides which face a triangle joins), and on real mesh hulls.
"""

from __future__ import annotations

import sysconfig
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from armguard._tolerance import DEFAULT_TOLERANCES
from armguard.geometry import ConvexPolyhedron, Prism
from armguard.geometry._hull_faces import merge_hull_faces

from _hull_faces_reference import merge_hull_faces_reference

ROBOTS = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share" / "example-robot-data" / "robots"
TOL = DEFAULT_TOLERANCES.planarity


def _assert_same(points: np.ndarray) -> tuple:
    used, faces, planes, tri = merge_hull_faces(points, TOL)
    r_used, r_faces, r_planes, r_tri = merge_hull_faces_reference(points, TOL)
    np.testing.assert_array_equal(used, r_used)
    assert len(faces) == len(r_faces)
    for f, rf in zip(faces, r_faces):
        np.testing.assert_array_equal(f, rf)
    np.testing.assert_array_equal(planes, r_planes)
    np.testing.assert_array_equal(tri, r_tri)
    return used, faces, planes, tri


def _cube_surface(n: int, noise: float, seed: int) -> np.ndarray:
    """``n`` points on each face of a 0.2 m cube, moved off their face by up to ``noise`` m."""
    rng = np.random.default_rng(seed)
    pts = []
    for axis in range(3):
        for side in (-0.1, 0.1):
            p = rng.uniform(-0.1, 0.1, size=(n, 3))
            p[:, axis] = side + rng.uniform(-noise, noise, size=n)
            pts.append(p)
    return np.vstack(pts + [np.array([[sx, sy, sz] for sx in (-.1, .1) for sy in (-.1, .1) for sz in (-.1, .1)])])


def test_a_box_merges_into_six_squares():
    used, faces, planes, tri = _assert_same(_cube_surface(0, 0.0, 0))
    assert len(faces) == 6 and all(len(f) == 4 for f in faces)
    assert len(used) == 8 and len(tri) == 12


def test_a_prism_merges_its_sides_and_caps():
    prism = Prism([0.3, -0.2, 1.0], np.eye(3), 0.05, 0.2, 12)
    _, faces, _, _ = _assert_same(np.asarray(prism.core_points))
    assert sorted(map(len, faces)) == [4] * 12 + [12, 12]


@pytest.mark.parametrize("noise", [0.0, 1e-13, 3e-10, 1e-9, 3e-9])
def test_nearly_coplanar_faces_merge_as_the_reference_does(noise):
    # noise near the tolerance: which triangles join a face depends on the seed and its plane
    used, faces, _, _ = _assert_same(_cube_surface(40, noise, 3))
    assert len(faces) >= 6


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(4, 300), far=st.sampled_from([0.0, 1.0, 100.0]))
def test_random_clouds_merge_as_the_reference_does(seed, n, far):
    rng = np.random.default_rng(seed)
    p = rng.normal(size=(n, 3)) * rng.uniform(0.01, 1.0, size=3) + far
    if n >= 10:  # some points rounded to a grid: exactly coplanar hull triangles
        p[: n // 2] = np.round(p[: n // 2] * 20) / 20
    try:
        merge_hull_faces_reference(p, TOL)
    except Exception as exc:  # noqa: BLE001 - a flat cloud: both refuse it the same way
        with pytest.raises(type(exc)):
            merge_hull_faces(p, TOL)
        return
    _assert_same(p)


@pytest.mark.parametrize("mesh", ["ur_description/meshes/ur5/collision/forearm.stl",
                                  "so_arm_description/meshes/so101/sts3215_03a_v1.stl"])
def test_real_mesh_hulls_merge_as_the_reference_does(mesh):
    import trimesh

    path = ROBOTS / mesh
    if not path.is_file():
        pytest.skip(f"example-robot-data has no {mesh}")
    v = np.asarray(trimesh.load(str(path), force="mesh", process=False).vertices, dtype=np.float64)
    from scipy.spatial import ConvexHull

    hv = v[ConvexHull(v).vertices]
    _, faces, planes, _ = _assert_same(hv)
    poly = ConvexPolyhedron(hv)
    # a closed polyhedron: every edge is on exactly two faces, and every vertex is inside every plane
    a = np.concatenate(poly.faces)
    b = np.concatenate([np.roll(f, -1) for f in poly.faces])
    assert len(set(zip(a.tolist(), b.tolist()))) == len(a) == 2 * len(poly.edges)
    assert (poly.vertices @ poly.planes[:, :3].T - poly.planes[:, 3]).max() <= 1e-9
