"""The scene's parts and small results: bodies, payloads, placed shapes, the workspace box,
checked pairs, canned tests — and the input checks the scene's methods share."""

from __future__ import annotations

import enum
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Mapping

import numpy as np

from .._errors import SceneError
from .._tolerance import DEFAULT_TOLERANCES
from ..geometry import Shape

if TYPE_CHECKING:  # pragma: no cover
    from ._scene import Scene

__all__ = [
    "Body",
    "Payload",
    "SceneItem",
    "WorkspaceBox",
    "CheckPair",
    "PairCategory",
    "CannedTest",
    "BODY_CATEGORIES",
]

BODY_CATEGORIES = ("vehicle", "environment")


class PairCategory(str, enum.Enum):
    """What a checked pair is, in the seeds' terms (Ranger's three categories, Hermes's four checks)."""

    ARM_ARM = "arm-arm"  # two links: of two robots, or non-adjacent links of one robot
    ARM_VEHICLE = "arm-vehicle"  # a link and a body of category "vehicle"
    ARM_ENVIRONMENT = "arm-environment"  # a link and a body of category "environment"
    ARM_PAYLOAD = "arm-payload"  # a link and a payload (not the link that holds it)
    PAYLOAD_VEHICLE = "payload-vehicle"
    PAYLOAD_ENVIRONMENT = "payload-environment"
    PAYLOAD_PAYLOAD = "payload-payload"


@dataclass(frozen=True)
class Body:
    """A static body: ``shapes`` in the world frame W; ``category`` ``"vehicle"`` or ``"environment"``."""

    name: str
    shapes: tuple[Shape, ...]
    category: str = "environment"


@dataclass(frozen=True, eq=False)
class Payload:
    """Shapes held by a robot link: ``shapes`` in the payload frame P, ``X_LP`` (4, 4) P in link frame L."""

    name: str
    robot: str
    link: str
    shapes: tuple[Shape, ...]
    X_LP: np.ndarray

    @property
    def owner_link(self) -> str:
        """The ``"robot/link"`` owner name of the holding link."""
        return f"{self.robot}/{self.link}"


@dataclass(frozen=True, eq=False)
class SceneItem:
    """One shape of the scene at a configuration: ``shape`` in W, owned by ``owner`` of ``kind``.

    ``kind`` is ``"body"``, ``"link"`` or ``"payload"``; ``robot`` / ``link`` name the robot and
    link for links and payloads (the holding link), ``None`` for bodies; ``category`` is the
    body category (``"vehicle"`` / ``"environment"``), ``None`` otherwise.
    """

    owner: str
    kind: str
    shape: Shape
    robot: str | None = None
    link: str | None = None
    category: str | None = None


@dataclass(frozen=True, eq=False)
class WorkspaceBox:
    """Ranger's workspace bounding box: axis-aligned in W, ``lo`` and ``hi`` each (3,) float64, m."""

    lo: np.ndarray
    hi: np.ndarray

    def __post_init__(self) -> None:
        lo = _finite(self.lo, (3,), "workspace.lo")
        hi = _finite(self.hi, (3,), "workspace.hi")
        big = DEFAULT_TOLERANCES.max_magnitude
        if max(float(np.abs(lo).max()), float(np.abs(hi).max())) > big:  # as every shape (a wall's box is one)
            raise SceneError(f"workspace: lo={lo.tolist()} hi={hi.tolist()} reach beyond the largest magnitude armguard "
                             f"handles ({big:g} m, Tolerances.max_magnitude)")
        if np.any(hi <= lo):
            raise SceneError(f"workspace: hi must exceed lo on every axis, got lo={lo.tolist()} hi={hi.tolist()}")
        object.__setattr__(self, "lo", lo)
        object.__setattr__(self, "hi", hi)

    @property
    def center(self) -> np.ndarray:
        """``(3,) float64, m``: the box centre in W."""
        return 0.5 * (self.lo + self.hi)


@dataclass(frozen=True)
class CheckPair:
    """Two owners whose distance must be checked, and the category of the check."""

    a: str
    b: str
    category: PairCategory


