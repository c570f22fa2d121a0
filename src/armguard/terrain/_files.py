"""Terrain files for a robot system: a sensed map placed in the system's frame W (the CLI's ``--terrain``).

:func:`load_terrain` reads

* a ``.npz`` with ``points_W (N, 3)`` (the shipped ``reference/terrain/*.npz``: the sensed
  stereo points) and ``cell``: the map is built from the points
  (:meth:`ElevationMap.from_points`, over the ``heights`` grid's extent when the file has one);
  without points, from ``heights (ny, nx)`` and ``cell`` as a fully known map;
* a point file (``.ply``, ``.pcd``, ``.npy``; :func:`read_points`) at ``cell`` (default 5 cm).

Where the points were seen from -- a ``.npz``'s ``X_WC (4, 4)`` (the camera's pose; the shipped
files have it) or ``sensor_W=`` (a PCD's :func:`read_viewpoint`, where its writer means it so) -- turns on the checks of the rays' free space (stage 3 of
:class:`OutlierRule`, :class:`Carving`): a point too far along its ray and a cell seen on a face
only are then caught, not mapped too low.

``path`` may also be the name of a shipped terrain (``"rocky"``; :func:`shipped_terrains` lists
them): a name with no folder and no suffix that is no file in the working directory is the
shipped ``reference/terrain/<name>.npz`` (:func:`terrain_path`), so ``load_terrain("rocky")`` and
``armguard check rover --terrain rocky`` work from any folder and from an installed wheel.

A file may give ``origin (2,)`` (m, W): the map's corner in W, used as it is.  Otherwise the
map's frame is placed so that its centre lies under the robot's base (the base link at home;
z unchanged): a terrain sensed from the rover's mast is stored in its own frame.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np

from ..model import scene_of
from .._errors import ArmguardWarning, TerrainError, TerrainFileError
from .._tolerance import DEFAULT_TOLERANCES
from .._resources import data_dir
from .._values import number
from ._io import read_points
from ._map import MAX_CELLS, ElevationMap

__all__ = ["load_terrain", "terrain_path", "shipped_terrains", "verify_items", "TerrainPointsDropped", "MAX_CELLS"]




class TerrainPointsDropped(ArmguardWarning):
    """A terrain file's point rows holding a NaN or inf were dropped (the message names the file and says how
    many): a lenient reading, so the command line shows it as one ``warning:`` line."""


def _shipped_folder() -> Path:
    """The folder of the shipped terrains: ``reference/terrain`` of the reference data (the installed
    package data, the checkout's ``reference/``, or ``$ARMGUARD_REFERENCE``)."""
    return data_dir("reference") / "terrain"


def shipped_terrains() -> tuple[str, ...]:
    """The names of the shipped terrains (``("gentle", "rocky", "rough")``): each loads by its name,
    ``load_terrain("rocky")`` (``reference/terrain/README.md`` says how they were made)."""
    folder = _shipped_folder()
    return tuple(sorted(f.stem for f in folder.glob("*.npz") if f.is_file())) if folder.is_dir() else ()


def _is_bare_name(text: str) -> bool:
    """``text`` has no folder and no suffix: ``rocky``, not ``./rocky``, ``terrain/rocky`` nor ``rocky.npz``."""
    seps = {"/", os.sep} | ({os.altsep} if os.altsep else set())
    return bool(text) and not any(c in text for c in seps) and not Path(text).suffix and text not in (".", "..")


def terrain_path(path) -> Path:
    """The file :func:`load_terrain` reads for ``path``: ``path`` itself when it exists; else, for a name
    with no folder and no suffix (``"rocky"``), the shipped terrain of that name (:func:`shipped_terrains`).
    Anything else raises a TerrainError naming ``path`` and listing the shipped names."""
    p = Path(path)
    if p.exists():
        return p
    given = os.fspath(path) if isinstance(path, (str, os.PathLike)) else str(p)  # as typed ("./rocky" stays so)
    names = shipped_terrains()
    listed = ", ".join(names) if names else "none found in " + str(_shipped_folder())
    if isinstance(given, str) and _is_bare_name(given):
        shipped = _shipped_folder() / f"{given}.npz"
        if shipped.is_file():
            return shipped
        raise TerrainError(f"terrain file {given!r} does not exist, and no shipped terrain is named so "
                           f"(shipped terrains: {listed})")
    raise TerrainError(f"terrain file {str(given)!r} does not exist (a shipped terrain loads by its name alone: {listed})")


def _base_xy(scene, robot: str | None) -> np.ndarray:
    names = list(scene.robots)
    if not names:
        return np.zeros(2)
    r = robot if robot in scene.robots else names[0]
    poses = scene.link_poses(scene.flat_q(scene.default_q()))[r]
    return np.asarray(poses[0][:2, 3], dtype=np.float64)


def load_terrain(path, scene=None, *, robot: str | None = None, cell: float | None = None,
                 sensor_W=None) -> ElevationMap:
    """The ElevationMap of the terrain file ``path`` in ``scene``'s frame W (module docstring).

    ``robot``: whose base the map is centred under (default: the scene's first robot); without a
    scene (or with an ``origin`` in the file) the map stays where the file puts it.

    Point rows holding a NaN or inf are dropped (a :class:`TerrainPointsDropped` warning says how
    many; the map's ``invalid`` counts them); a file with no finite point, a truncated PLY, a
    damaged ``.npz``, an array of the wrong shape or of non-numbers, NaN heights, a NaN or non-positive
    cell, or a cell that would make more than :data:`MAX_CELLS` cells of the points' extent raise
    :class:`~armguard._errors.TerrainFileError` naming the file and the array.

    ``path``: a file, or a shipped terrain's name (``"rocky"``: :func:`terrain_path`); a path that
    is neither raises a TerrainError naming it and listing the shipped names.  ``scene`` may be a Model.

    ``sensor_W``: where the points were seen from, ``(3,)`` or one row per point (m, in the file's
    frame); default the position of a ``.npz``'s ``X_WC``.  Both, and different, is an error (never
    one quietly for the other)."""
    p = terrain_path(path)
    if scene is not None:
        scene = scene_of(scene, "terrain map")  # a Model: its scene (it had no flat_q: AttributeError)
    origin = None
    heights = None
    if cell is not None:  # True is not 1 m, nor "0.1" 10 cm
        cell = number(cell, "load_terrain: cell", TerrainError, low=0.0, low_open=True, unit=" (m, a cell side)")
    if sensor_W is not None:
        try:
            sensor_W = np.asarray(sensor_W, dtype=np.float64)
        except (TypeError, ValueError):
            raise TerrainError(f"load_terrain: sensor_W: expected (3,) or (N, 3) numbers (m), got {sensor_W!r}") from None
        if sensor_W.shape[-1:] != (3,) or sensor_W.ndim > 2 or not np.all(np.isfinite(sensor_W)):
            raise TerrainError(f"load_terrain: sensor_W: expected (3,) or (N, 3) finite numbers (m), got shape "
                               f"{sensor_W.shape}")
    if p.suffix.lower() == ".npz":
        c, pts, heights, origin, X_WC = _read_npz(p, cell)
        if X_WC is not None and pts is not None:
            if sensor_W is not None and not (sensor_W.shape == (3,) and np.allclose(sensor_W, X_WC[:3, 3])):
                raise TerrainFileError(p, "X_WC", f"the file's camera is at {X_WC[:3, 3].tolist()} m and sensor_W="
                                       f"{sensor_W.tolist() if sensor_W.size <= 3 else sensor_W.shape} was given: give "
                                       "none, or the file's")
            sensor_W = X_WC[:3, 3]
    else:
        c = 0.05 if cell is None else cell
        pts = read_points(p)
    if not (np.isfinite(c) and c > 0.0):
        raise TerrainFileError(p, "cell", f"expected a cell side > 0 m, got {c!r}")
    if pts is not None:
        if len(pts) == 0:
            raise TerrainFileError(p, "points", "no points: an empty cloud is no terrain")
        finite = np.all(np.isfinite(pts), axis=1)
        if not finite.any():
            raise TerrainFileError(p, "points", f"none of the {len(pts)} points is finite (every row holds a NaN or inf)")
        if sensor_W is not None and sensor_W.ndim == 2 and len(sensor_W) != len(pts):
            raise TerrainError(f"load_terrain: sensor_W: {len(sensor_W)} rows for the {len(pts)} points of {p}")
        if not finite.all():  # dropped as documented; ElevationMap.from_points counts them in ``invalid``
            warnings.warn(f"{p}: {int(np.count_nonzero(~finite))} of {len(pts)} point rows hold a NaN or inf "
                          "and were dropped", TerrainPointsDropped, stacklevel=2)
    shift = np.zeros(3)
    if heights is not None:
        ny, nx = heights.shape
        extent = np.array([nx * c, ny * c])
        lo = np.zeros(2) if origin is None else origin
    else:
        lo, extent = pts[finite, :2].min(axis=0), np.ptp(pts[finite, :2], axis=0) + c
        nx, ny = (int(min(np.ceil(e / c), 2.0**62)) for e in extent)
        if nx * ny > MAX_CELLS:
            raise TerrainFileError(p, "cell", f"a {c:.6g} m cell over the points' {extent[0] - c:.6g} m x {extent[1] - c:.6g} m "
                                   f"extent makes {nx} x {ny} cells, more than MAX_CELLS = {MAX_CELLS} (a larger "
                                   "cell, or a cloud cropped to the workspace)")
    if origin is None and scene is not None:
        shift[:2] = _base_xy(scene, robot) - (lo + 0.5 * extent)
    x0, y0 = lo + shift[:2]
    try:
        if pts is None:
            return ElevationMap.from_heights(heights, c, origin=(x0, y0))
        return ElevationMap.from_points(pts + shift, c, bounds=(x0, y0, x0 + extent[0], y0 + extent[1]),
                                        sensor_W=None if sensor_W is None else sensor_W + shift)
    except TerrainFileError:
        raise
    except TerrainError as exc:  # what the map refuses (heights beyond any terrain, no supported point): this file's
        raise TerrainFileError(p, "heights" if pts is None else "points", str(exc)) from None


def _read_npz(p: Path, cell):
    """``(cell, points_W or None, heights or None, origin or None, X_WC or None)`` of a terrain ``.npz``, each
    checked."""
    try:
        with np.load(p, allow_pickle=False) as z:
            keys = set(z.files)
            _near_misses(p, keys)
            if "points_W" not in keys and "heights" not in keys:
                raise TerrainFileError(p, "", f"a terrain .npz holds 'points_W' or 'heights' (it has {sorted(keys)})")
            arrays = {k: np.asarray(z[k]) for k in ("cell", "points_W", "heights", "origin", "X_WC") if k in keys}
    except TerrainFileError:
        raise
    except Exception as exc:  # noqa: BLE001 - zipfile, zlib, EOF and format errors of a damaged .npz
        raise TerrainFileError(p, "", f"cannot read this .npz ({type(exc).__name__}: {exc})") from None
    if "cell" in arrays:
        a = _numbers(p, "cell", arrays["cell"])
        if a.size != 1:
            raise TerrainFileError(p, "cell", f"expected one number (m), got shape {a.shape}")
        c = float(a.reshape(()))
        if not 0.0 < c <= DEFAULT_TOLERANCES.max_magnitude:  # (a NaN fails too)
            raise TerrainFileError(p, "cell", f"expected a cell side > 0 and at most {DEFAULT_TOLERANCES.max_magnitude:g} m "
                                   f"(Tolerances.max_magnitude), got {c:g}")
        if cell is not None and cell != c:  # never one quietly for the other
            raise TerrainFileError(p, "cell", f"the file's cell is {c:.6g} m and cell={cell:.6g} was given: give none, "
                                   "or the file's")
    elif cell is None and "heights" in arrays and "points_W" not in arrays:  # a grid has no scale without its cell
        raise TerrainFileError(p, "cell", "a 'heights' grid needs its cell side (m): store 'cell' in the file, or "
                               "give load_terrain(..., cell=...)")
    else:
        c = 0.05 if cell is None else cell  # points: the map's resolution, a choice (docs/terrain.md)
    pts = heights = origin = None
    if "points_W" in arrays:
        pts = _numbers(p, "points_W", arrays["points_W"])
        if pts.ndim != 2 or pts.shape[1] != 3:
            raise TerrainFileError(p, "points_W", f"expected (N, 3) points (m, W), got shape {pts.shape}")
    if "heights" in arrays:
        heights = _numbers(p, "heights", arrays["heights"])
        if heights.ndim != 2 or heights.size == 0:
            raise TerrainFileError(p, "heights", f"expected a (ny, nx) grid of heights (m), got shape {heights.shape}")
        if pts is None and not np.all(np.isfinite(heights)):
            bad = np.argwhere(~np.isfinite(heights))[0]
            raise TerrainFileError(p, "heights", f"{int(np.count_nonzero(~np.isfinite(heights)))} non-finite heights "
                                   f"(first at row {bad[0]}, column {bad[1]}); a height map must hold numbers")
    if "origin" in arrays:
        origin = _numbers(p, "origin", arrays["origin"])
        if origin.shape != (2,) or not np.all(np.abs(origin) <= DEFAULT_TOLERANCES.max_magnitude):
            raise TerrainFileError(p, "origin", f"expected (x0, y0) finite and within {DEFAULT_TOLERANCES.max_magnitude:g} "
                                   f"(m, W), got {origin.tolist()}")
    X_WC = None
    if "X_WC" in arrays:
        X_WC = _numbers(p, "X_WC", arrays["X_WC"])
        if X_WC.shape != (4, 4) or not np.all(np.isfinite(X_WC)):
            raise TerrainFileError(p, "X_WC", f"expected the camera's (4, 4) pose (m, W), finite, got shape {X_WC.shape}")
    return c, pts, heights, origin, X_WC


_KEYS = ("cell", "points_W", "heights", "origin", "X_WC")


def _near_misses(p: Path, keys) -> None:
    """An array whose name looks like a misspelt key the file lacks (``orgin``, ``cel``) is refused: ignored, it
    would move or rescale the map without a word.  Other arrays (a sensor's ``intensity``, ``heights_std`` beside
    ``heights``, ``origin_W``) are left alone."""
    import difflib

    missing = [x for x in _KEYS if x not in keys]  # a present key's companion (heights_std beside heights) is none
    for k in sorted(set(keys) - set(_KEYS)):
        if any(x in k for x in _KEYS) or (k[:2] in ("X_", "p_") and k[2:].isalpha()):  # a name holding a key
            continue  # (origin_W, heights_std, cell_size) or another frame's pose (X_WS): not a misspelling
        near = difflib.get_close_matches(k, missing, n=1, cutoff=0.6) or [x for x in missing if x.lower() == k.lower()]
        if near:
            raise TerrainFileError(p, k, f"unknown array {k!r}: did you mean {near[0]!r}? (a terrain .npz holds "
                                   f"{', '.join(_KEYS)})")


def _numbers(p: Path, name: str, a: np.ndarray) -> np.ndarray:
    """``a`` as float64; an array of strings or other non-numbers is refused naming the file and the array."""
    if a.dtype.kind not in "iuf":  # booleans are not heights nor lengths
        raise TerrainFileError(p, name, f"expected numbers (m), got {a.dtype} values")
    return np.asarray(a, dtype=np.float64)


def verify_items(scene, items, terrain_file, *, robot=None, **kwargs) -> list:
    """:func:`verify_with_terrain` of every ``(name, trajectory)`` of ``items`` (serially), the terrain
    :func:`load_terrain` of ``terrain_file`` under each trajectory's robot; ``kwargs`` as
    :func:`armguard.verify` takes them (the CLI's)."""
    scene = scene_of(scene, "verification")  # a Model: its scene
    from ._guard import TerrainGuard
    from ._sweep import verify_with_terrain

    guards, out = {}, []
    for name, traj in items:
        r = robot or traj.robot_name
        if r not in guards:
            guards[r] = TerrainGuard(scene, load_terrain(terrain_file, scene, robot=r), robot=r)
        out.append(verify_with_terrain(scene, traj, guards[r], robot=robot, name=name, **kwargs))
    return out
