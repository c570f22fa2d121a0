"""Point clouds from files (PLY, PCD, NumPy) and from depth images (pinhole camera model).

* PLY (ASCII or binary): read with trimesh (vertices of a point cloud or a mesh).
* PCD (ASCII, binary, binary_compressed): read with ``pypcd4`` (pure Python plus the small
  ``python-neo-lzf`` wheel for the compressed encoding).
* ``.npy``: an ``(N, 3+)`` array; ``.npz``: the array named ``points`` (else the only array).

Points are returned as ``(N, 3) float64, m`` in the file's frame; pass ``X_WS`` to express them
in W.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._errors import TerrainError, TerrainFileError

__all__ = ["read_points", "write_points", "depth_to_points"]


def _pose(X, name: str) -> np.ndarray:
    X = np.asarray(X, dtype=np.float64)
    if X.shape != (4, 4) or not np.all(np.isfinite(X)):
        raise TerrainError(f"{name}: expected a finite (4, 4) pose, got shape {X.shape}")
    return X


def _as_points(a, where: str, file=None) -> np.ndarray:
    """``(N, 3) float64`` of ``a`` (its first three columns); ``file``: the file it came from (the
    error is then a :class:`TerrainFileError` naming it, ``where`` the array in it)."""
    def bad(message):
        return TerrainFileError(file, where, message) if file is not None else TerrainError(f"{where}: {message}")

    try:
        p = np.asarray(a, dtype=np.float64)
    except (TypeError, ValueError):
        raise bad(f"expected (N, 3) numbers (m), got {np.asarray(a).dtype} values") from None
    if p.ndim != 2 or p.shape[1] < 3:
        raise bad(f"expected (N, 3) points, got shape {p.shape}")
    return np.ascontiguousarray(p[:, :3])


def _ply_vertex_count(path: Path) -> int | None:
    """The vertex count ``element vertex N`` of a PLY header (None when the header has none)."""
    with open(path, "rb") as f:
        head = f.read(1 << 16)
    end = head.find(b"end_header")
    for line in head[:end if end >= 0 else len(head)].decode("ascii", "replace").splitlines():
        words = line.split()
        if len(words) == 3 and words[0] == "element" and words[1] == "vertex":
            try:
                return int(words[2])
            except ValueError:
                raise TerrainFileError(path, "header", f"'element vertex {words[2]}' is not a count") from None
    return None


def read_points(path, X_WS=None) -> np.ndarray:
    """``(N, 3) float64, m``: the points of a ``.ply``, ``.pcd``, ``.npy`` or ``.npz`` file, in the
    sensor frame S of the file, or in W when ``X_WS (4, 4)`` is given.  Non-finite rows are kept
    (:meth:`ElevationMap.from_points` drops and counts them).

    A file that cannot be read, holds no ``(N, 3)`` numbers, or whose body holds another number of
    points than its header says (a PLY's ``element vertex N``, a PCD's ``POINTS N``: a file cut
    short) raises :class:`~armguard._errors.TerrainFileError` naming the file, the place in it
    and both counts."""
    path = Path(path)
    if path.is_dir():
        raise TerrainError(f"read_points: {path} is a folder; expected a terrain or point file (.npz, .pcd, .ply, .npy)")
    if not path.is_file():
        raise TerrainError(f"read_points: no file {path}")
    ext = path.suffix.lower()
    try:
        if ext == ".npy":
            with open(path, "rb") as f:  # numpy calls any file without its header "pickled (object) data"
                if f.read(6) != b"\x93NUMPY":
                    raise TerrainFileError(path, "", "not a .npy file (no NumPy header: np.save writes one)")
            p = _as_points(np.load(path, allow_pickle=False), "array", path)
        elif ext == ".npz":
            with np.load(path, allow_pickle=False) as z:
                names = list(z.files)
                key = "points" if "points" in names else (names[0] if len(names) == 1 else None)
                if key is None:
                    raise TerrainFileError(path, "", f"an .npz needs an array named 'points' (has {names})")
                p = _as_points(z[key], key, path)
        elif ext == ".ply":
            import trimesh

            obj = trimesh.load(path, process=False)
            if not hasattr(obj, "vertices"):
                raise TerrainFileError(path, "", "no vertices in this PLY")
            p = _as_points(obj.vertices, "vertex", path)
            n = _ply_vertex_count(path)
            if n is not None and n != len(p):  # trimesh reads a cut ASCII body without a word
                raise TerrainFileError(path, "element vertex", f"the header says {n} vertices, the file holds "
                                       f"{len(p)} (truncated?)")
        elif ext == ".pcd":
            import pypcd4

            pc = pypcd4.PointCloud.from_path(path)
            missing = [f for f in ("x", "y", "z") if f not in pc.fields]
            if missing:
                raise TerrainFileError(path, "FIELDS", f"expected fields x, y and z; {missing} missing (has {list(pc.fields)})")
            p = _as_points(pc.numpy(("x", "y", "z")), "DATA", path)
            n = int(pc.metadata.points)
            if n != len(p):  # pypcd4 reads a cut ASCII or binary body without a word
                raise TerrainFileError(path, "POINTS", f"the header says {n} points, the file holds {len(p)} "
                                       f"({'truncated?' if len(p) < n else 'rows beyond the header'})")
        else:
            raise TerrainError(f"read_points: unsupported file type {ext!r} ({path}); use .ply, .pcd, .npy or .npz")
    except TerrainError:
        raise
    except Exception as e:  # noqa: BLE001 - a reader's own error, named with the file
        first = (str(e).splitlines() or [""])[0]  # pydantic's and numpy's messages run over lines
        raise TerrainFileError(path, "", f"cannot read points ({type(e).__name__}: {first})") from e
    if X_WS is not None:
        X = _pose(X_WS, "read_points: X_WS")
        p = p @ X[:3, :3].T + X[:3, 3]
    return p


def read_viewpoint(path) -> np.ndarray | None:
    """``(3,) m`` or None: the position in a ``.pcd`` header's ``VIEWPOINT tx ty tz qw qx qy qz`` (PCL's
    ``sensor_origin_``) when the header gives one other than the default ``0 0 0 1 0 0 0`` (which most
    writers leave whatever the frame: no evidence); None for any other file type.

    Not read by :func:`load_terrain` on its own: PCL reads the field two ways -- its occlusion and
    normal code as the sensor's position in the points' frame, its viewer as the pose of a cloud
    given in the sensor's frame (the sensor then at the points' origin) -- and a wrong position
    proves free space that is not.  Where the writer means the first,
    ``load_terrain(path, sensor_W=read_viewpoint(path))``."""
    path = Path(path)
    if path.suffix.lower() != ".pcd":
        return None
    import pypcd4

    try:
        vp = np.asarray(pypcd4.PointCloud.from_path(path).metadata.viewpoint, dtype=np.float64)
    except Exception as e:  # noqa: BLE001 - a reader's own error, named with the file
        first = (str(e).splitlines() or [""])[0]
        raise TerrainFileError(path, "VIEWPOINT", f"cannot read the header ({type(e).__name__}: {first})") from e
    if vp.shape != (7,) or not np.all(np.isfinite(vp)):
        raise TerrainFileError(path, "VIEWPOINT", f"expected 7 finite numbers (tx ty tz qw qx qy qz), got {vp.tolist()}")
    if np.array_equal(vp, [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]):
        return None
    if abs(float(np.linalg.norm(vp[3:])) - 1.0) > 1e-6:
        raise TerrainFileError(path, "VIEWPOINT", f"the orientation (qw qx qy qz) {vp[3:].tolist()} is no unit quaternion")
    return vp[:3].copy()


def write_points(path, points) -> Path:
    """Write ``points (N, 3) m`` to ``.ply`` (binary, trimesh), ``.pcd`` (ASCII, pypcd4; float32),
    ``.npy`` or ``.npz`` (array ``points``); returns the path.  The file is written whole or not at
    all (``armguard._io.atomic_write``: a full disk or a missing folder is an OutputError naming the
    file, and a previous file of that name is left as it was)."""
    from .._io import atomic_write

    path = Path(path)
    p = _as_points(points, "write_points")
    ext = path.suffix.lower()
    if ext == ".npy":
        data = lambda f: np.save(f, p)  # noqa: E731 - written into memory, then to the file at once
    elif ext == ".npz":
        data = lambda f: np.savez_compressed(f, points=p)  # noqa: E731
    elif ext == ".ply":
        import trimesh

        data = trimesh.PointCloud(p).export(file_type="ply")
    elif ext == ".pcd":
        import pypcd4

        data = lambda f: pypcd4.PointCloud.from_xyz_points(p.astype(np.float32)).save(f, encoding=pypcd4.Encoding.ASCII)  # noqa: E731
    else:
        raise TerrainError(f"write_points: unsupported file type {ext!r} (expected .ply, .pcd, .npy or .npz)")
    return atomic_write(path, data)


def depth_to_points(depth, fx: float, fy: float, cx: float, cy: float, X_WC=None, *, max_range: float | None = None) -> np.ndarray:
    """Back-project a depth image with the pinhole model.

    Parameters
    ----------
    depth : (H, W) float, m
        Depth along the optical axis (z of the camera frame C) per pixel; 0, negative or NaN: no data.
    fx, fy : float, px
        Focal lengths; ``cx, cy`` (px) the principal point.  Pixel ``(v, u)`` (row, column) at depth
        ``z`` is ``p_C = ((u - cx) z / fx, (v - cy) z / fy, z)`` (C: x right, y down, z forward).
    X_WC : (4, 4), optional
        Camera pose in W; default: points are returned in C.
    max_range : float, m, optional
        Drop pixels deeper than this.

    Returns
    -------
    (N, 3) float64, m: the valid pixels' points, row-major pixel order.
    """
    d = np.asarray(depth, dtype=np.float64)
    if d.ndim != 2:
        raise TerrainError(f"depth_to_points: expected an (H, W) depth image, got shape {d.shape}")
    if not all(np.isfinite(v) for v in (fx, fy, cx, cy)) or fx <= 0.0 or fy <= 0.0:
        raise TerrainError(f"depth_to_points: bad intrinsics fx={fx}, fy={fy}, cx={cx}, cy={cy}")
    v, u = np.indices(d.shape, dtype=np.float64)
    ok = np.isfinite(d) & (d > 0.0)
    if max_range is not None:
        ok &= d <= max_range
    z = d[ok]
    p = np.stack([(u[ok] - cx) * z / fx, (v[ok] - cy) * z / fy, z], axis=1)
    if X_WC is not None:
        X = _pose(X_WC, "depth_to_points: X_WC")
        p = p @ X[:3, :3].T + X[:3, 3]
    return p
