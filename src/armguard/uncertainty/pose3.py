"""``UncertainPose3``: a 6-DOF uncertain relation on SE(3) in exponential coordinates (no Euler
angles, no poles), a frozen value delegating to :mod:`.se3`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from . import se3 as _se3
from ._validate import as_covariance, as_transform, as_vector, freeze_relation, same_kind, sample_args

__all__ = ["UncertainPose3"]


@dataclass(frozen=True, eq=False)
class UncertainPose3:
    """Frame B's uncertain relation to frame A in space.

    Attributes
    ----------
    mean : (4, 4) float64
        Mean transform ``T̄_AB`` (B's pose in A; translation in m).
    cov : (6, 6) float64, m² / m·rad / rad²
        Covariance of the left perturbation ``ξ = (ρ, φ)`` in A's axes,
        ``T_AB = exp(ξ^) T̄_AB`` (translation part first, see :mod:`armguard.uncertainty.se3`).
    """

    mean: np.ndarray
    cov: np.ndarray

    def __post_init__(self) -> None:
        freeze_relation(self, as_transform(self.mean, "UncertainPose3.mean"), as_covariance(self.cov, 6, "UncertainPose3.cov"))

    @classmethod
    def _trusted(cls, mean: np.ndarray, cov: np.ndarray) -> "UncertainPose3":
        return freeze_relation(object.__new__(cls), mean, cov)

    @classmethod
    def identity(cls) -> "UncertainPose3":
        """The exact identity relation."""
        return cls._trusted(np.eye(4), np.zeros((6, 6)))

    @classmethod
    def from_exp_coords(cls, xi, cov, *, tol: Tolerances = DEFAULT_TOLERANCES) -> "UncertainPose3":
        """From a mean in exponential coordinates ``xi`` (6,) = (ρ m, φ rad) and ``cov`` (6, 6)."""
        t = _se3._exp(as_vector(xi, 6, "xi"))
        return cls._trusted(t, as_covariance(cov, 6, "cov", tol))

    @classmethod
    def from_pytransform3d(cls, mean, cov_pt3d) -> "UncertainPose3":
        """From pytransform3d's (mean (4, 4), covariance (6, 6) in its (ω, v) order)."""
        return cls(mean, _se3.from_pytransform3d_cov(cov_pt3d))

    def to_pytransform3d(self) -> tuple[np.ndarray, np.ndarray]:
        """(mean (4, 4), covariance (6, 6) in pytransform3d's (ω, v) order)."""
        return np.array(self.mean), _se3.to_pytransform3d_cov(self.cov)

    @property
    def exp_coords(self) -> np.ndarray:
        """(6,) float64, (ρ m, φ rad): ``log(T̄)``."""
        return _se3._log(self.mean)

    def compound(self, other: "UncertainPose3") -> "UncertainPose3":
        """``self ⊕ other``: A→B then B→C gives A→C; ``C = C1 + Ad(T̄1) C2 Ad(T̄1)^T``."""
        same_kind(self, other, "compound")
        t, c, _ = _se3._compound(self.mean, self.cov, other.mean, other.cov)
        return UncertainPose3._trusted(t, c)

    def compound_jacobians(self, other: "UncertainPose3") -> tuple[np.ndarray, np.ndarray]:
        """J⊕ = [I | Ad(T̄1)], (6, 6) each (``other`` enters only through the chain's order)."""
        same_kind(self, other, "compound_jacobians")
        return np.eye(6), _se3._adjoint(self.mean)

    def inverse(self) -> "UncertainPose3":
        """``⊖self``: B→A, ``C = Ad(T̄^-1) C Ad(T̄^-1)^T``."""
        t, c, _ = _se3._inverse(self.mean, self.cov)
        return UncertainPose3._trusted(t, c)

    reverse = inverse

    def inverse_jacobian(self) -> np.ndarray:
        """(6, 6): ``∂ξ_BA / ∂ξ_AB = -Ad(T̄^-1)``."""
        return -_se3._adjoint(_se3._invert(self.mean))

    def merge(self, other: "UncertainPose3", *, tol: Tolerances = DEFAULT_TOLERANCES) -> "UncertainPose3":
        """Merge with an independent estimate of the same relation (Eqns. 5–7 on the tangent space)."""
        same_kind(self, other, "merge")
        t, c, _ = _se3._merge3(self.mean, self.cov, other.mean, other.cov, tol)
        return UncertainPose3._trusted(t, c)

    @staticmethod
    def chain(*poses: "UncertainPose3") -> "UncertainPose3":
        """``poses[0] ⊕ poses[1] ⊕ …`` compounded left to right."""
        out = UncertainPose3.identity()
        for p in poses:
            out = out.compound(p)
        return out

    def sample(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """(n, 4, 4) float64: draws ``exp(ξ^) T̄`` with ``ξ ~ N(0, cov)`` from ``rng``."""
        n = sample_args(n, rng)
        xi = rng.multivariate_normal(np.zeros(6), self.cov, size=int(n), method="eigh")
        return _se3._exp(xi) @ self.mean

    def __repr__(self) -> str:
        sd = np.sqrt(np.diag(self.cov))
        return (f"UncertainPose3(t={np.array2string(self.mean[:3, 3], precision=4)} m, "
                f"sd_rho={np.array2string(sd[:3], precision=3)} m, sd_phi={np.array2string(sd[3:], precision=3)} rad)")
