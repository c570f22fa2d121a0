"""Smith & Cheeseman's operations on planar uncertain relations, array-first.

A relation of frame B with respect to frame A is ``x = (x, y, theta)``: B's origin in A's
coordinates (m) and B's x axis' angle from A's x axis (rad, counter-clockwise), with a
covariance ``C`` (3, 3) in the same coordinates (m², m·rad, rad²).  Equation numbers are those
of R. Smith and P. Cheeseman, *On the Representation and Estimation of Spatial Uncertainty*
(SRI, 1985; IJRR 5(4), 1986).

Angles are not wrapped by ``compound`` or ``reverse`` (Eqn. 1 writes ``theta3 = theta1 +
theta2``): theta is a continuous coordinate, and two relations whose angles differ by a
multiple of 2π are the same relation.  ``merge`` wraps the angle of the innovation
``x2 - x1`` into (-π, π], so that estimates on either side of ±π merge to the nearer angle.

Every public function validates its inputs (finite, right shapes, covariances symmetric PSD
within :attr:`Tolerances.covariance_relative`) and raises :class:`~armguard.UncertaintyError`;
the underscore kernels skip the checks and are what the validated classes call.
"""

from __future__ import annotations

import math

import numpy as np

from .._errors import UncertaintyError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from ._validate import as_covariance, as_vector, symmetrize

__all__ = [
    "wrap_angle",
    "compound_mean",
    "compound_jacobians",
    "compound",
    "reverse_mean",
    "reverse_jacobian",
    "reverse",
    "merge",
    "polar_to_cartesian",
]


def wrap_angle(theta):
    """Angle(s) ``theta`` (rad, any shape) wrapped into (-π, π]."""
    w = np.mod(np.asarray(theta, dtype=np.float64) + np.pi, 2.0 * np.pi) - np.pi
    return np.where(w == -np.pi, np.pi, w)


# --- kernels (no validation) -------------------------------------------------------------


def _compound_mean(x1: np.ndarray, x2: np.ndarray) -> np.ndarray:
    c, s = np.cos(x1[..., 2]), np.sin(x1[..., 2])
    return np.stack(
        (
            x2[..., 0] * c - x2[..., 1] * s + x1[..., 0],
            x2[..., 0] * s + x2[..., 1] * c + x1[..., 1],
            x1[..., 2] + x2[..., 2],
        ),
        axis=-1,
    )


