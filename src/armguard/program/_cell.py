"""The emulated cell: WORKMATE's nominal workcell model, the "real" cell it stands for (object
poses that differ from the nominal), and the simulated camera that answers FIND.

The camera reports an object's *true* pose plus Gaussian noise of a stated covariance: the
origin moves by ``δp`` and the object turns by ``δφ`` about its own origin, ``(δp, δφ) ~ N(0,
cov_origin)`` in W's axes (``X_found = [exp(δφ) R, p + δp]``).  The bound frame carries the same
uncertainty as an :class:`~armguard.uncertainty.UncertainPose3` (left perturbation in W; its
covariance is ``cov_origin`` moved to W's origin, Smith & Cheeseman 1986's compounding).
"""

from __future__ import annotations

import math
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
    """A camera at ``X_WC`` (its optical axis is its z axis) seeing a cone of full angle ``fov`` (rad);
    FIND's noise is ``cov_origin`` (6, 6): (δp m, δφ rad) about the object's origin, in W's axes."""

    X_WC: np.ndarray
    fov: float
    cov_origin: np.ndarray

    def sees(self, p_WO) -> bool:
        """Whether point ``p_WO`` (3,) is inside the field of view (in front, within fov/2 of the axis)."""
        d = np.asarray(p_WO, dtype=np.float64) - self.X_WC[:3, 3]
        n = float(np.linalg.norm(d))
        if n == 0.0:
            return False
        return float(d @ self.X_WC[:3, 2]) / n >= math.cos(0.5 * self.fov)

    def measure(self, X_WO_true: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """One noisy measurement of the true pose ``X_WO_true``."""
        sig = self.cov_origin
        xi = rng.multivariate_normal(np.zeros(6), sig) if np.any(sig) else np.zeros(6)
        X = np.array(X_WO_true, dtype=np.float64)
        X[:3, :3] = _rotvec(xi[3:]) @ X[:3, :3]
        X[:3, 3] = X[:3, 3] + xi[:3]
        return X

    def uncertain(self, X_WO_found: np.ndarray):
        """The bound frame as an :class:`UncertainPose3` (left perturbation in W): ``cov_origin``
        moved from the object's origin ``o`` to W's (``ρ = δp + o × δφ``)."""
        from ..uncertainty import UncertainPose3

        A = np.eye(6)
        A[:3, 3:] = _skew(X_WO_found[:3, 3])
        return UncertainPose3(X_WO_found, A @ self.cov_origin @ A.T)


class Cell:
    """The nominal cell (``model``, a :class:`armguard.Model`; ``robot`` the programmed robot's name),
    the nominal object frames ``objects`` (name -> X_WO), the real cell's object poses ``real``
    (name -> X_WO, the nominal where not given) and the ``camera``."""

    def __init__(self, model, robot: str | None = None, *, objects=None, real=None, camera: Camera | None = None,
                 name: str | None = None, file: str | None = None) -> None:
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
        self.objects = {b: object_frame(body.shapes) for b, body in scene.bodies.items()}
        for k, X in (objects or {}).items():
            if k not in scene.bodies:
                raise SceneError(f"objects.{k}: no body {k!r} in the cell; bodies are {list(scene.bodies)}")
            self.objects[k] = np.asarray(X, dtype=np.float64)
        self.real = dict(self.objects)
        for k, X in (real or {}).items():
            if k not in scene.bodies:
                raise SceneError(f"real.{k}: no body {k!r} in the cell; bodies are {list(scene.bodies)}")
            self.real[k] = _offset(self.objects[k], np.asarray(X, dtype=np.float64))
        if camera is None:
            X_WC = np.diag([1.0, -1.0, -1.0, 1.0])
            X_WC[:3, 3] = [0.6, 0.0, 2.0]
            camera = Camera(X_WC, math.radians(90.0), np.diag([1e-3, 1e-3, 1e-3, 0.0, 0.0, 0.0]) ** 2)
        self.camera = camera

    def nominal_scene(self):
        """A copy of the nominal scene."""
        return self.model.scene.copy()

    def real_scene(self):
        """A copy of the scene with every object at its real pose."""
        scene = self.model.scene.copy()
        for k, X in self.real.items():
            move_body(scene, k, X @ _inv(self.objects[k]))
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


def load_cell(name_or_path) -> Cell:
    """A cell from a cell file (``armguard_cell: 1``), or a model name / scene / URDF file (the real
    cell then equals the nominal; the default camera looks down from 2 m above the robot's front)."""
    from ..model import load_model
    from ._format import is_cell_file, read_cell

    if is_cell_file(name_or_path):
        spec = read_cell(name_or_path)
        try:
            model = load_model(spec.model)
            return Cell(model, spec.robot, objects=spec.objects, real=spec.real,
                        camera=Camera(spec.X_WC, spec.fov, spec.cov_origin), name=spec.name, file=spec.file)
        except SceneError as exc:
            if isinstance(exc, SceneFileError):
                raise
            where, _, msg = str(exc).partition(": ")
            raise SceneFileError(spec.file, where if msg else "", msg or str(exc)) from None
    return Cell(load_model(str(name_or_path)), file=str(name_or_path) if Path(str(name_or_path)).exists() else None)
