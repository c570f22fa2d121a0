"""Confidence regions of Gaussian relations (Smith & Cheeseman, Appendix A) and the
probability that an uncertain position lies inside a planar region.

The paper's ellipsoid is ``(x - X)^T C^-1 (x - X) = k²`` (Eqn. A1); the probability inside it
is, for N dimensions, the chi-square distribution function with N degrees of freedom at
``k²``.  Appendix A gives the closed forms::

    N = 1:  P = erf(k / √2)
    N = 2:  P = 1 - exp(-k² / 2),  so  k² = -2 ln(1 - P)   (50 % -> 1.386, 90 % -> 4.605)
    N = 3:  P = erf(k / √2) - √(2/π) k exp(-k² / 2)

(the OCR of the N = 1 and N = 3 lines is garbled; these are the chi-square CDFs for one and
three degrees of freedom, which the legible N = 2 line and the text's "erf" match).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import integrate, stats

from .._errors import UncertaintyError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from .._values import number, whole_number
from ._validate import as_covariance, as_vector

__all__ = [
    "k2_for_confidence",
    "confidence_for_k2",
    "Ellipse",
    "ellipse",
    "Box2",
    "Polygon2",
    "probability_inside",
]


def _dim(dim) -> int:
    """``dim`` as an integer >= 1 (NaN and text were raw ValueErrors)."""
    return whole_number(dim, "dim", UncertaintyError, low=1)


def k2_for_confidence(confidence: float, dim: int = 2) -> float:
    """``k²`` of the ``confidence`` ellipsoid in ``dim`` dimensions (Appendix A).

    ``dim = 2`` uses the paper's closed form ``k² = -2 ln(1 - P)``; other dimensions the
    chi-square quantile (the general form of Appendix A's table).

    Parameters
    ----------
    confidence : float in (0, 1), probability
    dim : int >= 1

    Returns
    -------
    float, dimensionless (squared Mahalanobis radius)
    """
    p = number(confidence, "confidence", UncertaintyError, low=0.0, high=1.0, low_open=True, high_open=True)
    dim = _dim(dim)
    if dim == 2:
        return -2.0 * math.log1p(-p)
    return float(stats.chi2.ppf(p, dim))


def confidence_for_k2(k2: float, dim: int = 2) -> float:
    """Probability inside the ellipsoid ``(x - X)^T C^-1 (x - X) <= k²`` in ``dim`` dimensions.

    Uses Appendix A's closed forms for ``dim`` 1, 2, 3 and the chi-square CDF otherwise.

    Parameters
    ----------
    k2 : float >= 0, dimensionless
    dim : int >= 1

    Returns
    -------
    float in [0, 1], probability
    """
    k2 = number(k2, "k2", UncertaintyError, low=0.0)
    dim = _dim(dim)
    k = math.sqrt(k2)
    if dim == 1:
        return math.erf(k / math.sqrt(2.0))
    if dim == 2:
        return -math.expm1(-0.5 * k2)
    if dim == 3:
        return math.erf(k / math.sqrt(2.0)) - math.sqrt(2.0 / math.pi) * k * math.exp(-0.5 * k2)
    return float(stats.chi2.cdf(k2, dim))


@dataclass(frozen=True)
class Ellipse:
    """A confidence ellipse of a 2-D Gaussian position.

    Attributes
    ----------
    center : (2,) float64, m — the mean position (frame of the relation's reference frame).
    half_axes : (2,) float64, m — half major and half minor axis, ``k sqrt(eigenvalue)``.
    angle : float, rad — angle of the major axis from the +x axis, in (-π/2, π/2].
    k2 : float — the ``k²`` of Eqn. (A1).
    confidence : float — the probability inside, ``1 - exp(-k²/2)``.
    """

    center: np.ndarray
    half_axes: np.ndarray
    angle: float
    k2: float
    confidence: float

    def points(self, n: int = 128) -> np.ndarray:
        """(n, 2) float64, m: points on the ellipse, counter-clockwise from the major axis."""
        t = np.linspace(0.0, 2.0 * np.pi, int(n), endpoint=False)
        c, s = math.cos(self.angle), math.sin(self.angle)
        rot = np.array([[c, -s], [s, c]])
        local = np.stack((self.half_axes[0] * np.cos(t), self.half_axes[1] * np.sin(t)), axis=1)
        return self.center + local @ rot.T

    def contains(self, points) -> np.ndarray:
        """(m,) bool: which of ``points`` (m, 2), m, lie inside or on the ellipse."""
        p = np.atleast_2d(np.asarray(points, dtype=np.float64)) - self.center
        c, s = math.cos(self.angle), math.sin(self.angle)
        u = (p[:, 0] * c + p[:, 1] * s) / max(self.half_axes[0], np.finfo(float).tiny)
        v = (-p[:, 0] * s + p[:, 1] * c) / max(self.half_axes[1], np.finfo(float).tiny)
        return u * u + v * v <= 1.0


def ellipse(mean2, cov2, confidence: float = 0.9, *, tol: Tolerances = DEFAULT_TOLERANCES) -> Ellipse:
    """The ``confidence`` ellipse of a 2-D Gaussian position (Appendix A).

    Appendix A writes the ellipse as ``A x² + 2 B x y + C y² = k²`` with ``[[A, B], [B, C]] =
    C2^-1`` and the major axis at ``½ arctan(2B / (A - C))``; the same ellipse is computed
    here from the eigen-decomposition of ``C2`` (half axes ``k sqrt(λ)``), which also covers
    singular ``C2`` (a degenerate ellipse, half axis 0).

    Parameters
    ----------
    mean2 : (2,) float64, m — mean position.
    cov2 : (2, 2) float64, m² — its covariance (for an (x, y, θ) relation: strike out θ's
        row and column, Appendix A).
    confidence : float in (0, 1)

    Returns
    -------
    :class:`Ellipse`
    """
    m = as_vector(mean2, 2, "mean2")
    c = as_covariance(cov2, 2, "cov2", tol)
    k2 = k2_for_confidence(confidence, 2)
    w, v = np.linalg.eigh(c)
    w = np.clip(w, 0.0, None)
    major = v[:, 1]
    angle = math.atan2(major[1], major[0])
    if angle > math.pi / 2:
        angle -= math.pi
    elif angle <= -math.pi / 2:
        angle += math.pi
    half = np.sqrt(k2 * w[::-1])
    return Ellipse(m, half, angle, k2, confidence_for_k2(k2, 2))


@dataclass(frozen=True)
class Box2:
    """An axis-aligned rectangle ``lower <= (x, y) <= upper``; (2,) float64 each, m."""

    lower: np.ndarray
    upper: np.ndarray

    def __post_init__(self) -> None:
        lo = as_vector(self.lower, 2, "Box2.lower")
        hi = as_vector(self.upper, 2, "Box2.upper")
        if np.any(hi < lo):
            raise UncertaintyError(f"Box2: upper {hi} below lower {lo}")
        object.__setattr__(self, "lower", lo)
        object.__setattr__(self, "upper", hi)

    def vertices(self) -> np.ndarray:
        """(4, 2) float64, m: the corners, counter-clockwise."""
        (x0, y0), (x1, y1) = self.lower, self.upper
        return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])


@dataclass(frozen=True)
class Polygon2:
    """A simple polygon (convex or not, either orientation); ``vertices`` (n, 2) float64, m, n >= 3.

    A self-intersecting vertex list gives the winding-number-weighted probability.
    """

    vertices: np.ndarray

    def __post_init__(self) -> None:
        try:
            v = np.array(self.vertices, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise UncertaintyError(f"Polygon2.vertices: not a numeric array ({exc})") from None
        if v.ndim != 2 or v.shape[1] != 2 or v.shape[0] < 3:
            raise UncertaintyError(f"Polygon2.vertices: expected shape (n >= 3, 2), got {v.shape}")
        if not np.all(np.isfinite(v)):
            raise UncertaintyError("Polygon2.vertices: contains NaN or infinity")
        object.__setattr__(self, "vertices", v)


def _winding_inside(point: np.ndarray, v: np.ndarray) -> bool:
    """Whether ``point`` (2,) is inside or on the polygon ``v`` (n, 2) (nonzero winding)."""
    a = v - point
    b = np.roll(a, -1, axis=0)
    cross = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    dot = np.einsum("ij,ij->i", a, b)
    on_edge = (np.abs(cross) <= 0.0) & (dot <= 0.0)
    if np.any(on_edge):
        return True
    return abs(np.sum(np.arctan2(cross, dot))) > np.pi


def probability_inside(mean2, cov2, region, *, tol: Tolerances = DEFAULT_TOLERANCES) -> float:
    """Probability that a Gaussian 2-D position lies inside a planar ``region``.

    Accepted regions: :class:`Box2` (axis-aligned rectangle) and :class:`Polygon2` (any simple
    polygon, convex or not).  Method: whiten the position (``z = Λ^-1/2 V^T (p - mean)`` for
    ``cov2 = V Λ V^T``), split the whitened polygon into the signed triangles (mean, v_i,
    v_i+1) and integrate the standard normal over each in polar coordinates about the mean,
    ``(1/2π) ∫ (1 - exp(-r(φ)²/2)) dφ``, a smooth 1-D integral per edge
    (``scipy.integrate.quad``, absolute error :attr:`Tolerances.probability_quadrature` each).
    Exact up to that quadrature error — not a bound.

    A position known exactly (``cov2 == 0``) gives 1.0 or 0.0 (inside or on the boundary
    counts as inside); a rank-1 covariance (known exactly along one direction only) raises
    :class:`UncertaintyError`.

    Parameters
    ----------
    mean2 : (2,) float64, m
    cov2 : (2, 2) float64, m²
    region : Box2 or Polygon2, m, same frame as ``mean2``

    Returns
    -------
    float in [0, 1], probability
    """
    m = as_vector(mean2, 2, "mean2")
    c = as_covariance(cov2, 2, "cov2", tol)
    if isinstance(region, Box2):
        verts = region.vertices()
    elif isinstance(region, Polygon2):
        verts = region.vertices
    else:
        raise UncertaintyError(f"region must be a Box2 or a Polygon2, got {type(region).__name__}")
    w, v = np.linalg.eigh(c)
    if w[1] <= 0.0:
        return 1.0 if _winding_inside(m, verts) else 0.0
    if w[0] <= tol.covariance_relative * w[1]:
        raise UncertaintyError(
            f"probability_inside: position covariance is singular (eigenvalues {w}); "
            "a position known exactly along one direction is not supported"
        )
    z = ((verts - m) @ v) / np.sqrt(w)
    total = 0.0
    for a, b in zip(z, np.roll(z, -1, axis=0)):
        cross = a[0] * b[1] - a[1] * b[0]
        if cross == 0.0:
            continue  # degenerate triangle (mean on the edge's line): zero measure
        sweep = math.atan2(cross, float(a @ b))  # signed angle a -> b, |sweep| < π
        e = b - a
        t0 = math.atan2(a[1], a[0])

        def f(t, t0=t0, e=e, cross=cross):
            ux, uy = math.cos(t0 + t), math.sin(t0 + t)
            r = cross / (ux * e[1] - uy * e[0])
            return -math.expm1(-0.5 * r * r)

        val, _ = integrate.quad(f, 0.0, sweep, epsabs=tol.probability_quadrature, epsrel=0.0, limit=200)
        total += val / (2.0 * math.pi)
    return float(min(1.0, max(0.0, abs(total))))

