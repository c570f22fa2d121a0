"""Confident verification: a trajectory verified on a copy of the scene whose uncertainly placed
bodies are grown by their confidence ellipsoid's extent (the displacement model: ``_checks.py``).

**Confident verification** (:func:`verify_with_confidence`): each of the ``n`` placements with
a displacement (rank ``r_i > 0``) gets its own radius, ``k_i² = χ²_{r_i}.ppf(confidence^(1/n))``,
so that ``P(m_i ≤ k_i) = confidence^(1/n)``.  Each event ``{m_i ≤ k_i}`` is a symmetric convex set
(an ellipsoidal cylinder) of the placements' joint Gaussian displacement, so by the Gaussian
correlation inequality (Royen 2014; Latała & Matlak 2017) ``P(every m_i ≤ k_i) ≥ Π P(m_i ≤ k_i)
= confidence`` *whatever the correlation between the placements* -- two objects found through
one camera whose pose is uncertain share its error.  (Šidák's split; before, one radius
``k² = χ²_r.ppf(confidence)`` of the summed rank ``r`` for all, valid too but wider: two
four-dof placements at 0.999 took k = 5.11 where 4.47 each suffice, five six-dof ones 7.73
where 5.12 do.)  Every point of a placed body then lies within ``k_i σ_max`` of its nominal
place.  The verification runs on a scene copy whose placed bodies are grown by ``k_i σ_max``
(their own points' ``σ_max``: translation and the rotational sweep about ``o``); for a
robot-base placement every body is grown by ``k_i σ_max`` of the base's displacement evaluated
over that body's points (the body moving by ``D⁻¹`` relative to the arm is the same relative
motion; a body placed too grows by both) and the workspace box shrunk by it.  Grown shapes contain the Minkowski sum
(:func:`armguard.uncertainty._grow.grow_shape`), so ``safe`` holds with probability at least
``confidence``.

**A held payload** (a body picked up after an uncertain FIND: WORKMATE's PICKUP) carries its
placement's displacement with it.  Its placement names the payload, with the pose of the payload's
frame P in W at the moment the relation holds (the grasp) and the relation's covariance: moved with
the hand by a rigid motion ``T``, the payload's true pose is ``T D X̄ = (T D T⁻¹) T X̄``; the
conjugate displacement moves the carried points exactly as ``D`` moved them at the grasp (distances
and directions turned by ``T``), so the payload is grown by the ``k σ_max`` of its shapes posed at
that pose, once, for the whole trajectory.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import stats

from ..model import scene_of
from .._errors import UncertaintyError
from ._checks import _check_placements, _confidence, _lift2
from ._grow import grow_shape
from .pose3 import UncertainPose3

__all__ = ["ConfidentVerification", "verify_with_confidence"]


@dataclass(frozen=True)
class ConfidentVerification:
    """:func:`verify_with_confidence`'s answer: ``report`` (the verifier's, on the grown scene);
    ``confidence``; ``k`` (the largest placement's Mahalanobis radius); ``dof`` (the placements'
    summed rank); ``growth`` (body or payload -> m it was grown by); ``workspace_shrink`` (m);
    ``scene`` (the grown copy); ``radii`` (placement -> its ``k_i``, module docstring)."""

    report: object
    confidence: float
    k: float
    dof: int
    growth: dict
    workspace_shrink: float
    scene: object
    radii: dict = field(default_factory=dict)

    @property
    def safe(self) -> bool:
        """True only when the grown scene verifies SAFE: safe with probability >= ``confidence``."""
        return bool(self.report.safe)

    @property
    def status(self):
        """The verifier's :class:`armguard.verify.VerificationStatus` on the grown scene."""
        return self.report.status


