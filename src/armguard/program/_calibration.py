"""Robot–camera calibration as WORKMATE's demonstration did it (Smith 1986, seed 004, §III.D.5):
"training a trajectory for the simulated arm, which positioned it at a number of points in the
camera field of view.  Next, a FIND command ... to locate ... the calibration object on the robot
hand, when it stopped at each location.  At execution time, the two sets of data ... were used to
compute the relationship between the robot and camera.  This calibration information was then used
to update the relational workcell model".

On an emulated cell: the arm moves through the trained tool poses (each motion verified before it
runs, as any program's — :class:`~armguard.program.Workcell`); at each stop the calibration
object, a point ``X_EK`` fixed in the hand, is where forward kinematics puts it in the robot's base
frame (``p_B``), and the real camera measures it in its own frame (``p_C``, with FIND's noise).
:func:`~armguard.program.fit_rigid_transform` (Horn / Umeyama) fits ``X_CB`` to the pairs with its
sandwich covariance for the camera's anisotropic noise; inverted (Smith & Cheeseman:
``cov_BC = Ad(X_BC) cov_CB Ad(X_BC)ᵀ``) it is the camera's pose in the robot's base, written to
the calibration file as the camera's relationship ``relative_to`` the robot.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field, replace

import numpy as np

from .._errors import UncertaintyError
from ._calibfile import Calibration
from ._cell import Cell, _inv
from ._workcell import ProgramRun, ProgramStopped, Workcell, _between, pose

__all__ = ["CalibrationStatus", "CameraCalibration", "calibration_poses", "calibrate_camera", "fit_camera",
           "CalibrationStop"]


class CalibrationStatus(enum.Enum):
    CALIBRATED = "calibrated"
    """Every motion verified and ran, every FIND answered: the fit is made."""
    STOPPED = "stopped"
    """A motion was refused or the camera could not see the calibration object: no fit."""


@dataclass(frozen=True)
class CalibrationStop:
    """One stop of the trained trajectory: ``q`` (rad), the calibration object's position in the
    robot's base frame by forward kinematics (``p_B``) and in W in the emulated real cell (``p_W``)."""

    q: np.ndarray
    p_B: np.ndarray
    p_W: np.ndarray


@dataclass
class CameraCalibration:
    """A robot–camera calibration: ``status``, ``stopped`` (why, when not calibrated), ``run`` (the
    trained trajectory's motions, each verified), ``stops``, ``p_C`` (N, 3: the camera's
    measurements), ``fit`` (:class:`~armguard.program.RigidFit` of ``X_CB``), ``X_BC`` (an
    UncertainPose3: the camera in the robot's base, left perturbation in its axes), ``X_WC_before``
    (the camera as the cell believed it) and ``X_WC_after`` (with the calibrated relation, in W)."""

    cell: Cell
    status: CalibrationStatus
    run: ProgramRun
    stops: list = field(default_factory=list)
    stopped: str = ""
    p_C: np.ndarray | None = None
    fit: object = None
    X_BC: object = None
    X_WC_before: np.ndarray | None = None
    X_WC_after: np.ndarray | None = None
    seed: int = 0

    @property
    def ok(self) -> bool:
        return self.status is CalibrationStatus.CALIBRATED

    def calibration(self) -> Calibration:
        """The cell's calibration with the camera's relationship updated (relative to the robot's
        base, with its covariance); what :func:`~armguard.program.write_calibration` writes."""
        if not self.ok:
            raise ProgramStopped(f"no calibration: {self.stopped}")
        cell = self.cell
        base = cell.calibration if cell.calibration is not None else cell.nominal_calibration()
        robots = dict(base.robots)
        robots.setdefault(cell.robot, np.array(cell.bases[cell.robot]))
        return replace(base, robots=robots, X_camera=np.array(self.X_BC.mean), camera_relative_to=cell.robot,
                       camera_cov=np.array(self.X_BC.cov), file=None,
                       description=f"cell {cell.name}: the camera calibrated to {cell.robot} "
                                   f"({len(self.stops)} points, camera noise seed {self.seed})",
                       record={"points": len(self.stops), "rms": float(self.fit.rms), "seed": int(self.seed)})

    def summary(self) -> str:
        """A text report: the motions and, when calibrated, the fit and how far the camera moved."""
        head = (f"robot-camera calibration of cell {self.cell.name}: "
                + (f"{len(self.stops)} points, rms {1e3 * self.fit.rms:.2f} mm" if self.ok else "STOPPED: " + self.stopped))
        out = [head]
        for m in self.run.motions:
            clear = "" if m.report is None else f", clearance {1e3 * m.min_clearance:.1f} mm{_between(m.report)}"
            out.append(f"  {m.label}: {m.status}{clear}")
            out.extend(f"    {line}" for line in m.why())
        if self.ok:
            from ..uncertainty import UncertainPlacement

            # the camera's position sigma: its origin's (rho + phi x c), not rho's (the perturbation at the base's origin)
            sd = np.sqrt(np.diag(UncertainPlacement("camera", self.X_BC).cov_origin))
            d = self.X_WC_after[:3, 3] - self.X_WC_before[:3, 3]
            turn = _angle(self.X_WC_after[:3, :3] @ self.X_WC_before[:3, :3].T)
            out.append(f"  camera in {self.cell.robot}'s base: xyz {np.round(self.X_BC.mean[:3, 3], 4).tolist()} m, "
                       f"sigma {np.round(1e3 * sd[:3], 2).tolist()} mm, {np.round(np.degrees(sd[3:]), 3).tolist()} deg")
            out.append(f"  the camera moved {1e3 * float(np.linalg.norm(d)):.1f} mm and turned {math.degrees(turn):.2f} deg "
                       f"from where the cell believed it")
        return "\n".join(out)


