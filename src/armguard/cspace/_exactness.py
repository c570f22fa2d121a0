"""Sampling a map against the exact check: allowed-but-colliding (must be 0) and false-forbidden shares."""

from __future__ import annotations

import enum
import os
from dataclasses import dataclass

import numpy as np

from ..model import scene_of
from .._errors import ForbiddenMapError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from ._clearance import link_obstacle_scene, resolve_scene

__all__ = ["ExactnessReport", "ExactnessStatus", "check_exactness", "random_configurations"]

_BATCH = 200_000  # configurations per exact-check call (bounds the memory of a 10^6 sample)


class ExactnessStatus(enum.Enum):
    CONSERVATIVE = "conservative"  #: no sampled configuration the map allows collides
    VIOLATED = "violated"  #: the map allows a sampled configuration that collides (a defect)


@dataclass(frozen=True)
class ExactnessReport:
    """A sample of ``n`` configurations, map vs the exact Detector (mapped links vs static bodies, the map's stopping distance).

    Attributes
    ----------
    status : ExactnessStatus
    n : int
    colliding : int
        Configurations the exact check finds within the stopping distance.
    allowed_but_colliding : int
        Configurations the map allows that collide (0 for a correct map).
    false_forbidden : int
        Configurations the map forbids that are clear.
    false_forbidden_share : float
        ``false_forbidden / n``: the volume share the map forbids beyond the truth.
    false_forbidden_of_free : float
        ``false_forbidden / (n - colliding)``: the share of free configurations the map refuses.
    """

    status: ExactnessStatus
    n: int
    colliding: int
    allowed_but_colliding: int
    false_forbidden: int
    false_forbidden_share: float
    false_forbidden_of_free: float


def random_configurations(scene, n: int, seed: int = 0) -> np.ndarray:
    """``(n, n_q)`` flat scene configurations (rad or m), every joint with finite limits uniform within them
    (the others at ``scene.default_q()``).  A map's joints 1–3 span the robot's limits, so they are uniform
    over the map's grid; the other joints do not move the mapped links."""
    scene = scene_of(scene)  # a Model: its scene
    rng = np.random.default_rng(seed)
    lo, hi = [], []
    for rob in scene.robots.values():
        lo.extend(np.asarray(rob.lower, dtype=np.float64))
        hi.extend(np.asarray(rob.upper, dtype=np.float64))
    lo, hi = np.array(lo), np.array(hi)
    finite = np.isfinite(lo) & np.isfinite(hi)
    base = np.asarray(scene.flat_q(scene.default_q()), dtype=np.float64)
    Q = np.repeat(base[None, :], n, axis=0)
    cols = np.flatnonzero(finite)
    Q[:, cols] = rng.uniform(lo[cols], hi[cols], size=(n, len(cols)))
    return Q


def check_exactness(fmap, scene=None, *, n: int = 10_000, seed: int = 0, Q=None,
                    tol: Tolerances = DEFAULT_TOLERANCES) -> ExactnessReport:
    """Compare ``fmap`` with the exact check on ``n`` random configurations (or the rows of ``Q`` ``(M, n_q)`` rad)."""
    from ..detect import Detector

    if scene is None and fmap.header.get("model") is None:
        raise ForbiddenMapError("the map was built from a Scene object: pass scene= (armguard cspace info: --model)")
    if scene is None or isinstance(scene, (str, os.PathLike)):
        from ._combined import map_model

        # the files checked against the map's before they are sampled: its recorded relative path, read in another
        # working directory, sampled another model's files (and passed a map that was not conservative)
        scene = map_model(fmap, scene).scene
    scene, _ = resolve_scene(scene)
    det = Detector(link_obstacle_scene(scene, fmap.robot, fmap.links), threshold=0.0,
                   stopping_distance=fmap.stopping_distance, tol=tol)
    if Q is None:
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
            raise ForbiddenMapError(f"n: expected a number of configurations >= 1, got {n!r} (no sample proves nothing)")
        Q = random_configurations(scene, int(n), seed)
    try:
        Q = np.asarray(Q, dtype=np.float64)
    except (TypeError, ValueError):
        raise ForbiddenMapError(f"Q: expected an (M, n_q) array of joint values (rad), got {type(Q).__name__}") from None
    if Q.ndim != 2 or Q.shape[1] != len(scene.joint_names) or len(Q) == 0:
        raise ForbiddenMapError(f"Q: expected an (M, {len(scene.joint_names)}) array with M >= 1 (no sample proves "
                                f"nothing), got shape {Q.shape}")
    if not np.all(np.isfinite(Q)):
        r, k = (int(x) for x in np.argwhere(~np.isfinite(Q))[0])
        raise ForbiddenMapError(f"Q row {r}: joint {scene.joint_names[k]!r} = {Q[r, k]}: every value must be finite")
    k0 = 0
    for name, rob in scene.robots.items():
        if name == fmap.robot:
            break
        k0 += len(rob.joint_names)
    cols = [k0 + k for k in fmap.joint_index]
    fmap.prepare()
    n_col = n_abc = n_ff = 0
    for a in range(0, len(Q), _BATCH):
        part = Q[a:a + _BATCH]
        hit = det.collides_many(part)
        ok = fmap.allowed_many(part[:, cols])
        n_col += int(hit.sum())
        n_abc += int((ok & hit).sum())
        n_ff += int((~ok & ~hit).sum())
    M = len(Q)
    free = M - n_col
    return ExactnessReport(ExactnessStatus.CONSERVATIVE if n_abc == 0 else ExactnessStatus.VIOLATED, M, n_col, n_abc,
                           n_ff, n_ff / M if M else 0.0, n_ff / free if free else 0.0)
