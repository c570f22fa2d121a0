"""armguard.terrain: the elevation map from points, the point readers, the OBB pyramid and its
coarse-to-fine check against the brute-force flat reference (the JPL brief, seed 002)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from armguard import TerrainError
from armguard.geometry import Box, Capsule, Prism, distance
from armguard.terrain import (
    ElevationMap,
    OutlierRule,
    TerrainPyramid,
    TerrainStatus,
    bounding_box,
    depth_to_points,
    read_points,
    write_points,
)
from armguard.terrain.generate import make_terrain

# ------------------------------------------------------------------------------- elevation map


def _grid_points(rng, heights, cell, per_cell=8, noise=0.002):
    """``per_cell`` points in every cell of ``heights`` with small height noise (below the top)."""
    ny, nx = heights.shape
    iy, ix = np.indices(heights.shape)
    iy, ix = np.repeat(iy.ravel(), per_cell), np.repeat(ix.ravel(), per_cell)
    x = (ix + rng.random(len(ix))) * cell
    y = (iy + rng.random(len(iy))) * cell
    z = heights[iy, ix] - np.abs(rng.normal(0, noise, len(ix)))
    return np.stack([x, y, z], axis=1)


def test_from_points_is_the_per_cell_max():
    rng = np.random.default_rng(1)
    h = rng.uniform(0, 0.2, (6, 9))
    pts = _grid_points(rng, h, 0.1)
    m = ElevationMap.from_points(pts, 0.1, bounds=(0, 0, 0.9, 0.6), rule=OutlierRule(k=np.inf, spike=np.inf))
    assert m.shape == (6, 9) and m.known.all() and m.rejected == 0
    row, col = m.cell_of(pts)
    expect = np.full((6, 9), -np.inf)
    np.maximum.at(expect, (row, col), pts[:, 2])
    np.testing.assert_array_equal(m.heights, expect)
    assert np.all(m.heights <= h) and np.all(m.heights > h - 0.01)


def test_outlier_rule_drops_stray_points_and_unsupported_spikes_but_keeps_a_rock():
    rng = np.random.default_rng(2)
    h = np.zeros((10, 10))
    h[6:9, 6:9] = 0.3  # a rock over 3 x 3 cells, well supported
    pts = _grid_points(rng, h, 0.1)
    in_cell = lambda r, c: (pts[:, 0] > c * 0.1) & (pts[:, 0] < c * 0.1 + 0.1) & (pts[:, 1] > r * 0.1) & (pts[:, 1] < r * 0.1 + 0.1)  # noqa: E731
    sparse = in_cell(1, 7) | in_cell(4, 2)
    two = pts[in_cell(4, 2)][:2]  # cell (4, 2): two ground points and a mismatch
    stray = [0.25, 0.25, 0.9]  # a bad match inside a dense flat cell (2, 2): stage 1
    lone = [0.75, 0.15, 0.8]  # the only point of cell (1, 7): stage 2
    mismatch = [0.25, 0.45, 0.7]  # stage 2 drops it, cell (4, 2) keeps its ground points
    cloud = np.vstack([pts[~sparse], two, [stray, lone, mismatch]])
    m = ElevationMap.from_points(cloud, 0.1, bounds=(0, 0, 1, 1))
    assert m.heights[2, 2] < 0.01  # the stray point is gone
    assert not m.known[1, 7] and m.heights[1, 7] < 0.01  # the spike cleared, then filled from its neighbours
    assert m.known[4, 2] and m.counts[4, 2] == 2 and m.heights[4, 2] < 0.01
    assert m.rejected == 3
    assert m.known[6:9, 6:9].all() and np.all(m.heights[6:9, 6:9] > 0.29)  # the rock survives
    off = ElevationMap.from_points(cloud, 0.1, bounds=(0, 0, 1, 1), rule=OutlierRule(k=np.inf, spike=np.inf))
    assert off.heights[2, 2] == pytest.approx(0.9) and off.heights[1, 7] == pytest.approx(0.8)
    assert off.rejected == 0
    far = ElevationMap.from_points(np.vstack([cloud, [[5.05, 5.05, 3.0]]]), 0.1, bounds=(0, 0, 6, 6))
    assert not far.known[50, 50] and far.rejected == 4  # nothing around it: unsupported


def test_unknown_cells_are_filled_conservatively_and_reported():
    rng = np.random.default_rng(3)
    h = rng.uniform(0, 0.1, (8, 8))
    h[3, 4] = 0.5
    pts = _grid_points(rng, h, 0.1)
    hole = (pts[:, 0] > 0.2) & (pts[:, 0] < 0.4) & (pts[:, 1] > 0.2) & (pts[:, 1] < 0.4)  # cells (2..3, 2..3)
    far = (pts[:, 0] < 0.1) & (pts[:, 1] > 0.7)  # cell (7, 0)
    m = ElevationMap.from_points(pts[~hole & ~far], 0.1, bounds=(0, 0, 0.8, 0.8), fill_radius=1)
    filled = np.argwhere(m.filled)
    assert sorted(map(tuple, filled)) == [(2, 2), (2, 3), (3, 2), (3, 3), (7, 0)]
    for r, c in filled:  # each fill is the highest known cell within one cell
        win = np.where(m.known, m.heights, -np.inf)[max(r - 1, 0):r + 2, max(c - 1, 0):c + 2]
        assert m.heights[r, c] == win.max()
    assert m.heights[3, 3] >= 0.49  # next to the tall cell: filled with it, never lower
    ceil = ElevationMap.from_points(pts[~hole], 0.1, bounds=(0, 0, 0.8, 0.8), fill="ceiling", ceiling=2.0)
    assert np.all(ceil.heights[ceil.filled] == 2.0) and ceil.filled.sum() == 4
    lone = ElevationMap.from_points(pts[~hole], 0.1, bounds=(0, 0, 0.8, 0.8), fill_radius=0)
    assert np.all(lone.heights[lone.filled] == lone.heights[lone.known].max())  # default ceiling


def test_from_points_rejects_bad_input_and_counts_non_finite_rows():
    with pytest.raises(TerrainError):
        ElevationMap.from_points(np.zeros((3, 2)), 0.1)
    with pytest.raises(TerrainError):
        ElevationMap.from_points(np.zeros((3, 3)), 0.0)
    with pytest.raises(TerrainError):
        ElevationMap.from_points(np.full((3, 3), np.nan), 0.1)
    p = np.array([[0.05, 0.05, 0.1], [np.nan, 0, 0], [0.15, 0.05, 0.2]])
    m = ElevationMap.from_points(p, 0.1, bounds=(0, 0, 0.2, 0.1), rule=OutlierRule(spike=np.inf))
    assert m.invalid == 1 and m.known.all() and m.heights.tolist() == [[0.1, 0.2]]


# ------------------------------------------------------------------------------- point readers


@pytest.mark.parametrize("ext", [".ply", ".pcd", ".npy", ".npz"])
def test_point_files_round_trip(tmp_path, ext):
    p = np.random.default_rng(4).uniform(-2, 2, (50, 3)).astype(np.float32).astype(np.float64)
    got = read_points(write_points(tmp_path / f"cloud{ext}", p))
    np.testing.assert_allclose(got, p, rtol=0, atol=1e-6)
    X = np.eye(4)
    X[:3, 3] = [1, 2, 3]
    np.testing.assert_allclose(read_points(tmp_path / f"cloud{ext}", X_WS=X), p + [1, 2, 3], atol=1e-6)


@pytest.mark.parametrize("ext", [".ply", ".pcd", ".npy", ".npz"])
def test_point_files_are_written_whole_or_not_at_all(tmp_path, monkeypatch, ext):
    """A full disk left a truncated file (and a raw OSError); a missing folder was a FileNotFoundError:
    now an OutputError naming the file, and the previous file as it was."""
    from armguard._errors import OutputError

    old = write_points(tmp_path / f"c{ext}", np.zeros((4, 3)))
    before = old.read_bytes()
    import armguard._io as io

    def full(path, blob):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(io, "_write_file", full)
    with pytest.raises(OutputError, match=f"cannot write .*c\\{ext}: No space left on device"):
        write_points(old, np.ones((2000, 3)))
    assert old.read_bytes() == before
    monkeypatch.undo()
    with pytest.raises(OutputError, match="the folder .*nodir does not exist"):
        write_points(tmp_path / "nodir" / f"x{ext}", np.zeros((2, 3)))


def test_reads_a_hand_written_ascii_pcd_and_names_bad_files(tmp_path):
    f = tmp_path / "scan.pcd"
    f.write_text("# .PCD v0.7\nVERSION 0.7\nFIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n"
                 "WIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n1.5 -2 0.25 7\n0 0 1 3\n")
    np.testing.assert_allclose(read_points(f), [[1.5, -2, 0.25], [0, 0, 1]])
    bad = tmp_path / "bad.pcd"
    bad.write_text("not a pcd\n")
    with pytest.raises(TerrainError, match="bad.pcd"):
        read_points(bad)
    with pytest.raises(TerrainError, match="unsupported"):
        read_points(write_points(tmp_path / "c.npy", np.zeros((2, 3))).rename(tmp_path / "c.xyz"))


def test_depth_image_pinhole_back_projection():
    depth = np.full((4, 6), np.nan)
    depth[1, 4] = 2.0
    depth[3, 0] = 0.5
    X = np.eye(4)
    X[:3, :3] = Rotation.from_euler("x", 90, degrees=True).as_matrix()
    X[:3, 3] = [0.0, 0.0, 1.0]
    p = depth_to_points(depth, 100.0, 50.0, 2.5, 1.5, X)
    pc = np.array([[(4 - 2.5) * 2.0 / 100.0, (1 - 1.5) * 2.0 / 50.0, 2.0], [(0 - 2.5) * 0.5 / 100.0, (3 - 1.5) * 0.5 / 50.0, 0.5]])
    np.testing.assert_allclose(p, pc @ X[:3, :3].T + X[:3, 3])
    assert len(depth_to_points(depth, 100.0, 50.0, 2.5, 1.5, max_range=1.0)) == 1


# ------------------------------------------------------------------------------- pyramid


def test_pyramid_levels_halve_and_enclose():
    m = make_terrain(n=40, cell=0.05, seed=3)
    pyr = TerrainPyramid(m)
    assert pyr.levels[0].boxes.shape == (1, 6) and (pyr.levels[-1].ny, pyr.levels[-1].nx) == (40, 40)
    assert [lv.nx for lv in pyr.levels] == [1, 2, 3, 5, 10, 20, 40]
    for up, lv in zip(pyr.levels[:-1], pyr.levels[1:]):
        assert up.block == 2 * lv.block
        for i in range(lv.ny * lv.nx):  # each box inside its parent
            r, c = divmod(i, lv.nx)
            parent = up.boxes[(r // 2) * up.nx + c // 2]
            b = lv.boxes[i]
            assert np.all(b[:3] - b[3:] >= parent[:3] - parent[3:]) and np.all(b[:3] + b[3:] <= parent[:3] + parent[3:])
    fine = pyr.levels[-1].boxes
    np.testing.assert_allclose(fine[:, 2] + fine[:, 5], m.heights.ravel())  # tight on the heights
    np.testing.assert_allclose(fine[:, 2] - fine[:, 5], m.floor)
    top = pyr.levels[0].boxes[0]
    assert top[2] + top[5] == pytest.approx(m.heights.max(), abs=1e-8)


def _random_volumes(rng, m, k):
    """``k`` link volumes (boxes and octagonal prisms) of 2-15 cm near the terrain's surface."""
    ny, nx = m.shape
    out = []
    for _ in range(k):
        x, y = m.origin + rng.uniform([0, 0], [nx * m.cell, ny * m.cell])
        r, c = m.cell_of([[x, y]])
        z = m.heights[r[0], c[0]] + rng.uniform(-0.05, 0.2)
        R = Rotation.random(random_state=rng.integers(2**31)).as_matrix()
        if rng.random() < 0.5:
            out.append(Box([x, y, z], rng.uniform(0.02, 0.15, 3), R))
        else:
            out.append(Prism([x, y, z], R, rng.uniform(0.02, 0.08), rng.uniform(0.03, 0.15), 8))
    return out


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**31 - 1), n=st.integers(1, 70), k=st.integers(1, 6),
       clearance=st.sampled_from([0.0, 0.01, 0.05]))