def _angle(R: np.ndarray) -> float:
    return float(np.arccos(np.clip(0.5 * (np.trace(R) - 1.0), -1.0, 1.0)))


def calibration_poses(cell: Cell, n: int = 12, *, height: float = 0.15, radius: float = 0.12,
                      depth: float = 0.1) -> list:
    """A trained trajectory: ``n`` tool poses (X_WE, hand pointing down) in the believed camera's view
    — a golden-angle spiral of radius ``radius`` (m) about the believed camera's axis, ``height``
    above the cell's highest body and alternately ``depth`` higher."""
    cam = cell.camera.X_WC
    axis, o = cam[:3, 2], cam[:3, 3]
    # above the highest body (a cell of a robot alone: above the floor, z = 0; max() of none was an internal error)
    top = max((float(np.asarray(s.aabb()).reshape(2, 3)[1, 2]) for b in cell.model.scene.bodies.values()
               for s in b.shapes), default=0.0)
    z0 = top + height
    t = (z0 - o[2]) / axis[2] if abs(axis[2]) > 1e-9 else 1.0
    c = o + t * axis
    out = []
    for i in range(int(n)):
        r = radius * math.sqrt((i + 0.5) / n)
        a = i * math.pi * (3.0 - math.sqrt(5.0))
        # a point the arm cannot reach (the default camera of a bare model cell stands where the spiral's
        # outer, higher points are beyond the PUMA's limits) is drawn in towards the axis and down to z0
        tries = [(r, depth if i % 2 else 0.0), (0.5 * r, depth if i % 2 else 0.0), (0.5 * r, 0.0), (0.0, 0.0)]
        for rr, dz in tries:
            X = pose([c[0] + rr * math.cos(a), c[1] + rr * math.sin(a), z0 + dz], [math.pi, 0.0, 0.0])
            if _reachable(cell, X):
                break
        out.append(X)  # the last try when none is reachable: the run stops there and says so
    return out


def _reachable(cell: Cell, X_WE) -> bool:
    """Whether the cell's robot has an inverse-kinematics solution within its limits for the tool pose ``X_WE``."""
    from .._errors import TrajectoryError
    from ..kinematics import Trajectory

    scene = cell.model.scene
    arm = scene.robots[cell.robot]
    try:
        Trajectory.through_poses(arm, scene.home(cell.robot), np.asarray(X_WE)[None], mode="joint", speed=0.1)
    except TrajectoryError:
        return False
    return True


