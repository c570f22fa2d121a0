"""Terrain files that do not hold what they say are refused, naming the file and the array;
NaN point rows are dropped as documented (and counted), never turned into a NaN map."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from armguard._errors import TerrainError, TerrainFileError
from armguard.terrain import TerrainPointsDropped, load_terrain, read_points
from armguard.terrain.generate import make_terrain


def _cloud(n=3404, seed=11):
    rng = np.random.default_rng(seed)
    xy = rng.uniform(0.0, 2.0, size=(n, 2))
    return np.column_stack([xy, 0.1 * np.sin(3 * xy[:, 0]) + rng.normal(0, 0.005, n)])


def _ascii_ply(path, pts, keep: int | None = None):
    trimesh.PointCloud(pts).export(path, encoding="ascii")
    lines = path.read_text().splitlines(True)
    end = next(i for i, ln in enumerate(lines) if ln.strip() == "end_header")
    if keep is not None:
        path.write_text("".join(lines[:end + 1 + keep]))
    return path


def test_a_truncated_ascii_ply_is_refused_with_the_count(tmp_path):
    full = _ascii_ply(tmp_path / "full.ply", _cloud())
    assert read_points(full).shape == (3404, 3)
    cut = _ascii_ply(tmp_path / "cut.ply", _cloud(), keep=10)
    with pytest.raises(TerrainFileError, match=r"cut\.ply: element vertex: the header says 3404 vertices, the file holds 10"):
        read_points(cut)
    with pytest.raises(TerrainFileError, match="3404"):
        load_terrain(cut)


def test_nan_point_rows_are_dropped_and_counted(tmp_path):
    pts = _cloud(2000, seed=12).astype(np.float32).astype(np.float64)  # what a (float32) PLY holds
    bad = np.random.default_rng(13).choice(len(pts), size=37, replace=False)
    with_nan = pts.copy()
    with_nan[bad[:20], 2] = np.nan
    with_nan[bad[20:], 0] = np.inf
    clean_file = tmp_path / "clean.npy"
    np.save(clean_file, pts[np.setdiff1d(np.arange(len(pts)), bad)])
    for ext in (".npy", ".ply"):
        f = tmp_path / f"holes{ext}"
        np.save(f, with_nan) if ext == ".npy" else trimesh.PointCloud(with_nan).export(f)
        with pytest.warns(TerrainPointsDropped, match="37 of 2000 point rows"):
            m = load_terrain(f, cell=0.1)
        ref = load_terrain(clean_file, cell=0.1)
        assert m.invalid == 37 and np.all(np.isfinite(m.heights))
        np.testing.assert_array_equal(m.heights, ref.heights)  # the same map as without the rows
        np.testing.assert_array_equal(m.origin, ref.origin)
    all_nan = tmp_path / "all_nan.npy"
    np.save(all_nan, np.full((5, 3), np.nan))
    with pytest.raises(TerrainFileError, match="none of the 5 points is finite"):
        load_terrain(all_nan)


def _npz(path, **arrays):
    np.savez(path, **arrays)
    return path


@pytest.mark.parametrize("case, where", [
    ("empty_cloud", "points"), ("two_columns", "points_W"), ("heights_1d", "heights"), ("origin_3", "origin"),
    ("nan_heights", "heights"), ("nan_cell", "cell"), ("zero_cell", "cell"), ("truncated", ""), ("zero_bytes", ""),
    ("no_arrays", ""), ("huge_cell", "cell"), ("huge_origin", "origin"),  # (messages about bounds and origins before)
])
def test_bad_terrain_npz_names_the_file_and_array(tmp_path, case, where):
    truth = make_terrain(n=8, cell=0.1, seed=3)
    h = np.array(truth.heights)
    p = tmp_path / f"{case}.npz"
    if case == "empty_cloud":
        _npz(p, points_W=np.zeros((0, 3)), cell=0.1)
    elif case == "two_columns":
        _npz(p, points_W=np.ones((10, 2)), cell=0.1)
    elif case == "heights_1d":
        _npz(p, heights=h.ravel(), cell=0.1)
    elif case == "origin_3":
        _npz(p, heights=h, cell=0.1, origin=np.zeros(3))
    elif case == "nan_heights":
        h[2, 3] = np.nan
        _npz(p, heights=h, cell=0.1)
    elif case == "nan_cell":
        _npz(p, heights=h, cell=np.nan)
    elif case == "zero_cell":
        _npz(p, heights=h, cell=0.0)
    elif case == "truncated":
        raw = _npz(tmp_path / "whole.npz", heights=h, cell=0.1).read_bytes()
        p.write_bytes(raw[: len(raw) // 2])
    elif case == "zero_bytes":
        p.write_bytes(b"")
    elif case == "no_arrays":
        _npz(p, other=np.zeros(3))
    elif case == "huge_cell":
        _npz(p, heights=h, cell=1e12)
    elif case == "huge_origin":
        _npz(p, heights=h, cell=0.1, origin=np.array([1e300, 0.0]))
    with pytest.raises(TerrainFileError) as e:
        load_terrain(p)
    assert e.value.file == str(p) and e.value.where == where, str(e.value)
    assert isinstance(e.value, TerrainError) and str(p) in str(e.value)


def test_a_good_heights_file_still_loads(tmp_path):
    truth = make_terrain(n=8, cell=0.1, seed=3)
    p = _npz(tmp_path / "ok.npz", heights=np.array(truth.heights), cell=0.1, origin=np.array([1.0, -2.0]))
    m = load_terrain(p)
    np.testing.assert_array_equal(m.heights, truth.heights)
    np.testing.assert_array_equal(m.origin, [1.0, -2.0])


@pytest.mark.parametrize("typo, key", [("orgin", "origin"), ("cel", "cell"), ("Heights", "heights")])
def test_a_misspelt_array_is_refused_not_ignored(tmp_path, typo, key):
    """``orgin=[5, 5]`` was ignored: the map was centred under the robot instead of 5 m away (``cel`` likewise
    left a 0.2 m grid read at the 5 cm default); an unrelated array (a sensor's intensity) is left alone."""
    truth = make_terrain(n=8, cell=0.1, seed=3)
    arrays = {"heights": np.array(truth.heights), "cell": 0.1, "origin": np.array([5.0, 5.0])}
    arrays[typo] = arrays.pop(key)
    if key == "cell":
        arrays["points_W"] = np.array([[0.0, 0.0, 0.0], [0.4, 0.4, 0.1]])
    p = _npz(tmp_path / "typo.npz", **arrays)
    with pytest.raises(TerrainFileError, match=f"unknown array '{typo}': did you mean '{key}'") as e:
        load_terrain(p)
    assert e.value.where == typo
    ok = _npz(tmp_path / "ok.npz", heights=np.array(truth.heights), cell=0.1, intensity=np.ones(3),
              heights_std=np.ones(3), origin_W=np.zeros(2), X_WS=np.eye(4), cel=np.ones(1) * 0.2)  # companions; a
    np.testing.assert_array_equal(load_terrain(ok).heights, truth.heights)  # near miss of a key the file has


def _ascii_pcd(path, pts, keep: int | None = None, extra: int = 0):
    import pypcd4

    pypcd4.PointCloud.from_xyz_points(pts.astype(np.float32)).save(path, encoding=pypcd4.Encoding.ASCII)
    lines = path.read_text().splitlines(True)
    end = next(i for i, ln in enumerate(lines) if ln.startswith("DATA"))
    body = lines[end + 1:] if keep is None else lines[end + 1:end + 1 + keep]
    path.write_text("".join(lines[:end + 1] + body) + "0.5 0.5 0.0\n" * extra)
    return path


def test_a_truncated_pcd_is_refused_with_the_count(tmp_path):
    """The PCD reader, like trimesh on PLY, reads a body cut short without a word: the header's POINTS is held to it."""
    import pypcd4

    pts = _cloud()
    assert read_points(_ascii_pcd(tmp_path / "full.pcd", pts)).shape == (3404, 3)
    for keep in (10, 1700):
        cut = _ascii_pcd(tmp_path / f"cut{keep}.pcd", pts, keep=keep)
        with pytest.raises(TerrainFileError, match=rf"cut{keep}\.pcd: POINTS: the header says 3404 points, the file holds {keep}"):
            load_terrain(cut)
    with pytest.raises(TerrainFileError, match="the header says 3404 points, the file holds 3407"):
        read_points(_ascii_pcd(tmp_path / "more.pcd", pts, extra=3))
    binary = tmp_path / "binary.pcd"
    pypcd4.PointCloud.from_xyz_points(pts.astype(np.float32)).save(binary, encoding=pypcd4.Encoding.BINARY)
    raw = binary.read_bytes()
    body = raw.index(b"DATA binary\n") + len(b"DATA binary\n")
    for n, cut in ((1700, raw[:body + 12 * 1700]), (None, raw[:body + 12 * 1700 + 5])):  # at a record's end, inside one
        binary.write_bytes(cut)
        with pytest.raises(TerrainFileError) as e:
            read_points(binary)
        assert e.value.file == str(binary) and (n is None or "the file holds 1700" in str(e.value)), str(e.value)


@pytest.mark.parametrize("case, where", [
    ("points_text", "points_W"), ("heights_text", "heights"), ("origin_text", "origin"), ("cell_text", "cell"),
    ("cell_two", "cell"), ("tiny_cell", "cell"), ("far_point", "cell"),
])
def test_terrain_npz_of_non_numbers_or_a_runaway_grid_is_refused(tmp_path, monkeypatch, case, where):
    """Strings where numbers belong, and a cell that would make billions of cells (a tiny cell, a point
    kilometres away), name the file and the array instead of numpy's error or a memory blow-up."""
    h = np.array(make_terrain(n=8, cell=0.1, seed=3).heights)
    pts = _cloud(200, seed=14)
    arrays = {
        "points_text": dict(points_W=np.array([["0", "0", "x"]]), cell=0.1),
        "heights_text": dict(heights=np.full((3, 3), "0.1"), cell=0.1),
        "origin_text": dict(heights=h, cell=0.1, origin=np.array(["0", "0"])),
        "cell_text": dict(points_W=pts, cell=np.array("0.1")),
        "cell_two": dict(points_W=pts, cell=np.array([0.1, 0.1])),
        "tiny_cell": dict(points_W=pts, cell=1e-9),
        "far_point": dict(points_W=np.vstack([pts, [[4e4, 0.0, 0.0]]]), cell=0.05),
    }[case]
    p = _npz(tmp_path / f"{case}.npz", **arrays)
    with pytest.raises(TerrainFileError) as e:
        load_terrain(p)
    assert e.value.file == str(p) and e.value.where == where, str(e.value)
    if case in ("tiny_cell", "far_point"):
        from armguard.terrain import MAX_CELLS

        assert f"more than MAX_CELLS = {MAX_CELLS}" in str(e.value)
        # the limit itself: a grid of exactly MAX_CELLS cells loads, one column more is refused
        import armguard.terrain._files as files

        monkeypatch.setattr(files, "MAX_CELLS", 20 * 20)
        square = np.array([[x, y, 0.0] for x in np.linspace(0, 1.9, 20) for y in np.linspace(0, 1.9, 20)])
        assert load_terrain(_npz(tmp_path / "at.npz", points_W=square, cell=0.1)).shape == (20, 20)
        wider = np.vstack([square, square[-20:] + [0.1, 0.0, 0.0]])
        with pytest.raises(TerrainFileError, match="makes 21 x 20 cells, more than MAX_CELLS = 400"):
            load_terrain(_npz(tmp_path / "over.npz", points_W=wider, cell=0.1))


@pytest.mark.parametrize("content, where", [(np.ones((10, 2)), "array"), (np.ones(10), "array"),
                                            (np.array([["a", "b", "c"]]), "array")])
def test_bad_point_files_name_the_file(tmp_path, content, where):
    p = tmp_path / "points.npy"
    np.save(p, content)
    with pytest.raises(TerrainFileError) as e:
        load_terrain(p)
    assert e.value.file == str(p) and e.value.where == where, str(e.value)
    z = tmp_path / "empty.ply"
    z.write_bytes(b"")
    with pytest.raises(TerrainFileError, match="empty.ply: cannot read points"):
        read_points(z)


@pytest.mark.parametrize("make, said", [
    (lambda: _map(origin=(np.nan, 0.0)), "ElevationMap.origin: expected (x0, y0), two finite numbers"),
    (lambda: _map(origin=(0.0, 0.0, 5.0)), "ElevationMap.origin: expected (x0, y0)"),
    (lambda: _map(origin=0.0), "ElevationMap.origin: expected (x0, y0)"),
    (lambda: _map(cell="abc"), "from_heights: cell (m): expected a number, got 'abc'"),
    (lambda: _map(heights=np.array([[1e308, -1e308]])), "beyond the largest magnitude a map holds"),
    (lambda: _from_points(1e-7), "more than MAX_CELLS"),
    (lambda: _from_points(0.1, bounds=(0.0, 0.0, np.inf, 1.0)), "bounds (m): expected a finite number, got inf"),
    (lambda: _from_points(0.1, bounds=(0.0, 0.0, 1.0)), "bounds: expected (x_min, y_min, x_max, y_max)"),
    (lambda: _from_points(0.1, floor="low"), "floor (m): expected a number"),
])
def test_a_map_refuses_what_would_give_a_verdict_from_nothing(make, said):
    """A NaN origin was kept and the pyramid then answered HIT from NaN boxes; an origin of three
    numbers, text for a cell, or heights of 1e308 failed later with numpy's errors; a 1e-7 m cell asked
    for 720 TiB."""
    with pytest.raises(TerrainError) as e:
        make()
    assert said in str(e.value), str(e.value)


def _map(heights=None, cell=0.05, origin=(0.0, 0.0)):
    from armguard.terrain import ElevationMap

    return ElevationMap.from_heights(np.zeros((8, 8)) if heights is None else heights, cell, origin=origin)


def _from_points(cell, **kw):
    from armguard.terrain import ElevationMap

    return ElevationMap.from_points(_cloud(200, seed=5), cell, **kw)


def test_load_terrain_never_takes_one_cell_for_another(tmp_path):
    """A cell= other than the file's own was dropped without a word (the file's won), cell=0 on a .npz
    without one read as 0.05 m, text raised ValueError; a cloud too sparse for the outlier rule named no
    file."""
    p = _npz(tmp_path / "grid.npz", heights=np.zeros((4, 4)), cell=0.1)
    assert load_terrain(p, cell=0.1).shape == (4, 4)
    with pytest.raises(TerrainFileError, match="the file's cell is 0.1 m and cell=0.5 was given") as e:
        load_terrain(p, cell=0.5)
    assert e.value.file == str(p)
    for bad in (0, -1.0, "abc", float("nan")):
        with pytest.raises(TerrainError, match="load_terrain: cell"):
            load_terrain(_npz(tmp_path / "pts.npz", points_W=_cloud(50, seed=2)), cell=bad)
    sparse = tmp_path / "sparse.npy"
    np.save(sparse, np.column_stack([np.linspace(0, 2, 10), np.linspace(0, 2, 10), np.zeros(10)]))
    with pytest.raises(TerrainFileError, match="no cell has a surviving point") as e:
        load_terrain(sparse)
    assert e.value.file == str(sparse) and e.value.where == "points"


def test_a_height_grid_without_its_cell_is_refused_not_read_at_5_cm(tmp_path):
    """A ``heights`` grid with no ``cell`` (in the file or given) has no scale: it was read at 0.05 m without a
    word (a 10 cm grid became a map half its size). Booleans are neither a cell nor heights."""
    p = _npz(tmp_path / "h.npz", heights=np.zeros((3, 3)))
    with pytest.raises(TerrainFileError, match="a 'heights' grid needs its cell side") as e:
        load_terrain(p)
    assert e.value.file == str(p) and e.value.where == "cell"
    assert load_terrain(p, cell=0.1).shape == (3, 3)
    both = _npz(tmp_path / "both.npz", points_W=_cloud(), heights=np.zeros((3, 3)))  # built from its points
    assert load_terrain(both).cell == 0.05
    with pytest.raises(TerrainError, match="load_terrain: cell"):
        load_terrain(p, cell=True)
    with pytest.raises(TerrainFileError, match="expected numbers"):
        load_terrain(_npz(tmp_path / "b.npz", heights=np.zeros((3, 3), bool), cell=0.1))


def test_a_npy_without_its_header_is_said_to_be_no_npy(tmp_path):
    """A text file named .npy was refused as "This file contains pickled (object) data"."""
    p = tmp_path / "g.npy"
    p.write_text("hello")
    with pytest.raises(TerrainFileError, match="not a .npy file") as e:
        load_terrain(p)
    assert e.value.file == str(p)


def test_a_pyramid_check_refuses_a_clearance_that_is_no_length():
    from armguard.geometry import Box
    from armguard.terrain import TerrainPyramid

    pyramid = TerrainPyramid(_map())
    box = Box([0.1, 0.1, 0.5], [0.05, 0.05, 0.05])
    for bad in ("x", np.nan, -1.0, True):
        with pytest.raises(TerrainError, match="clearance must be a finite length >= 0"):
            pyramid.check([box], clearance=bad)
        with pytest.raises(TerrainError, match="clearance must be a finite length >= 0"):
            pyramid.check_flat([box], clearance=bad)


def test_a_folder_given_as_terrain_is_said_to_be_a_folder(tmp_path):
    """``--terrain DIR`` said "read_points: no file DIR"."""
    with pytest.raises(TerrainError, match="is a folder; expected a terrain or point file"):
        read_points(tmp_path)
