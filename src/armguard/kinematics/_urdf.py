"""Robots from URDF files: yourdfpy parses, armguard flattens the tree for its own batched FK.

Joints: fixed, revolute, continuous (revolute with infinite limits), prismatic, and mimic
(a Coupling ``multiplier * q_master + offset``).  Floating and planar joints are rejected.
Collision geometry becomes armguard shapes in the link frame L: box -> Box, sphere -> Sphere,
cylinder -> Prism(n_sides=16) circumscribing it (conservative: apothem = radius), capsule ->
Capsule (where the parser provides one), mesh -> ConvexPolyhedron of its trimesh convex hull (scaled).
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from .._errors import ArmguardError, SceneFileError
from ..geometry import Box, Capsule, ConvexPolyhedron, Prism, Sphere
from ._robot import Coupling, JointSpec, JointType

__all__ = ["robot_from_urdf", "CYLINDER_PRISM_SIDES"]

CYLINDER_PRISM_SIDES = 16
"""Sides of the prism that circumscribes a URDF cylinder (the contract's choice)."""

_TYPES = {"fixed": JointType.FIXED, "revolute": JointType.REVOLUTE, "continuous": JointType.REVOLUTE,
          "prismatic": JointType.PRISMATIC}


def _resolve_mesh(filename: str, urdf_dir: Path, mesh_dir) -> Path | None:
    """Find a mesh file named by a URDF (relative, ``file://`` or ``package://pkg/...``)."""
    name = filename
    for scheme in ("file://", "package://"):
        if name.startswith(scheme):
            name = name[len(scheme):]
    parts = Path(name).parts
    bases = [Path(mesh_dir)] if mesh_dir is not None else []
    bases += [urdf_dir, *urdf_dir.parents]
    if Path(name).is_absolute() and Path(name).exists():
        return Path(name)
    for base in bases:  # try the full relative path, then with leading parts (the package name) dropped
        for k in range(len(parts)):
            cand = base.joinpath(*parts[k:])
            if cand.is_file():
                return cand
    return None


def _hull_polyhedron(path: Path, scale, X_LC: np.ndarray) -> ConvexPolyhedron:
    import trimesh

    mesh = trimesh.load(str(path), force="mesh")
    v = np.asarray(mesh.vertices, dtype=np.float64)
    if scale is not None:
        v = v * np.asarray(scale, dtype=np.float64)
    hull = trimesh.convex.convex_hull(v)
    p = np.asarray(hull.vertices) @ X_LC[:3, :3].T + X_LC[:3, 3]
    return ConvexPolyhedron(p)


def _primitive(g, c: np.ndarray, R: np.ndarray):
    """The shape of a URDF box / sphere / cylinder / capsule element (centre ``c``, rotation ``R`` in L), else None."""
    if g.box is not None:
        return Box(c, 0.5 * np.asarray(g.box.size, dtype=np.float64), R)
    if g.sphere is not None:
        return Sphere(c, g.sphere.radius)
    if g.cylinder is not None:
        return Prism(c, R, g.cylinder.radius, 0.5 * g.cylinder.length, CYLINDER_PRISM_SIDES)
    if getattr(g, "capsule", None) is not None:
        half = 0.5 * g.capsule.length * R[:, 2]
        return Capsule(c - half, c + half, g.capsule.radius)
    return None


def _collision_shapes(urdf, file: str, urdf_dir: Path, mesh_dir) -> dict[str, tuple]:
    shapes: dict[str, list] = {}
    for link in urdf.robot.links:
        out = []
        for k, col in enumerate(link.collisions):
            where = f"link[{link.name}].collision[{k}]"
            X = np.eye(4) if col.origin is None else np.asarray(col.origin, dtype=np.float64)
            g = col.geometry
            c, R = X[:3, 3], X[:3, :3]
            try:
                primitive = _primitive(g, c, R)
            except ArmguardError as exc:  # a bad size, radius or origin: say which link and element
                raise SceneFileError(file, where, str(exc)) from None
            if primitive is not None:
                out.append(primitive)
            elif g.mesh is not None:
                path = _resolve_mesh(g.mesh.filename, urdf_dir, mesh_dir)
                if path is None:
                    raise SceneFileError(file, where, f"mesh file {g.mesh.filename!r} not found (pass mesh_dir=...)")
                try:
                    out.append(_hull_polyhedron(path, g.mesh.scale, X))
                except Exception as exc:  # trimesh raises many types; report them located
                    raise SceneFileError(file, where, f"cannot build the convex hull of {str(path)!r}: {exc}") from exc
            else:
                raise SceneFileError(file, where, "collision geometry is empty; expected box, sphere, cylinder or mesh")
        shapes[link.name] = out
    return {k: tuple(v) for k, v in shapes.items()}


def robot_from_urdf(cls, path, *, name=None, X_WB=None, load_collision=True, mesh_dir=None):
    """Load a Robot from the URDF file ``path`` (see the module docstring).

    ``name`` defaults to the URDF's robot name; ``X_WB`` (4, 4) mounts the root link in W;
    ``mesh_dir`` is searched first for mesh files.  Raises SceneFileError naming the file and
    the element on unreadable files, unsupported joints or missing meshes.
    """
    import yourdfpy

    file = os.fspath(path)
    if not Path(file).is_file():
        raise SceneFileError(file, "", "file not found")
    try:
        urdf = yourdfpy.URDF.load(file, build_scene_graph=False, load_meshes=False, load_collision_meshes=False)
    except Exception as exc:  # lxml / yourdfpy raise various types
        raise SceneFileError(file, "", f"not a readable URDF: {exc}") from exc
    robot = urdf.robot
    children = {j.child for j in robot.joints}
    roots = [ln.name for ln in robot.links if ln.name not in children]
    if len(roots) != 1:
        raise SceneFileError(file, "robot", f"expected exactly one root link, found {roots}")
    specs = []
    for j in robot.joints:
        where = f"joint[{j.name}]"
        jt = _TYPES.get(j.type)
        if jt is None:
            raise SceneFileError(file, where, f"unsupported joint type {j.type!r}; expected one of {sorted(_TYPES)}")
        lower, upper, vmax = -math.inf, math.inf, math.inf
        if j.limit is not None:
            if j.type != "continuous":
                lower = -math.inf if j.limit.lower is None else float(j.limit.lower)
                upper = math.inf if j.limit.upper is None else float(j.limit.upper)
            if j.limit.velocity is not None and float(j.limit.velocity) > 0:
                vmax = float(j.limit.velocity)
        coupling = None
        if j.mimic is not None and jt is not JointType.FIXED:
            mult = 1.0 if j.mimic.multiplier is None else float(j.mimic.multiplier)
            off = 0.0 if j.mimic.offset is None else float(j.mimic.offset)
            coupling = Coupling(j.name, {j.mimic.joint: mult}, off)
        axis = np.array([1.0, 0.0, 0.0]) if j.axis is None else np.asarray(j.axis, dtype=np.float64)
        X_pre = np.eye(4) if j.origin is None else np.asarray(j.origin, dtype=np.float64)
        try:
            specs.append(JointSpec(name=j.name, joint_type=jt, parent=j.parent, child=j.child, X_pre=X_pre,
                                   axis=axis, lower=lower, upper=upper, max_velocity=vmax, coupling=coupling))
        except Exception as exc:
            raise SceneFileError(file, where, str(exc)) from exc
    link_shapes = _collision_shapes(urdf, file, Path(file).resolve().parent, mesh_dir) if load_collision else None
    try:
        return cls(name or robot.name, roots[0], specs, link_shapes=link_shapes, X_WB=X_WB)
    except SceneFileError:
        raise
    except Exception as exc:
        raise SceneFileError(file, "robot", str(exc)) from exc
