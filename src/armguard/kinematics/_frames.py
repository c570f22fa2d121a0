"""Elementary homogeneous transforms, WORKMATE's frame convention and DH A-matrices.

WORKMATE (Smith 1986, seed ``004``, "Modeling") writes a relation between object frames as

    X = trans(x, y, z) * rot(z, phi) * rot(y, theta) * rot(x, psi)

("first translating x, y, z along the current axes, then successive roll, pitch and yaw
rotations").  This is the URDF ``xyz`` + ``rpy`` convention with ``rpy = (psi, theta, phi)``:
:func:`pose_from_xyz_rpy` builds it and :func:`xyz_rpy_from_pose` inverts it.

Denavit-Hartenberg A-matrices (seed ``004`` "A-matrices"; seed ``001`` eq. of the direct
kinematics, after Denavit & Hartenberg 1955):

* standard (distal) convention:  ``A_i = rot(z, theta_i) trans(z, d_i) trans(x, a_i) rot(x, alpha_i)``
* modified (proximal, Craig):    ``A_i = rot(x, alpha_{i-1}) trans(x, a_{i-1}) rot(z, theta_i) trans(z, d_i)``
"""

from __future__ import annotations

import math

import numpy as np

from .._errors import KinematicsError

__all__ = [
    "rot_x",
    "rot_y",
    "rot_z",
    "trans",
    "pose_from_xyz_rpy",
    "xyz_rpy_from_pose",
    "dh_standard",
    "dh_modified",
    "invert_pose",
    "rotation_about_axis",
    "rotation_vector_from_matrix",
]


_GIMBAL_LOCK = 1e-12
"""``cos(pitch)`` below which roll and yaw are not separable (only their sum/difference is)."""


