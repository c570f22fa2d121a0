"""The rays' free space in a sensed map (terrain/_carve.py): the grid walk against a brute-force
reference, stage 3 of the outlier rule, a cell whose points lie far below the rays over it, a rock's
top kept by stage 1, and
the shipped terrains' maps with and without the camera's position."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from armguard._errors import TerrainError, TerrainFileError
from armguard.terrain import Carving, ElevationMap, OutlierRule, load_terrain
from armguard.terrain._carve import ray_lows
from armguard.terrain.generate import REFERENCE, reference_terrain

GRID = (-0.3, 0.2, 0.1, 7, 5)  # x0, y0, cell, nx, ny


def _reference_lows(o, p, use, grid, carving):
    """Every cell against every segment: the segment clipped to the cell's rectangle (Liang & Barsky,
    written out again), its lower end; the `votes`-th lowest per cell.  Crossings shorter than 1e-9
    of the segment are left out (a corner touched: the grid walk may or may not count it)."""
    x0, y0, cell, nx, ny = grid
    crossings = [[[] for _ in range(nx)] for _ in range(ny)]
    for oi, pi, ui in zip(o, p, use):
        if not ui:
            continue
        v = pi - oi
        length = np.linalg.norm(v)
        stop = carving.margin + carving.range_margin * length**2
        if length <= stop:
            continue
        d = v * (length - stop) / length
        for r in range(ny):
            for c in range(nx):
                lo = np.array([x0 + c * cell, y0 + r * cell])
                hi = lo + cell
                t0, t1 = 0.0, 1.0
                for k in range(2):
                    if d[k] == 0.0:
                        if not lo[k] <= oi[k] <= hi[k]:
                            t0, t1 = 1.0, 0.0
                    else:
                        a, b = (lo[k] - oi[k]) / d[k], (hi[k] - oi[k]) / d[k]
                        t0, t1 = max(t0, min(a, b)), min(t1, max(a, b))
                if t1 - t0 > 1e-9:
                    crossings[r][c].append(oi[2] + min(t0 * d[2], t1 * d[2]))
    out = np.full((ny, nx), np.inf)
    for r in range(ny):
        for c in range(nx):
            z = sorted(crossings[r][c])
            if len(z) >= carving.votes:
                out[r, c] = z[carving.votes - 1]
    return out


@settings(max_examples=60, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**31 - 1), votes=st.integers(1, 3))
def test_the_grid_walk_finds_every_cell_a_segment_crosses_and_its_lowest_point(seed, votes):
    rng = np.random.default_rng(seed)
    n = 12
    o = np.column_stack([rng.uniform(-1.0, 1.2, n), rng.uniform(-0.5, 1.2, n), rng.uniform(-0.5, 2.0, n)])
    p = np.column_stack([rng.uniform(-1.0, 1.2, n), rng.uniform(-0.5, 1.2, n), rng.uniform(-0.5, 2.0, n)])
    p[:3, :2] = o[:3, :2] + rng.uniform(-0.02, 0.02, (3, 2))  # near-vertical rays: one or two cells
    p[3, 0] = o[3, 0]  # a ray in the y-z plane (dx = 0)
    use = rng.random(n) < 0.9
    carving = Carving(margin=0.05, range_margin=0.01, votes=votes)
    got = ray_lows(o, p, use, GRID, carving)
    ref = _reference_lows(o, p, use, GRID, carving)
    both = np.isfinite(ref) & np.isfinite(got)
    np.testing.assert_allclose(got[both], ref[both], rtol=0, atol=1e-12)
    assert np.array_equal(np.isfinite(got), np.isfinite(ref))


def _flat_cloud(spacing=0.02, size=2.0, z=0.0):
    g = np.arange(0.5 * spacing, size, spacing)
    x, y = np.meshgrid(g, g)
    return np.column_stack([x.ravel(), y.ravel(), np.full(x.size, z)])


def test_a_point_too_far_along_its_ray_is_dropped_not_mapped_too_low():
    """A stereo mismatch that puts a point 60 % farther along its ray lands 0.9 m under the ground;
    where it is its cell's only point, the per-cell maximum maps the cell 0.9 m too low and calls it
    known.  Its ray crossed the ground other rays saw."""
    o = np.array([1.0, -1.0, 1.5])
    cloud = _flat_cloud(size=3.0)
    target = np.array([1.21, 1.43, 0.0])  # the ground the ray really met
    far = o + 1.6 * (target - o)  # ... and where the mismatch put it: (1.34, 2.89, -0.9)
    far_cell = (int(far[1] // 0.1), int(far[0] // 0.1))
    cloud = cloud[~((np.floor(cloud[:, 0] / 0.1) == far_cell[1]) & (np.floor(cloud[:, 1] / 0.1) == far_cell[0]))]
    pts = np.vstack([cloud, far])
    blind = ElevationMap.from_points(pts, 0.1, bounds=(0, 0, 3, 3))
    assert blind.known[far_cell] and blind.heights[far_cell] < -0.8  # known, 0.9 m too low
    m = ElevationMap.from_points(pts, 0.1, bounds=(0, 0, 3, 3), sensor_W=o)
    assert not m.known[far_cell] and m.heights[far_cell] >= 0.0  # unseen, filled from its neighbours
    assert m.rejected == blind.rejected + 1
    off = ElevationMap.from_points(pts, 0.1, bounds=(0, 0, 3, 3), sensor_W=o, rule=OutlierRule(ray=np.inf),
                                   carving=Carving(gap=np.inf))
    assert off.known[far_cell] and off.heights[far_cell] < -0.8  # both checks off: the points alone again
    gap_only = ElevationMap.from_points(pts, 0.1, bounds=(0, 0, 3, 3), sensor_W=o, rule=OutlierRule(ray=np.inf))
    assert not gap_only.known[far_cell]  # without stage 3, the rays over the cell still say its top was not seen


def test_stage_one_keeps_a_rock_top_the_cells_around_support():
    """A cell of ground points with two on a rock's top beside it: the robust z-score alone drops the
    two (the cell's height the ground's); the rock's cells next to it support them."""
    rng = np.random.default_rng(0)

    def cell_points(col, row, z, n):
        return np.column_stack([rng.uniform(col * 0.1, (col + 1) * 0.1, n), rng.uniform(row * 0.1, (row + 1) * 0.1, n),
                                z + rng.normal(0.0, 0.002, n)])

    ground = [cell_points(c, r, 0.0, 12) for r in range(6) for c in range(3)]
    rock = [cell_points(c, r, 0.3, 12) for r in range(6) for c in range(4, 6)]
    edge = np.vstack([cell_points(3, 2, 0.0, 12), cell_points(3, 2, 0.3, 2)])
    pts = np.vstack(ground + rock + [edge])
    m = ElevationMap.from_points(pts, 0.1, bounds=(0, 0, 0.6, 0.6))
    assert m.heights[2, 3] > 0.29  # the rock's top is the cell's height
    alone = np.vstack(ground + [edge])  # no rock beside: the two are a mismatch
    m2 = ElevationMap.from_points(alone, 0.1, bounds=(0, 0, 0.6, 0.6))
    assert m2.heights[2, 3] < 0.01 and m2.rejected == 2


