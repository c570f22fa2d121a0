"""Certified edges for motion planners: is the straight joint-space motion ``q0 -> q1`` free?

A sampling planner asks this of thousands of short edges (OMPL's ``MotionValidator``, MoveIt's and
Drake's edge checks).  Those peers sample the edge every 0.01-0.05 rad and can step over a thin
obstacle between two samples; :meth:`Verifier.check_edges` answers for every configuration of the
edge, with the lever-arm bounds of the certified verifier (:mod:`._motion`, per pair over the joints
between its two links' common ancestor and either link: :func:`._motion.relative_joints`).

**The covering** (Schwarzer, Saha & Latombe, *Adaptive dynamic collision checking for single and
multiple articulated robots in complex environments*, IEEE T-RO 21(3), 2005, §III: an evaluated
configuration with clearances ``d_p`` is the centre of a free interval).  Along
``q(s) = q0 + s (q1 - q0)`` pair ``p``'s clearance shrinks by at most ``rate_p |s' - s|``, so an
evaluation at ``s`` proves every ``s'`` with ``|s' - s| < rho = min_p (d_p - m) / rate_p`` at least
``m`` (the margin) from every obstacle.  Both ends are evaluated first; then, widest first, each
interval not yet covered by two neighbouring evaluations' radii is evaluated at its middle and split
in two.  The edge is

* ``CLEAR`` when the radii cover ``[0, 1]``: certified, not sampled;
* ``COLLISION`` at the first evaluation whose smallest gap ``min_p d_p - m`` is at most
  ``Tolerances.verify_contact``: a configuration of the edge in contact (or within the margin),
  found widest gap first, so in the middle of a long collision rather than at its start (the first
  contact along the edge: :meth:`Verifier.verify` of the two-knot trajectory);
* ``INCOMPLETE`` when ``max_evaluations`` are spent (``Tolerances.edge_max_evaluations``, 1000, by
  default: a grazing edge), never ``CLEAR``.

Every evaluation is one ``pair_distances`` of the moving robot's pairs; the per-pair arithmetic is
the certified verifier's :func:`._advance.advance_step` (its ``step`` is ``rho``).  A NaN clearance
is an error, never a verdict.
"""

from __future__ import annotations

import enum
import heapq
import math
import time as _time
from dataclasses import dataclass

import numpy as np

from .._errors import KinematicsError, VerificationError
from ._advance import advance_step
from ._record import _Run
from ._timelaw import finite_array

__all__ = ["EdgeStatus", "EdgeResults", "check_edges_on"]


class EdgeStatus(enum.IntEnum):
    """The verdict on one edge (``EdgeResults.code`` holds these values)."""

    CLEAR = 0  #: every configuration of the edge at least the margin from every obstacle (certified)
    COLLISION = 1  #: a configuration of the edge found in contact (within the margin)
    INCOMPLETE = 2  #: the evaluation budget was spent before either was proven: no verdict


@dataclass(frozen=True)
class EdgeResults:
    """The verdicts on ``M`` edges ``Q0[i] -> Q1[i]`` (:meth:`Verifier.check_edges`).

    Attributes
    ----------
    code : (M,) int8
        :class:`EdgeStatus` values.
    s : (M,) float64, 1
        Where along the edge (0 at ``Q0[i]``, 1 at ``Q1[i]``) the configuration in contact was found;
        NaN unless ``COLLISION``.
    q : (M, n) float64
        That configuration (the robot's joints, its order); NaN rows unless ``COLLISION``.
    distance : (M,) float64, m
        Its smallest clearance (at most ``margin + Tolerances.verify_contact``); NaN unless ``COLLISION``.
    pair : tuple of (str, str) or None
        Its closest pair (scene owners, as :class:`armguard.verify.Collision` names them).
    evaluations : (M,) int64
        Clearance evaluations spent on each edge.
    robot : str
    joint_names : tuple of str
    margin : float, m
    elapsed_s : float
        Wall time of the whole call.
    """

    code: np.ndarray
    s: np.ndarray
    q: np.ndarray
    distance: np.ndarray
    pair: tuple
    evaluations: np.ndarray
    robot: str
    joint_names: tuple
    margin: float
    elapsed_s: float

    def __len__(self) -> int:
        return len(self.code)

    @property
    def status(self) -> list:
        """``[EdgeStatus]`` per edge."""
        return [EdgeStatus(int(c)) for c in self.code]

    @property
    def clear(self) -> np.ndarray:
        """``(M,) bool``: the edges certified free (an INCOMPLETE edge is not)."""
        return self.code == EdgeStatus.CLEAR

    def counts(self) -> dict:
        """``{status name: number of edges}``."""
        return {st.name.lower(): int(np.sum(self.code == st)) for st in EdgeStatus}

    def summary(self) -> str:
        c = self.counts()
        ev = self.evaluations
        med = float(np.median(ev)) if len(ev) else 0.0
        return (f"{len(self)} edges of {self.robot!r}: {c['clear']} clear, {c['collision']} in collision, "
                f"{c['incomplete']} incomplete (margin {self.margin * 1e3:g} mm; evaluations per edge: median "
                f"{med:g}, max {int(ev.max()) if len(ev) else 0}; {self.elapsed_s * 1e3:.1f} ms)")


def _rows(Q, name: str, n: int, joint_names) -> np.ndarray:
    Q = finite_array(Q, name)
    if Q.ndim == 1:
        Q = Q[None, :]
    if Q.ndim != 2 or Q.shape[1] != n:
        raise VerificationError(f"{name}: expected shape (M, {n}) or ({n},), one value per joint {list(joint_names)}, "
                                f"got {np.shape(Q)}")
    return Q


