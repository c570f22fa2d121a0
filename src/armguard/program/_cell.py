"""The emulated cell: WORKMATE's nominal workcell model, the "real" cell it stands for (object
poses that differ from the nominal), and the simulated camera that answers FIND.

The camera reports an object's *true* pose plus Gaussian noise of a stated covariance: the
origin moves by ``δp`` and the object turns by ``δφ`` about its own origin, ``(δp, δφ) ~ N(0,
cov_origin)`` in the camera's axes (:meth:`Camera.measure_C`; docs/program.md).  The bound frame carries the same
uncertainty as an :class:`~armguard.uncertainty.UncertainPose3` (left perturbation in W; its
covariance is ``cov_origin`` moved to W's origin, Smith & Cheeseman 1986's compounding).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._errors import SceneError, SceneFileError

__all__ = ["Camera", "Cell", "load_cell", "object_frame"]


def _inv(X: np.ndarray) -> np.ndarray:
    out = np.eye(4)
    out[:3, :3] = X[:3, :3].T
    out[:3, 3] = -X[:3, :3].T @ X[:3, 3]
    return out


def _skew(v) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _rotvec(phi) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    return Rotation.from_rotvec(np.asarray(phi, dtype=np.float64)).as_matrix()


def object_frame(shapes) -> np.ndarray:
    """The default frame of an object made of ``shapes`` (in W): the centre of their axis-aligned
    bounding box, axes parallel to W's."""
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for s in shapes:
        b = np.asarray(s.aabb(), dtype=np.float64).reshape(2, 3)
        lo, hi = np.minimum(lo, b[0]), np.maximum(hi, b[1])
    X = np.eye(4)
    X[:3, 3] = 0.5 * (lo + hi)
    return X