@pytest.mark.parametrize("name", sorted(REFERENCE))
def test_the_shipped_terrains_with_their_camera_map_no_cell_far_too_low(name):
    """Measured on the shipped clouds (known cells under the ground truth by more than 10 cm, points
    only -> with the camera): gentle 0 -> 0, rocky 0 -> 0, rough 3 (worst 0.36 m) -> 1 (0.10 m)."""
    r = reference_terrain(name)
    truth, X = r["heights"], r["X_WC"]
    blind = ElevationMap.from_points(r["points_W"], 0.05, bounds=(0, 0, 3.2, 3.2))
    m = load_terrain(name)  # the file's X_WC: the camera's position
    assert m.upper is not None
    low, low_blind = truth - m.heights, truth - blind.heights
    assert float(low[m.known].max()) <= 0.11
    assert np.count_nonzero(m.known & (low > 0.1)) <= np.count_nonzero(blind.known & (low_blind > 0.1))
    assert np.count_nonzero(~m.known & (low > 0.1)) <= np.count_nonzero(~blind.known & (low_blind > 0.1))
    fin = np.isfinite(m.upper)
    assert fin.mean() > 0.8 and float((truth - m.upper)[fin].max()) < 0.1  # a bound, to the cells' own relief
    assert m.known.sum() > 0.85 * blind.known.sum()  # the price: cells seen in part only, unseen
    assert not np.array_equal(X, np.eye(4))


