"""The scene file format, version 1, as pydantic v2 models (unknown keys are rejected).

Every model forbids extra keys and non-finite numbers, so a typo or a ``.nan`` is an error
that names its place in the file.  Numbers are strict: a boolean or a string (``true``,
``"1e3"``) is not a number, and no number's magnitude may exceed ``Tolerances.max_magnitude``
(products of such coordinates would overflow or lose all precision).  Numbers are in the file's ``units`` (``angle: deg | rad``,
``length: m | mm``); :mod:`._load` converts them to m / rad.  ``docs/scene-format.md`` is the
user-facing description of the same format.
"""

from __future__ import annotations

from typing import Annotated, Literal, Union

from pydantic import AfterValidator, BaseModel, BeforeValidator, ConfigDict, Field, model_validator

from .._tolerance import DEFAULT_TOLERANCES

__all__ = [
    "SCHEMA_VERSION",
    "SHAPE_TYPES",
    "SceneFile",
    "ShapeSpec",
    "JointSpec",
    "RobotSpec",
]

SCHEMA_VERSION = 1


def _bounded(x: float) -> float:
    """A file number within ``Tolerances.max_magnitude`` (the error names the bound)."""
    big = DEFAULT_TOLERANCES.max_magnitude
    if abs(x) > big:
        raise ValueError(f"magnitude {x:.6g} is beyond {big:.3g} (Tolerances.max_magnitude): derived quantities "
                         "(squares, volumes) would overflow or lose all precision")
    return x


def _exact_int(x):
    """Booleans and floats are not format versions (``armguard_scene: true`` is not ``1``)."""
    if type(x) is not int:
        raise ValueError(f"expected the integer 1, got {x!r}")
    return x


VersionOne = Annotated[Literal[1], BeforeValidator(_exact_int)]
"""A file format's version key: the integer 1 (not ``1.0``, not ``true``)."""
Num = Annotated[float, AfterValidator(_bounded)]  # strict (the models' config): no bool, no string
Vec3 = Annotated[list[Num], Field(min_length=3, max_length=3)]
Vec2 = Annotated[list[Num], Field(min_length=2, max_length=2)]
Name = Annotated[str, Field(min_length=1, pattern=r"^[A-Za-z0-9_.\-]+$")]


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True, strict=True)


class _Posed(_Model):
    """A local pose: translate by ``xyz``, then rotate by rot(z, yaw) rot(y, pitch) rot(x, roll)."""

    xyz: Vec3 = [0.0, 0.0, 0.0]
    rpy: Vec3 = [0.0, 0.0, 0.0]


class BoxSpec(_Posed):
    type: Literal["box"]
    size: Vec3  # full edge lengths along the box's own x, y, z


class SphereSpec(_Posed):
    type: Literal["sphere"]
    radius: Num = Field(ge=0.0)


class CapsuleSpec(_Posed):
    """Either ``p0`` + ``p1`` (end points in the owner's frame) or ``length`` along the local z axis."""

    type: Literal["capsule"]
    radius: Num = Field(ge=0.0)
    p0: Vec3 | None = None
    p1: Vec3 | None = None
    length: Num | None = Field(default=None, ge=0.0)


class LinkCapsuleSpec(_Model):
    """Ranger's link: the segment from the parent link's origin to this link's origin, swept by ``radius``."""

    type: Literal["link_capsule"]
    radius: Num = Field(ge=0.0)


class PrismSpec(_Posed):
    """A right prism over a regular ``n_sides``-gon; its axis is the local z axis."""

    type: Literal["prism"]
    n_sides: int = Field(ge=3, le=DEFAULT_TOLERANCES.max_prism_sides)
    apothem: Num = Field(gt=0.0)
    length: Num = Field(gt=0.0)


class CylinderSpec(_Posed):
    """A solid right circular cylinder (URDF's ``<cylinder>``, exact); its axis is the local z axis,
    centred on the local origin."""

    type: Literal["cylinder"]
    radius: Num = Field(gt=0.0)
    length: Num = Field(gt=0.0)  # full axial length


class PolyhedronSpec(_Posed):
    type: Literal["polyhedron"]
    vertices: Annotated[list[Vec3], Field(min_length=4)]


class PolygonSpec(_Posed):
    type: Literal["polygon"]
    vertices: Annotated[list[Vec3], Field(min_length=3)]


class MeshSpec(_Posed):
    """A mesh file (STL, OBJ, ... read by trimesh), replaced by its convex hull."""

    type: Literal["mesh"]
    file: str
    scale: Vec3 = [1.0, 1.0, 1.0]


ShapeSpec = Annotated[
    Union[BoxSpec, SphereSpec, CapsuleSpec, LinkCapsuleSpec, PrismSpec, CylinderSpec, PolyhedronSpec, PolygonSpec,
          MeshSpec],
    Field(discriminator="type"),
]
SHAPE_TYPES = ("box", "sphere", "capsule", "link_capsule", "prism", "cylinder", "polyhedron", "polygon", "mesh")


class FrameSpec(_Posed):
    name: Name
    parent: Name = "world"


class BodySpec(_Posed):
    """A static body: its shapes are given in its own frame (``xyz`` / ``rpy`` in ``frame``)."""

    name: Name
    category: Literal["vehicle", "environment"] = "environment"
    frame: Name = "world"
    shapes: Annotated[list[ShapeSpec], Field(min_length=1)]


