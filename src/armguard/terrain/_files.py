"""Terrain files for a robot system: a sensed map placed in the system's frame W (the CLI's ``--terrain``).

:func:`load_terrain` reads

* a ``.npz`` with ``points_W (N, 3)`` (the shipped ``reference/terrain/*.npz``: the sensed
  stereo points) and ``cell``: the map is built from the points
  (:meth:`ElevationMap.from_points`, over the ``heights`` grid's extent when the file has one);
  without points, from ``heights (ny, nx)`` and ``cell`` as a fully known map;
* a point file (``.ply``, ``.pcd``, ``.npy``; :func:`read_points`) at ``cell`` (default 5 cm).

A file may give ``origin (2,)`` (m, W): the map's corner in W, used as it is.  Otherwise the
map's frame is placed so that its centre lies under the robot's base (the base link at home;
z unchanged): a terrain sensed from the rover's mast is stored in its own frame.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._errors import TerrainError
from ._io import read_points
from ._map import ElevationMap

__all__ = ["load_terrain", "verify_items"]


def _base_xy(scene, robot: str | None) -> np.ndarray:
    names = list(scene.robots)
    if not names:
        return np.zeros(2)
    r = robot if robot in scene.robots else names[0]
    poses = scene.link_poses(scene.flat_q(scene.default_q()))[r]
    return np.asarray(poses[0][:2, 3], dtype=np.float64)


def load_terrain(path, scene=None, *, robot: str | None = None, cell: float | None = None) -> ElevationMap:
    """The ElevationMap of the terrain file ``path`` in ``scene``'s frame W (module docstring).

    ``robot``: whose base the map is centred under (default: the scene's first robot); without a
    scene (or with an ``origin`` in the file) the map stays where the file puts it."""
    p = Path(path)
    if not p.exists():
        raise TerrainError(f"terrain file {str(p)!r} does not exist")
    origin = None
    heights = None
    if p.suffix.lower() == ".npz":
        with np.load(p) as z:
            keys = set(z.files)
            if "points_W" not in keys and "heights" not in keys:
                raise TerrainError(f"{p}: a terrain .npz holds 'points_W' or 'heights' (it has {sorted(keys)})")
            c = float(z["cell"]) if "cell" in keys else (cell or 0.05)
            pts = np.asarray(z["points_W"], dtype=np.float64) if "points_W" in keys else None
            heights = np.asarray(z["heights"], dtype=np.float64) if "heights" in keys else None
            if "origin" in keys:
                origin = np.asarray(z["origin"], dtype=np.float64).reshape(2)
    else:
        c = 0.05 if cell is None else float(cell)
        pts = read_points(p)
    shift = np.zeros(3)
    if heights is not None:
        ny, nx = heights.shape
        extent = np.array([nx * c, ny * c])
        lo = np.zeros(2) if origin is None else origin
    else:
        lo, extent = pts[:, :2].min(axis=0), np.ptp(pts[:, :2], axis=0) + c
    if origin is None and scene is not None:
        shift[:2] = _base_xy(scene, robot) - (lo + 0.5 * extent)
    x0, y0 = lo + shift[:2]
    if pts is None:
        m = ElevationMap.from_heights(heights, c, origin=(x0, y0))
    else:
        m = ElevationMap.from_points(pts + shift, c, bounds=(x0, y0, x0 + extent[0], y0 + extent[1]))
    return m


def verify_items(scene, items, terrain_file, *, robot=None, **kwargs) -> list:
    """:func:`verify_with_terrain` of every ``(name, trajectory)`` of ``items`` (serially), the terrain
    :func:`load_terrain` of ``terrain_file`` under each trajectory's robot; ``kwargs`` as
    :func:`armguard.verify` takes them (the CLI's)."""
    from ._guard import TerrainGuard
    from ._sweep import verify_with_terrain

    guards, out = {}, []
    for name, traj in items:
        r = robot or traj.robot_name
        if r not in guards:
            guards[r] = TerrainGuard(scene, load_terrain(terrain_file, scene, robot=r), robot=r)
        out.append(verify_with_terrain(scene, traj, guards[r], robot=robot, name=name, **kwargs))
    return out