def _compound_jacobians(x1: np.ndarray, x2: np.ndarray, x3: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    c, s = np.cos(x1[2]), np.sin(x1[2])
    j1 = np.array([[1.0, 0.0, -(x3[1] - x1[1])], [0.0, 1.0, x3[0] - x1[0]], [0.0, 0.0, 1.0]])
    j2 = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return j1, j2


def _compound(x1, c1, x2, c2, c12=None):
    # one relation: scalar arithmetic (the vectorised _compound_mean is for sample batches)
    a, b, t1 = float(x1[0]), float(x1[1]), float(x1[2])
    c, s = math.cos(t1), math.sin(t1)
    dx = float(x2[0]) * c - float(x2[1]) * s
    dy = float(x2[0]) * s + float(x2[1]) * c
    x3 = np.array((dx + a, dy + b, t1 + float(x2[2])))
    j1 = np.array(((1.0, 0.0, -dy), (0.0, 1.0, dx), (0.0, 0.0, 1.0)))
    j2 = np.array(((c, -s, 0.0), (s, c, 0.0), (0.0, 0.0, 1.0)))
    c3 = j1 @ c1 @ j1.T + j2 @ c2 @ j2.T
    if c12 is not None:
        cross = j1 @ c12 @ j2.T
        c3 = c3 + cross + cross.T
    return x3, symmetrize(c3), j1, j2


def _reverse_mean(x: np.ndarray) -> np.ndarray:
    c, s = np.cos(x[..., 2]), np.sin(x[..., 2])
    return np.stack(
        (-x[..., 0] * c - x[..., 1] * s, x[..., 0] * s - x[..., 1] * c, -x[..., 2]), axis=-1
    )


def _reverse_jacobian(x: np.ndarray, xr: np.ndarray) -> np.ndarray:
    c, s = np.cos(x[2]), np.sin(x[2])
    return np.array([[-c, -s, xr[1]], [s, -c, -xr[0]], [0.0, 0.0, -1.0]])


def _reverse(x, c):
    a, b, t = float(x[0]), float(x[1]), float(x[2])
    co, si = math.cos(t), math.sin(t)
    xr = np.array((-a * co - b * si, a * si - b * co, -t))
    j = np.array(((-co, -si, xr[1]), (si, -co, -xr[0]), (0.0, 0.0, -1.0)))
    return xr, symmetrize(j @ c @ j.T), j


def _merge(x1, c1, x2, c2, tol: Tolerances, angle_index=(2,)):
    s = c1 + c2
    ev = np.linalg.eigvalsh(s)
    if ev[-1] <= 0.0 or ev[0] < tol.merge_conditioning * ev[-1]:
        raise UncertaintyError(
            "merge: C1 + C2 is singular (both estimates claim exact knowledge along a common "
            f"direction; eigenvalues {ev})"
        )
    k = np.linalg.solve(s, c1.T).T  # Eqn. (5): K = C1 [C1 + C2]^-1  (s symmetric)
    d = x2 - x1
    for i in angle_index:
        d[i] = wrap_angle(d[i])
    x3 = x1 + k @ d  # Eqn. (7)
    # Eqn. (6), C3 = C1 - K C1, in Joseph's form (I - K) C1 (I - K)^T + K C2 K^T: equal for this K, and a sum
    # of positive semi-definite terms whatever the rounding (C1 - K C1 of a 1 m^2 prior and a 1e-8 m^2 sensor
    # came out with eigenvalue -1.3e-14, which armguard's own validation then refused)
    ik = np.eye(len(x1)) - k
    c3 = ik @ c1 @ ik.T + k @ c2 @ k.T
    return x3, symmetrize(c3), k


# --- validated, array-first API ------------------------------------------------------------


def compound_mean(x1, x2) -> np.ndarray:
    """Mean of ``x1 ⊕ x2`` (Eqn. 1): B's relation to A (``x1``) then C's to B (``x2``).

    Parameters
    ----------
    x1, x2 : (3,) float64, (m, m, rad)
        Relations A→B and B→C.

    Returns
    -------
    x3 : (3,) float64, (m, m, rad) — relation A→C.
    """
    return _compound_mean(as_vector(x1, 3, "x1"), as_vector(x2, 3, "x2"))


def compound_jacobians(x1, x2) -> tuple[np.ndarray, np.ndarray]:
    """The compounding Jacobian J⊕ of Eqn. (2) at the means, split into its two (3, 3) halves.

    ``J⊕ = [J1 | J2]`` (3 × 6) with, writing ``x3 = x1 ⊕ x2``::

        J1 = ∂x3/∂x1 = [[1, 0, -(y3 - y1)],     J2 = ∂x3/∂x2 = [[cos θ1, -sin θ1, 0],
                        [0, 1,   x3 - x1 ],                     [sin θ1,  cos θ1, 0],
                        [0, 0,      1    ]]                     [   0,       0,   1]]

    (the OCR of the paper garbles the third column of J1; it is re-derived here from Eqn. 1:
    ``∂x3/∂θ1 = -x2 sin θ1 - y2 cos θ1 = -(y3 - y1)``, ``∂y3/∂θ1 = x3 - x1``).

    Parameters
    ----------
    x1, x2 : (3,) float64, (m, m, rad)

    Returns
    -------
    j1, j2 : (3, 3) float64 each; rows (m, m, rad) over columns (m, m, rad).
    """
    x1 = as_vector(x1, 3, "x1")
    x2 = as_vector(x2, 3, "x2")
    return _compound_jacobians(x1, x2, _compound_mean(x1, x2))


def compound(x1, c1, x2, c2, c12=None, *, tol: Tolerances = DEFAULT_TOLERANCES):
    """Compound two uncertain relations, ``x3 = x1 ⊕ x2`` (Eqns. 1–3).

    ``C3 = J⊕ [[C1, C12], [C12^T, C2]] J⊕^T``; Eqn. (3) is the independent case ``C12 = 0``,
    the paper's dependent case ("treating the dependent combination as a unit") is ``c12``.

    Parameters
    ----------
    x1 : (3,) float64, (m, m, rad)
        Relation A→B.
    c1 : (3, 3) float64, m² / m·rad / rad²
        Its covariance.
    x2 : (3,) float64, (m, m, rad)
        Relation B→C, in B's coordinates.
    c2 : (3, 3) float64, m² / m·rad / rad²
        Its covariance.
    c12 : (3, 3) float64, optional
        Cross-covariance ``E[Δx1 Δx2^T]``; ``None`` for independent relations.

    Returns
    -------
    x3 : (3,) float64, (m, m, rad) — A→C.
    c3 : (3, 3) float64 — its covariance (exactly symmetric).
    j1, j2 : (3, 3) float64 — the Jacobian halves (see :func:`compound_jacobians`).
    """
    x1 = as_vector(x1, 3, "x1")
    x2 = as_vector(x2, 3, "x2")
    c1 = as_covariance(c1, 3, "c1", tol)
    c2 = as_covariance(c2, 3, "c2", tol)
    if c12 is not None:
        try:
            c12 = np.array(c12, dtype=np.float64)
        except (TypeError, ValueError):
            raise UncertaintyError(f"cross_cov: expected a finite (3, 3) array, got {type(c12).__name__}") from None
        if c12.shape != (3, 3):
            raise UncertaintyError(f"cross_cov: expected a finite (3, 3) array, got shape {c12.shape}")
        if not np.all(np.isfinite(c12)):
            raise UncertaintyError("cross_cov: contains NaN or infinity")
        as_covariance(np.block([[c1, c12], [c12.T, c2]]), 6, "joint covariance [[c1, c12], [c12^T, c2]]", tol)
    return _compound(x1, c1, x2, c2, c12)


def reverse_mean(x) -> np.ndarray:
    """Mean of ``⊖x`` (Eqn. 4): A's relation to B given B's relation ``x`` to A.

    ``x' = -x cos θ - y sin θ``, ``y' = x sin θ - y cos θ``, ``θ' = -θ``.

    Parameters
    ----------
    x : (3,) float64, (m, m, rad)

    Returns
    -------
    (3,) float64, (m, m, rad)
    """
    return _reverse_mean(as_vector(x, 3, "x"))


def reverse_jacobian(x) -> np.ndarray:
    """Jacobian J⊖ of the reversal (Section 3.1, after Eqn. 4) at ``x``::

        J⊖ = [[-cos θ, -sin θ,  y'],
              [ sin θ, -cos θ, -x'],
              [   0,      0,   -1 ]]

    with ``(x', y')`` the reversed mean (the OCR drops the third column's entries; they are
    re-derived from Eqn. 4: ``∂x'/∂θ = x sin θ - y cos θ = y'``, ``∂y'/∂θ = x cos θ + y sin θ
    = -x'``).

    Parameters
    ----------
    x : (3,) float64, (m, m, rad)

    Returns
    -------
    (3, 3) float64
    """
    x = as_vector(x, 3, "x")
    return _reverse_jacobian(x, _reverse_mean(x))


def reverse(x, c, *, tol: Tolerances = DEFAULT_TOLERANCES):
    """Reverse an uncertain relation, ``⊖x`` (Eqn. 4), ``C' = J⊖ C J⊖^T``.

    Parameters
    ----------
    x : (3,) float64, (m, m, rad)
        Relation A→B.
    c : (3, 3) float64, m² / m·rad / rad²

    Returns
    -------
    xr : (3,) float64 — relation B→A.
    cr : (3, 3) float64 — its covariance.
    j : (3, 3) float64 — J⊖.
    """
    return _reverse(as_vector(x, 3, "x"), as_covariance(c, 3, "c", tol))


def merge(x1, c1, x2, c2, *, tol: Tolerances = DEFAULT_TOLERANCES):
    """Merge two independent parallel estimates of one relation (Eqns. 5–7, Kalman update).

    ``K = C1 (C1 + C2)^-1`` (5), ``C3 = C1 - K C1`` (6), ``x3 = x1 + K (x2 - x1)`` (7); the
    angle of ``x2 - x1`` is wrapped into (-π, π].  Symmetric in its two arguments (the paper's
    remark after Eqn. 7); either covariance may be singular (a coordinate known exactly) as
    long as ``C1 + C2`` is not (:attr:`Tolerances.merge_conditioning`).

    Parameters
    ----------
    x1, x2 : (3,) float64, (m, m, rad)
        Two estimates of relation A→B (reverse one first if it points B→A).
    c1, c2 : (3, 3) float64, m² / m·rad / rad²

    Returns
    -------
    x3 : (3,) float64 — the merged estimate.
    c3 : (3, 3) float64 — its covariance (exactly symmetric).
    k : (3, 3) float64 — the Kalman gain.
    """
    return _merge(
        as_vector(x1, 3, "x1"), as_covariance(c1, 3, "c1", tol),
        as_vector(x2, 3, "x2"), as_covariance(c2, 3, "c2", tol), tol,
    )


def polar_to_cartesian(p, c, *, tol: Tolerances = DEFAULT_TOLERANCES):
    """Map a range/bearing(/orientation) estimate to Cartesian form (Appendix B).

    ``x = r cos φ``, ``y = r sin φ``, ``θ = θ``; ``C(x, y, θ) = R C(r, φ, θ) R^T`` with::

        R = [[cos φ, -r sin φ, 0],     (the paper writes cos φ = x/r, sin φ = y/r;
             [sin φ,  r cos φ, 0],      the OCR of R is garbled and this is re-derived)
             [  0,       0,    1]]

    Parameters
    ----------
    p : (3,) float64, (m, rad, rad)
        Range ``r >= 0``, bearing ``φ`` and the frame's rotation ``θ``, in the sensor frame.
    c : (3, 3) float64, m² / m·rad / rad²
        Covariance of ``(r, φ, θ)``.

    Returns
    -------
    x : (3,) float64, (m, m, rad) — the relation in Cartesian form.
    cx : (3, 3) float64 — its covariance.
    jac : (3, 3) float64 — R.
    """
    p = as_vector(p, 3, "p")
    c = as_covariance(c, 3, "c", tol)
    r, phi = p[0], p[1]
    if r < 0.0:
        raise UncertaintyError(f"p: range must be >= 0, got {r}")
    cp, sp = np.cos(phi), np.sin(phi)
    jac = np.array([[cp, -r * sp, 0.0], [sp, r * cp, 0.0], [0.0, 0.0, 1.0]])
    return np.array([r * cp, r * sp, p[2]]), symmetrize(jac @ c @ jac.T), jac