class JointSpec(_Model):
    """One DH row plus its joint's limits (``[lower, upper]``; omitted: unlimited)."""

    name: Name | None = None
    type: Literal["revolute", "prismatic"] = "revolute"
    a: Num = 0.0
    alpha: Num = 0.0
    d: Num = 0.0
    theta: Num = 0.0
    limits: Vec2 | None = None
    max_velocity: Num | None = Field(default=None, gt=0.0)
    max_acceleration: Num | None = Field(default=None, gt=0.0)


class CouplingSpec(_Model):
    """A dependent joint: ``offset + sum(coeff * q[independent])`` (GMF S-480 parallelogram)."""

    joint: Name
    terms: dict[Name, Num]
    offset: Num = 0.0


class MountSpec(_Posed):
    frame: Name = "world"


class RobotSpec(_Model):
    """A robot from a DH table (``joints``) or a URDF file (``urdf``), mounted on a frame."""

    name: Name
    mount: MountSpec = MountSpec()
    convention: Literal["standard", "modified"] = "standard"
    joints: list[JointSpec] | None = None
    links: list[Name] | None = None
    couplings: list[CouplingSpec] = []
    tool: _Posed | None = None
    urdf: str | None = None
    srdf: str | None = None
    max_acceleration: list[float] | None = None  # a URDF robot's, one per joint (URDF has no place for them)
    link_shapes: dict[Name, list[ShapeSpec]] = {}
    home: list[Num] | None = None
    self_pairs: list[Annotated[list[Name], Field(min_length=2, max_length=2)]] | None = None


class PayloadSpec(_Posed):
    """Shapes held by ``robot``'s ``link``; ``xyz`` / ``rpy`` place the payload frame P in the link frame."""

    name: Name
    robot: Name
    link: Name
    shapes: Annotated[list[ShapeSpec], Field(min_length=1)]


class WorkspaceSpec(_Model):
    """Ranger's workspace bounding box: axis-aligned in the world frame."""

    lo: Vec3
    hi: Vec3


class PairsSpec(_Model):
    exclude_adjacent: bool = True
    disable: list[Annotated[list[str], Field(min_length=2, max_length=2)]] = []
    enable: list[Annotated[list[str], Field(min_length=2, max_length=2)]] = []  # checked, though an SRDF disables them


class TrajectorySpec(_Model):
    """Joint waypoints of one robot (``profile`` trapezoidal or linear; optional knot ``times`` in s)."""

    name: Name
    robot: Name
    waypoints: Annotated[list[list[Num]], Field(min_length=2)]
    profile: Literal["trapezoidal", "linear"] = "trapezoidal"
    times: list[Num] | None = None
    description: str = ""


class MotionSpec(_Model):
    """A canned test motion, exactly one of: ``end_effector`` — the change of the tool's six
    coordinates ``[dx, dy, dz, droll, dpitch, dyaw]`` (length, angle units; W); ``arm_angle`` — the
    change of a 7-joint arm's arm angle (angle units), the tool pose held; ``goal`` — joint values
    reached by a synchronised joint-space trapezoid.  Seed 000 section 6: "a trapezoidal trajectory
    in one or more of the six end-effector coordinates or the arm angle"."""

    goal: list[Num] | None = None
    end_effector: Annotated[list[Num], Field(min_length=6, max_length=6)] | None = None
    arm_angle: Num | None = None

    @model_validator(mode="after")
    def _exactly_one(self):
        given = [k for k in ("end_effector", "arm_angle", "goal") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError(f"expected exactly one of end_effector, arm_angle, goal; got {given or 'none'}")
        return self


class CannedTestSpec(_Model):
    name: Name
    description: str = ""
    robot: Name
    threshold: Num = Field(ge=0.0)
    setup: dict[Name, list[Num]]
    motion: MotionSpec


class UnitsSpec(_Model):
    angle: Literal["deg", "rad"] = "rad"
    length: Literal["m", "mm"] = "m"


class ModelRefSpec(_Model):
    """A model sidecar's robot system: a URDF (and its SRDF), paths relative to the sidecar."""

    urdf: str
    srdf: str | None = None


class JointExtraSpec(_Model):
    """What a URDF cannot say about a joint (its acceleration limit, for trapezoidal profiles)."""

    max_acceleration: float | None = Field(default=None, gt=0.0)


class SceneFile(_Model):
    armguard_scene: VersionOne
    name: Name
    description: str = ""
    units: UnitsSpec = UnitsSpec()
    model: ModelRefSpec | None = None
    joints: dict[str, JointExtraSpec] = {}
    ik: dict[str, str] = {}  # robot -> its IK routine (a registered name, "module:function" or "numeric")
    frames: list[FrameSpec] = []
    bodies: list[BodySpec] = []
    robots: list[RobotSpec] = []
    payloads: list[PayloadSpec] = []
    workspace: WorkspaceSpec | None = None
    pairs: PairsSpec = PairsSpec()
    trajectories: list[TrajectorySpec] = []
    canned_tests: list[CannedTestSpec] = []


def near_key(key) -> str | None:
    """The key of the format nearest an unknown ``key`` (``mout`` -> ``mount``, ``trajectory`` ->
    ``trajectories``), or None when none is near."""
    import difflib

    known = sorted({f for v in globals().values() if isinstance(v, type) and issubclass(v, BaseModel) and v is not BaseModel
                    for f in v.model_fields} - {str(key)})  # a key of another mapping ('robot' of a payload) is not near
    near = difflib.get_close_matches(str(key), known, n=1, cutoff=0.75)
    return near[0] if near else None
