"""Certified verification of a commanded trajectory against the terrain (conservative advancement).

The verifier's method (:mod:`armguard.verify._verify`) with the terrain clearance as the
clearance function.  Every Trajectory segment moves on the joint-space line
``q(s) = q0 + s dq``; by the verifier's lever-arm bound (:mod:`armguard.verify._motion`) every
point of moving shape ``k`` moves at most ``rate_k |s' - s|`` with ``rate_k = |dq| . lever_k``,
whatever the configuration.  Let ``d_k(s)`` be the exact signed distance from shape ``k`` to the
nearest *known* column and ``u_k(s)`` to the nearest *unknown* one (a filled cell, or the slabs
beyond the map's edge; :class:`TerrainGuard`).  A column is fixed, so both are minima of
1-Lipschitz functions of the shape's motion: ``|d_k(s') - d_k(s)| <= rate_k |s' - s|`` (same for
``u_k``), and so are their caps ``min(d_k, R)`` at the query's reach ``R`` (a link beyond ``R``
is only known to be beyond it).  From an evaluation at ``s`` the sweep steps to

    s' = s + min_k min( (min(d_k, R) - m) / rate_k , (min(u_k, R) - m - mu) / rate_k )

(``m`` the stopping distance, ``mu`` the guard's ``unknown_margin``), and on ``[s, s']`` every
shape stays at least ``m`` from every known column and ``m + mu`` from every unknown one — the
whole segment is covered by such intervals or the sweep stops, so no contact, however brief or
thin, lies between evaluations.  It stops at

* a known column within ``m + verify_contact``: COLLISION, the first one along the trajectory;
* an unknown column within ``m + mu + verify_contact``: the arm would pass over terrain nobody
  has seen.  The time is recorded, the unknown columns are dropped from the step rule, and the
  sweep goes on over the known ones (a later known contact is still a COLLISION); without one
  the verdict is INCOMPLETE — never SAFE;
* the evaluation budget (``Tolerances.verify_max_evaluations``): INCOMPLETE.

:func:`verify_with_terrain` runs :func:`armguard.verify` on the scene and this sweep and returns
one :class:`~armguard.verify.VerificationReport` with a ``terrain`` category.
"""

from __future__ import annotations

import dataclasses
import math
import time as _time
from dataclasses import dataclass, field

import numpy as np

from ..model import scene_of
from .._errors import TerrainError, VerificationError
from ..verify import Clearance, ClearanceProfile, Collision, VerificationReport, VerificationStatus
from ..verify._advance import advance_step
from ..verify._timelaw import segment_times
from ._guard import TERRAIN, TerrainCell, TerrainGuard

__all__ = ["TerrainSweep", "sweep_terrain", "verify_with_terrain"]


@dataclass(frozen=True)
class TerrainSweep:
    """The terrain half of a verification (:func:`sweep_terrain`).

    Attributes
    ----------
    status : VerificationStatus
        SAFE (proven: every shape stays ``m`` from the known columns and ``m + unknown_margin`` from
        the unknown ones), COLLISION (``first_contact``) or INCOMPLETE (``unknown_at`` or the budget).
    first_contact : Collision | None
        The first known-terrain contact (``obstacle`` "terrain", ``feature`` a :class:`TerrainCell`).
    unknown_at : Clearance | None
        Where the arm first came within ``m + unknown_margin`` of unseen terrain.
    time : (M,) float64, s
        The evaluated configurations' times, increasing.
    clearance : (M,) float64, m
        Least distance from a moving shape to any column there, capped at ``reach``.
    min_clearance : float, m
        Its least value, at ``min_clearance_time`` (s), by ``min_clearance_owner``; ``lower_bound`` a proven lower bound on the terrain clearance over the
        verified part of the path (capped at ``reach``).
    evaluations, intervals : int
        Terrain queries made; joint-space intervals proven clear.
    reach, stopping_distance, unknown_margin : float, m
    reason : str
    elapsed_s : float, s
    """

    status: VerificationStatus
    first_contact: Collision | None
    unknown_at: Clearance | None
    time: np.ndarray = field(repr=False)
    clearance: np.ndarray = field(repr=False)
    min_clearance: float
    min_clearance_time: float
    min_clearance_owner: str
    lower_bound: float
    evaluations: int
    intervals: int
    reach: float
    stopping_distance: float
    unknown_margin: float
    reason: str
    elapsed_s: float


