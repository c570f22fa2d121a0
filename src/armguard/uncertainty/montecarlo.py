"""Monte Carlo validation of the first-order estimates (Smith & Cheeseman, Section 5.3).

Every input relation is drawn independently from its Gaussian with a seeded
``numpy.random.Generator``, pushed through the exact (nonlinear) operation, and the sample
mean and covariance (unbiased, ``ddof = 1``) are compared with the linearised ones.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from .._errors import UncertaintyError
from . import se2 as _se2
from . import se3 as _se3
from ._validate import as_covariance, as_transform, as_vector
from .pose2 import UncertainPose2
from .pose3 import UncertainPose3

__all__ = ["MonteCarloResult", "Agreement", "monte_carlo", "monte_carlo_chain", "monte_carlo_chain3", "agreement",
           "path_length"]


@dataclass(frozen=True)
class MonteCarloResult:
    """Sample statistics of a Monte Carlo run.

    Attributes
    ----------
    mean : (d,) float64 — sample mean (units of the output coordinates).
    cov : (d, d) float64 — sample covariance, ``ddof = 1``.
    samples : (n, d) float64 — the output samples.
    reference : (4, 4) float64 or None — for SE(3) runs, the transform whose tangent space
        holds the samples (``samples[i] = log(T_i reference^-1)``); None in the plane.
    """

    mean: np.ndarray
    cov: np.ndarray
    samples: np.ndarray
    reference: np.ndarray | None = None

    @property
    def n(self) -> int:
        """Number of samples."""
        return int(self.samples.shape[0])


def _check_n(n: int) -> int:
    if int(n) != n or n < 2:
        raise UncertaintyError(f"n must be an integer >= 2, got {n!r}")
    return int(n)


def _stats(samples: np.ndarray, reference=None) -> MonteCarloResult:
    if not np.all(np.isfinite(samples)):
        raise UncertaintyError("monte carlo: the operation produced NaN or infinite samples")
    return MonteCarloResult(samples.mean(axis=0), np.atleast_2d(np.cov(samples, rowvar=False)), samples, reference)


def _draws(covs: Sequence[np.ndarray], n: int, rng: np.random.Generator, moment_match: bool) -> list[np.ndarray]:
    """Zero-mean draws (n, k_i) for each covariance, independent across inputs.

    ``moment_match``: one standard-normal block (n, Σk_i) is centred and whitened by the
    Cholesky factor of its own sample covariance, so that the draws have exactly zero sample
    mean, exactly the given sample covariances and exactly zero sample cross-covariance
    between inputs (a standard variance reduction: what remains of the disagreement is the
    nonlinearity, not the O(1/√n) noise of the input moments).
    """
    sizes = [c.shape[0] for c in covs]
    z = rng.standard_normal((n, sum(sizes)))
    if moment_match:
        z -= z.mean(axis=0)
        chol = np.linalg.cholesky(np.cov(z, rowvar=False))
        z = np.linalg.solve(chol, z.T).T
    out, start = [], 0
    for c, k in zip(covs, sizes):
        w, v = np.linalg.eigh(c)
        out.append(z[:, start:start + k] @ (v * np.sqrt(np.clip(w, 0.0, None))).T)
        start += k
    return out


def monte_carlo(fn: Callable[..., np.ndarray], inputs: Sequence[tuple], n: int, rng: np.random.Generator,
                *, moment_match: bool = False) -> MonteCarloResult:
    """Sample each input Gaussian independently and push the samples through ``fn``.

    Parameters
    ----------
    fn : callable
        ``fn(*draws) -> (n, d)``; each draw is an (n, k_i) array of one input's samples.
        Must be vectorised over the first axis.
    inputs : sequence of (mean (k_i,), cov (k_i, k_i))
        The input Gaussians (validated: finite, symmetric PSD).
    n : int >= 2
    rng : numpy.random.Generator (seeded by the caller)
    moment_match : bool
        Correct the draws so their sample means and covariances are exactly the inputs'
        (see :func:`_draws`); needs ``n`` well above the total input dimension.

    Returns
    -------
    :class:`MonteCarloResult`
    """
    n = _check_n(n)
    means, covs = [], []
    for i, (m, c) in enumerate(inputs):
        m = np.atleast_1d(np.asarray(m, dtype=np.float64))
        means.append(as_vector(m, m.shape[0], f"inputs[{i}].mean"))
        covs.append(as_covariance(c, m.shape[0], f"inputs[{i}].cov"))
    draws = [m + d for m, d in zip(means, _draws(covs, n, rng, moment_match))]
    return _stats(np.asarray(fn(*draws), dtype=np.float64))


def _chain2(*draws: np.ndarray) -> np.ndarray:
    out = draws[0]
    for d in draws[1:]:
        out = _se2._compound_mean(out, d)
    return out


def monte_carlo_chain(poses: Sequence[UncertainPose2], n: int, rng: np.random.Generator,
                      *, moment_match: bool = False) -> MonteCarloResult:
    """Monte Carlo of ``poses[0] ⊕ poses[1] ⊕ …`` in the plane (Fig. 3 of the paper).

    Returns a :class:`MonteCarloResult` over ``(x, y, θ)`` (m, m, rad); θ unwrapped (the
    compounding of Eqn. 1 adds angles).
    """
    if not poses:
        raise UncertaintyError("monte_carlo_chain: empty chain")
    return monte_carlo(_chain2, [(p.mean, p.cov) for p in poses], n, rng, moment_match=moment_match)


def monte_carlo_chain3(poses: Sequence[UncertainPose3], n: int, rng: np.random.Generator,
                       reference=None, *, moment_match: bool = False) -> MonteCarloResult:
    """Monte Carlo of ``poses[0] ⊕ poses[1] ⊕ …`` on SE(3).

    Each relation is sampled as ``exp(ξ^) T̄`` and the products are expressed in the tangent
    space of ``reference`` (default: the product of the means, i.e. the linearised mean):
    ``samples = log(T reference^-1)`` (n, 6), (ρ m, φ rad).  The linearised estimate then
    predicts a sample mean of 0 and the compounded covariance.  ``moment_match`` as in
    :func:`monte_carlo` (on the ξ draws).
    """
    if not poses:
        raise UncertaintyError("monte_carlo_chain3: empty chain")
    n = _check_n(n)
    ref = np.eye(4)
    prod = np.broadcast_to(np.eye(4), (n, 4, 4)).copy()
    for p, xi in zip(poses, _draws([p.cov for p in poses], n, rng, moment_match)):
        prod = prod @ (_se3._exp(xi) @ p.mean)
        ref = ref @ p.mean
    if reference is not None:
        ref = as_transform(reference, "monte_carlo_chain3: reference")  # a non-rigid one was made rigid unseen
    return _stats(_se3._log(prod @ _se3._invert(ref)), ref)


@dataclass(frozen=True)
class Agreement:
    """How far a linearised estimate is from Monte Carlo statistics (dimensionless).

    Attributes
    ----------
    mean_position : float
        ``|Δmean| of the position components / length_scale`` (the paper's "within 1 %"
        read as relative to the size of the quantities; a chain's size is its path length,
        since a chain returning to its start has a mean near 0). NaN when no scale was given.
    mean_sigma : float
        ``max_i |Δmean_i| / σ_i``: the mean error in linearised standard deviations.
    cov : float
        ``max_ij |ΔC_ij| / (σ_i σ_j)``: each covariance element's error relative to the
        product of the linearised standard deviations (1 % on variances, 0.01 in correlation).
    """

    mean_position: float
    mean_sigma: float
    cov: float

    def within(self, fraction: float) -> bool:
        """Whether ``mean_position`` (if defined) and ``cov`` are both at most ``fraction``."""
        ok = self.cov <= fraction
        if not math.isnan(self.mean_position):
            ok = ok and self.mean_position <= fraction
        return bool(ok)


def agreement(mean, cov, mc: MonteCarloResult, *, length_scale: float | None = None,
              position: slice = slice(0, 2), angle_index: Sequence[int] = (2,)) -> Agreement:
    """Compare a linearised ``mean`` (d,) and ``cov`` (d, d) with Monte Carlo statistics.

    Parameters
    ----------
    mean : (d,) float64 — linearised mean (for SE(3) runs: zeros(6), the tangent mean).
    cov : (d, d) float64 — linearised covariance.
    mc : :class:`MonteCarloResult`
    length_scale : float, m, optional — path length for :attr:`Agreement.mean_position`.
    position : slice — the position components (default x, y; use ``slice(0, 3)`` for ρ).
    angle_index : indices whose mean difference is wrapped into (-π, π] (default θ; ``()``
        for SE(3) tangent coordinates).

    Returns
    -------
    :class:`Agreement`
    """
    d = mc.mean.shape[0]
    mean = as_vector(mean, d, "mean")
    cov = as_covariance(cov, d, "cov")
    dm = mc.mean - mean
    for i in angle_index:
        dm[i] = _se2.wrap_angle(dm[i])
    sd = np.sqrt(np.diag(cov))
    with np.errstate(divide="ignore", invalid="ignore"):
        msig = np.where(sd > 0, np.abs(dm) / sd, np.where(dm == 0, 0.0, np.inf))
        denom = np.outer(sd, sd)
        dc = np.abs(mc.cov - cov)
        csig = np.where(denom > 0, dc / denom, np.where(dc == 0, 0.0, np.inf))
    mpos = math.nan
    if length_scale is not None:
        if not length_scale > 0:
            raise UncertaintyError(f"length_scale must be > 0, got {length_scale!r}")
        mpos = float(np.linalg.norm(dm[position]) / length_scale)
    return Agreement(mpos, float(np.max(msig)), float(np.max(csig)))


def path_length(poses: Sequence[UncertainPose2 | UncertainPose3]) -> float:
    """Sum of the relations' mean translation lengths, m (the size of a chain)."""
    total = 0.0
    for p in poses:
        t = p.mean[:2] if isinstance(p, UncertainPose2) else p.mean[:3, 3]
        total += float(np.linalg.norm(t))
    return total