def verify_with_confidence(scene, trajectory, placements, confidence: float = 0.999, **verify_options) -> ConfidentVerification:
    """Verify ``trajectory`` so that SAFE holds with probability >= ``confidence`` under ``placements``.

    The placed bodies (and, for a robot-base placement, every body; for a payload's placement, the
    payload) are grown by the confidence ellipsoid's extent ``k σ_max`` (module docstring) on a
    copy of ``scene``, which ``armguard.verify`` then checks with ``verify_options``
    (``stopping_distance``, ``method``, …).
    A robot-base placement needs a scene with one robot (another robot's links would have to
    grow too): otherwise UncertaintyError.
    """
    # a Model: its scene; a snapshot (Scene.copy holds the scene's lock) from which everything below
    # is read: another thread's edit could otherwise add a body that the check would see ungrown
    scene = scene_of(scene, "verification").copy()
    from ..verify import verify

    _confidence(confidence)
    placements = _check_placements(scene, placements, payloads=True)
    dof = sum(p.rank for p in placements)
    radii = _radii(placements, float(confidence))
    growth = {b: 0.0 for b in scene.bodies}
    held = {}
    shrink = 0.0
    for p in placements:
        k = radii[p.name]
        if p.name in scene.payloads:
            X_WP = p.pose.mean if isinstance(p.pose, UncertainPose3) else _lift2(p.pose.mean)[0]
            held[p.name] = k * p.sigma_max([s.transformed(X_WP) for s in scene.payloads[p.name].shapes])
            continue
        if p.name in scene.bodies:
            growth[p.name] += k * p.sigma_max(scene.bodies[p.name].shapes)
            continue
        if len(scene.robots) > 1:
            raise UncertaintyError(f"placement {p.name!r}: a robot-base placement is supported in a scene with one "
                                   f"robot; scene {scene.name!r} has {list(scene.robots)}")
        for b, body in scene.bodies.items():
            growth[b] += k * p.sigma_max(body.shapes)
        ws = scene.workspace
        if ws is not None:
            from ..geometry import Box

            box = Box(0.5 * (ws.lo + ws.hi), 0.5 * (ws.hi - ws.lo))
            shrink += k * p.sigma_max([box])
    grown = scene.copy()
    for b, g in growth.items():
        if g > 0.0:
            body = scene.bodies[b]
            disabled = [pair for pair in scene.disabled_pairs if b in pair]
            grown.remove_body(b)
            grown.add_body(b, [grow_shape(s, g) for s in body.shapes], category=body.category)
            for pair in disabled:
                grown.disable_pair(*sorted(pair))
    for name, g in held.items():
        if g > 0.0:
            _grow_payload(grown, scene, name, g)
    if shrink > 0.0:
        ws = scene.workspace
        if np.any(ws.hi - ws.lo <= 2.0 * shrink):
            raise UncertaintyError(f"verify_with_confidence: the workspace box shrinks by {shrink:.3g} m on each side "
                                   "and vanishes; no trajectory can be verified at this confidence")
        grown.set_workspace(ws.lo + shrink, ws.hi - shrink)
    report = verify(grown, trajectory, **verify_options)
    grew = {b: g for b, g in growth.items() if g > 0.0} | {b: g for b, g in held.items() if g > 0.0}
    return ConfidentVerification(report, float(confidence), max(radii.values(), default=0.0), dof, grew, shrink, grown,
                                 radii)


def _radii(placements, confidence: float) -> dict:
    """Placement name -> ``k_i``: ``k_i² = χ²_{r_i}.ppf(confidence^(1/n))`` over the ``n`` placements
    of rank > 0 (0 for a placement without displacement; module docstring)."""
    n = sum(p.rank > 0 for p in placements)
    each = confidence ** (1.0 / n) if n else confidence
    return {p.name: math.sqrt(float(stats.chi2.ppf(each, p.rank))) if p.rank > 0 else 0.0 for p in placements}


def _grow_payload(grown, scene, name: str, g: float) -> None:
    """Payload ``name`` of ``grown`` (a copy of ``scene``) grown by ``g`` m, held where it was, its
    disabled pairs kept."""
    p = scene.payloads[name]
    disabled = [pair for pair in scene.disabled_pairs if name in pair]
    grown.release_payload(name, grown.home(p.robot))  # as a body for a moment, wherever: it is removed
    grown.remove_body(name)
    grown.attach_payload(name, p.robot, p.link, [grow_shape(s, g) for s in p.shapes], p.X_LP)
    for pair in disabled:
        grown.disable_pair(*sorted(pair))
