"""What both Detectors share: argument checks and Ranger's status rule."""

from __future__ import annotations

import math

import numpy as np

from .._errors import DetectionError

__all__ = ["check_length", "require_pairs", "status_code"]

ST_CLEAR, ST_WARNING, ST_COLLISION, ST_INCOMPLETE = 0, 1, 2, 3  # as armguard.detect._kernel


def check_length(value, name: str) -> float:
    """``value`` as a finite length >= 0 (m), else a DetectionError naming ``name``."""
    try:
        x = float(value)
    except (TypeError, ValueError) as exc:
        raise DetectionError(f"{name}: expected a number of metres, got {value!r}") from exc
    if not math.isfinite(x) or x < 0.0:
        raise DetectionError(f"{name}: must be finite and >= 0, got {x}")
    return x


def status_code(dmin: float, lbmin: float, level: float, thr_eff: float) -> int:
    """Ranger's status from the least evaluated distance ``dmin`` and the least lower bound of the
    pairs left unevaluated ``lbmin`` (``inf``: none), as the analytic kernel decides it: COLLISION
    when an evaluated pair is within the collision ``level``; CLEAR or WARNING only when no
    unevaluated pair can be within ``thr_eff`` (WARNING also when one is within it but no
    unevaluated pair can collide); otherwise INCOMPLETE — never CLEAR by omission."""
    if dmin <= level:
        return ST_COLLISION
    if lbmin > thr_eff:
        return ST_WARNING if dmin <= thr_eff else ST_CLEAR
    if dmin <= thr_eff and lbmin > level:
        return ST_WARNING
    return ST_INCOMPLETE


def require_pairs(scene, cs, active, with_terrain: bool) -> None:
    """A DetectionError when nothing would be checked (no pair, or none on the ``active`` arm), or
    nothing the configuration moves (every pair between two fixed shapes, and no workspace box
    around a moving one): the detector would otherwise say CLEAR, the same at every configuration,
    without having looked at the arm."""
    if with_terrain:
        return
    pa, pb = np.asarray(cs.pair_a, np.int64), np.asarray(cs.pair_b, np.int64)
    keep = np.ones(len(pa), bool)
    if active is not None and len(pa):
        r = list(cs.robot_names).index(active) if active in cs.robot_names else -1
        keep = (cs.owner_robot[pa] == r) | (cs.owner_robot[pb] == r)
    moves = np.array([scene.moves(o) for o in cs.owner_names], bool)
    n_all = int(np.count_nonzero(keep))
    n_moving = int(np.count_nonzero(keep & (moves[pa] | moves[pb]))) if len(pa) else 0
    box = bool(cs.has_workspace) and bool(moves.any())  # the box holds every moving robot shape
    if n_moving == 0 and not box:
        on = f" on arm {active!r}" if active is not None else ""
        what = (" (every pair is disabled or excluded)" if n_all == 0 else
                f" with a shape the configuration moves ({n_all} pairs, all between fixed shapes)")
        raise DetectionError(f"scene {scene.name!r} has no pair to check{on}{what}: "
                             "no verdict can be given; enable a pair, add a body or a workspace box")