@dataclass(frozen=True, eq=False)
class CannedTest:
    """A Ranger canned test: put every robot in ``setup``, then move ``robot`` by a trapezoid.

    Seed 000 section 6: "Each Setup button puts the dexterous arms into the starting pose ...,
    selects the active arm for the case, ... and turns obstacle detection on with an appropriate
    threshold.  Each Test or Demo button commands the active arm to execute a trapezoidal
    trajectory in one or more of the six end-effector coordinates or the arm angle."

    ``setup`` maps robot name -> (n_joints,) float64 (rad or m); ``threshold`` (m) is the detection
    threshold the test turns on.  The motion (:attr:`mode`) is exactly one of
    ``end_effector`` (6,) — the change ``(dx, dy, dz, droll, dpitch, dyaw)`` (m, rad, W) of the
    tool's coordinates —, ``arm_angle`` — the change (rad) of a 7-joint arm's arm angle with the
    tool pose held — (both :func:`armguard.kinematics.task_trapezoid`), or ``goal`` (n_joints,) —
    joint values reached by a trapezoid synchronised across joints (``Trajectory.trapezoidal``).
    """

    name: str
    description: str
    robot: str
    threshold: float
    setup: Mapping[str, np.ndarray]
    goal: np.ndarray | None = None
    end_effector: np.ndarray | None = None
    arm_angle: float | None = None
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    @property
    def mode(self) -> str:
        """``"end_effector"``, ``"arm_angle"`` or ``"joint"`` (the motion given)."""
        if self.end_effector is not None:
            return "end_effector"
        return "arm_angle" if self.arm_angle is not None else "joint"

    def trajectory(self, scene: "Scene"):
        """The test motion as a ``Trajectory`` from the setup (computed once per robot model)."""
        from ..kinematics import Trajectory, task_trapezoid

        robot = scene.robots[self.robot]
        hit = self._cache.get("trajectory")
        if hit is not None and hit[0] is robot:
            return hit[1]
        q0 = self.setup[self.robot]
        if self.mode == "joint":
            traj = Trajectory.trapezoidal(robot, q0, self.goal)
        elif self.mode == "end_effector":
            traj = task_trapezoid(robot, q0, self.end_effector, frequency=CANNED_FREQUENCY)
        else:
            traj = task_trapezoid(robot, q0, [0.0] * 6 + [float(self.arm_angle)], frequency=CANNED_FREQUENCY)
        self._cache["trajectory"] = (robot, traj)  # one assignment: a racing thread computes the same
        return traj


CANNED_FREQUENCY = 20.0
"""Hz: samples of a canned end-effector or arm-angle motion (each solved exactly; joint-space lines
between them)."""


def _canned_motion(test: CannedTest, active, check_in_limits):
    """``(goal, end_effector, arm_angle)`` of ``test`` checked for the active robot (exactly one not None)."""
    given = [k for k in ("end_effector", "arm_angle", "goal") if getattr(test, k) is not None]
    if len(given) != 1:
        raise SceneError(f"canned test {test.name!r}: expected exactly one motion (end_effector, arm_angle "
                         f"or goal), got {given or 'none'}")
    if test.goal is not None:
        return check_in_limits(test.robot, test.goal, f"canned test {test.name!r} motion.goal"), None, None
    if test.end_effector is not None:
        return None, _finite(test.end_effector, (6,), f"canned test {test.name!r} motion.end_effector"), None
    psi = float(_finite(test.arm_angle, (), f"canned test {test.name!r} motion.arm_angle"))
    if active.n_joints != 7:
        raise SceneError(f"canned test {test.name!r}: motion.arm_angle needs a 7-joint arm; "
                         f"{test.robot!r} has {active.n_joints} joints")
    return None, None, psi


def _finite(value, shape, name: str) -> np.ndarray:
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise SceneError(f"{name}: expected numbers, got {value!r}") from exc
    if shape is not None and arr.shape != shape:
        raise SceneError(f"{name}: expected shape {shape}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise SceneError(f"{name}: contains NaN or infinite values")
    arr.flags.writeable = False
    return arr


def _check_name(name: str, what: str) -> str:
    if not isinstance(name, str) or not name or "/" in name:
        raise SceneError(f"{what}: expected a non-empty name without '/', got {name!r}")
    return name


def _check_shapes(shapes, what: str) -> tuple[Shape, ...]:
    if isinstance(shapes, Shape):
        shapes = (shapes,)
    shapes = tuple(shapes)
    if not shapes:
        raise SceneError(f"{what}: expected at least one shape")
    for i, s in enumerate(shapes):
        if not isinstance(s, Shape):
            raise SceneError(f"{what}[{i}]: expected an armguard.geometry shape, got {type(s).__name__}")
    return shapes


def _check_pose(X, what: str) -> np.ndarray:
    from ..geometry._check import check_pose

    try:
        X = check_pose(X, what)
    except Exception as exc:  # GeometryError -> SceneError naming the argument
        raise SceneError(str(exc)) from exc
    X = X.copy()
    X.flags.writeable = False
    return X
