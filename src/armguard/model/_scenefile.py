"""YAML scene files (format version 1) into a Scene: the front end that the Model's loaders
(``_load``) and :mod:`armguard.scene`'s ``load_scene`` build on.

Every failure is a :class:`SceneFileError` naming the file, the place inside it written like
``robots[0].joints[3].limits`` (or ``line 12, column 3`` for YAML syntax) and what was
expected.  A scene is built completely before it is returned, so a file that fails to load
changes nothing already loaded.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
from pydantic import ValidationError

from .._errors import ArmguardError, KinematicsError, SceneError, SceneFileError, list_problems
from ..geometry import Box, Capsule, ConvexPolyhedron, Cylinder, Polygon, Prism, Sphere
from ._robot_urdf import robot_parts_from_urdf
from ._scene import Scene
from ._scenefile_motions import _canned_test, _in_limits, _q_scale, _trajectory
from ._srdf import NO_SRDF, read_srdf_disabled, reshaped_pairs
from ._schema import SHAPE_TYPES, SceneFile, near_key
from .._yaml import read_scene_yaml  # noqa: F401  (part of this module's interface)

__all__ = ["validate_scene_dict", "scene_from_dict_validated", "read_scene_yaml", "read_srdf_disabled", "where_of"]

_MM = 1e-3
_DEG = math.pi / 180.0



def _coupling_form(ctx, where: str, c, names: list, dependent: set) -> None:
    """A coupling a Model can hold (its URDF form: one mimic joint per term, of a commanded joint before it):
    the terms name commanded joints earlier in the chain, and a drive coupling's own coefficient is 1.  Each
    refused at ``where`` (a coupling on a later joint loaded here and then failed in ``load_model``, naming a
    deleted temporary URDF)."""
    row = names.index(c.joint)
    for t, coeff in c.terms.items():
        if t == c.joint:
            if coeff != 1.0:
                raise ctx.error(f"{where}.terms", f"a drive coupling's own term must be 1 (the joint's value is its "
                                f"command plus the other terms), got {t}: {coeff}")
            continue
        if t in dependent:
            raise ctx.error(f"{where}.terms", f"{t!r} follows a coupling itself: name the commanded joints it follows")
        if names.index(t) > row:
            raise ctx.error(f"{where}.terms", f"{t!r} comes after {c.joint!r} in the chain: a coupling follows "
                            "joints before it (its URDF form is a mimic of an earlier joint)")

def where_of(loc) -> str:
    """A pydantic error location as a path: ``('robots', 0, 'joints', 3, 'limits')`` -> ``robots[0].joints[3].limits``.

    Union tags that pydantic inserts after a shape index (``shapes[1].box.size``) are dropped.
    """
    out = ""
    prev_int = False
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
            prev_int = True
            continue
        part = str(part)
        if prev_int and part in SHAPE_TYPES:
            prev_int = False
            continue  # discriminated-union tag, not a key of the file
        if part.startswith("function-") or part.startswith("union["):
            continue
        out += ("." if out else "") + part
        prev_int = False
    return out


def _message(err: dict) -> str:
    t = err.get("type", "")
    if t == "extra_forbidden":
        near = near_key(err["loc"][-1]) if err.get("loc") else None
        return f"unknown key (not part of the armguard_scene format; {f'did you mean {near!r}?' if near else 'check the spelling'})"
    if t == "union_tag_invalid":
        got = err.get("input", {}).get("type") if isinstance(err.get("input"), dict) else None
        return f"unknown shape type {got!r}; expected one of {', '.join(SHAPE_TYPES)}"
    if t == "union_tag_not_found":
        return f"a shape needs a 'type': one of {', '.join(SHAPE_TYPES)}"
    if t == "finite_number":
        return "expected a finite number (NaN and infinity are not allowed)"
    if t in ("float_type", "int_type", "float_parsing", "int_parsing", "int_from_float"):
        kind = "an integer" if t.startswith("int") else "a number"
        why = " (booleans and quoted strings are not numbers)" if isinstance(err.get("input"), (bool, str)) else ""
        return f"expected {kind}, got {err.get('input')!r}{why}"
    if t == "value_error":
        return str(err.get("msg", "invalid value")).removeprefix("Value error, ")
    if t == "literal_error" and err.get("loc") == ("armguard_scene",):
        return f"unsupported format version {err.get('input')!r}; this armguard reads armguard_scene: 1"
    if t == "missing":
        return "required key is missing"
    return err.get("msg", "invalid value")


class _Ctx:
    """Per-file context: the file name for errors, its directory for relative paths, and units."""

    def __init__(self, file: str, base: Path, length: float, angle: float) -> None:
        self.file, self.base, self.L, self.A = file, base, length, angle
        self.read: list[Path] = []  # the files the scene's geometry was read from (meshes, URDFs, SRDFs)

    def error(self, where: str, message: str) -> SceneFileError:
        return SceneFileError(self.file, where, message)

    def pose(self, xyz, rpy, where: str) -> np.ndarray:
        from ..kinematics import pose_from_xyz_rpy

        try:
            return pose_from_xyz_rpy(np.asarray(xyz) * self.L, np.asarray(rpy) * self.A)
        except ArmguardError as exc:
            raise self.error(where, str(exc)) from None

    def path(self, name: str) -> Path:
        p = Path(name)
        return p if p.is_absolute() else self.base / p

    def not_found(self, where: str, what: str, name: str) -> SceneFileError:
        """``what`` (e.g. "URDF file") named at ``where`` is not there: the error names the absolute path
        tried and, for a relative ``name``, the folder it was read from (this file's)."""
        tried = os.path.abspath(self.path(name))
        if Path(name).is_absolute():
            return self.error(where, f"{what} not found: {tried}")
        return self.error(where, f"{what} not found: {tried} ({name!r} is relative to the folder of "
                                 f"{Path(self.file).name}, {os.path.abspath(self.base)}: give a path from there "
                                 "or an absolute one)")


def _apply(X: np.ndarray, pts) -> np.ndarray:
    return np.asarray(pts, dtype=np.float64) @ X[:3, :3].T + X[:3, 3]


def _shape(spec, ctx: _Ctx, where: str, X_FO: np.ndarray):
    """Build one shape; ``X_FO`` places the owner's shape frame in the frame the result is expressed in."""
    L = ctx.L
    X = X_FO @ ctx.pose(getattr(spec, "xyz", (0, 0, 0)), getattr(spec, "rpy", (0, 0, 0)), where)
    try:
        t = spec.type
        if t == "box":
            size = np.asarray(spec.size) * L
            if np.any(size <= 0):
                raise ctx.error(f"{where}.size", f"each edge length must be > 0, got {spec.size}")
            return Box(X[:3, 3], 0.5 * size, X[:3, :3])
        if t == "sphere":
            return Sphere(X[:3, 3], spec.radius * L)
        if t == "capsule":
            has_pts = spec.p0 is not None or spec.p1 is not None
            if has_pts == (spec.length is not None) or (has_pts and (spec.p0 is None or spec.p1 is None)):
                raise ctx.error(where, "a capsule needs either both p0 and p1, or length (along its local z axis)")
            if has_pts:
                p0, p1 = np.asarray(spec.p0) * L, np.asarray(spec.p1) * L
            else:
                h = 0.5 * spec.length * L
                p0, p1 = np.array([0.0, 0.0, -h]), np.array([0.0, 0.0, h])
            return Capsule(_apply(X, p0), _apply(X, p1), spec.radius * L)
        if t == "prism":
            prism = Prism(X[:3, 3], X[:3, :3], spec.apothem * L, 0.5 * spec.length * L, spec.n_sides)
            prism.as_polyhedron()  # the hull the detector builds: a degenerate one is refused here, named
            return prism
        if t == "cylinder":
            return Cylinder(X[:3, 3], X[:3, :3], spec.radius * L, 0.5 * spec.length * L)
        if t == "polyhedron":
            return ConvexPolyhedron(_apply(X, np.asarray(spec.vertices) * L))
        if t == "polygon":
            return Polygon(_apply(X, np.asarray(spec.vertices) * L))
        if t == "mesh":
            return _mesh(spec, ctx, where, X)
    except SceneFileError:
        raise
    except ArmguardError as exc:
        raise ctx.error(where, str(exc)) from None
    raise ctx.error(f"{where}.type", f"shape type {spec.type!r} is not allowed here")  # link_capsule outside links


def _mesh(spec, ctx: _Ctx, where: str, X: np.ndarray):
    import trimesh

    path = ctx.path(spec.file)
    if not path.is_file():
        raise ctx.error(f"{where}.file", f"mesh file not found: {path}")
    ctx.read.append(path)
    try:
        mesh = trimesh.load(str(path), force="mesh")
    except Exception as exc:  # trimesh raises many kinds; report which file failed
        raise ctx.error(f"{where}.file", f"could not read mesh {path}: {exc}") from None
    pts = np.asarray(mesh.vertices, dtype=np.float64) * np.asarray(spec.scale) * ctx.L
    if pts.shape[0] < 4 or not np.all(np.isfinite(pts)):
        raise ctx.error(f"{where}.file", f"mesh {path} has fewer than 4 finite vertices")
    return ConvexPolyhedron(_apply(X, pts))


def _frames(sf: SceneFile, ctx: _Ctx) -> dict[str, np.ndarray]:
    """Frame name -> X_WF: ``world``, the listed frames (any order), and every body's own frame."""
    specs = {}
    for i, f in enumerate(sf.frames):
        if f.name in specs or f.name == "world":
            raise ctx.error(f"frames[{i}].name", f"duplicate frame name {f.name!r}")
        specs[f.name] = (i, f)
    out = {"world": np.eye(4)}

    def resolve(name: str, stack: tuple, where: str) -> np.ndarray:
        if name in out:
            return out[name]
        if name not in specs:
            raise ctx.error(where, f"unknown frame {name!r}; frames are {['world', *specs]}")
        i, f = specs[name]
        if name in stack:
            raise ctx.error(f"frames[{i}].parent", f"frames form a cycle: {' -> '.join(stack + (name,))}")
        X = resolve(f.parent, stack + (name,), f"frames[{i}].parent") @ ctx.pose(f.xyz, f.rpy, f"frames[{i}]")
        out[name] = X
        return X

    for name, (i, _) in specs.items():
        resolve(name, (), f"frames[{i}]")
    for i, b in enumerate(sf.bodies):
        if b.name in out:
            raise ctx.error(f"bodies[{i}].name", f"name {b.name!r} is already used by a frame or a body")
        out[b.name] = resolve(b.frame, (), f"bodies[{i}].frame") @ ctx.pose(b.xyz, b.rpy, f"bodies[{i}]")
    return out


def _robot(spec, i: int, ctx: _Ctx, frames: dict) -> tuple:
    from ..kinematics import Coupling, DHRow, Robot

    w = f"robots[{i}]"
    if spec.mount.frame not in frames:
        raise ctx.error(f"{w}.mount.frame", f"unknown frame {spec.mount.frame!r}; frames and bodies are {list(frames)}")
    X_WB = frames[spec.mount.frame] @ ctx.pose(spec.mount.xyz, spec.mount.rpy, f"{w}.mount")
    if (spec.joints is None) == (spec.urdf is None):
        raise ctx.error(w, "a robot needs exactly one of 'joints' (a DH table) or 'urdf' (a file)")
    source: dict
    # a URDF robot's home, and the pairs its SRDF (named, or found beside the file) disables, as load_model applies them
    urdf_home = urdf_pairs = None
    if spec.joints is not None:
        if not spec.joints:
            raise ctx.error(f"{w}.joints", "a DH table needs at least one joint")
        L, A = ctx.L, ctx.A
        rows, lower, upper, vmax, amax, names = [], [], [], [], [], []
        for k, j in enumerate(spec.joints):
            s = L if j.type == "prismatic" else A
            rows.append(DHRow(j.a * L, j.alpha * A, j.d * L, j.theta * A, j.type))
            if j.limits is not None and j.limits[0] > j.limits[1]:
                raise ctx.error(f"{w}.joints[{k}].limits", f"expected [lower, upper] with lower <= upper, got {j.limits}")
            if j.type == "prismatic" and j.limits is None:  # the URDF it becomes needs them (every check failed)
                raise ctx.error(f"{w}.joints[{k}]", "a prismatic joint needs limits [lower, upper]")
            lo, hi = (j.limits if j.limits is not None else (-math.inf, math.inf))
            lower.append(lo * s), upper.append(hi * s)
            vmax.append(j.max_velocity * s if j.max_velocity is not None else math.inf)
            amax.append(j.max_acceleration * s if j.max_acceleration is not None else math.inf)
            names.append(j.name or f"joint{k + 1}")
        if len(set(names)) != len(names):
            raise ctx.error(f"{w}.joints", f"joint names must be unique, got {names}")
        if spec.links is not None and len(spec.links) != len(rows) + 1:
            raise ctx.error(f"{w}.links", f"expected {len(rows) + 1} link names (base, then one per joint), got {len(spec.links)}")
        couplings = []
        dependent = {c.joint for c in spec.couplings if c.joint not in c.terms}
        for k, c in enumerate(spec.couplings):
            if c.joint not in names:
                raise ctx.error(f"{w}.couplings[{k}].joint", f"unknown joint {c.joint!r}; joints are {names}")
            for t in c.terms:
                if t not in names:
                    raise ctx.error(f"{w}.couplings[{k}].terms", f"unknown joint {t!r}; joints are {names}")
            _coupling_form(ctx, f"{w}.couplings[{k}]", c, names, dependent)
            s = ctx.L if spec.joints[names.index(c.joint)].type == "prismatic" else ctx.A
            couplings.append(Coupling(c.joint, dict(c.terms), c.offset * s))
        for k, j in enumerate(spec.joints):  # a dependent joint's own limits were read and dropped without a word
            given = [key for key in ("limits", "max_velocity", "max_acceleration") if getattr(j, key) is not None]
            if names[k] in dependent and given:
                raise ctx.error(f"{w}.joints[{k}].{given[0]}", f"joint {names[k]!r} follows a coupling: its "
                                f"{given[0]} come from the joints it follows (give them there)")
        X_LT = None if spec.tool is None else ctx.pose(spec.tool.xyz, spec.tool.rpy, f"{w}.tool")
        try:
            robot = Robot.from_dh(
                spec.name, rows, convention=spec.convention, joint_names=names, link_names=spec.links,
                lower=lower, upper=upper, max_velocity=vmax, max_acceleration=amax, couplings=couplings,
                X_WB=X_WB, X_LT=X_LT,
            )
        except ArmguardError as exc:
            raise ctx.error(f"{w}.joints", str(exc)) from None
        source = {"kind": "dh"}
    else:
        path = ctx.path(spec.urdf)
        if not path.is_file():
            raise ctx.not_found(f"{w}.urdf", "URDF file", spec.urdf)
        ctx.read.append(path)
        # the SRDF the file names is the robot's (its groups, and its home where the file gives no home:),
        # "none" none at all, else one found
        srdf = None if spec.srdf is None else False if _no_srdf(spec.srdf) else ctx.path(spec.srdf)
        if srdf:  # a file this one names is refused at its place here, before the URDF's loader reads it
            _srdf_pairs(srdf, ctx, w)
        try:
            robot, urdf_home, own_pairs, srdf_file, groups = robot_parts_from_urdf(path, name=spec.name, X_WB=X_WB, srdf=srdf)
        except ArmguardError as exc:
            ours = bool(srdf) and isinstance(exc, SceneFileError) and Path(exc.file) == Path(srdf)
            raise ctx.error(f"{w}.srdf" if ours else f"{w}.urdf", str(exc)) from None
        if spec.max_acceleration is not None:
            robot = _with_accelerations(robot, spec.max_acceleration, ctx, f"{w}.max_acceleration")
        source = {"kind": "urdf", "urdf": os.path.abspath(path)}  # absolute: a saved file reads it from anywhere
        if srdf is False:
            source["srdf"] = NO_SRDF  # saved with it: the file loads back without the SRDF found beside the URDF
        else:
            urdf_pairs = own_pairs
            source["srdf_groups"] = groups  # its Model's groups (model_from_scene): joints="arm" as in load_model
            if srdf is None and srdf_file is not None:  # found beside the URDF: its pairs hold here as in load_model
                ctx.read.append(Path(srdf_file))
    # link shapes, in each link's own frame
    if spec.link_shapes:
        shapes = {}
        for ln, lst in spec.link_shapes.items():
            lw = f"{w}.link_shapes.{ln}"
            if ln not in robot.link_names:
                raise ctx.error(lw, f"unknown link {ln!r}; links are {list(robot.link_names)}")
            shapes[ln] = tuple(_link_shape(s, ctx, f"{lw}[{k}]", robot, ln) for k, s in enumerate(lst))
        robot = robot.with_link_shapes(shapes)
    scale = _q_scale(robot, ctx)
    home = urdf_home  # a DH robot's: None (zero, clipped); a URDF robot's: as load_model takes it (its SRDF's)
    if spec.home is not None:
        if len(spec.home) != robot.n_joints:
            raise ctx.error(f"{w}.home", f"expected {robot.n_joints} joint values {list(robot.joint_names)}, got {len(spec.home)}")
        home = np.asarray(spec.home) * scale
        _in_limits(robot, home, ctx, f"{w}.home")
    srdf_pairs = urdf_pairs or []
    if spec.srdf is not None and not _no_srdf(spec.srdf):
        path = ctx.path(spec.srdf)
        ctx.read.append(path)
        if urdf_pairs is None:  # a DH robot's: its pairs name its links
            srdf_pairs = _srdf_pairs(path, ctx, w)
        for a, b in srdf_pairs:
            for ln in (a, b):
                if ln not in robot.link_names:
                    raise ctx.error(f"{w}.srdf", f"{path.name}: disable_collisions names unknown link {ln!r}")
        source["srdf"] = os.path.abspath(path)
    if spec.link_shapes and srdf_pairs and urdf_pairs is not None:  # a URDF robot's SRDF: its verdicts were made
        # for the URDF's shapes, not these (a DH robot's link_shapes are its shapes)
        srdf_pairs = reshaped_pairs(robot, srdf_pairs, set(spec.link_shapes), f"{ctx.file}: {w}.link_shapes")
    return robot, home, srdf_pairs, source



def _link_shape(spec, ctx: _Ctx, where: str, robot, link: str):
    if spec.type != "link_capsule":
        return _shape(spec, ctx, where, np.eye(4))
    parent = robot.parent_link(link)
    if parent is None:
        raise ctx.error(where, f"link_capsule: link {link!r} is the root and has no parent link")
    # the parent's origin seen from this link, at two configurations: must not move (revolute DH)
    pts = []
    rng = np.random.default_rng(0)
    for q in (np.zeros(robot.n_joints), rng.uniform(-1.0, 1.0, robot.n_joints)):
        X = robot.forward_kinematics(q)
        X_WL, X_WP = X[robot.link_index(link)], X[robot.link_index(parent)]
        pts.append(X_WL[:3, :3].T @ (X_WP[:3, 3] - X_WL[:3, 3]))
    if np.linalg.norm(pts[0] - pts[1]) > 1e-9 * max(1.0, float(np.linalg.norm(pts[0]))):
        raise ctx.error(where, f"link_capsule: the origin of {parent!r} moves in the frame of {link!r}; give p0 and p1")
    try:
        return Capsule(pts[0], np.zeros(3), spec.radius * ctx.L)
    except ArmguardError as exc:
        raise ctx.error(where, str(exc)) from None


def _with_accelerations(robot, values, ctx: _Ctx, where: str):
    """``robot`` with its independent joints' acceleration limits set (file units)."""
    import dataclasses

    from ..kinematics import JointType, Robot

    if len(values) != robot.n_joints:
        raise ctx.error(where, f"expected {robot.n_joints} values {list(robot.joint_names)}, got {len(values)}")
    if any(not v > 0 for v in values):
        raise ctx.error(where, "every acceleration limit must be > 0")
    scale = {j: (ctx.L if t is JointType.PRISMATIC else ctx.A) * v
             for j, t, v in zip(robot.joint_names, robot.joint_types, values)}
    specs = [dataclasses.replace(sp, max_acceleration=scale[sp.name]) if sp.name in scale else sp for sp in robot.joints]
    return Robot(robot.name, robot.root_link, specs, joint_names=robot.joint_names, link_shapes=dict(robot.link_shapes),
                 X_WB=robot.X_WB, tool_link=robot.tool_link)


def _srdf_pairs(path, ctx, w: str) -> list:
    """The ``disable_collisions`` pairs of the SRDF ``path`` robot ``w`` names, its faults at ``{w}.srdf``."""
    try:
        return read_srdf_disabled(path)
    except SceneFileError as exc:
        raise ctx.error(f"{w}.srdf", exc.message) from None


def _no_srdf(named: str) -> bool:
    """Whether an SRDF path the file gives is :data:`._srdf.NO_SRDF` (no SRDF at all)."""
    return named.strip().lower() == NO_SRDF


def validate_scene_dict(data, file: str = "<dict>") -> SceneFile:
    """``data`` (a parsed scene file) checked against the format; errors name ``file`` and the place."""
    if not isinstance(data, dict):
        got = "an empty file" if data is None else type(data).__name__
        raise SceneFileError(file, "", f"expected a mapping at the top level (armguard_scene: 1, ...), got {got}")
    other = ("a trajectory", "`armguard verify SCENE FILE` checks it") if data.get("format") == "armguard.trajectory" else (
        ("a task program", "`armguard program run FILE` runs it") if "armguard_program" in data else None)
    if other is not None:  # its every key listed as a scene schema error said nothing of what it is
        raise SceneFileError(file, "format" if "format" in data else "armguard_program",
                             f"this file is {other[0]}, not a scene or model file (armguard_scene: 1): {other[1]}")
    try:
        sf = SceneFile.model_validate(data)
    except ValidationError as exc:
        raise SceneFileError(file, *list_problems(schema_problems(exc.errors()))) from None
    return sf


def schema_problems(errors) -> list[tuple[str, str]]:
    """Every schema error as ``(place, message)``, in the file's order; a missing key with an unknown
    key beside it that looks like its misspelling (``sise:`` for ``size:``) says so."""
    import difflib

    unknown: dict = {}
    for err in errors:
        loc = tuple(err["loc"])
        if err.get("type") == "extra_forbidden" and loc:
            unknown.setdefault(loc[:-1], []).append(str(loc[-1]))
    out = []
    seen = set()
    for err in errors:
        loc = tuple(err["loc"])
        msg = _message(err)
        if err.get("type") == "missing" and loc:
            near = difflib.get_close_matches(str(loc[-1]), unknown.get(loc[:-1], []), n=1, cutoff=0.6)
            if near:
                msg += f" (the unknown key {near[0]!r} beside it looks like a misspelling of {str(loc[-1])!r})"
        key = (where_of(loc), msg)
        if key not in seen:
            seen.add(key)
            out.append(key)
    return out


def scene_from_dict_validated(sf: SceneFile, file: str, base: Path | None = None) -> Scene:
    """The Scene of a validated scene file without ``model:`` (DH or URDF robots, shape bodies)."""
    ctx = _Ctx(file, base or Path.cwd(), _MM if sf.units.length == "mm" else 1.0, _DEG if sf.units.angle == "deg" else 1.0)
    if sf.joints:  # a sidecar's per-joint settings: here they would set nothing
        raise ctx.error(f"joints.{next(iter(sf.joints))}", "per-joint settings belong to a model sidecar (with model:); "
                        "a robot of this file takes its accelerations as robots[i].max_acceleration: [one per joint]")
    frames = _frames(sf, ctx)
    scene = Scene(sf.name, description=sf.description)
    try:
        _populate(scene, sf, ctx, frames)
    except SceneFileError:
        raise
    except SceneError as exc:  # a semantic error the scene found: report it against the file
        raise ctx.error("", str(exc)) from None
    scene._source_files = tuple(ctx.read)  # model_from_scene: the Model's files
    return scene


def _combined(problems: list) -> SceneFileError:
    """One error listing ``problems`` (SceneFileErrors of one file): the first, then "N more problems"."""
    return SceneFileError(problems[0].file, *list_problems([(e.where, e.message) for e in problems]))


def _body(scene: Scene, b, i: int, ctx: _Ctx, X) -> None:
    shapes = [_shape(s, ctx, f"bodies[{i}].shapes[{k}]", X) for k, s in enumerate(b.shapes)]
    try:
        scene.add_body(b.name, shapes, category=b.category)
    except SceneError as exc:
        raise ctx.error(f"bodies[{i}]", str(exc)) from None


def _add_robot(scene: Scene, r, i: int, ctx: _Ctx, frames: dict) -> list:
    robot, home, pairs, source = _robot(r, i, ctx, frames)
    self_pairs = None if r.self_pairs is None else [tuple(p) for p in r.self_pairs]
    if self_pairs is not None:  # pairs the file lists to be checked: no SRDF disables them
        pairs = [p for p in pairs if {tuple(p), tuple(p)[::-1]}.isdisjoint(self_pairs)]
    if source["kind"] == "urdf":  # its SRDF's pairs, for save_scene to list those the scene checks again
        source["srdf_pairs"] = tuple((f"{r.name}/{a}", f"{r.name}/{b}") for a, b in pairs)
    try:
        scene.add_robot(robot, home=home, self_pairs=self_pairs, _source={**source, "spec": r})
    except ArmguardError as exc:
        raise ctx.error(f"robots[{i}]", str(exc)) from None
    return [(f"{r.name}/{a}", f"{r.name}/{b}") for a, b in pairs]


def _set_ik(scene: Scene, sf: SceneFile, ctx: _Ctx) -> None:
    """``ik: {robot: routine}``: each robot's IK routine, resolved now (a located error when unknown)."""
    for rname, routine in sf.ik.items():
        if rname not in scene.robots:
            raise ctx.error(f"ik.{rname}", f"unknown robot; robots are {list(scene.robots)}")
        try:
            scene.set_robot_ik(rname, routine)
        except (KinematicsError, SceneError) as exc:
            raise ctx.error(f"ik.{rname}", str(exc)) from None


def _populate(scene: Scene, sf: SceneFile, ctx: _Ctx, frames: dict) -> None:
    problems: list[SceneFileError] = []  # bodies and robots are independent: report them all
    for i, b in enumerate(sf.bodies):
        try:
            _body(scene, b, i, ctx, frames[b.name])
        except SceneFileError as exc:
            problems.append(exc)
    srdf = []
    for i, r in enumerate(sf.robots):
        try:
            srdf.extend(_add_robot(scene, r, i, ctx, frames))
        except SceneFileError as exc:
            problems.append(exc)
    if problems:  # what follows refers to the bodies and robots: stop here
        raise _combined(problems)
    _set_ik(scene, sf, ctx)
    for i, p in enumerate(sf.payloads):
        w = f"payloads[{i}]"
        if p.robot not in scene.robots:
            raise ctx.error(f"{w}.robot", f"unknown robot {p.robot!r}; robots are {list(scene.robots)}")
        if p.link not in scene.robots[p.robot].link_names:
            raise ctx.error(f"{w}.link", f"robot {p.robot!r} has no link {p.link!r}")
        shapes = [_shape(s, ctx, f"{w}.shapes[{k}]", np.eye(4)) for k, s in enumerate(p.shapes)]
        try:
            scene.attach_payload(p.name, p.robot, p.link, shapes, ctx.pose(p.xyz, p.rpy, w))
        except SceneError as exc:
            raise ctx.error(w, str(exc)) from None
    if sf.workspace is not None:
        try:
            scene.set_workspace(np.asarray(sf.workspace.lo) * ctx.L, np.asarray(sf.workspace.hi) * ctx.L)
        except SceneError as exc:
            raise ctx.error("workspace", str(exc)) from None
    scene.exclude_adjacent = sf.pairs.exclude_adjacent
    for k, (a, b) in enumerate([*sf.pairs.disable, *srdf]):
        try:
            scene.disable_pair(a, b)
        except SceneError as exc:
            raise ctx.error(f"pairs.disable[{k}]", str(exc)) from None
    for k, (a, b) in enumerate(sf.pairs.enable):  # checked after all, an SRDF's or the list above's notwithstanding
        try:
            scene._check_owner_or_robot(a), scene._check_owner_or_robot(b)
        except SceneError as exc:
            raise ctx.error(f"pairs.enable[{k}]", str(exc)) from None
        scene.enable_pair(a, b)
        wide = [p for p in scene.disabled_pairs if p <= {a, b, a.split("/")[0], b.split("/")[0]} and p != {a, b}]
        if wide:  # disabled robot-wide ([A, post]): enabling one link's pair cannot take effect
            raise ctx.error(f"pairs.enable[{k}]", f"[{a}, {b}] stays disabled by {sorted(wide[0])} (a robot's name stands for "
                                                  "all its links): disable the other links' pairs one by one instead")
    # trajectories and canned tests are independent: report them all
    for i, t in enumerate(sf.trajectories):
        try:
            _trajectory(scene, t, ctx, f"trajectories[{i}]")
        except SceneFileError as exc:
            problems.append(exc)
    for i, c in enumerate(sf.canned_tests):
        try:
            _canned_test(scene, c, ctx, f"canned_tests[{i}]")
        except SceneFileError as exc:
            problems.append(exc)
    if problems:
        raise _combined(problems)
