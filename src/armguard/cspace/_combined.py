"""Hermes's combined check (Fig. 14): the map for links 1–3 vs the obstacles, a geometric backend for the rest.

:class:`CombinedChecker` is the one implementation: the ``forbidden`` backend
(``plugins/armguard_forbidden``) wraps it as a Checker, and its own :meth:`CombinedChecker.check_many`
answers over the scene's flat configurations.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

import numpy as np

from .._errors import ForbiddenMapError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from ._clearance import checker_over, rest_scene

__all__ = ["CombinedChecker", "CombinedStatus", "CombinedBatch", "map_model"]


class CombinedStatus(enum.IntEnum):
    """Per-configuration verdict of :meth:`CombinedChecker.check_many`."""

    FREE = 0  #: the map allows links 1–3 and the geometric check finds nothing else within the margin
    MAP_FORBIDDEN = 1  #: the map forbids joints 1–3 here (links 1–3 may reach an obstacle): treated as a collision
    COLLISION = 2  #: the geometric check of the other pairs finds a collision (the map allowed links 1–3)


@dataclass(frozen=True)
class CombinedBatch:
    """``status (M,) int8`` :class:`CombinedStatus` codes and ``collision (M,) bool`` (status != FREE)."""

    status: np.ndarray
    collision: np.ndarray


def map_model(fmap, model=None):
    """The Model ``fmap`` answers for, checked against it.

    ``model``: a Model (its ``files`` are checked against the map's sha256), a built-in name or a
    ``.yaml`` / ``.urdf`` path (loaded, then checked), a Scene (taken as given: a scene built in code
    has no files to check), or None (the map's own ``model`` record).  The map's robot must have
    joints 1–3 where the map says.
    """
    from ..model import Model, load_model, model_of
    from ..scene import Scene

    if model is None:
        if fmap.header.get("model") is None:
            raise ForbiddenMapError("the map was built from a Scene object: pass the scene or model")
        model = fmap.header["model"]
    if isinstance(model, Scene):
        mdl = model_of(model)
    else:
        mdl = model if isinstance(model, Model) else load_model(str(model))
        if not mdl.files:
            raise ForbiddenMapError(f"model {mdl.name!r} has no source files to check the map {fmap.path} against; "
                                    "load it with armguard.load_model(name or path)")
        fmap.check_model([str(p) for p in mdl.files])
    scene = mdl.scene
    if fmap.robot not in scene.robots or tuple(scene.robots[fmap.robot].joint_names[k] for k in fmap.joint_index) != fmap.joints:
        raise ForbiddenMapError(f"the model has no robot {fmap.robot!r} with joints {fmap.joints} at {fmap.joint_index}")
    _check_geometry(fmap, mdl, given_scene=isinstance(model, Scene))
    return mdl


def _check_geometry(fmap, mdl, *, given_scene: bool) -> None:
    """Refuse ``mdl`` unless its mapped links and static bodies are those the map was built on (the
    header's ``geometry`` digest, :mod:`._geometry_digest`): a Scene was taken as given, and a body
    added to it, or the robot's base moved, was answered by a map that never saw it.  A map written
    before the digest was recorded takes a Model whose files it checked, and refuses a Scene."""
    from ._geometry_digest import geometry_digest

    want = fmap.header.get("geometry")
    if want is None:
        if given_scene:
            raise ForbiddenMapError(f"the map {fmap.path} records no geometry to check a Scene against (built by an "
                                    "earlier armguard): pass the model it was built from, or build the map again")
        return
    got, bodies = geometry_digest(mdl, fmap.robot, fmap.links)
    if got != want:
        had = set(fmap.header.get("bodies", ()))
        added, removed = sorted(set(bodies) - had), sorted(had - set(bodies))
        what = "; ".join(x for x in (f"bodies added: {', '.join(added)}" if added else "",
                                     f"bodies removed: {', '.join(removed)}" if removed else "") if x)
        raise ForbiddenMapError(f"the map {fmap.path} was built on other geometry than this model's ("
                                + (what or f"a static body, {fmap.robot}'s base or its links {', '.join(fmap.links)} "
                                   "moved or changed shape") + "): its verdicts would not hold; build it for this model")


class CombinedChecker:
    """Fig. 14 as a checker.

    A configuration collides when the map does not allow its joints 1–3 (a conservative answer
    for the mapped links against the static bodies, proven at the map's stopping distance) or
    when the geometric backend finds a pair within the margin among every *other* pair of the
    model (links beyond joint 3, the payload, link–link pairs, other robots, the workspace walls).
    It never says free where the full geometric check at a margin up to the map's stopping
    distance says collision: the map's "allowed" is proven for the mapped pairs, the rest is the
    backend's own answer.

    Parameters
    ----------
    fmap : ForbiddenMap
    scene : Model | Scene | str | None
        What the map was built for (see :func:`map_model`; default: the map's ``model`` record).
    backend : str
        The geometric backend for the other pairs (any installed one; default ``"analytic"``).
    backend_options : mapping | None
        Its options.
    """

    def __init__(self, fmap, scene=None, *, backend: str = "analytic", backend_options=None,
                 tol: Tolerances = DEFAULT_TOLERANCES) -> None:
        model = map_model(fmap, scene)
        self.map = fmap
        self.model = model
        self.scene = model.scene_for()  # the Model as made, whatever model.scene does later
        self.tol = tol
        rest = rest_scene(self.scene, fmap.robot, fmap.links)
        self.geometric = checker_over(model, rest, backend, backend_options)
        k0 = 0
        for name, rob in self.scene.robots.items():
            if name == fmap.robot:
                break
            k0 += len(rob.joint_names)
        self._cols = np.array([k0 + k for k in fmap.joint_index], dtype=np.int64)
        self.n_q = len(self.scene.joint_names)

    @property
    def max_margin(self) -> float:
        """The largest margin (m) the map's "allowed" is proven for: its stopping distance plus ``cspace_contact``."""
        return self.map.stopping_distance + float(self.map.header.get("contact", self.tol.cspace_contact))

    def prepare(self) -> "CombinedChecker":
        """Load the map's lookup arrays (idempotent)."""
        self.map.prepare()
        return self

    def _check(self, Q_flat: np.ndarray, Q_pin: np.ndarray, margin: float) -> CombinedBatch:
        bad = np.argwhere(~np.isfinite(Q_flat))
        if len(bad):  # never a verdict from a NaN, whichever joint holds it (the map's bins took it as forbidden)
            r, k = (int(x) for x in bad[0])
            raise ForbiddenMapError(f"Q row {r}: joint {self.scene.joint_names[k]!r} = {Q_flat[r, k]}: every value must "
                                    "be finite")
        if not (math.isfinite(margin) and 0.0 <= margin <= self.max_margin):
            raise ForbiddenMapError(f"margin {margin!r} m: the map {self.map.path.name} proves links {self.map.links} clear "
                                    f"by at most its stopping distance {self.map.stopping_distance} m; rebuild it with "
                                    f"--stopping-distance {margin} for a larger margin")
        allowed = self.map.allowed_many(Q_flat[:, self._cols])
        status = np.where(allowed, CombinedStatus.FREE, CombinedStatus.MAP_FORBIDDEN).astype(np.int8)
        if np.any(allowed):  # the geometric part only where the map lets the configuration through
            hit = np.asarray(self.geometric.collides(Q_pin[allowed], margin=margin), dtype=bool)
            status[np.flatnonzero(allowed)[hit]] = CombinedStatus.COLLISION
        return CombinedBatch(status, status != CombinedStatus.FREE)

    def check_many(self, Q, *, margin: float | None = None) -> CombinedBatch:
        """Verdicts for ``Q`` ``(M, n_q)`` rad (the scene's flat joint vectors); ``margin`` (m) for the other
        pairs, default the map's stopping distance."""
        Q = np.ascontiguousarray(np.asarray(Q, dtype=np.float64))
        if Q.ndim != 2 or Q.shape[1] != self.n_q:
            raise ForbiddenMapError(f"Q: expected shape (M, {self.n_q}), got {Q.shape}")
        m = self.map.stopping_distance if margin is None else float(margin)
        return self._check(Q, self.model.pin_q(Q), m)

    def check_many_pin(self, Q, *, margin: float = 0.0) -> CombinedBatch:
        """Verdicts for ``Q`` ``(M, nq)`` in ``pin_model``'s order (the backend interface's), ``margin`` (m) for the
        other pairs."""
        Q = np.ascontiguousarray(np.asarray(Q, dtype=np.float64))
        return self._check(np.ascontiguousarray(self.model.scene_q(Q)), Q, float(margin))

    def collides_many(self, Q) -> np.ndarray:
        """``(M,) bool``: collision (or not proven free) per row of ``Q`` ``(M, n_q)``."""
        return self.check_many(Q).collision
