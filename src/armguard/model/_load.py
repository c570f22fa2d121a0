"""``load_model``: a built-in name, a URDF (+ SRDF) or a YAML scene file into a :class:`Model`.

* A ``.urdf``: Pinocchio builds the model and GeometryModel (checked, see ``_urdf``); its SRDF
  (``srdf=``, else found by :func:`srdf_candidates`; ``srdf=False``: none) gives groups, disabled
  pairs and home states.
* A model sidecar ``.yaml`` (``model: {urdf, srdf}``): the same, then the sidecar's workspace,
  accelerations, extra bodies, pair filters, trajectories and canned tests.
* A scene ``.yaml`` without ``model:`` (robots from DH tables, bodies as shapes): the scene as
  it is, and its Pinocchio model and GeometryModel built from it by writing it as URDF.
* A built-in name: ``urdf/<name>/<name>.yaml``.
* A public robot's name (``ur10``, ``xarm7``, ``kuka_iiwa``...): its URDF and SRDF where
  example-robot-data or pybullet_data installed them (``armguard.model._public``).
"""

from __future__ import annotations

import contextlib
import os
import tempfile
import threading
from pathlib import Path

import numpy as np

from .._errors import ArmguardError, SceneError, SceneFileError
from ._model import Model
from ._srdf import NO_SRDF, read_srdf, renamed_to

__all__ = ["load_model", "models_dir", "builtin_model_names", "model_from_scenefile", "model_from_scene", "model_of"]

_BUILTINS = ("ranger", "hermes", "puma560", "gmf_s480", "rover")


def models_dir() -> Path:
    """The folder of the built-in models: ``$ARMGUARD_MODELS``, the installed package data or the checkout's
    ``urdf/`` (:func:`armguard._resources.data_dir`)."""
    from .._resources import data_dir

    return data_dir("urdf")


def builtin_model_names() -> tuple[str, ...]:
    return _BUILTINS


def builtin_model_path(name: str) -> Path | None:
    """The sidecar of built-in ``name`` (None when it is not a built-in or its files are missing)."""
    if name not in _BUILTINS:
        return None
    p = models_dir() / name / f"{name}.yaml"
    return p if p.is_file() else None


def load_model(name_or_path, *, srdf=None, package_dirs=()) -> Model:
    """A :class:`Model` from a built-in or public robot name, a ``.urdf`` or a ``.yaml`` file (see the module
    docstring); ``srdf=`` replaces the SRDF a public robot or URDF would have; ``package_dirs``: folders
    ``package://`` mesh names resolve against (one path, or a list of them)."""
    if isinstance(package_dirs, (str, os.PathLike)):  # one folder (was read as a list of one-letter folders)
        package_dirs = (package_dirs,)
    if not isinstance(name_or_path, (str, os.PathLike)):  # str(None) was looked up as a model named 'None'
        raise TypeError(f"load_model: expected a model name or a path (str or os.PathLike), got {type(name_or_path).__name__}")
    s = str(name_or_path)
    p = Path(s)
    suffix = p.suffix.lower()
    if suffix == ".urdf":
        return model_from_urdf(p, srdf=srdf, package_dirs=package_dirs)
    if suffix in (".yaml", ".yml"):
        return model_from_yaml(p, srdf=srdf)
    if suffix == "" and "/" not in s and "\\" not in s:
        return _model_by_name(s, srdf=srdf, package_dirs=package_dirs)
    if suffix == ".xacro" or s.lower().endswith(".urdf.xacro"):
        raise SceneError(f"cannot load {s!r}: a xacro macro file, not a URDF; expand it first "
                         f"(`xacro {p.name} > {p.name.removesuffix('.xacro').removesuffix('.urdf')}.urdf`) and load that")
    raise SceneError(f"cannot load {s!r}: expected a model name ({_known_names_text()}), a .urdf or a .yaml file")