def _within_limits(rob, Q: np.ndarray, name: str, tol) -> None:
    """The ends within the joint limits (then the whole straight edge is), else the culprit named."""
    if bool(np.all(rob.within_limits(Q, tol=tol))):
        return
    for i, q in enumerate(Q):
        try:
            rob.check_limits(q, tol=tol)
        except KinematicsError as exc:
            raise VerificationError(f"{name}[{i}]: {exc}") from None


def _budget(max_evaluations, tol) -> int:
    if max_evaluations is None:
        return int(tol.edge_max_evaluations)
    if isinstance(max_evaluations, bool) or not isinstance(max_evaluations, (int, np.integer)) or max_evaluations < 2:
        raise VerificationError(f"max_evaluations: expected an integer >= 2 (both ends), got {max_evaluations!r}")
    return int(max_evaluations)


def check_edges_on(verifier, st, Q0, Q1, robot, margin, max_evaluations) -> EdgeResults:
    """:meth:`Verifier.check_edges` on one state ``st`` of the scene (its clearance model and configurations)."""
    t_start = _time.perf_counter()
    model, base_q = st.model, st.base
    rname = verifier._robot_of(None, robot)
    rob = verifier.scene.robots[rname]
    names = tuple(rob.joint_names)
    Q0 = _rows(Q0, "Q0", len(names), names)
    Q1 = _rows(Q1, "Q1", len(names), names)
    if Q0.shape != Q1.shape:
        raise VerificationError(f"Q0 and Q1: expected the same number of edges, got {len(Q0)} and {len(Q1)}")
    m = float(margin) if isinstance(margin, (int, float, np.floating, np.integer)) and not isinstance(margin, bool) else math.nan
    if not (math.isfinite(m) and m >= 0.0):
        raise VerificationError(f"margin: expected a finite number >= 0 (m), got {margin!r}")
    budget = _budget(max_evaluations, verifier.tol)
    _within_limits(rob, Q0, "Q0", verifier.tol)
    _within_limits(rob, Q1, "Q1", verifier.tol)
    base, k0, k1 = verifier._flat(rname, base_q)
    run = _Run(model, base, k0, k1, rname)
    if not run.moving.any():
        raise VerificationError(f"robot {rname!r} has no pair to check (no shapes, or every pair with it disabled)")
    contact = verifier.tol.verify_contact
    M = len(Q0)
    code = np.full(M, EdgeStatus.CLEAR, dtype=np.int8)
    s_hit = np.full(M, math.nan)
    q_hit = np.full((M, len(names)), math.nan)
    d_hit = np.full(M, math.nan)
    pair: list = [None] * M
    evals = np.zeros(M, dtype=np.int64)
    dQ = np.zeros(model.n_q)
    for i in range(M):
        q0, q1 = Q0[i], Q1[i]
        dq = q1 - q0
        dQ[k0:k1] = dq
        rates = model.pair_rates(dQ)
        if not np.all(np.isfinite(rates)):
            raise VerificationError("the motion bound is infinite (an unbounded prismatic joint): an edge cannot be certified")
        run.n = 0  # one record per edge: its rows are not kept beyond it
        verdict = _cover(run, q0, q1, dq, rates, m, contact, budget)
        evals[i] = run.n
        if verdict is None:
            continue
        code[i] = verdict[0]
        if verdict[0] == EdgeStatus.COLLISION:
            _, s, row, p = verdict
            s_hit[i] = s
            q_hit[i] = run.Q[row]
            d_hit[i] = run.D[row, p]
            pair[i] = (model.owner_a[p], model.owner_b[p])
    return EdgeResults(code, s_hit, q_hit, d_hit, tuple(pair), evals, rname, names, m, _time.perf_counter() - t_start)


def _evaluate(run, s, q0, q1, dq, rates, m):
    """Evaluate at ``s``: ``(row, gap, closest pair, radius rho)``; a NaN clearance is an error."""
    q = q0 if s == 0.0 else q1 if s == 1.0 else q0 + s * dq
    row = run.eval(0, s, q)
    d = run.D[row]
    g, p, rho, _ = advance_step(d, d, rates, m, 0.0, False)
    if g != g:
        raise VerificationError(f"a clearance is NaN at s = {s!r} of the edge: no verdict")
    return row, g, int(p), rho


def _cover(run, q0, q1, dq, rates, m, contact, budget):
    """The covering of one edge (see the module docstring): None when CLEAR, else
    ``(EdgeStatus.INCOMPLETE,)`` or ``(EdgeStatus.COLLISION, s, row, pair)``."""
    ends = []
    for s in (0.0, 1.0):
        row, g, p, rho = _evaluate(run, s, q0, q1, dq, rates, m)
        if g <= contact:
            return EdgeStatus.COLLISION, s, row, p
        ends.append(rho)
    heap = [(-((1.0 - ends[1]) - ends[0]), 0.0, ends[0], 1.0, ends[1])]  # widest uncovered interval first
    while heap:
        _, a, ra, b, rb = heapq.heappop(heap)
        lo, hi = a + ra, b - rb
        if not lo < hi:
            continue  # covered by the two ends' radii
        if run.n >= budget:
            return (EdgeStatus.INCOMPLETE,)
        s = 0.5 * (lo + hi)
        row, g, p, rho = _evaluate(run, s, q0, q1, dq, rates, m)
        if g <= contact:
            return EdgeStatus.COLLISION, s, row, p
        if s + rho < hi:
            heapq.heappush(heap, (-(hi - (s + rho)), s, rho, b, rb))
        if lo < s - rho:
            heapq.heappush(heap, (-((s - rho) - lo), a, ra, s, rho))
    return None