def fit_camera(cell: Cell, stops, rng: np.random.Generator):
    """The camera's measurement at each of ``stops`` (the real camera, FIND's noise from ``rng``) and
    the fit: ``(p_C, RigidFit of X_CB, X_BC)`` with ``X_BC`` an UncertainPose3 (left perturbation
    in the robot's base axes).  Raises ProgramStopped when the camera does not see a stop."""
    from ._calibrate import fit_rigid_transform

    cam = cell.camera
    p_C = []
    for i, s in enumerate(stops):
        if not cam.sees(s.p_W):
            raise ProgramStopped(f"FIND calibration object at point {i + 1}: outside the camera's field of view")
        X = np.eye(4)
        X[:3, 3] = s.p_W
        p_C.append(cam.measure_C(X, rng)[:3, 3])
    p_C = np.array(p_C)
    fit = fit_rigid_transform(p_C, np.array([s.p_B for s in stops]), cov=cam.cov_origin[:3, :3])
    return p_C, fit, fit.pose.inverse()


def calibrate_camera(cell: Cell, *, poses=None, n: int = 12, X_EK=None, seed: int = 0, speed: float = 0.1,
                     confidence: float = 0.999, method: str = "certified") -> CameraCalibration:
    """Calibrate ``cell``'s camera to its robot: move through ``poses`` (X_WE; default
    :func:`calibration_poses` with ``n`` points), each motion verified and emulated; FIND the
    calibration object at ``X_EK`` in the hand (default the tool point) at each stop; fit.  ``seed``
    seeds the camera's noise.  Every input is checked before the first motion: at least 3 points
    (the rigid fit's minimum; ``n`` an integer), each pose and ``X_EK`` a finite rigid transform (4, 4)."""
    from ..uncertainty._validate import as_transform

    if poses is None:
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 3:
            raise UncertaintyError(f"n: expected an integer >= 3 calibration points (the rigid fit needs three), got {n!r}")
        poses = calibration_poses(cell, n)
    else:
        try:
            poses = list(poses)
        except TypeError:
            raise UncertaintyError(f"poses: expected a sequence of X_WE (4, 4), got {type(poses).__name__}") from None
        if len(poses) < 3:
            raise UncertaintyError(f"poses: expected at least 3 tool poses (the rigid fit needs three), got {len(poses)}")
        poses = [as_transform(X, f"poses[{i}]") for i, X in enumerate(poses)]
    X_EK = np.eye(4) if X_EK is None else as_transform(X_EK, "X_EK")
    wc = Workcell(cell, seed=seed, speed=speed, confidence=confidence, method=method, name="calibrate_camera")
    arm, real = wc.believed.robots[cell.robot], wc.real.robots[cell.robot]
    out = CameraCalibration(cell, CalibrationStatus.STOPPED, wc.run, seed=seed, X_WC_before=np.array(cell.camera.X_WC))
    try:
        for i, X_WE in enumerate(poses):
            wc.move(X_WE, mode="joint", label=f"calibration point {i + 1}")
            X_BK = _inv(arm.X_WB) @ arm.link_pose(wc.q, arm.tool_link) @ X_EK
            X_WK = real.link_pose(wc.q, real.tool_link) @ X_EK
            if not cell.camera.sees(X_WK[:3, 3]):  # FIND at this stop: the camera must see the object
                raise ProgramStopped(f"FIND calibration object at point {i + 1}: outside the camera's field of view")
            out.stops.append(CalibrationStop(np.array(wc.q), X_BK[:3, 3], X_WK[:3, 3]))
        wc.home(label="calibration home")
        out.p_C, out.fit, out.X_BC = fit_camera(cell, out.stops, wc._rng)
    except ProgramStopped as exc:
        out.stopped = str(exc)
        wc.run.ok, wc.run.stopped = False, str(exc)
        return out
    out.status = CalibrationStatus.CALIBRATED
    out.X_WC_after = cell.bases[cell.robot] @ out.X_BC.mean
    return out