def _model_by_name(name: str, *, srdf=None, package_dirs=()) -> Model:
    """A built-in model (``urdf/<name>/<name>.yaml``), else a public robot (``armguard.model._public``)."""
    from ._public import public_robot, public_robot_files

    path = builtin_model_path(name)
    if path is not None:
        return model_from_yaml(path, srdf=srdf)
    if public_robot(name) is not None:
        urdf, known_srdf = public_robot_files(name)
        if srdf is None and known_srdf is not None:  # the package's own SRDF, as armguard's table names it
            return model_from_urdf(urdf, srdf=known_srdf, package_dirs=package_dirs,
                                   srdf_found=f"the SRDF of public robot {name!r} (docs/models.md)")
        return model_from_urdf(urdf, srdf=srdf, package_dirs=package_dirs)
    if name in _BUILTINS:
        raise SceneError(f"built-in model {name!r} is missing: no {name}/{name}.yaml in {models_dir()}")
    raise SceneError(f"unknown model {name!r}; known models are {_known_names_text()} "
                     "(`armguard info` lists them), or give a .urdf or .yaml path")


def _known_names_text() -> str:
    from ._public import public_robot_names

    return f"built-in {list(_BUILTINS)}, public {list(public_robot_names(aliases=True))}"


def srdf_candidates(urdf: Path) -> list[tuple[Path, str, bool]]:
    """Where :func:`load_model` looks for the SRDF of ``urdf``, in order: ``(path, how, partial)``.

    Under the URDF's file name ``<stem>``: ``<dir>/<stem>.srdf``, then ``<dir>/../srdf/<stem>.srdf``
    (example-robot-data's ``X_description/{urdf,srdf}/``); then under the robot's name ``<name>``
    (the URDF's ``<robot name>``, when it differs from the stem): ``<dir>/<name>.srdf``, then
    ``<dir>/../srdf/<name>.srdf`` -- ``panda_collision.urdf`` finds ``panda.srdf``, ``ur5_robot.urdf``
    ``ur5.srdf``, ``talos_left_arm.urdf`` ``talos.srdf``.  An SRDF found under the robot's name may
    describe a larger robot (``partial``): names the URDF lacks are then skipped with a warning."""
    urdf = Path(urdf)
    names = [(urdf.stem, False)]
    robot = _urdf_robot_name(urdf)
    if robot and robot != urdf.stem and "/" not in robot and "\\" not in robot:
        names.append((robot, True))
    out = []
    for name, partial in names:
        under = f"the robot's name {name!r}" if partial else "the URDF's name"
        out.append((urdf.parent / f"{name}.srdf", f"beside the URDF, under {under}", partial))
        out.append((urdf.parent.parent / "srdf" / f"{name}.srdf", f"in ../srdf/, under {under}", partial))
    return out


def _urdf_robot_name(urdf: Path) -> str | None:
    """The ``name`` of the URDF's ``<robot>`` element (None when the file does not say)."""
    import xml.etree.ElementTree as ET

    try:
        for _, el in ET.iterparse(urdf, events=("start",)):
            return el.get("name") if el.tag == "robot" else None
    except (ET.ParseError, OSError):
        return None  # the URDF's own reading reports it
    return None


def _srdf_for(urdf: Path, srdf, found: str = "given (srdf=)"):
    """The SRDF of ``urdf``: ``srdf`` when given (it wins; ``found`` says how it came), else the first of
    :func:`srdf_candidates` that exists; None when there is none (or ``srdf`` is False)."""
    if srdf is False:
        return None
    if srdf is not None:
        return read_srdf(srdf, found=found)
    for path, how, partial in srdf_candidates(urdf):
        if path.is_file():
            return read_srdf(path.resolve(), found=how, partial=partial)
    return None


