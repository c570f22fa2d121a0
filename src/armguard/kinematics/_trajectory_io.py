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

from .._errors import ArmguardError, SceneFileError, TrajectoryError, list_problems

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


def _not_a_number(value, place: str = ""):
    """``(place, what)`` of the first entry of ``value`` (a number or nested lists) that is not a YAML number,
    else None."""
    if isinstance(value, list):
        for k, v in enumerate(value):
            bad = _not_a_number(v, f"{place}[{k}]")
            if bad is not None:
                return bad
        return None
    if isinstance(value, bool):
        return place, f"a boolean ({str(value).lower()}; YAML reads yes/no/on/off so)"
    if value is None:
        return place, "nothing (null, or an empty entry)"
    if isinstance(value, str):
        return place, f"the text {value!r} (a number is written unquoted)"
    if not isinstance(value, (int, float)):
        return place, f"a {type(value).__name__}"
    return None


def _numbers(d, key: str, ndim: int, problems: list, width: int | None = None):
    """``d[key]`` as a float64 array of ``ndim`` dimensions, or None with the problem noted."""
    value = d[key]
    if ndim == 2 and isinstance(value, list):
        for k, row in enumerate(value):
            if not isinstance(row, list):
                problems.append((f"{key}[{k}]", f"expected a list of {width or ''} numbers, got {type(row).__name__}".replace("  ", " ")))
                return None
            if width is not None and len(row) != width:
                problems.append((f"{key}[{k}]", f"expected {width} joint values (one per joint_names entry), got {len(row)}"))
                return None
    bad = _not_a_number(value)
    if bad is not None:  # YAML's true / yes / on, null and quoted text: numpy would read 1.0, NaN or the number
        place, what = bad
        problems.append((f"{key}{place}", f"expected a number, got {what}"))
        return None
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):  # OverflowError: an integer beyond float range
        problems.append((key, f"expected {'a list' if ndim == 1 else 'a list of lists'} of numbers"))
        return None
    if arr.ndim != ndim:
        problems.append((key, f"expected {'a list' if ndim == 1 else 'a list of equal-length lists'} of numbers, got shape {arr.shape}"))
        return None
    bad = ~np.isfinite(arr)
    if np.any(bad):
        idx = "".join(f"[{i}]" for i in np.argwhere(bad)[0])
        problems.append((f"{key}{idx}", "expected a finite number, got NaN or inf"))
        return None
    return arr


def trajectory_from_dict(cls, d, *, file=None, groups=None):
    """A trajectory of ``cls`` from its YAML dictionary; every problem found is listed in one error
    (a missing key with a misspelt one beside it says so).  ``joint_names`` may be a group's name
    (a string) when ``groups`` (a callable: group name -> its joint names, e.g.
    :meth:`armguard.model.Model.group_joints`) resolves it."""
    import difflib

    if not isinstance(d, dict):
        if d is None:
            got = "an empty file (no YAML document)"
        elif isinstance(d, str) and d.lstrip().startswith("<"):
            got = "XML text (a URDF or SRDF? a trajectory is a YAML file: docs/trajectory-format.md)"
        else:
            got = f"a {type(d).__name__} ({str(d)[:40]!r})" if isinstance(d, (str, int, float)) else f"a {type(d).__name__}"
        raise _fail(file, "", f"expected a trajectory: a YAML mapping with keys {list(_KEYS)}, got {got}")
    problems: list[tuple[str, str]] = []
    unknown = sorted(str(k) for k in set(d) - set(_KEYS))
    for key in ("format", "version", "robot", "joint_names", "times", "waypoints"):
        if key not in d:
            near = difflib.get_close_matches(key, unknown, n=1, cutoff=0.6)
            hint = f" (the unknown key {near[0]!r} looks like a misspelling of {key!r})" if near else ""
            problems.append((key, "missing required key" + hint))
    for key in unknown:
        problems.append((key, f"unknown key; expected one of {list(_KEYS)}"))
    if "format" in d and d["format"] != FORMAT:
        problems.append(("format", f"expected {FORMAT!r}, got {d['format']!r}"))
    if "version" in d and (type(d["version"]) is not int or d["version"] != VERSION):  # 1.0 and true equal 1
        problems.append(("version", f"unsupported version {d['version']!r}; this armguard reads version {VERSION}"))
    if "robot" in d and not isinstance(d["robot"], str):
        problems.append(("robot", f"expected a robot name (string), got {d['robot']!r}"))
    names = d.get("joint_names")
    if isinstance(names, str):  # an SRDF group of the robot
        try:
            if groups is None:
                raise TrajectoryError("no model with SRDF groups to resolve it")
            names = list(groups(names))
        except ArmguardError as exc:
            problems.append(("joint_names", f"{names!r} is not a list of joint names nor a group of the model: {exc}"))
            names = None
    elif "joint_names" in d and (not isinstance(names, list) or not all(isinstance(n, str) for n in names)):
        problems.append(("joint_names", "expected a list of joint names (strings)"))
        names = None
    times = _numbers(d, "times", 1, problems) if "times" in d else None
    wp = _numbers(d, "waypoints", 2, problems, len(names) if names else None) if "waypoints" in d else None
    blend = _numbers(d, "blend_times", 1, problems) if "blend_times" in d else None
    if problems:
        raise _fail(file, *list_problems(problems))
    try:
        return cls(d["robot"], names, times, wp, blend)
    except TrajectoryError as exc:
        msg = str(exc)
        key = msg.split(":", 1)[0].split("[", 1)[0].strip()
        if key in _KEYS:  # "times: must be ..." -> place "times", message "must be ..."
            where, _, rest = msg.partition(":")
            raise _fail(file, where.strip(), rest.strip()) from None
        raise _fail(file, "", msg) from None


def save_yaml(traj, path) -> None:
    from .._io import atomic_write

    atomic_write(os.fspath(path), yaml.safe_dump(trajectory_to_dict(traj), sort_keys=False, default_flow_style=None),
                 parents=True)


def load_yaml(cls, path, groups=None):
    from .._lines import lines_for
    from .._yaml import read_scene_yaml

    file = os.fspath(path)
    d = read_scene_yaml(file)  # the scene files' strict reading: a repeated key, an alias or bad YAML located

    with lines_for(file):
        return trajectory_from_dict(cls, d, file=file, groups=groups)
