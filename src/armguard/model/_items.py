"""The scene's parts and small results: bodies, payloads, placed shapes, the workspace box,
checked pairs, canned tests — and the input checks the scene's methods share."""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import TYPE_CHECKING, Mapping

import numpy as np

from .._errors import SceneError
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
    """A Ranger canned test: put every robot in ``setup``, then move ``robot`` to ``goal``.

    ``setup`` maps robot name -> (n_joints,) float64 (rad or m); ``goal`` (n_joints,) of the
    active ``robot``; ``threshold`` (m) is the detection threshold the test turns on.  The motion
    is a trapezoidal velocity profile synchronised across joints (:meth:`trajectory`).
    """

    name: str
    description: str
    robot: str
    threshold: float
    setup: Mapping[str, np.ndarray]
    goal: np.ndarray

    def trajectory(self, scene: "Scene"):
        """The test motion as a ``Trajectory`` (``Trajectory.trapezoidal`` from the setup to ``goal``)."""
        from ..kinematics import Trajectory

        robot = scene.robots[self.robot]
        return Trajectory.trapezoidal(robot, self.setup[self.robot], self.goal)


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
