"""MoveIt's sampled collision matrix (``method="sampled"``): its rules and sample counts, on verdicts.

The rules (MoveIt Setup Assistant's ``computeDefaultCollisions``): a pair in contact in more than
95 % of :data:`ALWAYS_SAMPLES` random configurations is *Always*; a pair never within the margin
in ``samples`` random configurations is *Never*; the others stay checked, with the first random
configuration where they came within it as their witness.

Only a yes/no per pair and configuration is needed, so :func:`sampled` asks each undecided link
pair the backend's fastest verdict, :class:`PairVerdicts` (``Checker.collides`` over a Model whose
only active pairs are that link pair's geometry: on the analytic backend the fused kernel's yes/no
mode, with bounding-sphere and box culls before the narrow phase and no penetration depth), in
blocks that stop at the pair's first confirmed hit, and drops a pair from the batches once
witnessed.  A verdict "within the margin" is confirmed by the pair's exact distance there (the
distance the witness reports), so a pair's outcome is the one :func:`sampled_reference` -- every
pair's distances at every configuration, the rule as stated -- gives on the same configurations.
"""

from __future__ import annotations

import numpy as np

from .._errors import VerificationError
from ._matrix import MatrixEntry

__all__ = ["ALWAYS_SAMPLES", "ALWAYS_FRACTION", "PairVerdicts", "sampled", "sampled_reference", "random_configurations"]

ALWAYS_SAMPLES = 200
ALWAYS_FRACTION = 0.95
CHUNK = 2000  # random configurations drawn at a time (the draws are the same whatever is evaluated)
BLOCK = 250  # configurations per verdict call: a pair stops at the block of its first hit


def random_configurations(setup, n: int, rng) -> np.ndarray:
    """``(n, n_q)`` uniform in the joint limits of ``setup`` (flat scene order)."""
    Q = np.repeat(setup.home[None, :], n, axis=0)
    Q[:] = setup.lower + (setup.upper - setup.lower) * rng.random((n, len(setup.home)))
    return Q


class PairVerdicts:
    """``(k, Q (M, n_q)) -> (M,) bool``: link pair ``k`` of ``setup`` within ``margin`` at each row of ``Q``.

    ``Checker.collides(margin=margin)`` of ``backend`` over a Model whose only active pairs are link
    pair ``k``'s geometry (one Checker per pair, built at its first use).  A backend's contact level
    may be a tolerance above ``margin`` (the analytic kernel's ``Tolerances.length``): a True is a
    candidate that :func:`sampled` confirms with the exact distance; a False is final: a backend's
    ``collides`` must not say clear where its distance is within the margin (checked on the analytic
    backend by ``tests/test_srdf_sampled.py``)."""

    KEEP = 4  # Checkers kept at once (the pairs in turn: talos's 1,500 pairs kept every one, 9.4 GB and rising)

    def __init__(self, model, setup, backend: str | None = "analytic", options=None, margin: float = 0.0) -> None:
        self.model, self.setup, self.backend, self.options, self.margin = model, setup, backend, options, float(margin)
        self._checkers: dict = {}

    def checker(self, k: int):
        chk = self._checkers.pop(k, None)
        if chk is not None:
            self._checkers[k] = chk  # the most recent last
        else:
            while len(self._checkers) >= self.KEEP:
                del self._checkers[next(iter(self._checkers))]
            from ..cspace._clearance import checker_over

            p = self.setup.pairs[k]
            scene = self.setup.scene.copy()
            for cp in scene.allowed_pairs():
                if {cp.a, cp.b} != {p.owner1, p.owner2}:
                    scene.disable_pair(cp.a, cp.b)
            chk = self._checkers[k] = checker_over(self.model, scene, self.backend, self.options)
        return chk

    def __call__(self, k: int, Q: np.ndarray) -> np.ndarray:
        chk = self.checker(k)
        return np.asarray(chk.collides(chk.model.pin_q(Q), margin=self.margin), dtype=bool)


def _always(ev, setup, todo, entries, rng, advance) -> list:
    """MoveIt's Always rule on ``todo``; returns the pairs left for the Never rule."""
    cols = np.asarray(todo, dtype=np.int64)
    D = ev.all(random_configurations(setup, ALWAYS_SAMPLES, rng), pairs=cols)
    if not np.all(np.isfinite(D)):
        raise VerificationError("a sampled distance is not finite: no verdict")
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


def sampled(ev, verdicts, setup, todo, entries, margin, samples, seed, advance) -> None:
    """MoveIt's rules (module docstring) for the pairs ``todo``: Always from distances at
    :data:`ALWAYS_SAMPLES` configurations, then Never from ``verdicts`` (:class:`PairVerdicts`),
    confirmed by ``ev``'s exact distance at each candidate until the first within ``margin``."""
    rng = np.random.default_rng(seed)
    left = _always(ev, setup, todo, entries, rng, advance)
    n_q = len(setup.home)
    first = np.full(len(left), -1)
    first_d = np.full(len(left), np.nan)
    first_q = np.zeros((len(left), n_q))
    done = 0
    while done < samples and np.any(first < 0):
        n = min(CHUNK, samples - done)
        Q = random_configurations(setup, n, rng)
        for i in np.flatnonzero(first < 0):
            k = left[i]
            if not setup.pairs[k].joints:  # fixed to each other: one distance decides it, at any configuration
                d = float(ev(k, Q[:1])[0])
                if not np.isfinite(d):
                    raise VerificationError(f"a sampled distance of {setup.pairs[k].link1} - {setup.pairs[k].link2} "
                                            "is not finite: no verdict")
                if d <= margin:
                    first[i], first_d[i], first_q[i] = done, d, Q[0]
                continue
            for s in range(0, n, BLOCK):
                hit = verdicts(k, Q[s:s + BLOCK])
                for r in np.flatnonzero(hit):  # candidates in order: the first within the margin is the witness
                    d = float(ev(k, Q[s + r:s + r + 1])[0])
                    if not np.isfinite(d):
                        raise VerificationError(f"a sampled distance of {setup.pairs[k].link1} - {setup.pairs[k].link2} "
                                                "is not finite: no verdict")
                    if d <= margin:
                        first[i], first_d[i], first_q[i] = done + s + r, d, Q[s + r]
                        break
                if first[i] >= 0:
                    break
        done += n
    _finish(ev, setup, left, entries, samples, first, first_d, first_q, advance)


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
        if not np.all(np.isfinite(D)):
            raise VerificationError("a sampled distance is not finite: no verdict")
        for i in np.flatnonzero(first < 0):
            hit = np.flatnonzero(D[:, i] <= margin)
            if len(hit):
                first[i], first_d[i], first_q[i] = done + hit[0], D[hit[0], i], Q[hit[0]]
        done += n
    _finish(ev, setup, left, entries, samples, first, first_d, first_q, advance)
