"""``UncertainPose2``: a planar uncertain relation (Smith & Cheeseman's "uncertain
transformation"), a frozen value delegating to the array functions of :mod:`.se2` and
:mod:`.confidence`.  Networks of them are reduced in :mod:`.network`."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Hashable

import numpy as np

from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from . import confidence as _conf
from . import se2 as _se2
from ._validate import as_covariance, as_vector, freeze_relation, same_kind, sample_args

__all__ = ["UncertainPose2"]


@dataclass(frozen=True, eq=False)
class UncertainPose2:
    """Frame B's uncertain relation to frame A in the plane.

    Attributes
    ----------
    mean : (3,) float64, (m, m, rad)
        ``(x, y, θ)``: B's origin in A's coordinates and the angle of B's x axis from A's.
    cov : (3, 3) float64, m² / m·rad / rad²
        Covariance of ``(x, y, θ)``; validated finite and symmetric positive semi-definite
        (:attr:`Tolerances.covariance_relative`), stored exactly symmetric.

    Construction validates and raises :class:`~armguard.UncertaintyError`; the results of the
    operations are built from validated values and skip the checks.
    """

    mean: np.ndarray
    cov: np.ndarray

    def __post_init__(self) -> None:
        freeze_relation(self, as_vector(self.mean, 3, "UncertainPose2.mean"), as_covariance(self.cov, 3, "UncertainPose2.cov"))

    @classmethod
    def _trusted(cls, mean: np.ndarray, cov: np.ndarray) -> "UncertainPose2":
        return freeze_relation(object.__new__(cls), mean, cov)

    @classmethod
    def identity(cls) -> "UncertainPose2":
        """The exact identity relation: mean (0, 0, 0), zero covariance."""
        return cls._trusted(np.zeros(3), np.zeros((3, 3)))

    @classmethod
    def from_polar(cls, polar, cov_polar, *, tol: Tolerances = DEFAULT_TOLERANCES) -> "UncertainPose2":
        """From a range/bearing sensor estimate (Appendix B).

        Parameters
        ----------
        polar : (3,) float64, (m, rad, rad) — range ``r >= 0``, bearing ``φ``, rotation ``θ``.
        cov_polar : (3, 3) float64, m² / m·rad / rad² — covariance of ``(r, φ, θ)``.
        """
        x, c, _ = _se2.polar_to_cartesian(polar, cov_polar, tol=tol)
        return cls._trusted(x, c)

    # --- the paper's operations ---------------------------------------------------------

    def compound(self, other: "UncertainPose2", cross_cov=None) -> "UncertainPose2":
        """``self ⊕ other`` (Eqns. 1–3): ``self`` is A→B, ``other`` B→C; returns A→C.

        ``cross_cov`` : (3, 3) float64, optional — ``E[Δself Δother^T]`` when the two are
        dependent (the paper's "treat the dependent combination as a unit"); ``None``:
        independent.
        """
        same_kind(self, other, "compound")
        if cross_cov is None:
            x3, c3, _, _ = _se2._compound(self.mean, self.cov, other.mean, other.cov)
        else:
            x3, c3, _, _ = _se2.compound(self.mean, self.cov, other.mean, other.cov, cross_cov)
        return UncertainPose2._trusted(x3, c3)

    def compound_jacobians(self, other: "UncertainPose2") -> tuple[np.ndarray, np.ndarray]:
        """J⊕ = [J1 | J2] of ``self ⊕ other`` at the means, (3, 3) each (Eqn. 2)."""
        same_kind(self, other, "compound_jacobians")
        x3 = _se2._compound_mean(self.mean, other.mean)
        return _se2._compound_jacobians(self.mean, other.mean, x3)

    def reverse(self) -> "UncertainPose2":
        """``⊖self`` (Eqn. 4): the relation A→B reversed to B→A."""
        xr, cr, _ = _se2._reverse(self.mean, self.cov)
        return UncertainPose2._trusted(xr, cr)

    def reverse_jacobian(self) -> np.ndarray:
        """J⊖ (3, 3) of the reversal at the mean (Section 3.1)."""
        return _se2._reverse_jacobian(self.mean, _se2._reverse_mean(self.mean))

    def merge(self, other: "UncertainPose2", *, tol: Tolerances = DEFAULT_TOLERANCES) -> "UncertainPose2":
        """Merge with an independent parallel estimate of the same relation (Eqns. 5–7)."""
        same_kind(self, other, "merge")
        x3, c3, _ = _se2._merge(self.mean, self.cov, other.mean, other.cov, tol)
        return UncertainPose2._trusted(x3, c3)

    @staticmethod
    def reduce(network, source: Hashable, target: Hashable, *, tol: Tolerances = DEFAULT_TOLERANCES):
        """Reduce a network of relations to one, source→target; see
        :func:`~armguard.uncertainty.network.reduce_network`."""
        from .network import reduce_network  # network builds on this module

        return reduce_network(network, source, target, tol=tol)

    @staticmethod
    def chain(*poses: "UncertainPose2") -> "UncertainPose2":
        """``poses[0] ⊕ poses[1] ⊕ …`` compounded left to right (Section 3.1's recursion)."""
        out = UncertainPose2.identity()
        for p in poses:
            out = out.compound(p)  # (each checked: another UncertainPose2)
        return out

    # --- decisions -----------------------------------------------------------------------

    def ellipse(self, confidence: float = 0.9) -> _conf.Ellipse:
        """The positional ``confidence`` ellipse (Appendix A; θ's row and column struck out)."""
        return _conf.ellipse(self.mean[:2], self.cov[:2, :2], confidence)

    def probability_inside(self, region, *, tol: Tolerances = DEFAULT_TOLERANCES) -> float:
        """Probability that B's origin lies in ``region`` (:class:`Box2` or :class:`Polygon2`
        in A's coordinates, m), from the Gaussian (x, y) marginal; see
        :func:`~armguard.uncertainty.probability_inside`."""
        return _conf.probability_inside(self.mean[:2], self.cov[:2, :2], region, tol=tol)

    def mahalanobis2(self, x) -> float:
        """Squared Mahalanobis distance of a relation ``x`` (3,), (m, m, rad), from this one,
        angle difference wrapped; compare with :func:`k2_for_confidence` (..., dim=3) to
        decide whether an observation is plausible (Section 5.2, step 2).

        A singular covariance knows some direction exactly: ``x`` off the mean along it is impossible,
        ``inf`` (a pseudo-inverse drops that direction and called such an ``x`` a perfect fit, 0);
        along the known directions the distance is the pseudo-inverse's.  Eigenvalues below
        ``Tolerances.covariance_relative`` times the largest count as zero, as everywhere here."""
        d = as_vector(x, 3, "x") - self.mean
        d[2] = _se2.wrap_angle(d[2])
        lam, V = np.linalg.eigh(self.cov)
        c = V.T @ d
        zero = lam <= DEFAULT_TOLERANCES.covariance_relative * max(float(lam.max()), 0.0)
        if np.any(zero & (np.abs(c) > 1e-12 * (1.0 + float(np.abs(d).max())))):
            return float("inf")
        return float(np.sum(c[~zero] ** 2 / lam[~zero]))

    def sample(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """(n, 3) float64, (m, m, rad): draws from N(mean, cov) with ``rng``."""
        n = sample_args(n, rng)
        return rng.multivariate_normal(self.mean, self.cov, size=int(n), method="eigh")

    def __repr__(self) -> str:
        sd = np.sqrt(np.diag(self.cov))
        return (f"UncertainPose2(mean=({self.mean[0]:.6g} m, {self.mean[1]:.6g} m, {self.mean[2]:.6g} rad), "
                f"sd=({sd[0]:.3g} m, {sd[1]:.3g} m, {sd[2]:.3g} rad))")
