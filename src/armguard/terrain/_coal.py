"""The reference for the terrain: coal's ``HeightField`` on the same elevation map, beside the coal checker.

coal's height field (``coal.HeightFieldOBBRSS(x_dim, y_dim, heights, min_height)``) is a surface
through grid *vertices*, solid down to ``min_height``; the map's terrain is flat-topped cell
*columns*.  :func:`coal_heightfield` puts a vertex at every cell corner, at the highest of the (up
to four) cells around it, solid down to the map's floor, so that coal's solid contains every
column and lies within the columns raised to their 3 x 3 neighbourhood's highest cell
(:func:`dilated`).  Hence, for any shape, exactly

    distance(shape, dilated columns) <= distance(shape, coal's height field) <= distance(shape, columns)

— the comparison the tests and ``bench/terrain.py`` make with the pyramid (a pyramid HIT is always
a coal HIT; the converse fails only within a cell of a height step).

coal 3 computes no distance to a height field ("not implemented"), only collisions, exactly, with
a ``security_margin`` of either sign: :meth:`CoalTerrain.distances` finds the signed distance as
the least margin at which coal reports a collision, by bisection (to ``tol``).

:class:`HeightFieldCoalChecker` is the coal checker with the height field as an option: its
``pair_distances`` and ``collides`` are the plugin's, unchanged (the model's pairs only); the
terrain is a second GeometryModel — the moving geometries and the height field, one pair each —
answered by :meth:`~HeightFieldCoalChecker.terrain_distances` and ``terrain_collides``.
"""

from __future__ import annotations

import math

import numpy as np

from .._errors import TerrainError
from ._map import ElevationMap

__all__ = ["coal_heightfield", "dilated", "CoalTerrain", "HeightFieldCoalChecker", "coal_checker"]

TERRAIN_GEOMETRY = "terrain"


def coal_heightfield(elevation: ElevationMap):
    """``(coal.HeightFieldOBBRSS, X_WH (4, 4))``: coal's height field of ``elevation`` and its pose in W
    (module docstring).  coal's grid is centred on its frame's origin, its first row at +y."""
    import coal

    h = elevation.heights
    ny, nx = h.shape
    pad = np.pad(h, 1, constant_values=-np.inf)
    corner = np.maximum.reduce([pad[:-1, :-1], pad[:-1, 1:], pad[1:, :-1], pad[1:, 1:]])  # (ny + 1, nx + 1)
    c = elevation.cell
    hf = coal.HeightFieldOBBRSS(nx * c, ny * c, np.ascontiguousarray(corner[::-1]), elevation.floor)
    X = np.eye(4)
    X[:2, 3] = elevation.origin + 0.5 * c * np.array([nx, ny])
    return hf, X


def dilated(elevation: ElevationMap) -> ElevationMap:
    """``elevation`` with every cell raised to the highest cell of its 3 x 3 neighbourhood: its columns
    contain coal's height field of ``elevation`` (the lower bound of the sandwich above)."""
    pad = np.pad(elevation.heights, 1, constant_values=-np.inf)
    ny, nx = elevation.shape
    top = np.max([pad[i:i + ny, j:j + nx] for i in range(3) for j in range(3)], axis=0)
    return ElevationMap(top, elevation.origin, elevation.cell, elevation.known, elevation.counts, elevation.floor)


