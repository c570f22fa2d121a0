"""The brute-force reference detector: every allowed pair, shape by shape, no pruning.

Slow and obviously correct: the scene's own world-frame geometry (:meth:`Scene.shapes_at`),
its own pair list (:meth:`Scene.allowed_pairs`) and the geometry core's public
:func:`armguard.geometry.distance` for every shape pair; the workspace distance is the least
gap between a shape's extreme point along each axis and the matching wall (Ranger §2),
computed with the shape's support function.  The fast detector is tested against it.
"""

from __future__ import annotations

import math

import numpy as np

from ..model import scene_of
from .._tolerance import DEFAULT_TOLERANCES
from ._report import CATEGORIES

__all__ = ["check_reference", "ReferenceResult"]

_CAT = {
    "arm-arm": "arm",
    "arm-vehicle": "environment",
    "arm-environment": "environment",
    "arm-payload": "payload",
    "payload-vehicle": "payload",
    "payload-environment": "payload",
    "payload-payload": "payload",
}


class ReferenceResult:
    """``min_distance`` ``(4,)`` per category (inf where none), ``pairs``: list of
    ``(owner_a, owner_b, category, distance)`` of every shape pair, ``status`` code
    (0 clear, 1 warning, 2 collision)."""

    def __init__(self, min_distance, pairs, status):
        self.min_distance, self.pairs, self.status = min_distance, pairs, status


def _wall_distance(shape, lo, hi) -> float:
    best = math.inf
    for ax in range(3):
        e = np.zeros(3)
        e[ax] = 1.0
        best = min(best, hi[ax] - float(shape.support(e)[ax]), float(shape.support(-e)[ax]) - lo[ax])
    return best


def check_reference(scene, q, threshold: float, *, stopping_distance: float = 0.0, active: str | None = None,
                    tol=DEFAULT_TOLERANCES) -> ReferenceResult:
    """All pairs of ``scene`` at ``q`` by brute force; see the module docstring."""
    scene = scene_of(scene, "check")  # a Model: its scene
    from ..geometry import distance

    items = scene.shapes_at(q)
    by_owner: dict[str, list] = {}
    robot_of: dict[str, str | None] = {}
    for it in items:
        by_owner.setdefault(it.owner, []).append(it.shape)
        robot_of[it.owner] = it.robot
    mins = np.full(4, np.inf)
    pairs = []
    for cp in scene.allowed_pairs():
        if active is not None and robot_of.get(cp.a) != active and robot_of.get(cp.b) != active:
            continue
        cat = _CAT[cp.category.value]
        for sa in by_owner.get(cp.a, ()):
            for sb in by_owner.get(cp.b, ()):
                d = distance(sa, sb, tol).distance
                pairs.append((cp.a, cp.b, cat, d))
                c = CATEGORIES.index(cat)
                mins[c] = min(mins[c], d)
    ws = scene.workspace
    if ws is not None:
        for it in items:
            if it.kind == "body" or (active is not None and it.robot != active):
                continue
            d = _wall_distance(it.shape, ws.lo, ws.hi)
            pairs.append((it.owner, "workspace", "workspace", d))
            mins[2] = min(mins[2], d)
    dmin = float(np.min(mins)) if len(pairs) else math.inf
    level = max(tol.length, stopping_distance)  # the contact tolerance (geometry.intersects)
    status = 2 if dmin <= level else (1 if dmin <= max(threshold, stopping_distance) else 0)
    return ReferenceResult(mins, pairs, status)