def _build(urdf: Path, srdf_obj, package_dirs, accelerations, name=None, srdf_source=None, srdf_read=False):
    """``(scene, pin_model, collision_model, parts)`` of a URDF: robots, bodies, payloads, SRDF pairs.

    ``srdf_source``: what a scene file saved from this scene names as each arm's ``srdf:`` (None:
    nothing, the SRDF found beside the URDF then; :data:`._srdf.NO_SRDF`: none, as loaded);
    ``srdf_read``: the Srdf that file is (its pairs are what a reload applies: save_scene lists those this
    scene checks under ``pairs.enable``); False: ``srdf_obj``."""
    from ._scene import Scene
    from ._from_pin import scene_parts_from_pin
    from ._urdf import load_pinocchio

    pin_model, geom, info = load_pinocchio(urdf, [models_dir(), *package_dirs])
    parts = scene_parts_from_pin(pin_model, geom, info, srdf_obj, accelerations=accelerations)
    parts.hull_cache = dict(info.hull_cache)
    parts.hulls = _hulls_by_name(geom, info)
    scene = Scene(name or info.robot_name)
    try:
        for bname, shapes, cat in parts.bodies:
            scene.add_body(bname, shapes, category=cat)
        for robot, home, _ in parts.robots:
            source = {"kind": "urdf", "urdf": os.path.abspath(urdf), "arms": len(parts.robots), "srdf_pairs": ()}
            if srdf_source is not None:
                source["srdf"] = srdf_source
            scene.add_robot(robot, home=home, _source=source)
        for pname, rname, link, shapes, X_LP in parts.payloads:
            scene.attach_payload(pname, rname, link, shapes, X_LP)
    except ArmguardError as exc:
        raise SceneFileError(str(urdf), "", str(exc)) from None
    if srdf_obj is not None:
        skipped: list[str] = []
        for k, (a, b, _) in enumerate(srdf_obj.disabled):
            oa, ob = parts.link_owner.get(a), parts.link_owner.get(b)
            if oa is None or ob is None:
                missing = a if oa is None else b
                shaped = {pin_model.frames[int(go.parentFrame)].name for go in geom.geometryObjects}
                near = renamed_to(missing, [ln for ln in parts.link_owner if ln in shaped], srdf_obj.names())
                hint = f": a link renamed {near!r}? then update the SRDF" if near else ""
                if srdf_obj.partial:  # an SRDF of a larger robot: its pairs of links this URDF lacks do not apply
                    skipped.append(f"disable_collisions[{k}] ({missing}{hint})")
                    continue
                raise srdf_obj.error(f"disable_collisions[{k}]", f"names link {missing!r}, which the URDF {urdf} does not "
                                     f"have{hint.replace(': a', ' (a', 1) + ')' if hint else ''}")
            if oa == ob:
                continue
            try:
                scene.disable_pair(oa, ob)
            except SceneError as exc:
                raise srdf_obj.error(f"disable_collisions[{k}]", str(exc)) from None
        if skipped:
            one = len(skipped) == 1
            srdf_obj.warn(f"{len(skipped)} disabled {'pair names' if one else 'pairs name'} links {urdf.name} does not "
                          f"have and {'was' if one else 'were'} skipped "
                          f"(first: {', '.join(skipped[:3])})")
        _warn_stale(srdf_obj, pin_model, geom)
    read = srdf_obj if srdf_read is False else srdf_read
    for a, b, _ in (read.disabled if read is not None else ()):  # for save_scene: the pairs a reload's SRDF disables
        oa, ob = parts.link_owner.get(a), parts.link_owner.get(b)
        for rname, src in scene._robot_sources.items():
            if oa is not None and ob is not None and oa != ob and any(o.startswith(f"{rname}/") for o in (oa, ob)):
                src["srdf_pairs"] = (*src["srdf_pairs"], (oa, ob))
    return scene, pin_model, geom, parts


def _warn_stale(srdf_obj, pin_model, geom) -> None:
    """Warn when the SRDF disables pairs certified for another geometry or kinematics (``_certificate``)."""
    from ._certificate import older_certificates, stale_certificates, uncertified_pairs

    bare = uncertified_pairs(srdf_obj.file)
    if bare:  # kept disabled, as a hand-written SRDF's pairs are, but said: nothing vouches for them
        srdf_obj.warn(f"{len(bare)} disabled pair{'s' if len(bare) > 1 else ''} without a certificate in an SRDF armguard "
                      f"certified (added by hand?): {', '.join(bare[:4])}{' ...' if len(bare) > 4 else ''}; "
                      "`armguard check-srdf --strict` searches them, `armguard srdf --update` rewrites them")
    stale = stale_certificates(pin_model, geom, srdf_obj.file)
    if stale and older_certificates(srdf_obj.file):  # every certificate reads as stale: no edit to blame
        srdf_obj.warn(f"{len(stale)} disabled pairs carry certificates written by an older armguard (before the "
                      "verdict was hashed into them), which cannot vouch for them: `armguard srdf --update` searches "
                      "them again and rewrites the file (all of its pairs: minutes on a large robot)")
    elif stale:
        names = ", ".join(f"{s.link1}-{s.link2} ({s.reason})" for s in stale[:4]) + (" ..." if len(stale) > 4 else "")
        one = len(stale) == 1
        srdf_obj.warn(f"{len(stale)} disabled {'pair was' if one else 'pairs were'} certified for another geometry or "
                      f"kinematics than this URDF gives and may now collide: {names}; `armguard check-urdf` proves "
                      f"{'it' if one else 'them'} again, `armguard srdf --update` rewrites {'it' if one else 'them'}")


