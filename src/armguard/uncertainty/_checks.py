"""Uncertain placements in the checks: clearance in sigmas, collision probability, confident verification.

An obstacle (a static body) or a robot's base is placed by an uncertain relation
(:class:`UncertainPlacement`).  The scene holds the nominal geometry (the body's shapes, the
robot's base at the relation's mean); the true geometry is the nominal moved by a random rigid
displacement ``D``.

**The displacement model.**  Write ``o`` (3,) for the placement's origin (the mean pose's
translation, m) and ``(δo, φ)`` for the displacement of that origin (m) and the small rotation
about it (rad).  A point ``x`` of the placed geometry moves by, to first order,

    δx = δo + φ × (x − o) = J(x) (δo, φ),    J(x) = [I₃ | −[x − o]×]   (3 × 6),

so its position covariance is ``Σ_x = J(x) Σ_o J(x)ᵀ`` with ``Σ_o`` the (6 × 6) covariance of
``(δo, φ)`` — the rotational part enters through the lever arm ``x − o``.  From the relations:

* ``UncertainPose3`` (left perturbation ``T = exp(ξ^) T̄``, ``ξ = (ρ, φ)``): the origin moves
  by ``δo = ρ + φ × o``, so ``(δo, φ) = A ξ`` with ``A = [[I, −[o]×], [0, I]]`` and
  ``Σ_o = A Σ Aᵀ`` (the same ``δx = ρ + φ × x`` written about ``o``); ``D = exp(ξ^)``.
* ``UncertainPose2`` (x, y, θ) lifted to SE(3) (a rotation about z at height 0): ``δo =
  (δx, δy, 0)``, ``φ = (0, 0, δθ)``; ``D = T(x, y, θ) T̄⁻¹`` (exactly additive at the origin).

**Clearance in sigmas** (:func:`clearance_sigmas`).  A pair at signed distance ``d`` with
witness points ``p_A``, ``p_B`` has ``n̂ = (p_A − p_B) / d`` (the direction that increases
``d`` when ``A`` moves).  Moving side A by ``δp_A`` and B by ``δp_B`` changes the distance by
``n̂ · (δp_A − δp_B)`` to first order, so its standard deviation is

    σ = sqrt( Σ_k g_k Σ_o,k g_kᵀ ),   g_k = n̂ᵀ (s_A,k J_k(p_A) − s_B,k J_k(p_B)),

summed over the independent placements ``k`` (``s = 1`` where the placement moves that side;
a placement that moves both sides moves the pair rigidly and leaves ``d`` unchanged).
``sigmas = d / σ``; ``p_linear = Φ(−d/σ)`` is the linearised one-sided estimate (not a bound).

**The conservative bound.**  A collision after the displacement needs some point of a moved
owner to move by at least ``d``: if ``D x ∈ B`` for ``x ∈ A`` then ``d ≤ |x − D x|``.  With
``Σ_o = L Lᵀ`` and ``m = |L⁺ (δo, φ)|`` (the Mahalanobis radius, ``m² ~ χ²(r)``, ``r`` the
rank of ``Σ_o``), every point of the owner moves by at most ``σ_max m``, where

    σ_max = max over the owner's points x of ‖J(x) L‖₂  ≤  sqrt(λ_max(Σ_δo)) + max|x − o| sqrt(λ_max(Σ_φ))

(the maximum of a norm of an affine function is at an extreme point: over the hull vertices,
plus the radius times ``sqrt(λ_max(Σ_φ))`` for the rounded shapes).  Hence

    P(collision) ≤ P(m ≥ d / σ_max) = 1 − χ²_r.cdf((d / σ_max)²),

``r = 3`` for a planar placement or a translation-only one (the classic 3-D ellipsoid bound)
and ``r = 6`` for a full SE(3) placement (a 3-D quantile would understate it).  Two placements
on a pair combine by Cauchy–Schwarz: ``σ_max = sqrt(σ₁² + σ₂²)`` with ``r = r₁ + r₂``; a group
(a category, the whole scene) uses its least ``d / σ_max`` and the rank of every placement in
it; an owner pair's ``d`` is its nearest element pair's.  The bound is conservative for translation-only
placements and first order in the rotation (the
covariance's own linearisation: the chord ``(R − I)(x − o)`` is replaced by ``φ × (x − o)``)
otherwise.

**Monte Carlo** (``samples > 0``): seeded draws of every placement, the moved owners' shapes
at ``q``, and the exact signed distance (``armguard.geometry.distance``; the workspace walls by
support) for every affected pair — for reporting, beside the bound.

**Confident verification**: :mod:`armguard.uncertainty._confident`.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field

import numpy as np
from scipy import stats

from ..model import kinematics_of
from .._errors import UncertaintyError
from .._tolerance import DEFAULT_TOLERANCES
from .._values import number
from . import se3 as _se3
from ._grow import grow_shape
from .pose2 import UncertainPose2
from .pose3 import UncertainPose3

__all__ = ["UncertainPlacement", "ClearanceStatus", "PairSigma", "GroupSigma", "SigmaReport", "clearance_sigmas",
           "grow_shape"]


def _skew(v: np.ndarray) -> np.ndarray:
    """``[v]×`` for ``v (..., 3)``: ``(..., 3, 3)``."""
    out = np.zeros(v.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


def _inv_many(X: np.ndarray) -> np.ndarray:
    """Inverses of rigid transforms ``(n, 4, 4)``."""
    out = np.zeros_like(X)
    Rt = np.swapaxes(X[:, :3, :3], -1, -2)
    out[:, :3, :3] = Rt
    out[:, :3, 3] = -np.einsum("nij,nj->ni", Rt, X[:, :3, 3])
    out[:, 3, 3] = 1.0
    return out


def _lift2(xyt: np.ndarray) -> np.ndarray:
    """(x, y, θ) rows ``(n, 3)`` -> SE(3) ``(n, 4, 4)``: rotation about z, at height 0."""
    xyt = np.atleast_2d(xyt)
    T = np.tile(np.eye(4), (len(xyt), 1, 1))
    c, s = np.cos(xyt[:, 2]), np.sin(xyt[:, 2])
    T[:, 0, 0], T[:, 0, 1], T[:, 1, 0], T[:, 1, 1] = c, -s, s, c
    T[:, 0, 3], T[:, 1, 3] = xyt[:, 0], xyt[:, 1]
    return T


@dataclass(frozen=True, eq=False)
class UncertainPlacement:
    """A body (``name`` a static body of the scene) or a robot base (``name`` a robot) placed by
    an uncertain relation to W: ``pose`` an :class:`UncertainPose3` (W -> the placed frame) or an
    :class:`UncertainPose2` (planar, lifted to SE(3): rotation about z at height 0).

    The scene's geometry is the nominal (the relation's mean); :attr:`origin` ``(3,)`` m is the
    mean's translation and :attr:`cov_origin` ``(6, 6)`` (m², m·rad, rad²) the covariance of the
    origin's displacement and the rotation about it ``(δo, φ)`` (module docstring)."""

    name: str
    pose: object
    origin: np.ndarray = field(init=False, repr=False)
    cov_origin: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise UncertaintyError(f"UncertainPlacement.name: expected a body or robot name, got {self.name!r}")
        if isinstance(self.pose, UncertainPose3):
            o = np.array(self.pose.mean[:3, 3])
            A = np.eye(6)
            A[:3, 3:] = -_skew(o)
            cov = A @ self.pose.cov @ A.T
        elif isinstance(self.pose, UncertainPose2):
            o = np.array([self.pose.mean[0], self.pose.mean[1], 0.0])
            idx = [0, 1, 5]
            cov = np.zeros((6, 6))
            cov[np.ix_(idx, idx)] = self.pose.cov
        else:
            raise UncertaintyError(f"UncertainPlacement.pose: expected an UncertainPose3 or UncertainPose2, "
                                   f"got {type(self.pose).__name__}")
        cov = 0.5 * (cov + cov.T)
        o.flags.writeable = False
        cov.flags.writeable = False
        object.__setattr__(self, "origin", o)
        object.__setattr__(self, "cov_origin", cov)

    @property
    def rank(self) -> int:
        """Degrees of freedom of the displacement: the rank of :attr:`cov_origin` (3 planar, 6 in
        space; eigenvalues below ``Tolerances.covariance_relative`` times the largest are zero)."""
        w = np.linalg.eigvalsh(self.cov_origin)
        top = float(w.max())
        return int(np.sum(w > top * DEFAULT_TOLERANCES.covariance_relative)) if top > 0.0 else 0

    def jacobian(self, x) -> np.ndarray:
        """``J(x) = [I | −[x − o]×]`` ``(..., 3, 6)`` for points ``x (..., 3)`` m in W."""
        x = np.asarray(x, dtype=np.float64)
        J = np.zeros(x.shape[:-1] + (3, 6))
        J[..., :3, :3] = np.eye(3)
        J[..., :, 3:] = -_skew(x - self.origin)
        return J

    def point_cov(self, x) -> np.ndarray:
        """``Σ_x = J(x) Σ_o J(x)ᵀ`` ``(..., 3, 3)`` m²: the position covariance of a placed point."""
        J = self.jacobian(x)
        return J @ self.cov_origin @ np.swapaxes(J, -1, -2)

    def sigma_max(self, shapes) -> float:
        """``max ‖J(x) L‖₂`` over the points of ``shapes`` (in W, m): the largest standard
        deviation of any point's displacement in any direction (module docstring)."""
        w, V = np.linalg.eigh(self.cov_origin)
        L = V * np.sqrt(np.clip(w, 0.0, None))
        sd_rot = math.sqrt(max(float(np.linalg.eigvalsh(self.cov_origin[3:, 3:]).max()), 0.0))
        best = 0.0
        for s in shapes:
            pts = np.atleast_2d(np.asarray(s.core_points, dtype=np.float64))
            JL = self.jacobian(pts) @ L
            best = max(best, float(np.max(np.linalg.norm(JL, ord=2, axis=(1, 2)))) + float(s.core_radius) * sd_rot)
        return best

    def sample_displacements(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """``(n, 4, 4)`` rigid displacements ``D`` (true = ``D`` · nominal) drawn with ``rng``."""
        if isinstance(self.pose, UncertainPose3):
            xi = rng.multivariate_normal(np.zeros(6), self.pose.cov, size=int(n), method="eigh")
            return _se3._exp(xi)
        draws = self.pose.sample(int(n), rng)
        return _lift2(draws) @ _se3._invert(_lift2(self.pose.mean)[0])


class ClearanceStatus(enum.Enum):
    """A pair's or a group's standing under the placements' uncertainty at one configuration."""

    CONFIDENT = "confident"  # the bound on the collision probability is within 1 - confidence
    AT_RISK = "at_risk"  # apart nominally, but the bound exceeds 1 - confidence
    COLLIDING = "colliding"  # touching or penetrating at the nominal placement


@dataclass(frozen=True)
class PairSigma:
    """One owner pair: ``distance`` m, its nearest element pair's (witnesses ``p_WA``, ``p_WB``, W, m),
    which ``sigma_max`` (m, the owners' worst-direction extent) makes ``p_bound`` (conservative) and the
    status; ``sigma`` m (the linearised std of a distance along its nearest direction) and ``sigmas``,
    of the element pair with the fewest sigmas (maybe a farther one: along the lever arm sigma is 0);
    ``p_linear`` Φ(−sigmas), an estimate; ``p_monte_carlo`` (None without samples); ``placements``."""

    a: str
    b: str
    category: str
    distance: float
    sigma: float
    sigmas: float
    sigma_max: float
    p_linear: float
    p_bound: float
    p_monte_carlo: float | None
    status: ClearanceStatus
    placements: tuple
    p_WA: np.ndarray
    p_WB: np.ndarray


@dataclass(frozen=True)
class GroupSigma:
    """A category (or the whole scene): its least-sigmas pair and the group's own probabilities
    (the bound over the group's least ``d / σ_max`` with the rank of all its placements; the
    Monte Carlo share of draws with any of its pairs colliding)."""

    nearest: PairSigma
    p_bound: float
    p_monte_carlo: float | None
    status: ClearanceStatus


@dataclass(frozen=True)
class SigmaReport:
    """:func:`clearance_sigmas`' answer: ``pairs`` (affected owner pairs, least sigmas first),
    ``by_category`` (category -> :class:`GroupSigma`), ``overall`` (:class:`GroupSigma` or
    ``None`` when no pair is affected), ``confidence``, ``samples``."""

    pairs: tuple
    by_category: dict
    overall: GroupSigma | None
    confidence: float
    samples: int

    @property
    def status(self) -> ClearanceStatus:
        return ClearanceStatus.CONFIDENT if self.overall is None else self.overall.status


def _bound(ratio: float, dof: int) -> float:
    """``1 − χ²_dof.cdf(ratio²)`` for ``ratio = d / σ_max`` (1 when touching or penetrating)."""
    if not ratio > 0.0:
        return 1.0
    if math.isinf(ratio) or dof == 0:
        return 0.0
    return float(stats.chi2.sf(ratio * ratio, dof))


def _status(d: float, p: float, confidence: float) -> ClearanceStatus:
    if d <= 0.0:
        return ClearanceStatus.COLLIDING
    return ClearanceStatus.CONFIDENT if p <= 1.0 - confidence else ClearanceStatus.AT_RISK


def _check_placements(scene, placements, *, payloads: bool = False) -> tuple:
    placements = (placements,) if isinstance(placements, UncertainPlacement) else tuple(placements)
    seen = set()
    for p in placements:
        if not isinstance(p, UncertainPlacement):
            raise UncertaintyError(f"placements: expected UncertainPlacement objects, got {type(p).__name__}")
        if p.name not in scene.bodies and p.name not in scene.robots and not (payloads and p.name in scene.payloads):
            held = f", payloads {list(scene.payloads)}" if payloads else ""
            raise UncertaintyError(f"placement {p.name!r}: not a body or robot{' or payload' if payloads else ''} of "
                                   f"scene {scene.name!r}; bodies are {list(scene.bodies)}, robots {list(scene.robots)}"
                                   + held)
        if p.name in seen:
            raise UncertaintyError(f"placement {p.name!r}: given twice (merge the relations first)")
        seen.add(p.name)
    return placements


def _moved_by(scene, placement: UncertainPlacement) -> set:
    """The owners a placement moves: the body, or the robot's links and the payloads it holds."""
    if placement.name in scene.bodies:
        return {placement.name}
    r = scene.robots[placement.name]
    out = {f"{placement.name}/{ln}" for ln in r.link_names}
    out.update(p.name for p in scene.payloads.values() if p.robot == placement.name)
    return out


def _consistent_rows(source, q, tries: int = 3):
    """:func:`_pair_rows` with a snapshot of the scene (``Scene.copy``, under its lock) of the same
    revision as the rows: a Detector's scene may be edited by another thread between its query and
    the reads of the shapes (a body added there had no rows but was read as moved).  Retried when
    the revision changed; :class:`UncertaintyError` if it changes on every try."""
    live = getattr(source, "scene", None) if not hasattr(source, "capabilities") else None
    for _ in range(tries):
        before = getattr(live, "revision", None)
        scene, q_scene, rows = _pair_rows(source, q)
        if live is None:  # a Checker's Model: immutable
            return scene, q_scene, rows
        with live.lock:
            snap, after = live.copy(), live.revision
        if after == before:
            return snap, q_scene, rows
    raise UncertaintyError(f"clearance_sigmas: the scene changed during each of {tries} tries (another thread's edits)")


def _pair_rows(source, q):
    """``(scene, q_scene, rows)``: rows of ``(a, b, category, d, p_WA, p_WB)`` from a Checker
    (``pair_distances``; ``q`` in pin_model's order) or a Detector (``q`` as it takes)."""
    from ..detect import CATEGORIES

    if hasattr(source, "capabilities") and hasattr(source, "model"):
        model = source.model
        r = source.pair_distances(q)
        pairs = model.pairs
        rows = zip(pairs.owner_a, pairs.owner_b, pairs.category, r.distance, r.p_WA, r.p_WB)
        return model.scene_for(), model.scene_q(q), list(rows)
    if hasattr(source, "pair_distances") and hasattr(source, "scene"):
        r = source.pair_distances(q)
        cats = [CATEGORIES[int(c)] for c in r.category]
        return source.scene, q, list(zip(r.owner_a, r.owner_b, cats, r.distance, r.p_WA, r.p_WB))
    raise UncertaintyError(f"clearance_sigmas: expected a Detector or a backend Checker, got {type(source).__name__}")


@dataclass(frozen=True)
class _Core:
    """A shape's core in W: ``core_points (n, 3)`` m and ``core_radius`` m (what ``sigma_max`` reads)."""

    core_points: np.ndarray
    core_radius: float


def _link_poses(scene, q_scene) -> dict:
    """Robot name -> ``(n_links, 4, 4)`` at ``q_scene``: the scene's Model moves the links (``pin_model``)."""
    kin = kinematics_of(scene)
    return kin.link_poses(q_scene) if kin is not None else {}


def _owner_cores(scene, q_scene) -> dict:
    """Owner -> the cores of its shapes in W at ``q_scene`` (posed points only: no shapes rebuilt)."""
    out: dict = {b: list(body.shapes) for b, body in scene.bodies.items()}
    fk = _link_poses(scene, q_scene)
    for rn, robot in scene.robots.items():
        X = fk[rn]
        for i, ln in enumerate(robot.link_names):
            for sh in robot.link_shapes.get(ln, ()):
                out.setdefault(f"{rn}/{ln}", []).append(
                    _Core(np.atleast_2d(sh.core_points) @ X[i, :3, :3].T + X[i, :3, 3], float(sh.core_radius)))
    for pn, p in scene.payloads.items():
        robot = scene.robots[p.robot]
        X = fk[p.robot][robot.link_index(p.link)] @ p.X_LP
        out[pn] = [_Core(np.atleast_2d(sh.core_points) @ X[:3, :3].T + X[:3, 3], float(sh.core_radius)) for sh in p.shapes]
    return out


def _workspace_distance(shapes, ws) -> float:
    """Signed distance of convex shapes inside the workspace box to its walls (solid outside):
    the least ``wall − support`` over the six walls (negative when a shape sticks out)."""
    best = math.inf
    for s in shapes:
        pts = np.atleast_2d(s.core_points)
        r = float(s.core_radius)
        best = min(best, float(np.min(ws.hi - (pts.max(axis=0) + r))), float(np.min((pts.min(axis=0) - r) - ws.lo)))
    return best


def clearance_sigmas(source, q, placements, *, confidence: float = 0.999, samples: int = 1000,
                     seed: int = 0) -> SigmaReport:
    """Clearance in sigmas and collision probabilities of every pair an uncertain placement moves.

    Parameters
    ----------
    source : armguard.Detector or a backend Checker answering distances (``armguard.checker``)
    q : one configuration (a Checker's: pin_model order ``(nq,)``; a Detector's: as it takes)
    placements : UncertainPlacement or a sequence of them (independent)
    confidence : float in (0, 1): the status threshold (``p_bound <= 1 − confidence`` is CONFIDENT)
    samples : int >= 0, Monte Carlo draws for the reported estimate (0: none)
    seed : the draws' ``numpy.random.default_rng`` seed

    Returns
    -------
    SigmaReport (module docstring: linearised sigmas, the χ² bound, the Monte Carlo share)
    """
    _confidence(confidence)
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or samples < 0:
        raise UncertaintyError(f"samples: expected an integer >= 0 (Monte Carlo draws; 0: none), got {samples!r}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
        raise UncertaintyError(f"seed: expected an integer, got {seed!r}")
    scene, q_scene, rows = _consistent_rows(source, q)
    placements = _check_placements(scene, placements)
    moved = [_moved_by(scene, p) for p in placements]
    cores = _owner_cores(scene, q_scene)
    smax_cache: dict = {}

    def smax(k: int, owner: str) -> float:
        if (k, owner) not in smax_cache:
            smax_cache[(k, owner)] = placements[k].sigma_max(cores.get(owner, ()))
        return smax_cache[(k, owner)]

    best: dict = {}  # owner pair -> (sigmas, PairSigma pieces) of the row with the fewest sigmas
    nearest: dict = {}  # owner pair -> (d, p_WA, p_WB) of its nearest row
    for a, b, cat, d, pa, pb in rows:
        d = float(d)
        ks = [k for k, m in enumerate(moved) if (a in m) != (b in m)]
        if not ks:
            continue
        n = (pa - pb) / d if abs(d) > 0.0 and np.linalg.norm(pa - pb) > 0.0 else None
        var, s2max = 0.0, 0.0
        for k in ks:
            p = placements[k]
            on_a = a in moved[k]
            # the side that moves and its witness point; the sign makes g the change of d
            x, sgn, owner = (pa, 1.0, a) if on_a else (pb, -1.0, b)
            if n is not None:
                g = sgn * (n @ p.jacobian(x))
                var += float(g @ p.cov_origin @ g)
            else:  # no direction (exact touching): the worst direction at the witness point
                var += float(np.linalg.eigvalsh(p.point_cov(x)).max())
            s2max += smax(k, owner) ** 2
        sigma, sig_max = math.sqrt(max(var, 0.0)), math.sqrt(s2max)
        sigmas = d / sigma if sigma > 0.0 else math.copysign(math.inf, d) if d != 0.0 else 0.0
        key = (a, b)
        if key not in best or sigmas < best[key][0]:
            best[key] = (sigmas, cat, d, sigma, sig_max, tuple(ks), np.array(pa), np.array(pb))
        if key not in nearest or d < nearest[key][0]:  # the bound and the status read the pair's nearest shapes:
            nearest[key] = (d, np.array(pa), np.array(pb))  # a row with fewer sigmas may be farther (sigma 0 there)
    shapes: dict[str, list] = {}
    if samples > 0:
        for it in scene.shapes_at(q_scene, poses=_link_poses(scene, q_scene)):
            shapes.setdefault(it.owner, []).append(it.shape)
    mc = _monte_carlo(scene, shapes, placements, moved, list(best), samples, seed) if samples > 0 else None
    pairs = []
    for key, (sigmas, cat, _, sigma, sig_max, ks, _, _) in best.items():
        d, pa, pb = nearest[key]  # sig_max is the owners', the same on every row of the pair
        dof = sum(placements[k].rank for k in ks)
        ratio = d / sig_max if sig_max > 0.0 else (math.inf if d > 0.0 else 0.0)
        pb_ = _bound(ratio, dof)
        p_lin = float(stats.norm.sf(sigmas)) if math.isfinite(sigmas) else (0.0 if sigmas > 0 else 1.0)
        p_mc = None if mc is None else float(np.mean(mc[key]))
        pairs.append(PairSigma(key[0], key[1], cat, d, sigma, sigmas, sig_max, p_lin, pb_, p_mc,
                               _status(d, pb_, confidence), tuple(placements[k].name for k in ks), pa, pb))
    pairs.sort(key=lambda p: p.sigmas)

    by_name = {p.name: p for p in placements}

    def group(members) -> GroupSigma:
        dof = sum(by_name[n].rank for n in sorted({n for m in members for n in m.placements}))
        ratios = [m.distance / m.sigma_max if m.sigma_max > 0.0 else (math.inf if m.distance > 0 else 0.0) for m in members]
        worst = min(ratios)
        pg = _bound(worst, dof)
        p_mc = None if mc is None else float(np.mean(np.any([mc[(m.a, m.b)] for m in members], axis=0)))
        d = min(m.distance for m in members)
        return GroupSigma(members[0], pg, p_mc, _status(d, pg, confidence))

    by_cat: dict = {}
    for p in pairs:
        by_cat.setdefault(p.category, []).append(p)
    return SigmaReport(tuple(pairs), {c: group(m) for c, m in by_cat.items()}, group(pairs) if pairs else None,
                       float(confidence), int(samples))


def _monte_carlo(scene, shapes, placements, moved, keys, samples: int, seed: int) -> dict:
    """Owner pair -> ``(samples,) bool``: collides in each seeded draw (exact distances)."""
    rng = np.random.default_rng(seed)
    D = [p.sample_displacements(samples, rng) for p in placements]
    eye = np.broadcast_to(np.eye(4), (samples, 4, 4))

    def pose(owner: str) -> np.ndarray:  # (samples, 4, 4): the owner's displacement per draw
        X = eye
        for k, m in enumerate(moved):
            if owner in m:
                X = D[k] @ X
        return X

    out = {}
    for a, b in keys:
        Xa = pose(a)
        if b == "workspace":
            out[(a, b)] = np.array([_workspace_distance([sh.transformed(X) for sh in shapes.get(a, ())], scene.workspace)
                                    <= 0.0 for X in Xa])
            continue
        # distances are invariant under a common rigid motion: re-pose one side only, by the
        # relative displacement of A seen from B
        X_rel = _inv_many(pose(b)) @ Xa
        hit = np.zeros(samples, dtype=bool)
        for sa in shapes.get(a, ()):
            for sb in shapes.get(b, ()):
                hit |= _moved_hits(sa, sb, X_rel)
        out[(a, b)] = hit
    return out


def _moved_hits(sa, sb, X_rel: np.ndarray) -> np.ndarray:
    """``(n,) bool``: does ``sa`` moved by each ``X_rel (n, 4, 4)`` touch or penetrate ``sb``?

    A round side (Sphere, Capsule) is re-posed and measured by the batched exact kernels
    (signed distance ``<= 0``); two polytopes are clipped (:mod:`armguard.clip`, whose polyhedral
    guards settle every check at the second level), any MAYBE left measured by ``distance``."""
    from ..clip import Guard, Obstacle, check_many
    from ..geometry import Capsule, Polygon, Sphere, distance
    from ..geometry import batch as gb

    def ends(sh):
        return (sh.center, sh.center) if isinstance(sh, Sphere) else (sh.p0, sh.p1)

    round_a, round_b = isinstance(sa, (Sphere, Capsule)), isinstance(sb, (Sphere, Capsule))
    if round_a or round_b:
        mover, other, X = (sa, sb, X_rel) if round_a else (sb, sa, _inv_many(X_rel))
        p0, p1 = (np.einsum("nij,j->ni", X[:, :3, :3], e) + X[:, :3, 3] for e in ends(mover))
        if isinstance(other, (Sphere, Capsule)):
            q0, q1 = ends(other)
            return gb.capsule_capsule(p0, p1, mover.radius, q0, q1, other.radius).distance <= 0.0
        return gb.capsule_convex(p0, p1, np.full(len(X), mover.radius), other).distance <= 0.0
    if isinstance(sa, Polygon) and isinstance(sb, Polygon):
        return np.array([distance(sa.transformed(X), sb).distance <= 0.0 for X in X_rel])
    guard, ob, X = (sa, sb, X_rel) if not isinstance(sa, Polygon) else (sb, sa, _inv_many(X_rel))
    status, _ = check_many(Guard.from_shape(guard), Obstacle.from_shape(ob), np.ascontiguousarray(X))
    hit = status == 1
    for i in np.flatnonzero(status == 2):
        hit[i] = distance(guard.transformed(X[i]), ob).distance <= 0.0
    return hit


def _confidence(value) -> float:
    """``value`` as a probability in (0, 1); else an UncertaintyError (text was a raw ValueError)."""
    return number(value, "confidence", UncertaintyError, low=0.0, high=1.0, low_open=True, high_open=True)
