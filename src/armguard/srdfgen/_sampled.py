"""MoveIt's sampled collision matrix (``method="sampled"``): its rules and sample counts, on exact distances.

The rules (MoveIt Setup Assistant's ``computeDefaultCollisions``): a pair in contact in more than
95 % of :data:`ALWAYS_SAMPLES` random configurations is *Always*; a pair never within the margin
in ``samples`` random configurations is *Never*; the others stay checked, with the first random
configuration where they came within it as their witness.

The random configurations are drawn in chunks of :data:`CHUNK` and evaluated :data:`BLOCK` rows
at a time: every pair not yet seen within the margin gets its exact distance at each row of the
block from one shared Checker (``PairEvaluator.all``, the pair's geometry rows only), and a pair
leaves the blocks at its first row within the margin.  The configurations drawn and the entries
are those of :func:`sampled_reference` -- every pair's distance at every configuration, the rule
as stated -- which differs only in evaluating the pairs already witnessed too.

(A Checker per pair, each pair's own culled yes/no, cost more to build than it saved: kinova
25.6 s against 0.12 s at 10^4 samples; talos's 1,326 pairs over 100 s and 1.1 GB against 13 s.)
"""

from __future__ import annotations

import numpy as np

from .._errors import VerificationError
from ._matrix import MatrixEntry

__all__ = ["ALWAYS_SAMPLES", "ALWAYS_FRACTION", "sampled", "sampled_reference", "random_configurations"]

ALWAYS_SAMPLES = 200
ALWAYS_FRACTION = 0.95
CHUNK = 2000  # random configurations drawn at a time (the draws are the same whatever is evaluated)
BLOCK = 250  # configurations per verdict call: a pair stops at the block of its first hit


def random_configurations(setup, n: int, rng) -> np.ndarray:
    """``(n, n_q)`` uniform in the joint limits of ``setup`` (flat scene order)."""
    Q = np.repeat(setup.home[None, :], n, axis=0)
    Q[:] = setup.lower + (setup.upper - setup.lower) * rng.random((n, len(setup.home)))
    return Q


def _always(ev, setup, todo, entries, rng, advance) -> list:
    """MoveIt's Always rule on ``todo``; returns the pairs left for the Never rule."""
    cols = np.asarray(todo, dtype=np.int64)
    D = ev.all(random_configurations(setup, ALWAYS_SAMPLES, rng), pairs=cols)
    _finite(D, setup, todo)
    frac = np.mean(D <= 0.0, axis=0)
    left = []
    for i, k in enumerate(todo):
        p = setup.pairs[k]
        if frac[i] > ALWAYS_FRACTION:
            entries[k] = MatrixEntry(p.link1, p.link2, "Always", "disabled", None, float(np.min(D[:, i])),
                                     f"in contact in {frac[i]:.0%} of {ALWAYS_SAMPLES} random configurations", ALWAYS_SAMPLES)
            advance()
        else:
            left.append(k)
    return left


def _finish(ev, setup, left, entries, samples, first, first_d, first_q, advance) -> None:
    for i, k in enumerate(left):
        p = setup.pairs[k]
        if first[i] < 0:
            entries[k] = MatrixEntry(p.link1, p.link2, "Never", "disabled", None, float("nan"),
                                     f"not within the margin in {samples} random configurations", samples)
        else:
            q = tuple(float(x) for x in ev.pin(first_q[i][None, :])[0])
            entries[k] = MatrixEntry(p.link1, p.link2, None, "witnessed", q, float(first_d[i]),
                                     f"within the margin at random configuration {first[i]}", int(first[i]) + 1)
        advance()


def sampled(ev, setup, todo, entries, margin, samples, seed, advance) -> None:
    """MoveIt's rules (module docstring) for the pairs ``todo``: Always from distances at
    :data:`ALWAYS_SAMPLES` configurations, then Never from ``ev``'s exact distances, block by block,
    each pair until its first configuration within ``margin``."""
    rng = np.random.default_rng(seed)
    left = _always(ev, setup, todo, entries, rng, advance)
    first = np.full(len(left), -1)
    first_d = np.full(len(left), np.nan)
    first_q = np.zeros((len(left), len(setup.home)))
    done = 0
    while done < samples and np.any(first < 0):
        n = min(CHUNK, samples - done)
        Q = random_configurations(setup, n, rng)
        for s in range(0, n, BLOCK):
            open_ = np.flatnonzero(first < 0)
            if not len(open_):
                break
            D = ev.all(Q[s:s + BLOCK], pairs=[left[i] for i in open_])
            _finite(D, setup, [left[i] for i in open_])
            for j, i in enumerate(open_):
                hit = np.flatnonzero(D[:, j] <= margin)
                if len(hit):  # the first within the margin is the witness
                    first[i], first_d[i], first_q[i] = done + s + hit[0], D[hit[0], j], Q[s + hit[0]]
        done += n
    _finish(ev, setup, left, entries, samples, first, first_d, first_q, advance)


def _finite(D: np.ndarray, setup, ks) -> None:
    """No verdict from a distance that is not finite: a VerificationError naming the first such pair."""
    if not np.all(np.isfinite(D)):
        p = setup.pairs[ks[int(np.argwhere(~np.isfinite(D))[0][1])]]
        raise VerificationError(f"a sampled distance of {p.link1} - {p.link2} is not finite: no verdict")


def sampled_reference(ev, setup, todo, entries, margin, samples, seed, advance) -> None:
    """:func:`sampled` as the rule states it: every pair's exact distance at every configuration
    (slow: the tests' reference)."""
    rng = np.random.default_rng(seed)
    left = _always(ev, setup, todo, entries, rng, advance)
    cols = np.asarray(left, dtype=np.int64)
    first = np.full(len(left), -1)
    first_d = np.full(len(left), np.nan)
    first_q = np.zeros((len(left), len(setup.home)))
    done = 0
    while done < samples and len(cols):
        n = min(CHUNK, samples - done)
        Q = random_configurations(setup, n, rng)
        D = ev.all(Q, pairs=cols)
        _finite(D, setup, left)
        for i in np.flatnonzero(first < 0):
            hit = np.flatnonzero(D[:, i] <= margin)
            if len(hit):
                first[i], first_d[i], first_q[i] = done + hit[0], D[hit[0], i], Q[hit[0]]
        done += n
    _finish(ev, setup, left, entries, samples, first, first_d, first_q, advance)
