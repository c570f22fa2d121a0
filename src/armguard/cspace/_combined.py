"""Hermes's combined check (Fig. 14): the map for links 1–3 vs the obstacles, the geometric method for the rest."""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np

from .._errors import ForbiddenMapError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from ._clearance import resolve_scene, rest_scene

__all__ = ["CombinedChecker", "CombinedStatus", "CombinedBatch"]


class CombinedStatus(enum.IntEnum):
    """Per-configuration verdict of :meth:`CombinedChecker.check_many`."""

    FREE = 0  #: the map allows links 1–3 and the exact check finds nothing else within the stopping distance
    MAP_FORBIDDEN = 1  #: the map forbids joints 1–3 here (links 1–3 may reach an obstacle): treated as a collision
    COLLISION = 2  #: the exact check of the other pairs finds a collision (the map allowed links 1–3)


@dataclass(frozen=True)
class CombinedBatch:
    """``status (M,) int8`` :class:`CombinedStatus` codes and ``collision (M,) bool`` (status != FREE)."""

    status: np.ndarray
    collision: np.ndarray


class CombinedChecker:
    """Fig. 14 as a checker: ``collides_many(Q)`` over the scene's flat configurations.

    A configuration collides when the map does not allow its joints 1–3 (a conservative answer
    for the mapped links against the static bodies) or when the exact :class:`armguard.Detector`
    finds a collision among every *other* pair of the scene (links beyond joint 3, the payload,
    link-link pairs, other robots, the workspace walls), with the map's stopping distance.  It
    never says free where the full exact check says collision: the map's "allowed" is proven for
    the mapped pairs and the rest is exact.

    Parameters
    ----------
    fmap : ForbiddenMap
    scene : Scene | str | None
        The scene the map was built for (default: the map's ``model`` record, a name or path).  A
        name or path is checked against the map's model sha256; a Scene object is taken as given.
    """

    def __init__(self, fmap, scene=None, *, tol: Tolerances = DEFAULT_TOLERANCES) -> None:
        from ..detect import Detector

        if scene is None:
            if fmap.header.get("model") is None:
                raise ForbiddenMapError("the map was built from a Scene object: pass scene=")
            scene = fmap.header["model"]
        if isinstance(scene, str):
            fmap.check_model(scene)
        scene, _ = resolve_scene(scene)
        if fmap.robot not in scene.robots or tuple(scene.robots[fmap.robot].joint_names[k] for k in fmap.joint_index) != fmap.joints:
            raise ForbiddenMapError(f"the scene has no robot {fmap.robot!r} with joints {fmap.joints} at {fmap.joint_index}")
        self.map = fmap
        self.scene = scene
        self._rest = Detector(rest_scene(scene, fmap.robot, fmap.links), threshold=0.0,
                              stopping_distance=fmap.stopping_distance, tol=tol)
        k0 = 0
        for name, rob in scene.robots.items():
            if name == fmap.robot:
                break
            k0 += len(rob.joint_names)
        self._cols = np.array([k0 + k for k in fmap.joint_index], dtype=np.int64)
        self.n_q = len(scene.joint_names)

    def prepare(self) -> "CombinedChecker":
        """Load the map's lookup arrays (idempotent)."""
        self.map.prepare()
        return self

    def check_many(self, Q) -> CombinedBatch:
        """Verdicts for ``Q`` ``(M, n_q)`` rad (the scene's flat joint vectors)."""
        Q = np.ascontiguousarray(np.asarray(Q, dtype=np.float64))
        if Q.ndim != 2 or Q.shape[1] != self.n_q:
            raise ForbiddenMapError(f"Q: expected shape (M, {self.n_q}), got {Q.shape}")
        allowed = self.map.allowed_many(Q[:, self._cols])
        status = np.where(allowed, CombinedStatus.FREE, CombinedStatus.MAP_FORBIDDEN).astype(np.int8)
        if np.any(allowed):  # the geometric part only where the map lets the configuration through
            hit = self._rest.collides_many(Q[allowed])
            idx = np.flatnonzero(allowed)[hit]
            status[idx] = CombinedStatus.COLLISION
        return CombinedBatch(status, status != CombinedStatus.FREE)

    def collides_many(self, Q) -> np.ndarray:
        """``(M,) bool``: collision (or not proven free) per row of ``Q`` ``(M, n_q)``."""
        return self.check_many(Q).collision