def _finite_vector(value, n: int, name: str) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise KinematicsError(f"{name}: expected {n} numbers, got {value!r}") from exc
    if arr.shape != (n,):
        raise KinematicsError(f"{name}: expected {n} numbers, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise KinematicsError(f"{name}: contains NaN or infinite values: {arr.tolist()!r}")
    return arr


def rot_x(angle: float) -> np.ndarray:
    """``(4, 4)``: rotation by ``angle`` (rad) about x."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])


def rot_y(angle: float) -> np.ndarray:
    """``(4, 4)``: rotation by ``angle`` (rad) about y."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, 0, s, 0], [0, 1.0, 0, 0], [-s, 0, c, 0], [0, 0, 0, 1.0]])


def rot_z(angle: float) -> np.ndarray:
    """``(4, 4)``: rotation by ``angle`` (rad) about z."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1.0, 0], [0, 0, 0, 1.0]])


def trans(x: float, y: float, z: float) -> np.ndarray:
    """``(4, 4)``: translation by ``(x, y, z)`` m."""
    X = np.eye(4)
    X[:3, 3] = (x, y, z)
    return X


def rotation_about_axis(axis, angle: float) -> np.ndarray:
    """``(4, 4)``: rotation by ``angle`` (rad) about the unit ``axis`` (3,) through the origin (Rodrigues)."""
    k = np.asarray(axis, dtype=np.float64)
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    X = np.eye(4)
    X[:3, :3] = np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * (K @ K)
    return X


def pose_from_xyz_rpy(xyz, rpy) -> np.ndarray:
    """WORKMATE's frame relation ``trans(x, y, z) rot(z, yaw) rot(y, pitch) rot(x, roll)``.

    xyz : (3,) float, m.  rpy : (3,) float, rad — ``(roll, pitch, yaw)``.
    Returns X : (4, 4) float64.  Raises KinematicsError on NaN/inf or wrong lengths.
    """
    x, y, z = _finite_vector(xyz, 3, "xyz")
    roll, pitch, yaw = _finite_vector(rpy, 3, "rpy")
    return trans(x, y, z) @ rot_z(yaw) @ rot_y(pitch) @ rot_x(roll)


def xyz_rpy_from_pose(X) -> tuple[np.ndarray, np.ndarray]:
    """Inverse of :func:`pose_from_xyz_rpy`: ``(xyz (3,) m, rpy (3,) rad)``.

    ``pitch`` is returned in ``[-pi/2, pi/2]``; at ``|pitch| = pi/2`` (gimbal lock) only
    ``yaw - roll`` (or ``yaw + roll``) is determined and ``roll`` is set to 0.
    """
    X = np.asarray(X, dtype=np.float64)
    if X.shape != (4, 4) or not np.all(np.isfinite(X)):
        raise KinematicsError(f"X: expected a finite 4x4 pose, got shape {X.shape}")
    R = X[:3, :3]
    if not np.allclose(R.T @ R, np.eye(3), rtol=0.0, atol=1e-6) or np.linalg.det(R) < 0.0:
        raise KinematicsError("X: not a rigid transform (its rotation part is not orthonormal with det +1)")
    # R = Rz(yaw) Ry(pitch) Rx(roll):  R[2,0] = -sin(pitch), R[2,1] = cos(pitch) sin(roll), ...
    sp = -R[2, 0]
    cp = math.hypot(R[0, 0], R[1, 0])
    pitch = math.atan2(sp, cp)
    if cp > _GIMBAL_LOCK:
        roll = math.atan2(R[2, 1], R[2, 2])
        yaw = math.atan2(R[1, 0], R[0, 0])
    else:
        roll = 0.0
        yaw = math.atan2(-R[0, 1], R[1, 1])
    rpy = np.array([roll, pitch, yaw])
    if cp < _POLISH_BELOW:
        rpy = _polish_rpy(R, rpy)
    return X[:3, 3].copy(), rpy


_POLISH_BELOW = 1e-2
"""``cos(pitch)`` below which :func:`xyz_rpy_from_pose` polishes its angles (:func:`_polish_rpy`):
near gimbal lock ``roll = atan2(R21, R22)`` divides two entries of size ``cos(pitch)``, so each
angle alone is off by ``~1e-16 / cos(pitch)`` and the rotation they make by as much (so101's URDF:
pitch 3.7e-6 rad from pi/2, 3.2e-11 off)."""


def _rpy_matrix(rpy: np.ndarray) -> np.ndarray:
    return (rot_z(rpy[2]) @ rot_y(rpy[1]) @ rot_x(rpy[0]))[:3, :3]


def _polish_rpy(R: np.ndarray, rpy: np.ndarray, steps: int = 4) -> np.ndarray:
    """Gauss-Newton steps on ``min |Rz(yaw) Ry(pitch) Rx(roll) - R|_F`` from ``rpy``: the angles are
    ill-conditioned near gimbal lock but the rotation they make is not, so a few least-squares
    steps bring it back to rounding; a step is kept only where it reduces the residual."""
    best, err = rpy, np.abs(_rpy_matrix(rpy) - R).max()
    for _ in range(steps):
        if err < 1e-15:
            break
        r, p, y = best
        Rx, Ry, Rz = rot_x(r)[:3, :3], rot_y(p)[:3, :3], rot_z(y)[:3, :3]
        dRx = np.array([[0.0, 0, 0], [0, -math.sin(r), -math.cos(r)], [0, math.cos(r), -math.sin(r)]])
        dRy = np.array([[-math.sin(p), 0, math.cos(p)], [0, 0.0, 0], [-math.cos(p), 0, -math.sin(p)]])
        dRz = np.array([[-math.sin(y), -math.cos(y), 0], [math.cos(y), -math.sin(y), 0], [0, 0, 0.0]])
        J = np.stack([(Rz @ Ry @ dRx).ravel(), (Rz @ dRy @ Rx).ravel(), (dRz @ Ry @ Rx).ravel()], axis=1)
        step = np.linalg.lstsq(J, (R - Rz @ Ry @ Rx).ravel(), rcond=None)[0]
        cand = best + step
        e = np.abs(_rpy_matrix(cand) - R).max()
        if not e < err:
            break
        best, err = cand, e
    return best


def dh_standard(a: float, alpha: float, d: float, theta: float) -> np.ndarray:
    """Standard DH A-matrix ``rot(z, theta) trans(z, d) trans(x, a) rot(x, alpha)`` (4, 4)."""
    return rot_z(theta) @ trans(0, 0, d) @ trans(a, 0, 0) @ rot_x(alpha)


def dh_modified(a: float, alpha: float, d: float, theta: float) -> np.ndarray:
    """Modified (Craig) DH A-matrix ``rot(x, alpha) trans(x, a) rot(z, theta) trans(z, d)`` (4, 4)."""
    return rot_x(alpha) @ trans(a, 0, 0) @ rot_z(theta) @ trans(0, 0, d)


def invert_pose(X: np.ndarray) -> np.ndarray:
    """Inverse of rigid transforms ``X`` (..., 4, 4): ``[R^T, -R^T p]``."""
    try:
        X = np.asarray(X, dtype=np.float64)
    except (TypeError, ValueError):
        raise KinematicsError(f"X: expected rigid transforms (..., 4, 4), got {X!r}") from None
    if X.shape[-2:] != (4, 4):
        raise KinematicsError(f"X: expected rigid transforms (..., 4, 4), got shape {X.shape}")
    out = np.zeros_like(X)
    Rt = np.swapaxes(X[..., :3, :3], -1, -2)
    out[..., :3, :3] = Rt
    out[..., :3, 3] = -np.einsum("...ij,...j->...i", Rt, X[..., :3, 3])
    out[..., 3, 3] = 1.0
    return out


def rotation_vector_from_matrix(R: np.ndarray) -> np.ndarray:
    """Rotation vector (axis * angle, rad) of the rotation matrix ``R`` (3, 3); angle in [0, pi].

    Uses the skew part for small and moderate angles and the symmetric part near pi, so it is
    accurate over the whole range.
    """
    R = np.asarray(R, dtype=np.float64)
    c = max(-1.0, min(1.0, 0.5 * (R[0, 0] + R[1, 1] + R[2, 2] - 1.0)))
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    s = 0.5 * float(np.linalg.norm(w))
    angle = math.atan2(s, c)
    if c > -0.5:  # angle < 2 pi / 3: the skew part is well conditioned
        if s == 0.0:
            return 0.5 * w  # exactly zero rotation (w = 0)
        return w * (angle / (2.0 * s))
    # near pi: axis from the largest diagonal of (R + I) / 2 = k k^T (1 - c)/... + c I
    B = 0.5 * (R + R.T) - c * np.eye(3)
    i = int(np.argmax(np.diag(B)))
    k = B[:, i] / math.sqrt(B[i, i])  # B[i, i] >= (1 - c) / 3 > 0 for the largest diagonal
    k /= np.linalg.norm(k)
    if float(np.dot(k, w)) < 0.0:
        k = -k
    return k * angle
