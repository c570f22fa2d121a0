"""The box's closed-form feature_at agrees with the generic polytope path (vertex / edge / face search)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from armguard import GeometryError
from armguard.geometry import Box, feature_at
from armguard.geometry._feature import Feature, FeatureKind, _point_segments, _polytope_parts


def _generic(box: Box, p: np.ndarray, eps: float = 1e-7) -> Feature:
    """The slow reference: nearest vertex, else nearest edge, else the face plane the point is on."""
    v, edges, planes = _polytope_parts(box)
    dv = np.linalg.norm(v - p, axis=1)
    if dv.min() <= eps:
        return Feature(FeatureKind.VERTEX, int(np.argmin(dv)))
    de = _point_segments(p, v[edges[:, 0]], v[edges[:, 1]])
    if de.min() <= eps:
        return Feature(FeatureKind.EDGE, int(np.argmin(de)))
    s = planes[:, :3] @ p - planes[:, 3]
    return Feature(FeatureKind.FACE, int(np.argmax(s)))


@pytest.mark.parametrize("on_planes", [1, 2, 3], ids=["face", "edge", "vertex"])
def test_box_feature_closed_form_matches_generic(on_planes):
    rng = np.random.default_rng(on_planes)
    seen = set()
    for k in range(400):
        box = Box(rng.normal(size=3), rng.uniform(0.1, 1.0, 3), Rotation.random(random_state=k).as_matrix())
        local = rng.uniform(-0.9, 0.9, 3) * box.half_extents
        for a in rng.choice(3, on_planes, replace=False):
            local[a] = np.sign(rng.normal()) * box.half_extents[a]
        p = box.center + box.rotation @ local
        got = feature_at(box, p)
        assert got == _generic(box, p)
        seen.add(got.index)
    expected = {1: FeatureKind.FACE, 2: FeatureKind.EDGE, 3: FeatureKind.VERTEX}[on_planes]
    assert got.kind is expected
    assert len(seen) == {1: 6, 2: 12, 3: 8}[on_planes]  # every face / edge / vertex was hit


def test_box_feature_rejects_points_off_the_surface():
    box = Box([0, 0, 0], [1, 1, 1])
    with pytest.raises(GeometryError):
        feature_at(box, [0.5, 0.5, 0.5])  # inside
    with pytest.raises(GeometryError):
        feature_at(box, [1.1, 0.0, 0.0])  # outside