def _hulls_by_name(geom, info) -> dict:
    """GeometryObject name -> the MeshPolytope its coal.Convex was built from (load_pinocchio's hulls)."""
    objs = geom.geometryObjects
    return {objs[i].name: mp for i, mp in info.hulls.items()}


def _link_frames(parts, pin_model) -> dict:
    """Scene link ``"robot/link"`` -> its BODY frame in ``pin_model`` (from the converter's URDF link owners)."""
    import pinocchio as pin

    return {owner: int(pin_model.getFrameId(ln, pin.FrameType.BODY))
            for ln, owner in parts.link_owner.items() if "/" in owner}


def _q_index(parts) -> np.ndarray:
    return np.concatenate([qi for _, _, qi in parts.robots]) if parts.robots else np.zeros(0, np.int64)


def _circular(parts) -> np.ndarray:
    """Scene-q positions of continuous joints (pinocchio holds their (cos, sin))."""
    out, base = [], 0
    for (robot, _, qi), circ in zip(parts.robots, parts.circular):
        out.extend(base + int(k) for k in circ)
        base += len(qi)
    return np.asarray(out, dtype=np.int64)


def model_from_urdf(path, *, srdf=None, package_dirs=(), srdf_found: str = "given (srdf=)") -> Model:
    """A Model of one URDF file (and its SRDF; ``srdf_found``: how a given ``srdf`` came, for ``Srdf.found``)."""
    path = Path(path).resolve()
    if not path.is_file():
        raise SceneFileError(str(path), "", "URDF file not found")
    try:
        srdf_obj = _srdf_for(path, srdf, srdf_found)
        named = NO_SRDF if srdf is False else None if srdf is None else str(Path(srdf).resolve())
        scene, pin_model, geom, parts = _build(path, srdf_obj, package_dirs, {}, srdf_source=named)
    except SceneFileError as exc:
        if srdf is not None or not exc.file.lower().endswith(".srdf"):
            raise
        # an SRDF armguard found (not one the caller named) refuses this URDF: say how to load it without
        raise SceneFileError(exc.file, exc.where, f"{exc.message}; this SRDF was found for {path.name} (docs/models.md, "
                             f"\"Finding the SRDF\"): to load the URDF without it, load_model(path, srdf=False), "
                             f"`--srdf {NO_SRDF}` on `armguard info` or `check`, or `srdf: {NO_SRDF}` beside "
                             f"`urdf: {path.name}` in a model sidecar's `model:` or a scene file's robot", line=exc.line) from None
    files = [path, *parts_files(parts, srdf_obj)]
    return Model(scene.name, pin_model, geom, scene, q_index=_q_index(parts), circular=_circular(parts), hull_cache=parts.hull_cache,
                 link_frames=_link_frames(parts, pin_model), hulls=parts.hulls,
                 geometry_names=parts.geometry_names,
                 notes=parts.notes, files=files, srdf=srdf_obj)


def parts_files(parts, srdf_obj) -> list:
    return [Path(srdf_obj.file)] if srdf_obj is not None else []


def model_from_yaml(path, *, srdf=None) -> Model:
    """A Model of a sidecar or scene YAML file; ``srdf=`` (a path, or False for none) replaces the sidecar's."""
    from ._scenefile import read_scene_yaml, validate_scene_dict

    from .._lines import lines_for

    path = Path(path)
    with lines_for(path):
        data = read_scene_yaml(path)
        sf = validate_scene_dict(data, str(path))
        return model_from_scenefile(sf, str(path), path.parent, srdf=srdf)


