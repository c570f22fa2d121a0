"""Guards for a list of link shapes and obstacles from static shapes: what a backend wraps.

``ClipModel(links, statics)`` builds one :class:`Guard` per link shape (given in its link frame)
and one :class:`Obstacle` per static shape (in W) once; :meth:`ClipModel.check` takes the links'
poses in W and answers the verdict for every pair.  ``answers = "verdicts"``: no distances.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._errors import ClipError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from ._guard import Guard
from ._obstacle import Obstacle
from ._procedure import ClipResult, ClipStatus, _pose, check

__all__ = ["ClipModel", "PairVerdict", "ModelVerdict"]


@dataclass(frozen=True)
class PairVerdict:
    """One (link shape, static shape) pair: names and its :class:`ClipResult`."""

    link: str
    obstacle: str
    result: ClipResult


@dataclass(frozen=True)
class ModelVerdict:
    """Every pair at one configuration; ``status`` INTERSECTED if any pair is, else MAYBE if any
    is, else CLEAR."""

    status: ClipStatus
    pairs: tuple[PairVerdict, ...]


class ClipModel:
    """``links``: ``(name, shape)`` pairs, each shape in its link frame L (several may share a
    name); ``statics``: ``(name, shape)`` pairs in W.  Keyword options go to
    :meth:`Guard.from_shape`."""

    answers = "verdicts"

    def __init__(self, links, statics, *, tol: Tolerances = DEFAULT_TOLERANCES, **guard_options) -> None:
        self.links = [(str(n), s) for n, s in links]
        self.statics = [(str(n), s) for n, s in statics]
        self.guards = [Guard.from_shape(s, tol=tol, **guard_options) for _, s in self.links]
        self.obstacles = [Obstacle.from_shape(s, name=n, tol=tol) for n, s in self.statics]
        self.tol = tol

    def check(self, X_W_links, *, subdivide: bool = True) -> ModelVerdict:
        """``X_W_links (n_link_shapes, 4, 4)``: each link shape's link pose in W."""
        X = _pose(X_W_links, "X_W_links").reshape(-1, 4, 4)
        if len(X) != len(self.guards):
            raise ClipError(f"ClipModel.check: {len(self.guards)} link shapes but {len(X)} poses")
        pairs = []
        for (ln, _), g, Xl in zip(self.links, self.guards, X):
            for ob in self.obstacles:
                pairs.append(PairVerdict(ln, ob.name, check(g, ob, Xl, None, subdivide=subdivide, tol=self.tol)))
        statuses = {p.result.status for p in pairs}
        for s in (ClipStatus.INTERSECTED, ClipStatus.MAYBE):
            if s in statuses:
                return ModelVerdict(s, tuple(pairs))
        return ModelVerdict(ClipStatus.CLEAR, tuple(pairs))

    @classmethod
    def from_scene(cls, scene, robot: str, **options) -> "ClipModel":
        """The model of one robot of an ``armguard`` scene against the scene's bodies; pose it
        with :meth:`link_poses`."""
        r = scene.robots[robot]
        links = [(name, sh) for name, shapes in r.link_shapes.items() for sh in shapes]
        statics = [(f"{bn}[{i}]", sh) for bn, body in scene.bodies.items() for i, sh in enumerate(body.shapes)]
        model = cls(links, statics, **options)
        model._robot = r
        model._index = np.array([r.link_names.index(n) for n, _ in links], dtype=np.int64)
        return model

    def link_poses(self, q) -> np.ndarray:
        """``(n_link_shapes, 4, 4)`` poses for joint values ``q`` (a model from :meth:`from_scene`)."""
        if not hasattr(self, "_robot"):
            raise ClipError("ClipModel.link_poses: only for a model built by from_scene")
        return self._robot.forward_kinematics(np.asarray(q, dtype=np.float64))[self._index]
