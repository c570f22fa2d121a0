"""Task-program files (``armguard_program: 1``) and cell files (``armguard_cell: 1``): the YAML
formats of WORKMATE's off-line programs (Smith 1986, seed 004, §III.D) as pydantic models.

Both are read like scene files: the strict YAML loader (no duplicate keys, no aliases), unknown
keys refused, numbers strict and finite, and every error a :class:`SceneFileError` naming the
file, the place (``tasks[2].grasp.xyz``, with its line) and what was expected.
``docs/program.md`` is the user-facing description of both formats.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from .._errors import SceneFileError, list_problems
from ..model._schema import Name, Num, Vec3, VersionOne, VersionOne

__all__ = ["TASK_KINDS", "ProgramFile", "CellFile", "Task", "Motion", "read_program", "read_cell", "is_cell_file"]

TASK_KINDS = ("find", "pickup", "place", "move")


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True, strict=True)


class _Units(_Model):
    angle: Literal["deg", "rad"] = "rad"
    length: Literal["m", "mm"] = "m"


class MotionSpec(_Model):
    """A tool pose relative to a frame, and how the tool gets there (``line`` or ``joint``)."""

    xyz: Vec3 = [0.0, 0.0, 0.0]
    rpy: Vec3 = [0.0, 0.0, 0.0]
    mode: Literal["line", "joint"] | None = None


class _Find(_Model):
    find: Name


class _Pickup(_Model):
    pickup: Name
    approach: MotionSpec
    grasp: MotionSpec
    depart: MotionSpec


class _Place(_Model):
    place: Name
    onto: Name
    approach: MotionSpec
    release: MotionSpec
    depart: MotionSpec


class _Move(_Model):
    move: Literal["pose", "home", "joints"] = "pose"
    frame: Name = "world"
    xyz: Vec3 = [0.0, 0.0, 0.0]
    rpy: Vec3 = [0.0, 0.0, 0.0]
    joints: list[Num] | None = None
    mode: Literal["line", "joint"] = "joint"


_TASK_MODELS = {"find": _Find, "pickup": _Pickup, "place": _Place, "move": _Move}


class _ProgramHead(_Model):
    armguard_program: VersionOne
    name: Name
    description: str = ""
    cell: str | None = None
    robot: Name | None = None
    units: _Units = _Units()
    speed: Annotated[Num, Field(gt=0.0)] = 0.1
    confidence: Annotated[Num, Field(gt=0.0, lt=1.0)] = 0.999
    tasks: list[dict] = Field(min_length=1)


class _Posed(_Model):
    xyz: Vec3 = [0.0, 0.0, 0.0]
    rpy: Vec3 = [0.0, 0.0, 0.0]


class _Camera(_Posed):
    real: _Posed | None = None  # the real camera's offset from this (nominal) pose: the emulated truth
    fov: Annotated[Num, Field(gt=0.0, lt=180.0)] = 60.0  # full cone angle, always degrees
    sigma_xyz: Vec3 = [0.001, 0.001, 0.001]
    sigma_rpy: Vec3 = [0.0, 0.0, 0.0]


class CellFile(_Model):
    armguard_cell: VersionOne
    name: Name = "cell"
    description: str = ""
    model: str
    robot: Name | None = None
    units: _Units = _Units()
    objects: dict[Name, _Posed] = {}
    real: dict[Name, _Posed] = {}
    camera: _Camera = _Camera(xyz=[0.0, 0.0, 2.0], rpy=[math.pi, 0.0, 0.0])
    calibration: str | None = None


# ------------------------------------------------------------------ parsed forms (SI units)
@dataclass(frozen=True)
class Motion:
    """A tool pose ``X_FE`` (4, 4) in frame ``frame``, reached by a ``mode`` (``line``/``joint``) motion."""

    frame: str
    X_FE: np.ndarray
    mode: str


@dataclass(frozen=True)
class Task:
    """One task of a program: ``kind`` (find, pickup, place, move), the ``object`` it names, the
    ``target`` (place: the frame it is placed on), its ``motions`` in order, ``q`` (move joints),
    ``where`` (its place in the file: ``tasks[3]``) and ``line``."""

    kind: str
    object: str | None
    target: str | None
    motions: tuple
    q: np.ndarray | None
    where: str
    line: int | None


@dataclass(frozen=True)
class ProgramFile:
    """A parsed program: ``name``, ``description``, ``cell`` (as written, resolved against ``base``),
    ``robot``, ``speed`` (m/s), ``confidence``, ``tasks``, ``file``."""

    name: str
    description: str
    cell: str | None
    robot: str | None
    speed: float
    confidence: float
    tasks: tuple
    file: str
    base: Path
    angle: tuple = (1.0, "rad")  # the file's angle unit: (its value in rad, its name)


def _schema_error(file: str, exc: ValidationError, prefix: tuple = (), kind: str = "armguard_program") -> list:
    from ..model._scenefile import schema_problems

    errs = [{**e, "loc": prefix + tuple(e["loc"])} for e in exc.errors()]
    return [(w, m.replace("armguard_scene format", f"{kind} format")) for w, m in schema_problems(errs)]


def _pose(spec, L: float, A: float, file: str, where: str) -> np.ndarray:
    from .._errors import ArmguardError
    from ..kinematics import pose_from_xyz_rpy

    try:
        return pose_from_xyz_rpy(np.asarray(spec.xyz) * L, np.asarray(spec.rpy) * A)
    except ArmguardError as exc:
        raise SceneFileError(file, where, str(exc)) from None


def _units(u) -> tuple[float, float]:
    return (1e-3 if u.length == "mm" else 1.0), (math.pi / 180.0 if u.angle == "deg" else 1.0)


_DEFAULT_MODES = {"approach": "joint", "grasp": "line", "release": "line", "depart": "line"}


def _task(raw, i: int, L: float, A: float, file: str, lines: dict) -> Task:
    where = f"tasks[{i}]"
    if not isinstance(raw, dict):
        raise SceneFileError(file, where, f"expected a mapping with one of the keys {', '.join(TASK_KINDS)}, "
                                          f"got {type(raw).__name__}")
    kinds = [k for k in TASK_KINDS if k in raw]
    if len(kinds) != 1:
        got = f"{kinds}" if kinds else f"keys {sorted(map(str, raw))}"
        raise SceneFileError(file, where, f"a task has exactly one of the keys {', '.join(TASK_KINDS)}; got {got}")
    kind = kinds[0]
    if kind == "move" and raw.get("move") is None:
        raw = {**raw, "move": "pose"}
    try:
        spec = _TASK_MODELS[kind].model_validate(raw)
    except ValidationError as exc:
        raise _TaskProblems(_schema_error(file, exc, ("tasks", i))) from None
    line = lines.get(("tasks", i))
    if kind == "find":
        return Task("find", spec.find, None, (), None, where, line)
    if kind in ("pickup", "place"):
        obj = spec.pickup if kind == "pickup" else spec.place
        frame = obj if kind == "pickup" else spec.onto
        keys = ("approach", "grasp", "depart") if kind == "pickup" else ("approach", "release", "depart")
        motions = tuple(Motion(frame, _pose(getattr(spec, k), L, A, file, f"{where}.{k}"),
                               getattr(spec, k).mode or _DEFAULT_MODES[k]) for k in keys)
        return Task(kind, obj, None if kind == "pickup" else spec.onto, motions, None, where, line)
    # move
    if spec.move == "joints":
        if spec.joints is None:
            raise SceneFileError(file, f"{where}.joints", "move: joints needs 'joints: [q1, q2, ...]' (the angle unit)")
        return Task("move", None, None, (), np.asarray(spec.joints, dtype=np.float64) * A, where, line)
    if spec.joints is not None:
        raise SceneFileError(file, f"{where}.joints", "'joints' is only for 'move: joints'")
    if spec.move == "home":
        return Task("move", None, "home", (), None, where, line)
    return Task("move", None, None, (Motion(spec.frame, _pose(spec, L, A, file, where), spec.mode),), None, where, line)


class _TaskProblems(Exception):
    """A task's schema problems, ``(where, message)`` pairs, for :func:`read_program`'s one listing."""

    def __init__(self, problems) -> None:
        super().__init__(problems)
        self.problems = list(problems)


def _load(path, head_model, kind: str):
    from .._lines import line_map, lines_for
    from .._yaml import read_scene_yaml

    if not isinstance(path, (str, os.PathLike)):
        from .._errors import SceneError

        raise SceneError(f"expected the path of an {kind} file, got {type(path).__name__}")
    path = Path(path)
    file = str(path)
    with lines_for(file):
        data = read_scene_yaml(path)
        if not isinstance(data, dict):
            raise SceneFileError(file, "", f"expected a mapping at the top level ({kind}: 1, ...), got {type(data).__name__}")
        try:
            head = head_model.model_validate(data)
        except ValidationError as exc:
            raise SceneFileError(file, *list_problems(_schema_error(file, exc, (), kind))) from None
    return path, file, head, line_map(path.read_text(encoding="utf-8"))


def read_program(path) -> ProgramFile:
    """The task program in ``path`` (``armguard_program: 1``); errors are located SceneFileErrors."""
    from .._lines import lines_for

    path, file, head, lines = _load(path, _ProgramHead, "armguard_program")
    L, A = _units(head.units)
    tasks, problems = [], []
    with lines_for(file):
        for i, raw in enumerate(head.tasks):
            try:
                tasks.append(_task(raw, i, L, A, file, lines))
            except _TaskProblems as exc:  # each of a task's problems one line of the one listing
                problems.extend(exc.problems)
            except SceneFileError as exc:
                problems.append((exc.where, exc.message))
        if problems:
            raise SceneFileError(file, *list_problems(problems))
    return ProgramFile(head.name, head.description, head.cell, head.robot, float(head.speed) * L,
                       float(head.confidence), tuple(tasks), file, path.parent, (A, head.units.angle))


@dataclass(frozen=True)
class CellSpec:
    """A parsed cell file in SI units: ``model`` (resolved path or built-in name), ``robot``,
    ``objects`` / ``real`` (name -> X, 4x4), ``X_WC`` the camera, ``fov`` (rad, full cone),
    ``cov_origin`` (6, 6) FIND's noise covariance of (δp, δφ) about the object's origin in the
    camera's axes, ``camera_real`` (4, 4) the real camera's offset from ``X_WC`` (None: none),
    ``calibration`` (the calibration file's resolved path, or None)."""

    name: str
    model: str
    robot: str | None
    objects: dict
    real: dict
    X_WC: np.ndarray
    fov: float
    cov_origin: np.ndarray
    file: str
    camera_real: np.ndarray | None = None
    calibration: str | None = None


def read_cell(path) -> CellSpec:
    """The cell file ``path`` (``armguard_cell: 1``)."""
    from .._lines import lines_for

    path, file, head, _ = _load(path, CellFile, "armguard_cell")
    L, A = _units(head.units)
    with lines_for(file):
        model = head.model
        if not _is_builtin(model):
            p = Path(model)
            p = p if p.is_absolute() else path.parent / p
            if not p.is_file():
                raise SceneFileError(file, "model", f"not a built-in model name and no such file: {p}")
            model = str(p)
        objects = {k: _pose(v, L, A, file, f"objects.{k}") for k, v in head.objects.items()}
        real = {k: _pose(v, L, A, file, f"real.{k}") for k, v in head.real.items()}
        cam = head.camera
        X_WC = _pose(cam, L, A, file, "camera")
        cam_real = None if cam.real is None else _pose(cam.real, L, A, file, "camera.real")
        sig = np.concatenate([np.asarray(cam.sigma_xyz) * L, np.asarray(cam.sigma_rpy) * A])
        if np.any(sig < 0.0):
            raise SceneFileError(file, "camera", "sigma_xyz and sigma_rpy must be >= 0")
        calibration = head.calibration
        if calibration is not None:
            c = Path(calibration)
            c = c if c.is_absolute() else path.parent / c
            if not c.is_file():
                raise SceneFileError(file, "calibration", f"expected a calibration file (armguard_calibration: 1); no such file: {c}")
            calibration = str(c)
    return CellSpec(head.name, model, head.robot, objects, real, X_WC, math.radians(cam.fov), np.diag(sig ** 2), file,
                    cam_real, calibration)


def _is_builtin(name: str) -> bool:
    from ..model import builtin_model_names

    return name in builtin_model_names()


def is_cell_file(path) -> bool:
    """True when ``path`` is a YAML file whose top level has ``armguard_cell``."""
    p = Path(path)
    if p.suffix not in (".yaml", ".yml") or not p.is_file():
        return False
    try:
        head = p.read_text(encoding="utf-8")[:4096]
    except (OSError, UnicodeDecodeError):
        return False
    return any(ln.strip().startswith("armguard_cell:") for ln in head.splitlines())
