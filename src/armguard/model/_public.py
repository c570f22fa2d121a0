"""Public robots by name: the arms of example-robot-data and pybullet_data, found where those packages install them.

``load_model("ur10")`` (and every command that takes a model) looks a name up here after the
built-in models.  Each entry names the package, its URDF (relative to the package's robot
folder) and the SRDF that package pairs with it (the file example-robot-data's own loader
reads), given to ``load_model`` as ``srdf=``; None when there is none, or when the SRDF is one
that :func:`armguard.model.load_model`'s SRDF search should find and read leniently (kinova's,
talos's).  The files are never copied: they are found where the package installed them, so a
robot is *available* only when its package is installed.

* example-robot-data ships data only (no Python module): its files lie under the installing
  environment's ``cmeel.prefix/share/example-robot-data/robots/``, found through the
  distribution's record (:func:`importlib.metadata.distribution`), else on ``sys.path``.
* pybullet_data (from the ``pybullet`` package, a test extra): ``pybullet_data.getDataPath()``,
  found without importing pybullet.
"""

from __future__ import annotations

import importlib.metadata
import importlib.util
import sys
from dataclasses import dataclass
from pathlib import Path

from .._errors import SceneError

__all__ = ["PublicRobot", "KnownModel", "PUBLIC_ROBOTS", "public_robot", "public_robot_names", "public_robot_files",
           "public_robot_srdf", "package_root", "known_models"]

EXAMPLE_ROBOT_DATA = "example-robot-data"
PYBULLET_DATA = "pybullet_data"
_ERD_ROBOTS = Path("share") / "example-robot-data" / "robots"


@dataclass(frozen=True)
class PublicRobot:
    """A public robot description: ``urdf`` and ``srdf`` are relative to :func:`package_root` of ``package``."""

    name: str
    package: str
    urdf: str
    srdf: str | None = None
    aliases: tuple[str, ...] = ()


PUBLIC_ROBOTS: tuple[PublicRobot, ...] = (
    PublicRobot("panda", EXAMPLE_ROBOT_DATA, "panda_description/urdf/panda.urdf", "panda_description/srdf/panda.srdf"),
    # the same arm with capsules and spheres; the SRDF names the same links
    PublicRobot("panda_collision", EXAMPLE_ROBOT_DATA, "panda_description/urdf/panda_collision.urdf",
                "panda_description/srdf/panda.srdf"),
    PublicRobot("ur3", EXAMPLE_ROBOT_DATA, "ur_description/urdf/ur3_robot.urdf"),
    PublicRobot("ur5", EXAMPLE_ROBOT_DATA, "ur_description/urdf/ur5_robot.urdf", "ur_description/srdf/ur5.srdf"),
    PublicRobot("ur10", EXAMPLE_ROBOT_DATA, "ur_description/urdf/ur10_robot.urdf"),
    PublicRobot("ur5_gripper", EXAMPLE_ROBOT_DATA, "ur_description/urdf/ur5_gripper.urdf",
                "ur_description/srdf/ur5_gripper.srdf"),
    # kinova.srdf (a group_state without a group) is left to the SRDF search, which reads it leniently
    PublicRobot("kinova", EXAMPLE_ROBOT_DATA, "kinova_description/robots/kinova.urdf"),
    PublicRobot("xarm7", EXAMPLE_ROBOT_DATA, "xarm_description/urdf/xarm7.urdf", "xarm_description/srdf/xarm7.srdf"),
    PublicRobot("z1", EXAMPLE_ROBOT_DATA, "z1_description/urdf/z1.urdf", "z1_description/srdf/z1.srdf"),
    PublicRobot("so100", EXAMPLE_ROBOT_DATA, "so_arm_description/urdf/so100.urdf"),
    PublicRobot("so101", EXAMPLE_ROBOT_DATA, "so_arm_description/urdf/so101.urdf"),
    # talos.srdf describes the whole humanoid (links this arm lacks): left to SRDF discovery
    PublicRobot("talos_left_arm", EXAMPLE_ROBOT_DATA, "talos_data/robots/talos_left_arm.urdf"),
    PublicRobot("franka_panda", PYBULLET_DATA, "franka_panda/panda.urdf"),
    PublicRobot("kuka_iiwa", PYBULLET_DATA, "kuka_iiwa/model.urdf", aliases=("iiwa",)),
    PublicRobot("xarm6", PYBULLET_DATA, "xarm/xarm6_robot.urdf"),
)

_BY_NAME = {n: r for r in PUBLIC_ROBOTS for n in (r.name, *r.aliases)}


def public_robot_names(*, aliases: bool = False) -> tuple[str, ...]:
    """The public robots' names, in table order (with their aliases after each when ``aliases``)."""
    return tuple(n for r in PUBLIC_ROBOTS for n in ((r.name, *r.aliases) if aliases else (r.name,)))