def test_load_terrain_takes_the_files_camera_and_refuses_another(tmp_path):
    r = reference_terrain("gentle")
    f = tmp_path / "t.npz"
    np.savez(f, points_W=r["points_W"], cell=0.05, X_WC=r["X_WC"])
    m = load_terrain(f)
    assert m.upper is not None
    same = load_terrain(f, sensor_W=r["X_WC"][:3, 3])
    assert np.array_equal(same.heights, m.heights)
    with pytest.raises(TerrainFileError, match="X_WC.*the file's camera is at"):
        load_terrain(f, sensor_W=[0.0, 0.0, 9.0])
    bad = tmp_path / "bad.npz"
    np.savez(bad, points_W=r["points_W"], cell=0.05, X_WC=np.eye(3))
    with pytest.raises(TerrainFileError, match=r"X_WC.*\(4, 4\) pose"):
        load_terrain(bad)
    bare = tmp_path / "bare.npz"
    np.savez(bare, points_W=r["points_W"], cell=0.05)
    assert load_terrain(bare).upper is None
    given_ = load_terrain(bare, sensor_W=r["X_WC"][:3, 3])
    assert np.array_equal(given_.heights, m.heights) and np.array_equal(given_.known, m.known)
    with pytest.raises(TerrainError, match="sensor_W"):
        load_terrain(bare, sensor_W=[1.0, 2.0])
    with pytest.raises(TerrainError, match="sensor_W: 2 rows for the"):
        load_terrain(bare, sensor_W=np.zeros((2, 3)))


def test_from_points_checks_the_sensor_position():
    pts = _flat_cloud(0.1, 1.0)
    for bad in ([0.0, 0.0], [np.nan, 0.0, 1.0], np.zeros((3, 3)), "up"):
        with pytest.raises(TerrainError, match="sensor_W: expected"):
            ElevationMap.from_points(pts, 0.1, sensor_W=bad)
    per_point = np.tile([0.5, -1.0, 1.0], (len(pts), 1))
    a = ElevationMap.from_points(pts, 0.1, sensor_W=per_point)
    b = ElevationMap.from_points(pts, 0.1, sensor_W=[0.5, -1.0, 1.0])
    assert np.array_equal(a.upper, b.upper) and np.array_equal(a.known, b.known)


def _cast(o, dirs, boxes):
    """The nearest hit of rays ``o + t d`` (t > 0) with the ground z = 0 and axis-aligned boxes (lo, hi)."""
    t_best = np.where(dirs[:, 2] < 0, -o[2] / np.where(dirs[:, 2] < 0, dirs[:, 2], -1), np.inf)
    for lo, hi in boxes:
        lo, hi = np.asarray(lo, float), np.asarray(hi, float)
        with np.errstate(divide="ignore", invalid="ignore"):
            a, b = (lo - o) / dirs, (hi - o) / dirs
        tmin, tmax = np.nanmax(np.minimum(a, b), axis=1), np.nanmin(np.maximum(a, b), axis=1)
        hit = (tmax >= tmin) & (tmin > 0)
        t_best = np.where(hit & (tmin < t_best), tmin, t_best)
    ok = np.isfinite(t_best)
    return o + dirs[ok] * t_best[ok, None]


def _fan(o, target, n=300, half=0.5):
    f = np.asarray(target, float) - o
    f /= np.linalg.norm(f)
    r = np.cross(f, [0.0, 0.0, 1.0])
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    a = np.linspace(-half, half, n)
    A, B = np.meshgrid(a, a)
    d = f[None] + A.ravel()[:, None] * r[None] + B.ravel()[:, None] * u[None]
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def test_a_ray_beside_a_post_in_its_cell_is_no_ray_under_the_ground():
    """A 3 cm post 1.5 m tall in a 10 cm cell, a 20 cm stone 1 m behind it in the same row: the rays
    to the stone pass the post's cell beside the post, far below its top.  Judged against the
    cells' highest points, stage 3 dropped every point of the stone and left its cell unknown at the
    ground's height (a link 10 cm over the ground there was no longer a collision)."""
    o = np.array([0.0, 0.05, 1.2])
    post = ([0.50, 0.00, 0.0], [0.53, 0.03, 1.5])
    stone = ([1.50, 0.035, 0.0], [1.56, 0.07, 0.20])
    pts = _cast(o, _fan(o, [1.5, 0.05, 0.0]), [post, stone])
    bounds = (0.0, -0.5, 2.5, 0.6)
    blind = ElevationMap.from_points(pts, 0.1, bounds=bounds)
    m = ElevationMap.from_points(pts, 0.1, bounds=bounds, sensor_W=o)
    assert blind.known[5, 15] and blind.heights[5, 15] == pytest.approx(0.2)
    assert m.known[5, 15] and m.heights[5, 15] == pytest.approx(0.2) and m.counts[5, 15] == blind.counts[5, 15]
    assert m.heights[5, 5] == pytest.approx(blind.heights[5, 5], abs=1e-12) and m.heights[5, 5] > 1.0  # its top seen
    assert np.all(m.heights >= blind.heights) and np.all(blind.known | ~m.known)