def model_from_scenefile(sf, file: str, base: Path, *, srdf=None) -> Model:
    """The Model of a validated scene file ``sf`` read from ``file`` (paths relative to ``base``);
    ``srdf=`` (a path, or False for none) replaces the sidecar's ``model.srdf``."""
    from ._scenefile import _DEG, _MM, _Ctx, _frames, _no_srdf, _populate

    ctx = _Ctx(file, base, _MM if sf.units.length == "mm" else 1.0, _DEG if sf.units.angle == "deg" else 1.0)
    if sf.model is None:
        if srdf not in (None, False):
            raise SceneFileError(file, "", f"srdf={srdf!s}: a scene file without a URDF (no 'model:') has no SRDF to replace")
        return _model_from_plain_scene(sf, file, base, ctx)
    if sf.robots or sf.payloads:
        raise ctx.error("robots" if sf.robots else "payloads", "a model sidecar takes its arms and payloads from the "
                        "URDF (model.urdf); add extra static bodies under 'bodies'")
    urdf = ctx.path(sf.model.urdf)
    if not urdf.is_file():
        raise ctx.not_found("model.urdf", "URDF file", sf.model.urdf)
    named = sf.model.srdf
    if named is not None and _no_srdf(named):  # the URDF alone: no SRDF, not even one found beside it
        srdf_obj = None
    else:
        srdf_obj = _srdf_for(urdf, ctx.path(named) if named else None, found=f"named by {Path(file).name}'s model.srdf")
    side = srdf_obj  # the sidecar's SRDF (its groups name the arms)
    if srdf is not None:
        srdf_obj = _replace_pairs(srdf_obj, srdf)
    acc = {}
    for jn, spec in sf.joints.items():
        if spec.max_acceleration is not None:
            acc[jn] = acc[jn.replace("/", "_", 1)] = spec.max_acceleration * ctx.A  # "R/joint"; an exported URDF's "R_joint"
    # what a scene file saved from it names as each arm's srdf: the file whose groups name the arms (the
    # sidecar's, unless srdf= gives groups), its pairs that this Model checks then listed under pairs.enable
    given_groups = srdf_obj is not None and srdf_obj.groups and (side is None or srdf_obj.groups is not side.groups)
    groups_from = srdf_obj if srdf not in (None, False) and given_groups else side
    if groups_from is None:
        srdf_source = NO_SRDF
    elif srdf is None and not named:
        srdf_source = None  # found beside the URDF: found again
    else:
        srdf_source = os.path.abspath(groups_from.file)
    scene, pin_model, geom, parts = _build(urdf, srdf_obj, (), acc, name=sf.name, srdf_source=srdf_source,
                                           srdf_read=groups_from)
    known = {jn.replace("/", "_", 1) for jn in scene.joint_names} | set(scene.joint_names)
    for jn in sf.joints:
        if jn not in known and jn.replace("/", "_", 1) not in known:
            robot = jn.split("/", 1)[0]
            hint = ""
            if srdf not in (None, False) and "/" in jn and robot not in scene.robots:
                hint = (f" (the arms are named by the SRDF's groups, and srdf={os.fspath(srdf)} names "
                        f"{', '.join(map(repr, scene.robots)) or 'none'} where this file names {robot!r}: give it the "
                        "sidecar's group names, or no groups to keep the sidecar's)")
            raise ctx.error(f"joints.{jn}", f"unknown joint; joints are {list(scene.joint_names)}{hint}")
    scene.description = sf.description
    frames = _frames(sf, ctx)
    try:
        _populate(scene, sf, ctx, frames)
    except SceneFileError:
        raise
    except SceneError as exc:
        raise ctx.error("", str(exc)) from None
    geometry_names = dict(parts.geometry_names)
    _add_extra_bodies(scene, geom, geometry_names, {b for b, _, _ in parts.bodies})
    files = [Path(file), urdf, *parts_files(parts, srdf_obj), *ctx.read]
    return Model(sf.name, pin_model, geom, scene, q_index=_q_index(parts), circular=_circular(parts), hull_cache=parts.hull_cache,
                 link_frames=_link_frames(parts, pin_model), hulls=parts.hulls,
                 geometry_names=geometry_names,
                 notes=parts.notes, files=files, srdf=srdf_obj)