def _segments(trajectory):
    T = np.asarray(trajectory.times, dtype=np.float64)
    W = np.asarray(trajectory.waypoints, dtype=np.float64)
    if len(T) < 2:
        raise VerificationError("the trajectory has no segment")
    if not np.all(np.isfinite(W)):
        raise VerificationError("trajectory knot: contains NaN or infinite values")
    return T, W


def sweep_terrain(guard: TerrainGuard, trajectory, *, stopping_distance: float = 0.0, q_others=None,
                  reach: float | None = None) -> TerrainSweep:
    """Certified sweep of ``trajectory`` (one robot's) against ``guard``'s terrain (module docstring).

    ``stopping_distance`` (m): the terrain grows by it; ``q_others``: where the other robots stand
    (default: home); ``reach`` (m): the distance queries' reach (default
    ``max(guard.reach, 0.15, m + unknown_margin + 0.1)``: a larger reach takes longer steps far from the
    ground, each step costing more candidate columns)."""
    t_start = _time.perf_counter()
    scene, tol = guard.scene, guard.tol
    m = float(stopping_distance)
    if not (math.isfinite(m) and m >= 0.0):
        raise VerificationError(f"stopping_distance: expected a finite number >= 0 (m), got {stopping_distance!r}")
    mu = guard.unknown_margin
    R = max(guard.reach, 0.15, m + mu + 0.1) if reach is None else float(reach)
    if not (math.isfinite(R) and R > m + mu):
        raise TerrainError(f"reach: must be finite and > stopping distance + unknown_margin ({m + mu:g} m), got {R!r}")
    rname = getattr(trajectory, "robot_name", None)
    if rname not in scene.robots:
        raise VerificationError(f"robot {rname!r} is not in the scene; robots are {list(scene.robots)}")
    rob = scene.robots[rname]
    if tuple(trajectory.joint_names) != tuple(rob.joint_names):
        raise VerificationError(f"trajectory joints {list(trajectory.joint_names)} do not match robot {rname!r}")
    base = scene.default_q()
    for k, v in dict(q_others or {}).items():
        base[k] = np.asarray(v, dtype=np.float64)
    flat0 = scene.flat_q(base)
    k0 = 0
    for n, r in scene.robots.items():
        if n == rname:
            break
        k0 += len(r.joint_names)
    k1 = k0 + len(rob.joint_names)
    T, W = _segments(trajectory)
    inside = rob.within_limits(W, tol=tol)
    if not np.all(inside):
        i = int(np.argmin(inside))
        raise VerificationError(f"trajectory waypoints[{i}]: outside the joint limits of robot {rname!r}")
    K = len(guard.owners)
    contact, budget = tol.verify_contact, tol.verify_max_evaluations
    extra = np.r_[np.zeros(K), np.full(K, -mu)]  # the unknown columns count mu closer
    rec_t, rec_d, rec_o = [], [], []
    lower, intervals, evals = math.inf, 0, 0
    status, reason, first, unknown_at = VerificationStatus.SAFE, "", None, None

    def evaluate(q):
        known, unknown, res, cell, wit = guard.distances(q, reach=R)
        return np.minimum(known, R), np.minimum(unknown, R), cell, wit

    q_full = flat0.copy()
    for si in range(len(T) - 1):
        q0, q1 = W[si], W[si + 1]
        dq = np.zeros(guard.n_q)
        dq[k0:k1] = q1 - q0
        rate = guard.lever @ np.abs(dq)
        if not np.all(np.isfinite(rate)):
            raise VerificationError("the motion bound is infinite (an unbounded prismatic joint)")
        rates = np.r_[rate, rate]
        s, prev, L = 0.0, None, 0.0
        while True:
            q_full[k0:k1] = q1 if s >= 1.0 else q0 + s * (q1 - q0)
            known, unknown, cell, wit = evaluate(q_full)
            evals += 1
            d = np.r_[known, unknown] + extra
            both = np.minimum(known, unknown)
            _, _, _, lb = advance_step(both, prev if prev is not None else both, rate, m, L, prev is not None)
            if prev is not None:
                lower = min(lower, lb)
                intervals += 1
            prev = both
            t = float(segment_times(trajectory, [(T[si], T[si + 1], W[si], W[si + 1])], [0], [s])[0])
            rec_t.append(t)
            rec_d.append(float(both.min()))
            rec_o.append(guard.owners[int(np.argmin(both))])
            if unknown_at is None:
                ku = int(np.argmin(d[K:]))
                if d[K + ku] - m <= contact:  # unseen terrain within m + mu: recorded, then the known columns only
                    unknown_at = Clearance(float(unknown[ku]), t, guard.owners[ku], TERRAIN, TERRAIN,
                                           q_full[k0:k1].copy())
                    rc = cell[1, ku]
                    where = "off the map" if rc[0] < 0 else f"unseen cell ({rc[0]}, {rc[1]})"
                    reason = (f"terrain: {guard.owners[ku]} within {unknown[ku] * 1e3:.1f} mm of {where} at "
                              f"t = {t:.4f} s (unknown terrain within the stopping distance + {mu * 1e3:.0f} mm)")
            if unknown_at is not None:
                d[K:] = np.inf
            g, i_min, step, _ = advance_step(d, d, rates, m, 0.0, False)
            if g <= contact:  # a known column: the first contact
                k = int(i_min)
                rc = cell[0, k]
                first = Collision(time=t, q=q_full[k0:k1].copy(), distance=float(known[k]),
                                  link=guard.owners[k].split("/", 1)[-1], obstacle=TERRAIN, payload=None,
                                  feature=TerrainCell(int(rc[0]), int(rc[1]), True,
                                                      int(rc[0]) * guard.pyramid.map.shape[1] + int(rc[1])),
                                  p_W=0.5 * (wit[0, k, :3] + wit[0, k, 3:]), p_WA=wit[0, k, :3].copy(),
                                  p_WB=wit[0, k, 3:].copy(), a=guard.owners[k], b=TERRAIN, category=TERRAIN,
                                  check="link-terrain", objects=("arm", TERRAIN), segment=si)
                status = VerificationStatus.COLLISION
                break
            if s >= 1.0:
                break
            s_next = min(1.0, s + step)
            if not s_next > s:
                status, reason = VerificationStatus.INCOMPLETE, f"terrain: no progress in segment {si} (t = {t:.4f} s)"
                break
            if evals >= budget:
                status, reason = VerificationStatus.INCOMPLETE, f"terrain: evaluation budget ({budget}) spent at t = {t:.4f} s"
                break
            L, s = s_next - s, s_next
        if status is not VerificationStatus.SAFE:
            break
    if status is VerificationStatus.SAFE and unknown_at is not None:
        status = VerificationStatus.INCOMPLETE
    t_arr, d_arr = np.array(rec_t), np.array(rec_d)
    order = np.argsort(t_arr, kind="stable")
    t_arr, d_arr = t_arr[order], d_arr[order]
    i = int(np.argmin(d_arr))
    nearest = rec_o[int(order[i])]
    if status is VerificationStatus.SAFE:
        reason = f"terrain: proven at least {min(lower, R) * 1e3:.1f} mm clear ({evals} evaluations)"
    return TerrainSweep(status, first, unknown_at, t_arr, d_arr, float(d_arr[i]), float(t_arr[i]), nearest,
                        float(min(lower, d_arr.min())), evals, intervals, R, m, mu, reason,
                        _time.perf_counter() - t_start)


