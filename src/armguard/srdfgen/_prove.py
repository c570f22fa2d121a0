"""Branch and bound over the joints of one link pair: proven never within the margin, or a witness.

For a box ``B = [lo, hi]`` of the pair's joints (the others fixed: they move both links
rigidly), with centre ``c`` and half-widths ``h``, every point of either link moves at most
``h . lever`` from its place at ``c`` (the certified verifier's lever-arm bound,
:mod:`armguard.verify._motion`; Schwarzer, Saha & Latombe, "Exact collision checking of robot
paths", 2002), so for every ``q`` in ``B``

    d(q) >= d(c) - h . (lever_A + lever_B).

A box is *proven* when that bound exceeds ``margin`` (plus the verifier's contact tolerance); a
centre with ``d(c) <= margin`` is a *witness* (the pair comes within the margin there, and the
search stops); any other box is split in two along the joint of largest ``h_j weight_j``.  A box
that would have to be split below ``min_width`` rad, or a search that runs out of
``max_evaluations``, leaves the pair *undecided*.  A NaN distance is never read as clear.

Before the search, ``home`` and ``presample`` random configurations look for an easy witness (a
pair that collides somewhere usually does so in a large region).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np

from .._errors import VerificationError

__all__ = ["PairVerdict", "PairProof", "prove_pair"]


class PairVerdict(str, enum.Enum):
    NEVER = "never"  # proven: no configuration within the limits brings the pair within the margin
    WITNESSED = "witnessed"  # a configuration found where it comes within the margin
    UNDECIDED = "undecided"  # neither, within the limits of the search


@dataclass(frozen=True)
class PairProof:
    """One pair's search: verdict, the witness (flat scene q) and its distance (m), work done.

    ``boxes`` the boxes proven clear (their union is the pair's joint box when NEVER),
    ``evaluations`` distance evaluations, ``smallest_width`` rad the narrowest box split to,
    ``lower_bound`` m the least certified lower bound over the proven boxes (NEVER only).
    """

    verdict: PairVerdict
    witness: np.ndarray | None
    distance: float
    evaluations: int
    boxes: int
    smallest_width: float
    lower_bound: float


def prove_pair(evaluate, home: np.ndarray, joints, lower: np.ndarray, upper: np.ndarray, weight: np.ndarray, *,
               margin: float = 0.0, contact: float = 1e-6, min_width: float = 1e-3, max_evaluations: int = 200_000,
               batch: int = 2048, presample: int = 256, rng=None) -> PairProof:
    """Search one pair (module docstring).

    Parameters
    ----------
    evaluate : callable ``(Q (M, n_q) flat scene q) -> (M,) m``
        The pair's signed distance at each row.
    home : (n_q,) the flat configuration the other joints keep.
    joints : the flat indices of the pair's joints; ``lower``, ``upper`` ``(n_q,)`` their limits.
    weight : (len(joints),) m/rad, ``lever_A + lever_B`` on those joints.
    """
    joints = np.asarray(joints, dtype=np.int64)
    weight = np.asarray(weight, dtype=np.float64)
    if not np.all(np.isfinite(weight)):
        return PairProof(PairVerdict.UNDECIDED, None, np.nan, 0, 0, np.inf, np.nan)
    home = np.asarray(home, dtype=np.float64)
    lo0, hi0 = lower[joints].astype(np.float64), upper[joints].astype(np.float64)
    rng = np.random.default_rng(0) if rng is None else rng
    evaluations = 0

    def run(Qj: np.ndarray) -> np.ndarray:
        nonlocal evaluations
        Q = np.repeat(home[None, :], len(Qj), axis=0)
        Q[:, joints] = Qj
        d = np.asarray(evaluate(Q), dtype=np.float64).reshape(-1)
        if d.shape != (len(Qj),):
            raise VerificationError(f"the distance hook returned shape {d.shape} for {len(Qj)} configurations")
        evaluations += len(Qj)
        return d

    def witness(Qj, d, k) -> PairProof:
        q = home.copy()
        q[joints] = Qj[k]
        return PairProof(PairVerdict.WITNESSED, q, float(d[k]), evaluations, boxes, float(np.min(2 * h_min)), np.nan)

    boxes = 0
    h_min = np.full(1, np.inf)
    if len(joints) == 0:  # nothing moves the pair relative to itself: one evaluation decides
        d = run(np.zeros((1, 0)))
        if np.isfinite(d[0]) and d[0] <= margin:
            return witness(np.zeros((1, 0)), d, 0)
        ok = np.isfinite(d[0]) and d[0] > margin + contact
        return PairProof(PairVerdict.NEVER if ok else PairVerdict.UNDECIDED, None, float(d[0]), evaluations, int(ok), 0.0,
                         float(d[0]))
    if presample:  # home, then random configurations
        Qs = np.concatenate([home[joints][None, :], lo0 + rng.random((presample, len(joints))) * (hi0 - lo0)])
        d = run(Qs)
        hit = np.flatnonzero(np.isfinite(d) & (d <= margin))
        if len(hit):
            return witness(Qs, d, int(hit[np.argmin(d[hit])]))
    stack = [(lo0[None, :], hi0[None, :])]
    undecided = False
    lower_bound = np.inf
    while stack:
        los, his, n = [], [], 0
        while stack and n < batch:  # the newest boxes first (depth first), gathered into one batch
            a, b = stack.pop()
            los.append(a)
            his.append(b)
            n += len(a)
        lo, hi = (los[0], his[0]) if len(los) == 1 else (np.concatenate(los), np.concatenate(his))
        if len(lo) > batch:  # evaluate one batch now, the rest later
            stack.append((lo[batch:], hi[batch:]))
            lo, hi = lo[:batch], hi[:batch]
        c = 0.5 * (lo + hi)
        h = 0.5 * (hi - lo)
        d = run(c)
        hit = np.flatnonzero(np.isfinite(d) & (d <= margin))
        if len(hit):
            return witness(c, d, int(hit[np.argmin(d[hit])]))
        contrib = h * weight
        bound = d - contrib.sum(axis=1)
        free = bound > margin + contact  # False for NaN
        boxes += int(np.count_nonzero(free))
        if np.any(free):
            lower_bound = min(lower_bound, float(np.min(bound[free])))
        rest = np.flatnonzero(~free)
        if not len(rest):
            continue
        ax = np.argmax(contrib[rest], axis=1)
        width = 2.0 * h[rest, ax]
        split = width > min_width
        if not np.all(split):
            undecided = True
        rest, ax = rest[split], ax[split]
        if not len(rest):
            continue
        if evaluations + 2 * len(rest) > max_evaluations:
            undecided = True
            break
        h_min = np.minimum(h_min, float(np.min(h[rest, ax])))
        mid = c[rest, ax]
        lo1, hi1 = lo[rest].copy(), hi[rest].copy()
        lo2, hi2 = lo[rest].copy(), hi[rest].copy()
        r = np.arange(len(rest))
        hi1[r, ax] = mid
        lo2[r, ax] = mid
        stack.append((np.concatenate([lo1, lo2]), np.concatenate([hi1, hi2])))
    verdict = PairVerdict.UNDECIDED if undecided else PairVerdict.NEVER
    return PairProof(verdict, None, np.nan, evaluations, boxes, float(np.min(2 * h_min)),
                     lower_bound if verdict is PairVerdict.NEVER else np.nan)
