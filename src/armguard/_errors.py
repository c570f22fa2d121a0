"""The armguard error hierarchy: one base class, one subclass per kind of failure."""

from __future__ import annotations

__all__ = [
    "ArmguardError",
    "GeometryError",
    "KinematicsError",
    "IKError",
    "SceneError",
    "SceneFileError",
    "TrajectoryError",
    "DetectionError",
    "VerificationError",
]


class ArmguardError(Exception):
    """Base class of every error armguard raises on purpose."""


class GeometryError(ArmguardError, ValueError):
    """A shape or geometric query was given invalid data (NaN, negative radius, degenerate hull...)."""


class KinematicsError(ArmguardError, ValueError):
    """A kinematic model or a joint configuration is invalid (wrong length, outside limits, bad DH row)."""


class IKError(KinematicsError):
    """Inverse kinematics found no solution within tolerance and joint limits."""


class SceneError(ArmguardError, ValueError):
    """A scene operation is invalid (unknown body, duplicate name, unknown robot)."""


class SceneFileError(SceneError):
    """A scene, robot or trajectory file could not be loaded; names the file, the place in it and what was expected."""

    def __init__(self, file: str, where: str, message: str) -> None:
        self.file = str(file)
        self.where = where
        self.message = message
        loc = f"{self.file}: {where}" if where else self.file
        super().__init__(f"{loc}: {message}")


class TrajectoryError(ArmguardError, ValueError):
    """A trajectory is invalid (non-monotone times, wrong joint count, limits exceeded)."""


class DetectionError(ArmguardError, ValueError):
    """A detector was given an invalid query (bad configuration, unknown arm)."""


class VerificationError(ArmguardError, ValueError):
    """A trajectory verification request is invalid."""
