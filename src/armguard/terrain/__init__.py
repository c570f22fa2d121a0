"""Terrain from sensed points, as a multi-resolution OBB pyramid checked coarse-to-fine.

The JPL rover-arm method (Leger, NASA Tech Brief NPO-30356, seed ``002``): stereo points become an
elevation map (:class:`ElevationMap`), the map a pyramid of OBBs (:class:`TerrainPyramid`) whose
top box encloses all the data and each level below has twice the horizontal resolution; each
link's low-resolution OBP (or OBB) is tested coarse-to-fine, descending only into boxes it hits,
"without any divisions or transcendental functions".  Inputs are shapes posed in W and maps, so
the module stands alone.  :mod:`armguard.terrain.generate` makes synthetic terrains and
stereo-like point clouds.  Guide: ``docs/terrain.md``.
"""

from ._io import depth_to_points, read_points, read_viewpoint, write_points
from ._carve import Carving
from ._map import ElevationMap, OutlierRule
from ._pyramid import PyramidLevel, TerrainPyramid, TerrainResult, TerrainStatus
from ._volumes import bounding_box, link_volume
from ._guard import TERRAIN, TerrainCell, TerrainGuard, TerrainReport
from ._detect import TerrainDetectionReport, attach_terrain, check_with_terrain
from ._sweep import TerrainSweep, sweep_terrain, verify_with_terrain
from ._files import MAX_CELLS, TerrainPointsDropped, load_terrain, shipped_terrains, terrain_path, verify_items

__all__ = [
    "ElevationMap",
    "OutlierRule",
    "Carving",
    "TerrainPyramid",
    "PyramidLevel",
    "TerrainResult",
    "TerrainStatus",
    "bounding_box",
    "link_volume",
    "TERRAIN",
    "TerrainGuard",
    "TerrainReport",
    "TerrainDetectionReport",
    "attach_terrain",
    "check_with_terrain",
    "TerrainCell",
    "TerrainSweep",
    "sweep_terrain",
    "verify_with_terrain",
    "load_terrain",
    "terrain_path",
    "shipped_terrains",
    "verify_items",
    "TerrainPointsDropped",
    "MAX_CELLS",
    "read_points",
    "read_viewpoint",
    "write_points",
    "depth_to_points",
]

_COAL = ("coal_checker", "coal_heightfield", "dilated", "CoalTerrain", "HeightFieldCoalChecker")
_BODY = ("BodyHierarchy", "BodyNode", "BodyResult")


def __getattr__(name):  # coal's height field and the body hierarchy load on first use (coal, pinocchio)
    if name in _COAL:
        from . import _coal

        return getattr(_coal, name)
    if name in _BODY:
        from . import _body

        return getattr(_body, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