def public_robot(name: str) -> PublicRobot | None:
    """The entry of ``name`` (a name or an alias), None when it is not a public robot."""
    return _BY_NAME.get(str(name))


def _example_robot_data_root() -> Path | None:
    try:
        d = importlib.metadata.distribution(EXAMPLE_ROBOT_DATA)
    except importlib.metadata.PackageNotFoundError:
        d = None
    if d is not None:
        p = Path(d.locate_file(Path("cmeel.prefix") / _ERD_ROBOTS))
        if p.is_dir():
            return p
    # no record: a cmeel.prefix on sys.path, or a system prefix (<prefix>/lib/pythonX.Y/site-packages -> <prefix>/share)
    for entry in map(Path, sys.path):
        candidates = [entry / "cmeel.prefix" / _ERD_ROBOTS]
        if len(entry.parents) > 2:
            candidates.append(entry.parents[2] / _ERD_ROBOTS)
        for p in candidates:
            if p.is_dir():
                return p
    return None


def _pybullet_data_root() -> Path | None:
    try:
        spec = importlib.util.find_spec(PYBULLET_DATA)
    except (ImportError, ValueError):
        return None
    if spec is None or not spec.origin:
        return None
    p = Path(spec.origin).parent
    return p if p.is_dir() else None


def package_root(package: str) -> Path | None:
    """The folder ``package``'s robot files are relative to; None when the package is not installed."""
    if package == EXAMPLE_ROBOT_DATA:
        return _example_robot_data_root()
    if package == PYBULLET_DATA:
        return _pybullet_data_root()
    raise ValueError(f"unknown robot package {package!r}; packages are {[EXAMPLE_ROBOT_DATA, PYBULLET_DATA]}")


def public_robot_files(name: str) -> tuple[Path, Path | None]:
    """``(urdf, srdf or None)`` of public robot ``name``; SceneError when it is not one, or its package or
    files are not installed (saying which)."""
    robot = public_robot(name)
    if robot is None:
        raise SceneError(f"{name!r} is not a public robot; public robots are {list(public_robot_names())}")
    root = package_root(robot.package)
    if root is None:
        hint = "pip install pybullet" if robot.package == PYBULLET_DATA else f"pip install {EXAMPLE_ROBOT_DATA}"
        raise SceneError(f"public robot {name!r} comes from {robot.package}, which is not installed ({hint})")
    urdf = root / robot.urdf
    srdf = root / robot.srdf if robot.srdf else None
    for p in (urdf, srdf):
        if p is not None and not p.is_file():
            raise SceneError(f"public robot {name!r}: {p} is missing from the installed {robot.package}")
    return urdf, srdf



def public_robot_srdf(name: str) -> tuple[Path, bool] | None:
    """``(srdf, partial)``: the SRDF :func:`armguard.model.load_model` reads for public robot ``name`` --
    the table's, else the first that its SRDF search finds beside the URDF
    (:func:`armguard.model._load.srdf_candidates`: ``talos_left_arm`` finds ``talos_data/srdf/talos.srdf``
    under its robot name ``talos``, ``kinova`` ``kinova.srdf``); ``partial`` when that file may describe a
    larger robot (its pairs naming links the URDF lacks do not apply).  None when there is none."""
    from ._load import srdf_candidates

    urdf, srdf = public_robot_files(name)
    if srdf is not None:
        return srdf, False
    for path, _how, partial in srdf_candidates(urdf):
        if path.is_file():
            return path.resolve(), partial
    return None

@dataclass(frozen=True)
class KnownModel:
    """A name :func:`armguard.load_model` takes: ``source`` is ``"built-in"`` or the package; ``path`` the file
    it loads (None when not available); ``reason`` why it is not available ("" when it is)."""

    name: str
    source: str
    available: bool
    path: Path | None
    aliases: tuple[str, ...] = ()
    reason: str = ""


def known_models() -> list[KnownModel]:
    """Every model name :func:`armguard.load_model` takes: the built-ins, then the public robots."""
    from ._load import builtin_model_names, builtin_model_path, models_dir

    out = []
    for n in builtin_model_names():
        p = builtin_model_path(n)
        out.append(KnownModel(n, "built-in", p is not None, p, reason="" if p else f"missing from {models_dir()}"))
    for r in PUBLIC_ROBOTS:
        try:
            urdf, _ = public_robot_files(r.name)
        except SceneError as exc:
            out.append(KnownModel(r.name, r.package, False, None, r.aliases, str(exc)))
        else:
            out.append(KnownModel(r.name, r.package, True, urdf, r.aliases))
    return out