@pytest.mark.parametrize("name", sorted(REFERENCE))
def test_the_camera_only_raises_a_cell_or_takes_its_known(name):
    """With the sensor's position every cell is at least as high as from the points alone, and known
    only where the points alone know it: the rays add caution, never take it away (the fill of the
    holes reads every cell's points, carved or not)."""
    r = reference_terrain(name)
    blind = ElevationMap.from_points(r["points_W"], 0.05, bounds=(0, 0, 3.2, 3.2))
    m = ElevationMap.from_points(r["points_W"], 0.05, bounds=(0, 0, 3.2, 3.2), sensor_W=r["X_WC"][:3, 3])
    assert np.all(m.heights >= blind.heights)
    assert np.all(blind.known | ~m.known)
    assert m.known.sum() < blind.known.sum()  # the rays did find cells not seen on top


@pytest.mark.parametrize("bad, what", [
    (dict(gap=np.nan), "Carving.gap: expected a number > 0"), (dict(votes=0), "Carving.votes: expected an integer >= 1"),
    (dict(votes=1.5), "Carving.votes"), (dict(range_margin=np.nan), "Carving.range_margin"),
    (dict(margin=-1.0), "Carving.margin: expected a number >= 0"), (dict(margin=np.inf), "Carving.margin")])
def test_a_carving_that_would_carve_nothing_or_too_much_is_refused(bad, what):
    with pytest.raises(TerrainError, match=what.replace(".", "\\.")):
        Carving(**bad)


@pytest.mark.parametrize("bad, what", [
    (dict(ray=np.nan), "OutlierRule.ray"), (dict(ray=0.0), "OutlierRule.ray"), (dict(k=-1.0), "OutlierRule.k"),
    (dict(spike_radius=-1), "OutlierRule.spike_radius"), (dict(min_points=True), "OutlierRule.min_points"),
    (dict(sigma_min=np.inf), "OutlierRule.sigma_min")])
def test_an_outlier_rule_with_a_meaningless_field_is_refused(bad, what):
    with pytest.raises(TerrainError, match=what.replace(".", "\\.")):
        OutlierRule(**bad)
    assert OutlierRule(k=np.inf, spike=np.inf, ray=np.inf).ray == np.inf  # inf: the stage is off


def test_a_pcds_viewpoint_is_read_when_asked_not_on_its_own(tmp_path):
    """PCL writes the sensor's origin into a PCD's VIEWPOINT, but reads it two ways (the sensor's
    position in the points' frame, or a cloud's pose): load_terrain does not take it on its own; given
    as sensor_W it reads the rays from it, as from a .npz's X_WC.  The default VIEWPOINT (0 0 0 1 0 0 0,
    what most writers leave) is no position; a quaternion that is no unit one is refused."""
    from armguard.terrain import read_viewpoint, write_points

    r = reference_terrain("gentle")
    plain = write_points(tmp_path / "plain.pcd", r["points_W"])
    assert read_viewpoint(plain) is None and load_terrain(plain).upper is None
    eye = r["X_WC"][:3, 3]
    text = plain.read_text()
    vp = next(line for line in text.splitlines() if line.startswith("VIEWPOINT"))
    seen = tmp_path / "seen.pcd"
    seen.write_text(text.replace(vp, "VIEWPOINT " + " ".join(repr(float(x)) for x in (*eye, 1.0, 0.0, 0.0, 0.0))))
    np.testing.assert_array_equal(read_viewpoint(seen), eye)
    assert load_terrain(seen).upper is None  # not on its own
    m = load_terrain(seen, sensor_W=read_viewpoint(seen))
    given = load_terrain(plain, sensor_W=eye)
    assert m.upper is not None
    np.testing.assert_array_equal(m.heights, given.heights)
    np.testing.assert_array_equal(m.known, given.known)
    odd = tmp_path / "odd.pcd"
    odd.write_text(text.replace(vp, "VIEWPOINT 1 2 3 5 0 0 0"))
    with pytest.raises(TerrainFileError, match="VIEWPOINT.*no unit quaternion"):
        read_viewpoint(odd)


def test_the_shipped_terrain_files_are_what_the_generator_writes(tmp_path, monkeypatch):
    """reference/terrain/*.npz are ``python -m armguard.terrain.generate``'s output, byte for byte (their source),
    written whole or not at all: a full disk left the shipped file cut short."""
    from pathlib import Path

    import armguard._io as io_mod
    from armguard import OutputError
    from armguard.terrain.generate import _write_reference

    shipped = Path(__file__).resolve().parents[1] / "reference" / "terrain"
    _write_reference(tmp_path)
    for name in sorted(REFERENCE):
        assert (tmp_path / f"{name}.npz").read_bytes() == (shipped / f"{name}.npz").read_bytes(), name
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}

    def full(fd, blob):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(io_mod, "_write_all", full)
    with pytest.raises(OutputError, match="No space left"):
        _write_reference(tmp_path)
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before