def _replace_pairs(sidecar_srdf, srdf):
    """A sidecar's SRDF with the caller's disabled pairs: none (``srdf=False``), or those of the file
    ``srdf`` -- with that file's groups and states where it has them, else the sidecar's (which name the
    arms and their home: an SRDF ``armguard srdf`` wrote has only pairs)."""
    import dataclasses

    if srdf is False:
        return None if sidecar_srdf is None else dataclasses.replace(sidecar_srdf, disabled=())
    given = read_srdf(srdf, found="given (srdf=)")
    if sidecar_srdf is None:
        return given
    return dataclasses.replace(given, groups=given.groups or sidecar_srdf.groups,
                               states=given.states or sidecar_srdf.states)


def _add_extra_bodies(scene, geom, geometry_names: dict, known: set) -> None:
    """Bodies the YAML added beside the URDF's: into the GeometryModel too (fixed to the world)."""
    import pinocchio as pin

    from ._shapes import coal_from_shape

    for name, body in scene.bodies.items():
        if name in known:
            continue
        for i, shape in enumerate(body.shapes):
            g, X = coal_from_shape(shape)
            gname = f"{name}_{i}"
            go = pin.GeometryObject(gname, 0, 0, pin.SE3(X[:3, :3], X[:3, 3]), g)
            geom.addGeometryObject(go)
            geometry_names[(name, i)] = gname


def _model_from_plain_scene(sf, file: str, base: Path, ctx) -> Model:
    """A scene file with DH/URDF robots and shape bodies: its Pinocchio side written as URDF first."""
    from ._scenefile import scene_from_dict_validated

    return model_from_scene(scene_from_dict_validated(sf, file, base), file=file)


_DERIVE_LOCK = threading.Lock()


def model_of(scene, *, geometry: bool = True) -> Model:
    """The Model of ``scene``: the one it was loaded as (when unchanged since), else one built from it.

    Unchanged: the scene holds the robots the Model was built with (:meth:`Model.moves_robots_of`:
    ``set_robot_base`` or ``add_robot`` make a new one) and, with ``geometry`` (the default),
    nothing the Model's shapes or pairs depend on changed (:meth:`Model.is_model_of`: a Model's
    pairs are fixed when it is made).  Pair filters or the workspace box changed: a Model sharing
    this one's Pinocchio models; bodies, payloads, robot bases (``set_robot_base``) or robots added
    after its own (``add_robot``: only the new robot is written as URDF, then appended): a Model
    derived from it (:func:`armguard.model._derive.derive_model`); either becomes the scene's; a scene with no
    Model yet, or whose robots changed otherwise: one built from the scene.  ``geometry=False`` asks
    only for the kinematics (``pin_model``, ``q_index``, ``link_frames``): the Model of record also
    serves after bodies, payloads or pairs changed, and a :meth:`Scene.copy` with the same robots."""
    m = getattr(scene, "_model_of_record", None)
    if m is not None and m.moves_robots_of(scene) and (not geometry or m.is_model_of(scene)):
        return m
    lock = getattr(scene, "lock", None)
    with lock if lock is not None else contextlib.nullcontext():  # no edit while it is read (Scene.lock)
        return _model_of_locked(scene, geometry)


def _model_of_locked(scene, geometry: bool) -> Model:
    """:func:`model_of` past its fast path, the scene's lock held (always taken before
    ``_DERIVE_LOCK``: an edit holding the scene's lock may ask for its kinematics)."""
    m = getattr(scene, "_model_of_record", None)
    if m is not None and m.moves_robots_of(scene) and (not geometry or m.is_model_of(scene)):
        return m
    if m is not None:
        from ._derive import derive_model

        with _DERIVE_LOCK:  # one derived Model per change, whichever thread asks first
            m = scene._model_of_record
            if m.moves_robots_of(scene) and (not geometry or m.is_model_of(scene)):
                return m
            derived = derive_model(m, scene)  # bodies, payloads or robot bases changed (see _derive)
            if derived is not None:
                return derived
    new = model_from_scene(scene)
    if m is not None and m.scene is scene and m.srdf is not None and new.srdf is None:
        from ._srdf import carry_srdf

        new.srdf = carry_srdf(m, new)  # a moved or added robot keeps the groups and states it was loaded with
    return new