def test_coarse_to_fine_equals_flat(seed, n, k, clearance):
    rng = np.random.default_rng(seed)
    m = make_terrain(n=max(n, 2), cell=0.05, seed=seed % 1000, rocks=int(rng.integers(0, 8)))
    if n == 1:
        m = ElevationMap.from_heights(m.heights[:1, :1], 0.05)
    pyr = TerrainPyramid(m)
    vols = _random_volumes(rng, m, k)
    c2f, flat = pyr.check(vols, clearance=clearance), pyr.check_flat(vols, clearance=clearance)
    assert c2f.status == flat.status
    assert sorted(map(tuple, c2f.cells_hit)) == sorted(map(tuple, flat.cells_hit))
    np.testing.assert_array_equal(c2f.links_hit, flat.links_hit)
    assert c2f.tests == int(c2f.tests_per_level.sum())
    one = pyr.check(vols, clearance=clearance, first=True)
    assert one.status == flat.status and len(one.cells_hit) == (1 if flat.status is TerrainStatus.HIT else 0)


def test_many_links_are_checked_in_chunks():
    rng = np.random.default_rng(8)
    m = make_terrain(n=32, cell=0.05, seed=8)
    pyr = TerrainPyramid(m)
    vols = _random_volumes(rng, m, 70)  # more than one 63-link mask
    c2f, flat = pyr.check(vols), pyr.check_flat(vols)
    assert sorted(map(tuple, c2f.cells_hit)) == sorted(map(tuple, flat.cells_hit))
    np.testing.assert_array_equal(c2f.links_hit, flat.links_hit)
    assert 0 < c2f.links_hit.sum() < 70