def _merge_profile(p: ClearanceProfile, sw: TerrainSweep) -> ClearanceProfile:
    """The scene's profile and the terrain's on one time axis: each category is NaN at the other's times."""
    t = np.r_[p.time, sw.time]
    order = np.argsort(t, kind="stable")
    n = len(p.time)
    cats = {}
    for c, y in p.by_category.items():
        cats[c] = np.r_[y, np.full(len(sw.time), np.nan)][order]
    cats[TERRAIN] = np.r_[np.full(n, np.nan), sw.clearance][order]
    overall = np.r_[p.overall, sw.clearance][order]
    return ClearanceProfile(t[order], overall, cats)


def verify_with_terrain(scene, trajectory, terrain, *, unknown_margin: float | None = None, reach: float | None = None,
                        **kwargs) -> VerificationReport:
    """:func:`armguard.verify` of ``trajectory`` in ``scene`` and :func:`sweep_terrain` against ``terrain``
    (a :class:`TerrainGuard`, or a pyramid / map for one), as one report.

    ``kwargs`` go to :func:`armguard.verify` (``stopping_distance``, ``method``, ``q_others`` ...);
    the terrain sweep is always certified, at the largest stopping distance the scene check used.
    The merged report: COLLISION if either part found one (``first_collision`` the earlier),
    else INCOMPLETE if either is, else SAFE; ``profile.by_category["terrain"]`` the terrain
    clearance (capped at the sweep's reach; NaN at the scene check's times and vice versa);
    ``min_clearance`` / its lower bound over both; ``reason`` says what the terrain sweep found.
    """
    scene = scene_of(scene, "verification")  # a Model: its scene
    from ..verify import verify

    scene = getattr(scene, "scene", scene)
    if not isinstance(terrain, TerrainGuard):
        terrain = TerrainGuard(scene, terrain, robot=getattr(trajectory, "robot_name", None),
                               **({} if unknown_margin is None else {"unknown_margin": unknown_margin}))
    elif unknown_margin is not None and unknown_margin != terrain.unknown_margin:
        raise TerrainError("unknown_margin: set it on the TerrainGuard passed in")
    rep = verify(scene, trajectory, **kwargs)
    sw = sweep_terrain(terrain, trajectory, stopping_distance=rep.stopping_distance, q_others=kwargs.get("q_others"),
                       reach=reach)
    S = VerificationStatus
    first = rep.first_collision
    if sw.first_contact is not None and (first is None or sw.first_contact.time < first.time):
        first = sw.first_contact
    if first is not None:
        status = S.COLLISION
    elif S.INCOMPLETE in (rep.status, sw.status):
        status = S.INCOMPLETE
    else:
        status = S.SAFE
    note = sw.reason
    if first is sw.first_contact and first is not None and note.startswith("terrain: ") and "unknown terrain" in note:
        # the sweep's note of unseen terrain (before its first contact) is not the collision: the headline said
        # "COLLISION - terrain: ... unseen cell ... at t = 0.82 s" for a contact with a seen cell at 1.12 s
        note = (f"contact with seen terrain at t = {first.time:.4f} s (before it, "
                + note[len("terrain: "):].replace(" (unknown terrain within", "; unknown terrain within", 1))
    reason = "; ".join(x for x in (rep.reason, note) if x)
    min_at = rep.min_clearance_at
    if sw.min_clearance < rep.min_clearance:
        k = sw.min_clearance_time
        min_at = Clearance(sw.min_clearance, k, sw.min_clearance_owner, TERRAIN, TERRAIN, np.asarray(trajectory.at(k), dtype=np.float64))
    lb = rep.min_clearance_lower_bound
    if rep.details.method == "certified":
        lb = min(lb, sw.lower_bound)
    details = dataclasses.replace(rep.details, samples_evaluated=rep.details.samples_evaluated + sw.evaluations,
                                  intervals_certified=rep.details.intervals_certified + (
                                      sw.intervals if rep.details.method == "certified" else 0))
    return dataclasses.replace(rep, status=status, first_collision=first,
                               min_clearance=min(rep.min_clearance, sw.min_clearance), min_clearance_at=min_at,
                               min_clearance_lower_bound=lb, profile=_merge_profile(rep.profile, sw), details=details,
                               reason=reason, elapsed_s=rep.elapsed_s + sw.elapsed_s)