class CoalTerrain:
    """coal's height field of ``elevation`` with the moving geometries of ``model`` (an
    :class:`armguard.Model`), one collision pair each, in a GeometryModel of their own.

    Attributes
    ----------
    names : tuple[str, ...]
        The moving GeometryObjects' names (the pair order).
    geometry_model : pinocchio.GeometryModel
    """

    def __init__(self, model, elevation: ElevationMap) -> None:
        import pinocchio as pin

        if not isinstance(elevation, ElevationMap):
            raise TerrainError(f"CoalTerrain: expected an ElevationMap, got {type(elevation).__name__}")
        self.model, self.elevation = model, elevation
        geom = pin.GeometryModel()
        names = []
        for go in model.collision_model.geometryObjects:
            if go.parentJoint > 0:  # moves with a joint: an arm link or a payload
                geom.addGeometryObject(go.copy() if hasattr(go, "copy") else go)
                names.append(go.name)
        if not names:
            raise TerrainError(f"CoalTerrain: model {model.name!r} has no moving geometry")
        hf, X = coal_heightfield(elevation)
        self.heightfield = hf
        j = geom.addGeometryObject(pin.GeometryObject(TERRAIN_GEOMETRY, 0, 0, pin.SE3(X[:3, :3], X[:3, 3]), hf))
        for i in range(len(names)):
            geom.addCollisionPair(pin.CollisionPair(i, j))
        self.names = tuple(names)
        self.geometry_model = geom
        self._data = model.pin_model.createData()
        self._gdata = pin.GeometryData(geom)
        for req in self._gdata.collisionRequests:
            req.enable_contact = False

    def _collide(self, margin: float) -> np.ndarray:
        import pinocchio as pin

        for req in self._gdata.collisionRequests:
            req.security_margin = margin
        g, gd = self.geometry_model, self._gdata
        out = np.empty(len(self.names), bool)
        for i in range(len(self.names)):
            out[i] = pin.computeCollision(g, gd, i)
        return out

    def _place(self, q) -> None:
        import pinocchio as pin

        q = np.asarray(q, dtype=np.float64)
        if q.shape != (self.model.nq,):
            raise TerrainError(f"q: expected {self.model.q_layout(q.shape[-1] if q.ndim else None)}, got shape {q.shape}")
        pin.updateGeometryPlacements(self.model.pin_model, self._data, self.geometry_model, self._gdata, q)

    def collides(self, q, *, margin: float = 0.0) -> np.ndarray:
        """``(K,) bool`` per moving geometry: within ``margin`` (m; negative: penetrating deeper than
        ``-margin``) of the height field at ``q`` (Pinocchio's order)."""
        self._place(q)
        return self._collide(float(margin))

    def distances(self, q, *, reach: float = 0.1, tol: float = 1e-7) -> np.ndarray:
        """``(K,) float64, m``: each moving geometry's signed distance to the height field at ``q``
        (Pinocchio's order), by bisection on coal's ``security_margin`` over ``[-reach, reach]`` to
        ``tol`` (the upper end of the final bracket); ``inf`` beyond ``reach``, ``-inf`` deeper."""
        import pinocchio as pin

        self._place(q)
        reqs = self._gdata.collisionRequests
        K = len(self.names)
        lo = np.full(K, -reach)
        hi = np.full(K, reach)
        top = self._collide(reach)
        bottom = self._collide(-reach)
        out = np.where(top, np.nan, np.inf)
        out[bottom] = -np.inf
        todo = np.isnan(out)
        for _ in range(max(1, int(math.ceil(math.log2(2.0 * reach / tol))))):
            if not todo.any():
                break
            mid = 0.5 * (lo + hi)
            hit = np.zeros(K, bool)
            for i in np.flatnonzero(todo).tolist():  # each pair at its own margin
                reqs[i].security_margin = float(mid[i])
                hit[i] = pin.computeCollision(self.geometry_model, self._gdata, i)
            hi = np.where(todo & hit, mid, hi)
            lo = np.where(todo & ~hit, mid, lo)
        out[todo] = hi[todo]
        return out


class HeightFieldCoalChecker:
    """The coal checker (``armguard.checker(model, "coal")``) with coal's height field of ``elevation``
    as an option: ``pair_distances`` / ``collides`` (every attribute of the coal checker) unchanged;
    the terrain through :meth:`terrain_distances` and :meth:`terrain_collides` (see the module
    docstring).  The coal checker is found by its entry point like any backend: the framework does
    not import the plugin."""

    name = "coal"

    def __init__(self, model, elevation: ElevationMap, options=None) -> None:
        from ..backends import checker

        self.checker = checker(model, "coal", options)
        self.terrain = CoalTerrain(model, elevation)

    def __getattr__(self, name: str):  # the coal checker's own interface, unchanged
        if name == "checker":  # not set yet (an error in __init__): no recursion
            raise AttributeError(name)
        return getattr(self.checker, name)

    def terrain_distances(self, q, *, reach: float = 0.1, tol: float = 1e-7) -> np.ndarray:
        """:meth:`CoalTerrain.distances` (``q`` in Pinocchio's order, one row per ``terrain.names``)."""
        return self.terrain.distances(q, reach=reach, tol=tol)

    def terrain_collides(self, Q, *, margin: float = 0.0) -> np.ndarray:
        """``(M,) bool``: some moving geometry within ``margin`` (m) of the height field, per row of
        ``Q`` ``(M, nq)`` (Pinocchio's order)."""
        Q = np.atleast_2d(np.asarray(Q, dtype=np.float64))
        return np.array([bool(self.terrain.collides(q, margin=margin).any()) for q in Q], dtype=bool)


def coal_checker(model, elevation: ElevationMap, options=None) -> HeightFieldCoalChecker:
    """The coal checker of ``model`` with coal's height field of ``elevation`` (the reference)."""
    return HeightFieldCoalChecker(model, elevation, options)