def kinematics_of(scene_or_model):
    """The Model whose ``pin_model`` moves the robots of ``scene_or_model`` (a Model: itself; a
    scene: ``model_of(scene, geometry=False)``), or None for a scene without robots.  What the
    framework moves links with (:meth:`Model.link_poses`, :meth:`Model.kinematic_tree`)."""
    if isinstance(scene_or_model, Model):
        return scene_or_model
    if not scene_or_model.robots:
        return None
    return model_of(scene_or_model, geometry=False)


def model_from_scene(scene, *, file: str | None = None) -> Model:
    """A Model of a Scene built in code or from a plain scene file: the scene is written as URDF
    (:func:`armguard.model.export.export_scene`) and Pinocchio loads that; the Model keeps
    ``scene`` itself as its scene (the analytic backend's input is unchanged)."""
    from .export import export_scene, plain_name
    from ._from_pin import scene_parts_from_pin
    from ._urdf import load_pinocchio

    file = file or f"<scene {scene.name}>"
    with tempfile.TemporaryDirectory(prefix="armguard-model-") as tmp:
        # the files' stem: the scene's name where it is a plain file name ("cells/small" had no folder there)
        written = export_scene(scene, tmp, name=scene.name if plain_name(scene.name) else "scene", sidecar=False)
        urdf = Path(written["urdf"])
        pin_model, geom, info = load_pinocchio(urdf)
        srdf_obj = read_srdf(written["srdf"]) if "srdf" in written else None
        parts = scene_parts_from_pin(pin_model, geom, info, srdf_obj)
        hulls = _hulls_by_name(geom, info)
    q_index = np.empty(len(scene.joint_names), np.int64)
    pin_names = {}
    for robot, _, qi in parts.robots:
        for j, iq in zip(robot.joint_names, qi):
            pin_names[f"{robot.name}/{j}"] = iq
    for k, jn in enumerate(scene.joint_names):
        if jn not in pin_names:
            raise SceneFileError(file, "", f"joint {jn!r} did not survive the URDF export (a bug: please report)")
        q_index[k] = pin_names[jn]
    geometry_names = {}
    for owner in scene.owners():
        n = len(_owner_shapes(scene, owner))
        for i in range(n):
            if (owner, i) not in parts.geometry_names:
                raise SceneFileError(file, "", f"shape {i} of {owner!r} did not survive the URDF export (a bug: please report)")
            geometry_names[(owner, i)] = parts.geometry_names[(owner, i)]
    files = [Path(file)] if Path(file).is_file() else []
    if files:  # the meshes, URDFs and SRDFs the scene file named (not for a scene built in code)
        files += [p for p in getattr(scene, "_source_files", ()) if Path(p).is_file()]
    all_frames, link_frames = _link_frames(parts, pin_model), {}
    for owner in (f"{r}/{ln}" for r, robot in scene.robots.items() for ln in robot.link_names):
        if owner not in all_frames:
            raise SceneFileError(file, "", f"link {owner!r} did not survive the URDF export (a bug: please report)")
        link_frames[owner] = all_frames[owner]  # not the export's zero-length links of a coupled joint's chain
    placements = {}  # the export's URDF link is the joint frame: the scene link sits at its X_post in it
    for r, robot in scene.robots.items():
        for ln in robot.link_names:
            spec = robot.joint_of_link(ln)
            if spec is not None and spec.X_post is not None:
                placements[f"{r}/{ln}"] = np.asarray(spec.X_post, dtype=np.float64)
    model = Model(scene.name, pin_model, geom, scene, q_index=q_index, circular=_circular(parts), geometry_names=geometry_names,
                  notes=parts.notes, files=files, link_frames=link_frames, link_placements=placements, hulls=hulls)
    from ._srdf import srdf_of_scene  # a scene file's URDF robots' SRDF groups, in this Model's names

    model.srdf = srdf_of_scene({r: src["srdf_groups"] for r, src in getattr(scene, "_robot_sources", {}).items()
                                if src.get("srdf_groups") is not None and r in scene.robots}, model)
    return model


def _owner_shapes(scene, owner: str):
    if owner in scene.bodies:
        return scene.bodies[owner].shapes
    if owner in scene.payloads:
        return scene.payloads[owner].shapes
    r, ln = owner.split("/", 1)
    return scene.robots[r].link_shapes.get(ln, ())