def _reach(rng, m, k=5):
    """An arm's reach: ``k`` octagonal-prism links of 12 cm chained from a random base above the
    terrain, heading down towards it."""
    ny, nx = m.shape
    p = m.origin + rng.uniform(0.2, 0.8, 2) * [nx * m.cell, ny * m.cell]
    p = np.r_[p, m.heights.max() + rng.uniform(0.0, 0.15)]
    out = []
    for _ in range(k):
        d = rng.normal(size=3)
        d[2] = -abs(d[2])
        d *= 0.12 / np.linalg.norm(d)
        z = d / 0.12
        a = np.cross(z, [1.0, 0, 0]) if abs(z[0]) < 0.9 else np.cross(z, [0, 1.0, 0])
        a /= np.linalg.norm(a)
        out.append(Prism(p + d / 2, np.stack([a, np.cross(z, a), z], axis=1), 0.03, 0.06, 8))
        p = p + d
    return out


def test_pyramid_tests_ten_times_fewer_boxes_on_a_small_reach():
    m = make_terrain(n=128, cell=0.05, seed=4, rocks=8)
    pyr = TerrainPyramid(m)
    rng = np.random.default_rng(4)
    ratios, hits = [], 0
    for _ in range(20):
        vols = _reach(rng, m)
        c2f, flat = pyr.check(vols), pyr.check_flat(vols)
        assert c2f.status == flat.status
        hits += c2f.status is TerrainStatus.HIT
        ratios.append(flat.boxes_tested / c2f.boxes_tested)
    assert 0 < hits < 20  # a mix of hits and clears
    assert min(ratios) >= 10.0, ratios


