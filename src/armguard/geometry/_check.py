"""Validation helpers for the public boundary: coerce, check, return (kernels trust their inputs)."""

from __future__ import annotations

import numpy as np

from .._errors import GeometryError
from .._tolerance import DEFAULT_TOLERANCES

__all__ = ["check_point", "check_points", "check_rotation", "check_nonnegative", "check_pose"]


def _as_float_array(value, name: str) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise GeometryError(f"{name}: expected numbers, got {value!r}") from exc
    if not np.all(np.isfinite(arr)):
        raise GeometryError(f"{name}: contains NaN or infinite values: {arr.tolist()!r}")
    big = DEFAULT_TOLERANCES.max_magnitude
    if arr.size and float(np.abs(arr).max()) > big:  # squared lengths overflow from ~1e154: 'apart' by overflow
        raise GeometryError(f"{name}: {float(np.abs(arr).max()):.6g} is beyond the largest magnitude armguard handles "
                            f"({big:g} m, Tolerances.max_magnitude)")
    return arr


def check_point(value, name: str) -> np.ndarray:
    """Return ``value`` as a finite read-only ``(3,)`` float64 array, or raise GeometryError naming ``name``."""
    arr = _as_float_array(value, name)
    if arr.shape != (3,):
        raise GeometryError(f"{name}: expected a 3-vector, got shape {arr.shape}")
    arr = arr.copy()
    arr.flags.writeable = False
    return arr


def check_points(value, name: str, min_count: int = 1) -> np.ndarray:
    """Return ``value`` as a finite read-only ``(n, 3)`` float64 array with ``n >= min_count``."""
    arr = _as_float_array(value, name)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise GeometryError(f"{name}: expected an (n, 3) array of points, got shape {arr.shape}")
    if arr.shape[0] < min_count:
        raise GeometryError(f"{name}: expected at least {min_count} points, got {arr.shape[0]}")
    arr = np.ascontiguousarray(arr).copy()
    arr.flags.writeable = False
    return arr


def check_nonnegative(value, name: str) -> float:
    """Return ``value`` as a finite float >= 0."""
    try:
        x = float(value)
    except (TypeError, ValueError) as exc:
        raise GeometryError(f"{name}: expected a number, got {value!r}") from exc
    if not np.isfinite(x):
        raise GeometryError(f"{name}: must be finite, got {x}")
    if x < 0.0:
        raise GeometryError(f"{name}: must be >= 0, got {x}")
    if x > DEFAULT_TOLERANCES.max_magnitude:
        raise GeometryError(f"{name}: {x:.6g} is beyond the largest magnitude armguard handles "
                            f"({DEFAULT_TOLERANCES.max_magnitude:g} m, Tolerances.max_magnitude)")
    return x


def check_rotation(value, name: str, atol: float = 1e-9) -> np.ndarray:
    """Return ``value`` as a read-only proper rotation matrix ``(3, 3)`` (orthonormal, det +1)."""
    arr = _as_float_array(value, name)
    if arr.shape != (3, 3):
        raise GeometryError(f"{name}: expected a 3x3 rotation matrix, got shape {arr.shape}")
    if not np.allclose(arr.T @ arr, np.eye(3), atol=atol) or np.linalg.det(arr) < 0.0:
        raise GeometryError(f"{name}: not a proper rotation matrix (R^T R != I or det(R) != +1)")
    if np.abs(arr.T @ arr - np.eye(3)).max() > 1e-12:  # within the tolerance, past rounding (written to 6 places):
        u, _, vt = np.linalg.svd(arr)  # the nearest rotation, so that every kernel sees one shape ((1 + 4e-6) I was
        arr = u @ vt                   # a box 4 µm/m larger to the box kernel than to the polytope one)
    arr = arr.copy()
    arr.flags.writeable = False
    return arr


def check_pose(value, name: str, atol: float = 1e-9) -> np.ndarray:
    """Return ``value`` as a homogeneous rigid transform ``(4, 4)``; raises GeometryError otherwise."""
    arr = _as_float_array(value, name)
    if arr.shape != (4, 4):
        raise GeometryError(f"{name}: expected a 4x4 homogeneous transform, got shape {arr.shape}")
    if not np.allclose(arr[3], [0.0, 0.0, 0.0, 1.0], atol=atol):
        raise GeometryError(f"{name}: last row must be [0, 0, 0, 1], got {arr[3].tolist()}")
    R = check_rotation(arr[:3, :3], f"{name}[:3, :3]", atol=atol)
    if not np.array_equal(R, arr[:3, :3]):  # made the nearest rotation (check_rotation)
        arr = arr.copy()
        arr[:3, :3] = R
    return arr
