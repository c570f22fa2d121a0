"""YAML form of a Trajectory (versioned), with errors that name the file and the key.

::

    format: armguard.trajectory
    version: 1
    robot: puma560
    joint_names: [joint1, ...]
    times: [0.0, 1.5, ...]             # s
    waypoints: [[...], [...], ...]     # rad or m, one row per knot
    blend_times: [0.5, ...]            # s, one per segment (0: constant speed)
"""

from __future__ import annotations

import os

import numpy as np
import yaml

from .._errors import SceneFileError, TrajectoryError

__all__ = ["trajectory_to_dict", "trajectory_from_dict", "save_yaml", "load_yaml", "FORMAT", "VERSION"]

FORMAT = "armguard.trajectory"
VERSION = 1
_KEYS = ("format", "version", "robot", "joint_names", "times", "waypoints", "blend_times")


def trajectory_to_dict(traj) -> dict:
    return {
        "format": FORMAT,
        "version": VERSION,
        "robot": traj.robot_name,
        "joint_names": list(traj.joint_names),
        "times": [float(x) for x in traj.times],
        "waypoints": [[float(x) for x in row] for row in traj.waypoints],
        "blend_times": [float(x) for x in traj.blend_times],
    }


def _fail(file, where: str, message: str):
    if file is not None:
        return SceneFileError(file, where, message)
    return TrajectoryError(f"{where}: {message}")


def _numbers(d, key: str, ndim: int, file):
    value = d[key]
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):  # OverflowError: an integer beyond float range
        raise _fail(file, key, f"expected {'a list' if ndim == 1 else 'a list of lists'} of numbers") from None
    if arr.ndim != ndim:
        raise _fail(file, key, f"expected {'a list' if ndim == 1 else 'a list of equal-length lists'} of numbers, got shape {arr.shape}")
    bad = ~np.isfinite(arr)
    if np.any(bad):
        idx = "".join(f"[{i}]" for i in np.argwhere(bad)[0])
        raise _fail(file, f"{key}{idx}", "expected a finite number, got NaN or inf")
    return arr


def trajectory_from_dict(cls, d, *, file=None):
    if not isinstance(d, dict):
        raise _fail(file, "", f"expected a mapping with keys {list(_KEYS)}, got {type(d).__name__}")
    unknown = sorted(set(d) - set(_KEYS))
    if unknown:
        raise _fail(file, unknown[0], f"unknown key; expected one of {list(_KEYS)}")
    for key in ("format", "version", "robot", "joint_names", "times", "waypoints"):
        if key not in d:
            raise _fail(file, key, "missing required key")
    if d["format"] != FORMAT:
        raise _fail(file, "format", f"expected {FORMAT!r}, got {d['format']!r}")
    if d["version"] != VERSION:
        raise _fail(file, "version", f"unsupported version {d['version']!r}; this armguard reads version {VERSION}")
    if not isinstance(d["robot"], str):
        raise _fail(file, "robot", f"expected a robot name (string), got {d['robot']!r}")
    names = d["joint_names"]
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        raise _fail(file, "joint_names", "expected a list of joint names (strings)")
    times = _numbers(d, "times", 1, file)
    wp = _numbers(d, "waypoints", 2, file)
    blend = _numbers(d, "blend_times", 1, file) if "blend_times" in d else None
    try:
        return cls(d["robot"], names, times, wp, blend)
    except TrajectoryError as exc:
        msg = str(exc)
        key = msg.split(":", 1)[0].split("[", 1)[0]
        raise _fail(file, key if key in _KEYS else "", msg) from None


def save_yaml(traj, path) -> None:
    with open(os.fspath(path), "w", encoding="utf-8") as fh:
        yaml.safe_dump(trajectory_to_dict(traj), fh, sort_keys=False, default_flow_style=None)


def load_yaml(cls, path):
    file = os.fspath(path)
    try:
        with open(file, encoding="utf-8") as fh:
            d = yaml.safe_load(fh)
    except OSError as exc:
        raise SceneFileError(file, "", f"cannot read: {exc.strerror or exc}") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
        raise SceneFileError(file, where, f"not valid YAML: {getattr(exc, 'problem', exc)}") from None
    return trajectory_from_dict(cls, d, file=file)
