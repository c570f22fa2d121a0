"""Calibration files (``armguard_calibration: 1``): the cell's relationships — each robot's base,
the camera, the tables and fixtures — as WORKMATE kept them (Smith 1986, seed 004, §III.D.5: "special
calibration data files — initially containing only the nominal relationships among all the
components defined in the cell layout.  After physical calibration ... the calibration files are
updated.  When the model workcell is next regenerated, the computed (calibrated) relationships are
used").

A file is read like a scene file (strict YAML, unknown keys refused, numbers finite, every error a
:class:`SceneFileError` naming the file, the place with its line and what was expected); names
are checked against the cell's model by :func:`check_calibration`.  :func:`write_calibration`
writes one whole or not at all (``armguard._io.atomic_write``), with every number exact, so the
file read back gives the same cell.  ``docs/program.md`` describes the format.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated

import numpy as np
from pydantic import Field

from .._errors import SceneError, SceneFileError, list_problems
from ..model._schema import Name, Num, Vec3, VersionOne
from ._format import _load, _Model, _pose, _Units, _units

__all__ = ["Calibration", "read_calibration", "write_calibration", "calibration_text", "check_calibration"]


class _Frame(_Model):
    xyz: Vec3 = [0.0, 0.0, 0.0]
    rpy: Vec3 = [0.0, 0.0, 0.0]


class _Record(_Model):
    points: Annotated[int, Field(ge=3)]
    rms: Annotated[Num, Field(ge=0.0)]
    seed: int | None = None


class _CameraEntry(_Frame):
    relative_to: Name = "world"
    cov: Annotated[list[Annotated[list[Num], Field(min_length=6, max_length=6)]],
                   Field(min_length=6, max_length=6)] | None = None
    calibrated: _Record | None = None


class _CalibrationHead(_Model):
    armguard_calibration: VersionOne
    name: Name = "cell"
    description: str = ""
    units: _Units = _Units()
    robots: dict[Name, _Frame] = {}
    camera: _CameraEntry | None = None
    bodies: dict[Name, _Frame] = {}


@dataclass(frozen=True)
class Calibration:
    """A cell's relationships in SI units: ``robots`` (name -> X_WB, the base in W), ``bodies``
    (name -> X_WO, the object's frame in W), the camera's pose ``X_camera`` in the frame
    ``camera_relative_to`` (``world`` or a robot's base) with its covariance ``camera_cov`` (6, 6,
    left perturbation in that frame's axes; None: nominal, exact), ``record`` (``points``, ``rms``
    m, ``seed`` of the calibration that wrote it; None), ``name``, ``description``, ``file``.
    A robot or body not listed keeps the cell's nominal relationship."""

    robots: dict = field(default_factory=dict)
    bodies: dict = field(default_factory=dict)
    X_camera: np.ndarray | None = None
    camera_relative_to: str = "world"
    camera_cov: np.ndarray | None = None
    record: dict | None = None
    name: str = "cell"
    description: str = ""
    file: str | None = None

    def camera_in_world(self, X_WB: dict) -> tuple[np.ndarray, np.ndarray] | None:
        """``(X_WC, cov_W)``: the camera in W with its covariance as a left perturbation in W, the
        robots' bases taken from ``X_WB`` (name -> 4x4; Smith & Cheeseman's compounding with an
        exact base: ``cov_W = Ad(X_WB) cov Ad(X_WB)ᵀ``); None when the file gives no camera."""
        if self.X_camera is None:
            return None
        cov = np.zeros((6, 6)) if self.camera_cov is None else np.asarray(self.camera_cov)
        if self.camera_relative_to == "world":
            return np.array(self.X_camera), np.array(cov)
        from ..uncertainty import se3

        X = np.asarray(X_WB[self.camera_relative_to])
        ad = se3.adjoint(X)
        return X @ self.X_camera, ad @ cov @ ad.T


def _cov(rows, file: str, where: str) -> np.ndarray:
    C = np.asarray(rows, dtype=np.float64)
    scale = max(float(np.abs(C).max()), 1e-300)
    if not np.allclose(C, C.T, rtol=0.0, atol=1e-9 * scale):
        raise SceneFileError(file, where, "expected a symmetric 6x6 covariance (m², rad²), got an unsymmetric one")
    C = 0.5 * (C + C.T)
    lo = float(np.linalg.eigvalsh(C)[0])
    if lo < -1e-9 * scale:
        raise SceneFileError(file, where, f"expected a positive semi-definite covariance, its least eigenvalue is {lo:.3g}")
    return C


def read_calibration(path) -> Calibration:
    """The calibration file ``path`` (``armguard_calibration: 1``); errors are located SceneFileErrors."""
    from .._lines import lines_for

    path, file, head, _ = _load(path, _CalibrationHead, "armguard_calibration")
    L, A = _units(head.units)
    with lines_for(file):
        robots = {k: _pose(v, L, A, file, f"robots.{k}") for k, v in head.robots.items()}
        bodies = {k: _pose(v, L, A, file, f"bodies.{k}") for k, v in head.bodies.items()}
        X_cam, rel, cov, record = None, "world", None, None
        if head.camera is not None:
            cam = head.camera
            X_cam, rel = _pose(cam, L, A, file, "camera"), cam.relative_to
            if cam.cov is not None:
                cov = _cov(cam.cov, file, "camera.cov")
            if cam.calibrated is not None:
                record = {"points": cam.calibrated.points, "rms": float(cam.calibrated.rms) * L,
                          "seed": cam.calibrated.seed}
    return Calibration(robots, bodies, X_cam, rel, cov, record, head.name, head.description, file)


def check_calibration(cal: Calibration, scene) -> None:
    """Every robot and body ``cal`` names is in ``scene`` and the camera's ``relative_to`` is
    ``world`` or a robot; else one SceneFileError naming ``cal.file`` and listing every problem."""
    problems = []
    for k in cal.robots:
        if k not in scene.robots:
            problems.append((f"robots.{k}", f"no robot {k!r} in the cell's model; expected one of {sorted(scene.robots)}"))
    for k in cal.bodies:
        if k not in scene.bodies:
            problems.append((f"bodies.{k}", f"no body {k!r} in the cell's model; expected one of {sorted(scene.bodies)}"))
    if cal.X_camera is not None and cal.camera_relative_to != "world" and cal.camera_relative_to not in scene.robots:
        problems.append(("camera.relative_to", f"{cal.camera_relative_to!r} is not a frame of the cell; expected "
                                               f"'world' or a robot's base: {sorted(scene.robots)}"))
    if problems:
        from .._lines import lines_for

        with lines_for(cal.file or "calibration"):
            raise SceneFileError(cal.file or "calibration", *list_problems(problems))


def _num(v: float) -> str:
    v = float(v)
    return "0" if v == 0.0 else repr(v)


def _frame(X: np.ndarray) -> str:
    from ..kinematics import xyz_rpy_from_pose

    xyz, rpy = xyz_rpy_from_pose(np.asarray(X, dtype=np.float64))
    return (f"{{xyz: [{', '.join(_num(v) for v in xyz)}], "
            f"rpy: [{', '.join(_num(math.degrees(float(v))) for v in rpy)}]}}")


def calibration_text(cal: Calibration) -> str:
    """``cal`` as a calibration file (m and degrees; covariance in m² and rad²; numbers exact)."""
    out = ["# armguard calibration file (docs/program.md, \"Calibration files\"): the cell's relationships,",
           "# nominal until a calibration updates them; the cell is regenerated from them when it is loaded.",
           "armguard_calibration: 1",
           f"name: {cal.name}"]
    if cal.description:
        out.append(f"description: {_quote(cal.description)}")
    out.append("units: {angle: deg, length: m}")
    if cal.robots:
        out.append("robots:                      # each robot's base (its root link) in W")
        out += [f"  {k}: {_frame(X)}" for k, X in cal.robots.items()]
    if cal.X_camera is not None:
        rec = cal.record
        note = (f"   # calibrated: {rec['points']} points, rms {1e3 * rec['rms']:.2f} mm" if rec else "   # nominal")
        out.append("camera:" + note)
        out.append(f"  relative_to: {cal.camera_relative_to}")
        xyz_rpy = _frame(cal.X_camera)[1:-1]
        xyz, rpy = xyz_rpy.split(", rpy: ")
        out.append(f"  {xyz}")
        out.append(f"  rpy: {rpy}")
        if cal.camera_cov is not None:
            out.append(f"  cov:                         # (m², rad²): left perturbation in {cal.camera_relative_to}'s axes")
            out += [f"    - [{', '.join(_num(v) for v in row)}]" for row in np.asarray(cal.camera_cov)]
        if rec:
            seed = "" if rec.get("seed") is None else f", seed: {int(rec['seed'])}"
            out.append(f"  calibrated: {{points: {int(rec['points'])}, rms: {_num(rec['rms'])}{seed}}}")
    if cal.bodies:
        out.append("bodies:                      # each object's frame (the frame FIND binds) in W")
        out += [f"  {k}: {_frame(X)}" for k, X in cal.bodies.items()]
    return "\n".join(out) + "\n"


def _quote(s: str) -> str:
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'


def write_calibration(cal: Calibration, path) -> Path:
    """Write ``cal`` to ``path`` (whole or not at all: a FIFO, a folder or a full disk is an
    OutputError and the previous file stays as it was); returns the path."""
    from .._io import atomic_write

    if not isinstance(cal, Calibration):
        raise SceneError(f"write_calibration: expected a Calibration, got {type(cal).__name__}")
    return atomic_write(Path(path), calibration_text(cal))
