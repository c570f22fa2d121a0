"""Geometry inputs at their edges (a review's findings, each reproduced before the fix against an exact or
closed-form reference): a rotation within the tolerance but scaled, batch inputs beyond the magnitude the
scalar API refuses, a flat polygon far from the origin, a segment across a polygon in its plane."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from armguard import GeometryError
from armguard.geometry import Box, Capsule, Polygon, Sphere, batch, distance


def test_a_rotation_scaled_within_the_tolerance_is_one_shape_to_every_kernel():
    """``Box(0, [1, 1, 1], (1 + 4e-6) I)`` passed the check (numpy's default rtol) and was 1.000008 from a point at
    x = 2 to the box kernel, 0.999996 to the polytope one.  It is now the nearest rotation, I."""
    b = Box([0.0, 0.0, 0.0], [1.0, 1.0, 1.0], (1.0 + 4e-6) * np.eye(3))
    np.testing.assert_array_equal(b.rotation, np.eye(3))
    p = Sphere([2.0, 0.0, 0.0], 0.0)
    assert distance(p, b).distance == pytest.approx(1.0, abs=1e-15)
    assert distance(p, b.as_polyhedron()).distance == pytest.approx(1.0, abs=1e-15)
    R = Rotation.from_euler("xyz", [0.3, -0.2, 0.9]).as_matrix()
    np.testing.assert_array_equal(Box([0, 0, 0], [1, 1, 1], R).rotation, R)  # a rotation to rounding: kept as given
    with pytest.raises(GeometryError, match="not a proper rotation"):
        Box([0, 0, 0], [1, 1, 1], (1.0 + 1e-4) * np.eye(3))


@pytest.mark.parametrize("call", [
    lambda: batch.capsule_capsule([-1e160, 0, 0], [1e160, 0, 0], 0.1, [0, -1e160, 0.05], [0, 1e160, 0.05], 0.1),
    lambda: batch.sphere_sphere([1e160, 0, 0], 0.1, [-1e160, 0, 0], 0.1),
    lambda: batch.capsule_box([0, 0, 0], [1, 0, 0], 0.1, [1e200, 0, 0], [1, 1, 1], np.eye(3)),
    lambda: batch.capsule_convex([1e200, 0, 0], [1e200, 0, 0], 0.1, Box([3, 0, 0], [1, 1, 1])),
])
def test_batch_inputs_beyond_the_scalar_bound_are_refused(call):
    """The batch functions answered -0.2 (for -0.15), inf, or a zero normal at 1e160-1e200 m, which the scalar
    constructors refuse (Tolerances.max_magnitude, 1e9 m)."""
    with pytest.raises(GeometryError, match="max_magnitude"):
        call()


def test_batch_inputs_within_the_bound_still_answer():
    r = batch.capsule_capsule([0, 0, 0], [1, 0, 0], 0.1, [0, 1, 0], [1, 1, 0], 0.1)
    assert float(r.distance) == pytest.approx(0.8, abs=1e-15)
    r = batch.sphere_sphere([5e8, 0, 0], 0.5, [-5e8, 0, 0], 0.5)
    assert float(r.distance) == pytest.approx(1e9 - 1.0, rel=1e-15)


@pytest.mark.parametrize("T", [1e6, 1e7, 1e8])
def test_a_flat_polygon_far_from_the_origin_stays_planar(T):
    """A tilted 0.5 m square moved to 1e7 m was refused as "not planar": its coordinates' rounding there (9e-10 m)
    is the size of the planarity tolerance."""
    R = Rotation.from_euler("xyz", [0.3, -0.5, 0.7]).as_matrix()
    sq = np.array([[0, 0, 0], [0.5, 0, 0], [0.5, 0.5, 0], [0, 0.5, 0.0]]) @ R.T
    X = np.eye(4)
    X[:3, 3] = [T, -0.7 * T, 0.3 * T]
    moved = Polygon(sq).transformed(X)
    assert np.abs(moved.vertices - (sq + X[:3, 3])).max() <= 4 * np.spacing(T)
    with pytest.raises(GeometryError, match="not planar"):  # still refused when it is not flat
        Polygon(sq + [[0, 0, 0], [0, 0, 0], [0, 0, 0], 1e-3 * R[:, 2]])


@pytest.mark.parametrize("r", [0.0, 0.05])
def test_a_segment_across_a_polygon_in_its_plane_has_witnesses_on_both(r):
    """A capsule lying in a triangle's plane and crossing it: the distances (-r) were right, the polygon's
    witness was the segment's end, 1 m off the triangle."""
    tri = Polygon(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.0]]))
    cap = Capsule([0.2, -1, 0], [0.2, 1, 0], r)
    for a, b in ((cap, tri), (tri, cap)):
        pr = distance(a, b)
        assert pr.distance == pytest.approx(-r, abs=1e-12)
        on_tri = pr.p_WB if b is tri else pr.p_WA
        assert abs(on_tri[2]) <= 1e-12 and on_tri[0] >= -1e-12 and on_tri[1] >= -1e-12 and on_tri[0] + on_tri[1] <= 1 + 1e-12
        np.testing.assert_allclose(pr.p_WB - pr.p_WA, pr.distance * pr.nhat_AB_W, atol=1e-12)