@dataclass(frozen=True)
class Camera:
    """A camera the model believes at ``X_WC`` (its nominal or calibrated pose; the optical axis is
    its z axis) and that really stands at ``X_WC_real`` (the emulated truth; default ``X_WC``),
    seeing a cone of full angle ``fov`` (rad).  FIND's noise is ``cov_origin`` (6, 6): (δp m, δφ
    rad) about the object's origin, in the camera's axes.  ``cov_pose`` (6, 6): the believed pose's
    own covariance (left perturbation in W, from a calibration; zero for a nominal pose)."""

    X_WC: np.ndarray
    fov: float
    cov_origin: np.ndarray
    X_WC_real: np.ndarray | None = None
    cov_pose: np.ndarray | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "X_WC", np.array(self.X_WC, dtype=np.float64))
        real = self.X_WC if self.X_WC_real is None else self.X_WC_real
        object.__setattr__(self, "X_WC_real", np.array(real, dtype=np.float64))
        cov = np.zeros((6, 6)) if self.cov_pose is None else self.cov_pose
        object.__setattr__(self, "cov_pose", np.array(cov, dtype=np.float64))

    def sees(self, p_WO) -> bool:
        """Whether point ``p_WO`` (3,) is inside the real camera's field of view (in front, within
        fov/2 of its axis)."""
        d = np.asarray(p_WO, dtype=np.float64) - self.X_WC_real[:3, 3]
        n = float(np.linalg.norm(d))
        if n == 0.0:
            return False
        return float(d @ self.X_WC_real[:3, 2]) / n >= math.cos(0.5 * self.fov)

    def measure_C(self, X_WO_true: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """One noisy measurement ``X_CO`` of the true pose ``X_WO_true``, in the camera's frame: what
        the real camera sees, ``X_CO = [exp(δφ) R, p + δp]`` with ``(δp, δφ)`` in its axes."""
        sig = self.cov_origin
        xi = rng.multivariate_normal(np.zeros(6), sig) if np.any(sig) else np.zeros(6)
        X = _inv(self.X_WC_real) @ np.asarray(X_WO_true, dtype=np.float64)
        X[:3, :3] = _rotvec(xi[3:]) @ X[:3, :3]
        X[:3, 3] = X[:3, 3] + xi[:3]
        return X

    def measure(self, X_WO_true: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """One noisy measurement of the true pose ``X_WO_true``, as the model places it:
        ``X_WC @ measure_C(...)`` — off by the believed pose's error where it has one."""
        return self.X_WC @ self.measure_C(X_WO_true, rng)

    def uncertain(self, X_WO_found: np.ndarray):
        """The bound frame as an :class:`UncertainPose3` (left perturbation in W): ``cov_origin``
        turned into W's axes by the believed ``R_WC`` and moved from the object's origin ``o`` to W's
        (``ρ = δp + o × δφ``), plus ``cov_pose`` (``X_WO = X_WC X_CO`` compounded: the camera's
        left perturbation is the object's)."""
        from ..uncertainty import UncertainPose3

        R = np.zeros((6, 6))
        R[:3, :3] = R[3:, 3:] = self.X_WC[:3, :3]
        A = np.eye(6)
        A[:3, 3:] = _skew(X_WO_found[:3, 3])
        M = A @ R
        return UncertainPose3(X_WO_found, M @ self.cov_origin @ M.T + self.cov_pose)


class Cell:
    """The cell a program runs on: the nominal model (``model``, a :class:`armguard.Model`; ``robot``
    the programmed robot's name) and three layouts of it.

    * the *nominal layout*: the model as built, the object frames ``layout`` (name -> X_WO: the
      model's bodies, framed by ``objects`` where given) and ``camera``'s nominal pose;
    * the *believed* one, regenerated from a calibration (:class:`Calibration`, default the nominal
      layout): ``bases`` (robot -> X_WB), ``objects`` (name -> X_WO, the frames a program starts
      from) and ``camera`` (believed pose and its covariance) — :meth:`nominal_scene`;
    * the emulated *real* one: ``real`` (name -> X_WO; ``real`` offsets from the layout, the
      nominal where not given) and the camera's real pose (``camera_real``, an offset from its
      nominal pose) — :meth:`real_scene`.  The real robots stand where the model puts them."""

    def __init__(self, model, robot: str | None = None, *, objects=None, real=None, camera: Camera | None = None,
                 name: str | None = None, file: str | None = None, calibration=None) -> None:
        self.model = model
        scene = model.scene
        robots = list(scene.robots)
        if robot is None:
            if len(robots) != 1:
                raise SceneError(f"cell {model.name!r} has robots {robots}: name the programmed one (robot:)")
            robot = robots[0]
        if robot not in scene.robots:
            raise SceneError(f"cell {model.name!r} has no robot {robot!r}; robots are {robots}")
        self.robot = robot
        self.name = name or model.name
        self.file = file
        self.layout = {b: object_frame(body.shapes) for b, body in scene.bodies.items()}
        for k, X in (objects or {}).items():
            if k not in scene.bodies:
                raise SceneError(f"objects.{k}: no body {k!r} in the cell; bodies are {list(scene.bodies)}")
            self.layout[k] = np.asarray(X, dtype=np.float64)
        self.real = dict(self.layout)
        for k, X in (real or {}).items():
            if k not in scene.bodies:
                raise SceneError(f"real.{k}: no body {k!r} in the cell; bodies are {list(scene.bodies)}")
            self.real[k] = _offset(self.layout[k], np.asarray(X, dtype=np.float64))
        if camera is None:
            X_WC = np.diag([1.0, -1.0, -1.0, 1.0])
            X_WC[:3, 3] = [0.6, 0.0, 2.0]
            camera = Camera(X_WC, math.radians(90.0), np.diag([1e-3, 1e-3, 1e-3, 0.0, 0.0, 0.0]) ** 2)
        self.nominal_camera = Camera(camera.X_WC, camera.fov, camera.cov_origin, camera.X_WC_real)
        self.calibrate(calibration)

    def calibrate(self, calibration=None) -> None:
        """Regenerate the believed cell from ``calibration`` (a :class:`Calibration`, a calibration
        file, or None: the nominal layout): robots, bodies and camera the calibration does not list
        keep their nominal relationships."""
        from ._calibfile import Calibration, check_calibration, read_calibration

        if calibration is not None and not isinstance(calibration, Calibration):
            calibration = read_calibration(calibration)
        cal = calibration if calibration is not None else Calibration()
        scene = self.model.scene
        check_calibration(cal, scene)
        self.calibration = calibration
        self.bases = {r: np.array(arm.X_WB) for r, arm in scene.robots.items()}
        self.bases.update({r: np.array(X) for r, X in cal.robots.items()})
        self.objects = dict(self.layout)
        self.objects.update({k: np.array(X) for k, X in cal.bodies.items()})
        cam = self.nominal_camera
        in_world = cal.camera_in_world(self.bases)
        if in_world is not None:
            cam = Camera(in_world[0], cam.fov, cam.cov_origin, cam.X_WC_real, in_world[1])
        self.camera = cam

    def nominal_calibration(self):
        """The nominal layout as a :class:`Calibration` (what a calibration file starts as): every
        robot's base, the camera's nominal pose and every body's frame."""
        from ._calibfile import Calibration

        return Calibration({r: np.array(a.X_WB) for r, a in self.model.scene.robots.items()},
                           {k: np.array(X) for k, X in self.layout.items()}, np.array(self.nominal_camera.X_WC),
                           name=self.name, description=f"cell {self.name}: the nominal layout")

    def nominal_scene(self):
        """A copy of the model as the cell believes it: regenerated from the calibration (the nominal
        scene when there is none)."""
        scene = self.model.scene.copy()
        for r, X in self.bases.items():
            if not np.array_equal(X, scene.robots[r].X_WB):
                scene.set_robot_base(r, X)
        for k, X in self.objects.items():
            if not np.array_equal(X, self.layout[k]):
                move_body(scene, k, X @ _inv(self.layout[k]))
        return scene

    believed_scene = nominal_scene

    def real_scene(self):
        """A copy of the scene with every object at its real pose."""
        scene = self.model.scene.copy()
        for k, X in self.real.items():
            move_body(scene, k, X @ _inv(self.layout[k]))
        return scene


def _offset(X_WO: np.ndarray, D: np.ndarray) -> np.ndarray:
    """``X_WO`` moved by ``D`` (translation in W, rotation in W's axes about the object's origin)."""
    out = np.array(X_WO)
    out[:3, :3] = D[:3, :3] @ X_WO[:3, :3]
    out[:3, 3] = X_WO[:3, 3] + D[:3, 3]
    return out


def move_body(scene, name: str, D_W: np.ndarray) -> None:
    """Move static body ``name`` of ``scene`` by ``D_W`` (applied in W), keeping its disabled pairs."""
    body = scene.bodies[name]
    disabled = [tuple(sorted(p)) for p in scene.disabled_pairs if name in p]
    scene.remove_body(name)
    scene.add_body(name, [s.transformed(D_W) for s in body.shapes], category=body.category)
    for a, b in disabled:
        scene.disable_pair(a, b)


def load_cell(name_or_path, calibration=None) -> Cell:
    """A cell from a cell file (``armguard_cell: 1``), or a model name / scene / URDF file (the real
    cell then equals the nominal; the default camera looks down from 2 m above the robot's front).
    ``calibration`` (a calibration file or :class:`Calibration`) replaces the one the cell file names."""
    from ..model import load_model
    from ._calibfile import Calibration, read_calibration
    from ._format import is_cell_file, read_cell

    if calibration is not None and not isinstance(calibration, Calibration):
        calibration = read_calibration(calibration)
    if not isinstance(name_or_path, (str, os.PathLike)):
        raise SceneError(f"load_cell: expected a cell file, a model file or a model name, got {type(name_or_path).__name__}")
    if is_cell_file(name_or_path):
        spec = read_cell(name_or_path)
        if calibration is None and spec.calibration is not None:
            calibration = read_calibration(spec.calibration)
        try:
            model = load_model(spec.model)
            X_real = None if spec.camera_real is None else _offset(spec.X_WC, spec.camera_real)
            return Cell(model, spec.robot, objects=spec.objects, real=spec.real,
                        camera=Camera(spec.X_WC, spec.fov, spec.cov_origin, X_real), name=spec.name, file=spec.file,
                        calibration=calibration)
        except SceneError as exc:
            if isinstance(exc, SceneFileError):
                raise
            where, _, msg = str(exc).partition(": ")
            raise SceneFileError(spec.file, where if msg else "", msg or str(exc), line=_line(spec.file, where)) from None
    return Cell(load_model(str(name_or_path)), file=str(name_or_path) if Path(str(name_or_path)).exists() else None,
                calibration=calibration)


def _line(file, where: str) -> int | None:
    """The line of place ``where`` (``real.tabel``) in YAML file ``file``, or None."""
    from .._lines import line_map, line_of

    try:
        return line_of(where, line_map(Path(file).read_text(encoding="utf-8"))) if file and where else None
    except OSError:
        return None
