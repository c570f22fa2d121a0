"""armguard: model-based collision and proximity detection for robot manipulators.

The top-level names are imported lazily, so ``import armguard`` is fast and compiles no
kernels until they are used.
"""

from __future__ import annotations

import importlib

from ._errors import (
    ArmguardError,
    ArmguardWarning,
    AvoidanceError,
    ClipError,
    BackendError,
    DetectionError,
    ForbiddenMapError,
    GeometryError,
    IKError,
    JointLimitError,
    KinematicsError,
    OutputError,
    SceneError,
    SceneFileError,
    TerrainError,
    ToleranceError,
    TrajectoryError,
    UncertaintyError,
    StaleModelError,
    VerificationError,
)
from ._tolerance import DEFAULT_TOLERANCES, Tolerances
from ._numba_cache import ensure_numba_cache as _ensure_numba_cache
from . import _hooks

_ensure_numba_cache()  # before any kernel is defined: a read-only install still caches them somewhere


def _read_robot_urdf(*args, **kwargs):
    from .model._robot_urdf import robot_from_urdf

    return robot_from_urdf(*args, **kwargs)


_hooks.read_robot_urdf = _read_robot_urdf  # Robot.from_urdf (kinematics) reads through armguard.model

__version__ = "0.1.0"

# public name -> module that defines it (imported on first access)
_LAZY = {
    "load_scene": "armguard.scene",
    "load_model": "armguard.model",
    "Model": "armguard.model",
    "checker": "armguard.backends",
    "Scene": "armguard.scene",
    "Robot": "armguard.kinematics",
    "Trajectory": "armguard.kinematics",
    "Detector": "armguard.detect",
    "DetectionReport": "armguard.detect",
    "Status": "armguard.detect",
    "verify": "armguard.verify",
    "verify_many": "armguard.verify",
    "avoid": "armguard.avoidance",
    "VerificationReport": "armguard.verify",
}

__all__ = [
    "ArmguardError",
    "ArmguardWarning",
    "AvoidanceError",
    "BackendError",
    "GeometryError",
    "KinematicsError",
    "IKError",
    "JointLimitError",
    "SceneError",
    "SceneFileError",
    "TrajectoryError",
    "DetectionError",
    "StaleModelError",
    "VerificationError",
    "OutputError",
    "ClipError",
    "ForbiddenMapError",
    "TerrainError",
    "ToleranceError",
    "UncertaintyError",
    "Tolerances",
    "DEFAULT_TOLERANCES",
    *_LAZY,
]


# subpackages reachable as attributes after a plain ``import armguard`` (``armguard.backends.available()``
# raised AttributeError until something had imported the subpackage)
_SUBPACKAGES = frozenset({"avoidance", "backends", "clip", "cspace", "detect", "geometry", "harness", "kinematics",
                          "model", "models", "program", "scene", "srdfgen", "terrain", "testing", "uncertainty", "verify"})


def __getattr__(name: str):
    if name in _SUBPACKAGES:
        return importlib.import_module(f"armguard.{name}")
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'armguard' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_LAZY) | _SUBPACKAGES)
