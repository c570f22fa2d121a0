"""Input checks at the public boundary of ``armguard.uncertainty``: finite arrays of the right
shape, covariances symmetric positive semi-definite within ``Tolerances.covariance_relative``."""

from __future__ import annotations

import numpy as np

from .._errors import UncertaintyError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances

__all__ = ["as_vector", "as_covariance", "as_transform", "symmetrize", "freeze_relation"]


def freeze_relation(obj, mean: np.ndarray, cov: np.ndarray):
    """Set ``obj.mean`` and ``obj.cov`` (a frozen dataclass's fields) to read-only float64 copies; returns ``obj``.

    A result that is not finite (an overflow: exponential coordinates of 1e300 m, a compound of two
    relations near 1e308) is refused here, where it is made, not later by a LinAlgError."""
    mean = np.array(mean, dtype=np.float64)
    cov = np.array(cov, dtype=np.float64)
    if not (np.all(np.isfinite(mean)) and np.all(np.isfinite(cov))):
        raise UncertaintyError(f"{type(obj).__name__}: the result is not finite (an overflow; mean {mean.tolist()}): "
                               "inputs of this magnitude have no finite relation")
    mean.flags.writeable = False
    cov.flags.writeable = False
    object.__setattr__(obj, "mean", mean)
    object.__setattr__(obj, "cov", cov)
    return obj


def as_vector(value, n: int, name: str) -> np.ndarray:
    """``value`` as a finite (n,) float64 array, or raise :class:`UncertaintyError`."""
    try:
        a = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise UncertaintyError(f"{name}: not a numeric array ({exc})") from None
    if a.shape != (n,):
        raise UncertaintyError(f"{name}: expected shape ({n},), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise UncertaintyError(f"{name}: contains NaN or infinity: {a}")
    big = DEFAULT_TOLERANCES.max_magnitude
    if float(np.max(np.abs(a), initial=0.0)) > big:
        raise UncertaintyError(f"{name}: {a} holds a value beyond {big:g} (Tolerances.max_magnitude; m or rad)")
    return a


def symmetrize(c: np.ndarray) -> np.ndarray:
    """``(C + C^T) / 2``: removes the round-off asymmetry of products such as ``J C J^T``."""
    return 0.5 * (c + c.T)


def as_covariance(value, n: int, name: str, tol: Tolerances = DEFAULT_TOLERANCES) -> np.ndarray:
    """``value`` as a finite, symmetric positive semi-definite (n, n) float64 array.

    The checks are made in each entry's own units: a covariance holds m² and rad² side by side, and
    a tolerance relative to its largest entry let a position variance of 100 m² pass an angle
    variance of -5e-8 rad² (whose merge then moved the angle away from both estimates).  With
    ``s_i = sqrt(C_ii)`` and ``r = tol.covariance_relative``:

    * no variance below ``-e``, ``e = 64 eps max|C|`` (round-off of products such as ``J C J^T``);
    * ``|C_ij - C_ji| <= r s_i s_j + e``;
    * the correlation matrix ``C_ij / (s_i s_j)`` (``s_i`` at least ``sqrt(e)``) has no eigenvalue
      below ``-r``.

    The returned matrix is exactly symmetric (an eigenvalue round-off left below zero stays: the
    callers that factor a covariance treat those within the tolerance as zero).  Raises
    :class:`UncertaintyError` otherwise, naming the failed check.
    """
    try:
        c = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise UncertaintyError(f"{name}: not a numeric array ({exc})") from None
    if c.shape != (n, n):
        raise UncertaintyError(f"{name}: expected shape ({n}, {n}), got {c.shape}")
    if not np.all(np.isfinite(c)):
        raise UncertaintyError(f"{name}: contains NaN or infinity")
    scale = float(np.max(np.abs(c)))
    if scale > tol.max_magnitude**2:
        raise UncertaintyError(f"{name}: an entry of {scale:.3g} is beyond {tol.max_magnitude**2:g} (Tolerances.max_magnitude "
                               "squared; m^2, rad^2)")
    if scale == 0.0:
        return c  # every relation known exactly
    e = 64.0 * np.finfo(np.float64).eps * scale
    var = np.diag(c)
    i = int(np.argmin(var))
    if var[i] < -e:
        raise UncertaintyError(f"{name}: not positive semi-definite: a variance is negative (C[{i}, {i}] = {var[i]:.3g})")
    s = np.sqrt(np.maximum(var, e))
    r = tol.covariance_relative
    excess = np.abs(c - c.T) - (r * np.outer(s, s) + e)
    if float(np.max(excess)) > 0.0:
        i, j = np.unravel_index(int(np.argmax(excess)), excess.shape)
        raise UncertaintyError(f"{name}: not symmetric (C[{i}, {j}] = {c[i, j]:.6g} but C[{j}, {i}] = {c[j, i]:.6g})")
    c = symmetrize(c)
    lo = float(np.linalg.eigvalsh(c / np.outer(s, s))[0])
    if lo < -r:
        raise UncertaintyError(
            f"{name}: not positive semi-definite (the correlation matrix C_ij / sqrt(C_ii C_jj) has the eigenvalue "
            f"{lo:.3g} < -{r:g})"
        )
    return c


def as_transform(value, name: str, tol: Tolerances = DEFAULT_TOLERANCES) -> np.ndarray:
    """``value`` as a finite (4, 4) rigid transform (rotation block orthonormal, last row 0 0 0 1).

    The rotation block must satisfy ``max|R^T R - I| <= tol.rotation_orthonormality`` and
    ``det R > 0``.
    """
    try:
        t = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise UncertaintyError(f"{name}: not a numeric array ({exc})") from None
    if t.shape != (4, 4):
        raise UncertaintyError(f"{name}: expected shape (4, 4), got {t.shape}")
    if not np.all(np.isfinite(t)):
        raise UncertaintyError(f"{name}: contains NaN or infinity")
    r = t[:3, :3]
    ortho = float(np.max(np.abs(r.T @ r - np.eye(3))))
    if ortho > tol.rotation_orthonormality:
        raise UncertaintyError(f"{name}: rotation block is not a rotation (max |R^T R - I| = {ortho:.3g})")
    if np.linalg.det(r) <= 0.0:
        raise UncertaintyError(f"{name}: rotation block is a reflection (det R = {np.linalg.det(r):.3g}), not a rotation")
    if np.any(t[3] != (0.0, 0.0, 0.0, 1.0)):
        raise UncertaintyError(f"{name}: last row must be 0 0 0 1, got {t[3]}")
    return t


def same_kind(self, other, op: str) -> None:
    """Refuse ``other`` unless it is a relation of ``self``'s class (a 3-D pose compounded with a 2-D one,
    a list, None), naming the operation and both types."""
    if type(other) is not type(self):
        raise UncertaintyError(f"{type(self).__name__}.{op}: expected another {type(self).__name__}, got "
                               f"{type(other).__name__}")


def sample_args(n, rng) -> int:
    """``n`` (draws, an integer >= 0) after checking it and ``rng`` (a numpy Generator)."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 0:
        raise UncertaintyError(f"sample: n: expected an integer >= 0, got {n!r}")
    if not isinstance(rng, np.random.Generator):
        raise UncertaintyError(f"sample: rng: expected a numpy Generator (np.random.default_rng(seed)), got "
                               f"{type(rng).__name__}")
    return int(n)