def test_a_link_above_everything_is_decided_at_the_top():
    m = make_terrain(n=64, cell=0.05, seed=5)
    pyr = TerrainPyramid(m)
    r = pyr.check([Box([1.6, 1.6, m.heights.max() + 0.3], [0.1, 0.1, 0.1])])
    assert r.status is TerrainStatus.CLEAR and r.level == 0 and r.boxes_tested == 1


def test_exact_mode_matches_brute_force_distances():
    m = make_terrain(n=16, cell=0.05, seed=6, rocks=3)
    pyr = TerrainPyramid(m)
    rng = np.random.default_rng(6)
    ny, nx = m.shape
    cols = [pyr.cell_box(r, c) for r in range(ny) for c in range(nx)]
    seen = set()
    for _ in range(25):
        x, y = rng.uniform(0.1, 0.7, 2)
        z = m.heights.max() + rng.uniform(-0.15, 0.1)
        d = rng.normal(size=3)
        d *= 0.08 / np.linalg.norm(d)
        cap = Capsule([x, y, z] - d, [x, y, z] + d, 0.015)
        clearance = 0.02
        r = pyr.check([bounding_box(cap)], shapes=[cap], exact=True, clearance=clearance)
        brute = min(distance(cap, b).distance for b in cols)
        if brute <= clearance:
            assert r.status is TerrainStatus.HIT and r.min_distance == pytest.approx(brute, abs=1e-9)
            assert r.level == pyr.n_levels - 1
        else:
            assert r.status is TerrainStatus.CLEAR and r.min_distance > clearance
        seen.add(r.status)
    assert seen == {TerrainStatus.HIT, TerrainStatus.CLEAR}


def test_a_hit_on_a_filled_cell_is_flagged():
    pts = _grid_points(np.random.default_rng(7), np.zeros((6, 6)), 0.1)
    keep = ~((pts[:, 0] > 0.2) & (pts[:, 0] < 0.3) & (pts[:, 1] > 0.2) & (pts[:, 1] < 0.3))
    m = ElevationMap.from_points(pts[keep], 0.1, bounds=(0, 0, 0.6, 0.6), fill="ceiling", ceiling=0.5)
    pyr = TerrainPyramid(m)
    r = pyr.check([Box([0.25, 0.25, 0.3], [0.03, 0.03, 0.03])])
    assert r.status is TerrainStatus.HIT and r.hit_unknown and r.cells_hit.tolist() == [[2, 2]]
    r2 = pyr.check([Box([0.45, 0.45, 0.3], [0.03, 0.03, 0.03])])
    assert r2.status is TerrainStatus.CLEAR and not r2.hit_unknown


def test_check_rejects_bad_queries():
    pyr = TerrainPyramid(make_terrain(n=8, cell=0.05, seed=1))
    with pytest.raises(TerrainError):
        pyr.check([])
    with pytest.raises(TerrainError):
        pyr.check([Capsule([0, 0, 0], [1, 0, 0], 0.1)])
    with pytest.raises(TerrainError):
        pyr.check([Box([0, 0, 0], [1, 1, 1])], clearance=-1.0)
    with pytest.raises(TerrainError):
        pyr.check([Box([0, 0, 0], [1, 1, 1])], exact=True, first=True)
