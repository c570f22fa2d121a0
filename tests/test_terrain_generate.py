"""armguard.terrain.generate: the documented terrain generator, its stereo-like point clouds, and
the terrains shipped in reference/terrain/ (regenerated here from their recorded calls)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from armguard.terrain import ElevationMap, OutlierRule, TerrainPyramid, TerrainStatus
from armguard.terrain.generate import (
    REFERENCE,
    fractal_heights,
    look_at,
    make_terrain,
    reference_terrain,
    stereo_points,
)

REF = Path(__file__).resolve().parent.parent / "reference" / "terrain"


def test_fractal_heights_are_seeded_scaled_and_rougher_with_lower_beta():
    a, b = fractal_heights(64, sigma=0.05, seed=1), fractal_heights(64, sigma=0.05, seed=1)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, fractal_heights(64, sigma=0.05, seed=2))
    assert a.std() == pytest.approx(0.05) and abs(a.mean()) < 1e-12
    smooth, rough = fractal_heights(64, beta=3.0, seed=3), fractal_heights(64, beta=1.5, seed=3)
    step = lambda h: np.abs(np.diff(h, axis=1)).mean()  # noqa: E731
    assert step(rough) > 2 * step(smooth)


def test_noise_free_render_lies_on_the_surface_and_rocks_cast_shadows():
    m = make_terrain(n=64, cell=0.05, seed=0, rocks=8)
    X = look_at([1.6, -0.8, 1.5], [1.6, 1.6, 0.0])
    pts, depth, _ = stereo_points(m, X, sigma_1m=0.0, min_grazing=0.0, outliers=0.0, seed=0)
    from armguard.terrain.generate import _surface

    assert np.abs(pts[:, 2] - _surface(m, pts[:, 0], pts[:, 1])).max() < 0.01  # bisection to 1/128 of a step
    bare = make_terrain(n=64, cell=0.05, seed=0, rocks=0)  # the same ground without its rocks
    bare_pts, _, _ = stereo_points(bare, X, sigma_1m=0.0, min_grazing=0.0, outliers=0.0, seed=0)
    seen = ElevationMap.from_points(pts, 0.05, bounds=(0, 0, 3.2, 3.2), rule=OutlierRule(k=np.inf, spike=np.inf))
    seen_bare = ElevationMap.from_points(bare_pts, 0.05, bounds=(0, 0, 3.2, 3.2), rule=OutlierRule(k=np.inf, spike=np.inf))
    shadow = seen_bare.known & ~seen.known & (m.heights <= bare.heights)  # ground visible without rocks, hidden with
    assert shadow.sum() >= 10

def test_stereo_noise_grows_with_range_and_holes_appear():
    m = make_terrain(n=64, cell=0.05, seed=1, rocks=4)
    X = look_at([1.6, -0.8, 1.5], [1.6, 1.6, 0.0])
    clean, _, K = stereo_points(m, X, sigma_1m=0.0, min_grazing=0.0, outliers=0.0, seed=5)
    noisy, d, _ = stereo_points(m, X, sigma_1m=0.01, min_grazing=0.0, outliers=0.0, seed=5)
    assert len(clean) == len(noisy)
    rng_ = np.linalg.norm(clean - X[:3, 3], axis=1)
    err = np.linalg.norm(noisy - clean, axis=1)
    near, far = rng_ < np.median(rng_), rng_ >= np.median(rng_)
    assert err[far].mean() > 1.5 * err[near].mean()
    grazing, _, _ = stereo_points(m, X, min_grazing=0.3, outliers=0.0, seed=5)
    assert len(grazing) < len(clean)
    with_out, _, _ = stereo_points(m, X, sigma_1m=0.0, min_grazing=0.0, outliers=0.01, seed=5)
    moved = np.linalg.norm(with_out - clean, axis=1) > 1e-9
    assert moved.sum() == round(0.01 * len(clean))


@pytest.mark.parametrize("name", sorted(REFERENCE))
def test_shipped_terrain_regenerates(name):
    with np.load(REF / f"{name}.npz") as z:
        shipped = {k: z[k] for k in z.files}
    r = reference_terrain(name)
    assert float(shipped["cell"]) == r["cell"]
    np.testing.assert_allclose(shipped["heights"], r["heights"], rtol=0, atol=1e-6)
    np.testing.assert_allclose(shipped["X_WC"], r["X_WC"], rtol=0, atol=1e-12)
    assert shipped["points_W"].shape == r["points_W"].shape
    np.testing.assert_allclose(shipped["points_W"], r["points_W"], rtol=0, atol=1e-5)


def test_shipped_terrain_end_to_end():
    """Stereo points -> map -> pyramid: a box resting on the true surface hits the sensed terrain."""
    with np.load(REF / "rocky.npz") as z:
        pts, truth = z["points_W"].astype(np.float64), z["heights"].astype(np.float64)
    m = ElevationMap.from_points(pts, 0.05, bounds=(0, 0, 3.2, 3.2))
    err = (m.heights - truth)[m.known]
    assert np.median(np.abs(err)) < 0.03
    pyr = TerrainPyramid(m)
    r, c = np.argwhere(m.known)[len(np.argwhere(m.known)) // 2]
    x, y = m.origin + (np.array([c, r]) + 0.5) * m.cell
    from armguard.geometry import Box

    assert pyr.check([Box([x, y, m.heights[r, c]], [0.02, 0.02, 0.02])]).status is TerrainStatus.HIT
    assert pyr.check([Box([x, y, m.heights.max() + 0.1], [0.02, 0.02, 0.02])]).status is TerrainStatus.CLEAR
