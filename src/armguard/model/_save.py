"""Saving scenes as YAML scene files (format version 1, SI units: m and rad).

The saved file loads back to an equivalent scene: same robots (DH tables or URDF paths),
bodies (shapes written in W), payloads, workspace box, pair filters, trajectories and canned
tests.  Frames are flattened into the world frame.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import yaml

from .._errors import SceneError
from ..geometry import Box, Capsule, ConvexPolyhedron, Cylinder, Polygon, Prism, Sphere
from ..kinematics import JointType
from ._scene import Scene
from ._schema import SCHEMA_VERSION
from ._srdf import NO_SRDF

__all__ = ["save_scene", "scene_to_dict"]


def _l(a) -> list[float]:
    return [float(x) for x in np.asarray(a, dtype=np.float64).ravel()]


def _pose(X) -> dict:
    from ..kinematics import xyz_rpy_from_pose

    xyz, rpy = xyz_rpy_from_pose(X)
    return {"xyz": _l(xyz), "rpy": _l(rpy)}


def _R_pose(center, R) -> dict:
    X = np.eye(4)
    X[:3, :3] = R
    X[:3, 3] = center
    return _pose(X)


def shape_to_dict(s) -> dict:
    """One shape as a scene-file mapping (in the frame its coordinates are in)."""
    if isinstance(s, Sphere):
        return {"type": "sphere", "radius": float(s.radius), "xyz": _l(s.center)}
    if isinstance(s, Capsule):
        return {"type": "capsule", "radius": float(s.radius), "p0": _l(s.p0), "p1": _l(s.p1)}
    if isinstance(s, Box):
        return {"type": "box", "size": _l(2.0 * s.half_extents), **_R_pose(s.center, s.rotation)}
    if isinstance(s, Prism):
        return {
            "type": "prism", "n_sides": int(s.n_sides), "apothem": float(s.apothem),
            "length": 2.0 * float(s.half_length), **_R_pose(s.center, s.rotation),
        }
    if isinstance(s, Cylinder):
        return {"type": "cylinder", "radius": float(s.radius), "length": 2.0 * float(s.half_length),
                **_R_pose(s.center, s.rotation)}
    if isinstance(s, ConvexPolyhedron):
        return {"type": "polyhedron", "vertices": [_l(v) for v in s.vertices]}
    if isinstance(s, Polygon):
        return {"type": "polygon", "vertices": [_l(v) for v in s.vertices]}
    raise SceneError(f"cannot save a shape of type {type(s).__name__}")


def _limits(lo: float, hi: float, what: str):
    if math.isinf(lo) and math.isinf(hi):
        return None
    if math.isinf(lo) or math.isinf(hi):
        raise SceneError(f"{what}: a one-sided joint limit [{lo}, {hi}] cannot be written to a scene file")
    return [float(lo), float(hi)]


def _robot_to_dict(scene: Scene, name: str) -> dict:
    robot = scene.robots[name]
    source = scene._robot_sources.get(name, {})
    out: dict = {"name": name, "mount": _pose(robot.X_WB)}
    if robot.dh is not None and source.get("kind", "dh") == "dh":
        convention, rows = robot.dh
        out["convention"] = convention
        joints = []
        specs = robot.joints
        for k, row in enumerate(rows):
            js = specs[k]
            j = {"name": js.name, "type": row.joint_type, "a": row.a, "alpha": row.alpha, "d": row.d, "theta": row.theta}
            lim = _limits(js.lower, js.upper, f"robot {name!r} joint {js.name!r}")
            if lim is None and js.joint_type is JointType.PRISMATIC:  # the file would not load back
                raise SceneError(f"robot {name!r} joint {js.name!r}: a prismatic joint without limits cannot be written "
                                 "to a scene file (a scene file's prismatic joint needs finite limits)")
            if lim is not None:
                j["limits"] = lim
            if math.isfinite(js.max_velocity):
                j["max_velocity"] = float(js.max_velocity)
            if math.isfinite(js.max_acceleration):
                j["max_acceleration"] = float(js.max_acceleration)
            joints.append(j)
        out["joints"] = joints
        n = len(rows)
        out["links"] = list(robot.link_names[: n + 1])
        if len(specs) > n:  # the fixed tool transform appended by from_dh
            out["tool"] = _pose(specs[n].X_pre)
        if robot.couplings:
            out["couplings"] = [
                {"joint": c.joint, "terms": {k: float(v) for k, v in c.terms.items()}, "offset": float(c.offset)}
                for c in robot.couplings
            ]
        shapes = {ln: [shape_to_dict(s) for s in sh] for ln, sh in robot.link_shapes.items() if sh}
        if shapes:
            out["link_shapes"] = shapes
    elif source.get("kind") == "urdf":
        shared = [n for n, src in scene._robot_sources.items() if src.get("kind") == "urdf" and src.get("urdf") == source["urdf"]]
        if source.get("arms", 1) > 1:  # the file would not load back: a scene file's robot takes a URDF of one arm
            raise SceneError(f"cannot save robot {name!r}: its URDF {source['urdf']} holds the arms {shared}, and a scene "
                             "file's robot takes a URDF of one arm; load that URDF with armguard.load_model (its sidecar "
                             "YAML is the scene file of such a model)")
        out["urdf"] = source["urdf"]
        if "srdf" in source:  # the SRDF the file named (or none): the robot's own, its groups as well as its pairs
            out["srdf"] = source["srdf"]
        if np.all(np.isfinite(robot.max_acceleration)):
            out["max_acceleration"] = _l(robot.max_acceleration)
    else:
        raise SceneError(f"cannot save robot {name!r}: it has neither a DH table nor a URDF file")
    out["home"] = _l(scene.home(name))
    if name in scene.self_pairs:
        out["self_pairs"] = [list(p) for p in sorted(scene.self_pairs[name])]
    return out


def scene_to_dict(scene: Scene) -> dict:
    """The scene as a scene-file mapping (SI units), ready for ``yaml.safe_dump``."""
    d: dict = {"armguard_scene": SCHEMA_VERSION, "name": scene.name}
    if scene.description:
        d["description"] = scene.description
    d["units"] = {"angle": "rad", "length": "m"}
    d["bodies"] = [
        {"name": b.name, "category": b.category, "shapes": [shape_to_dict(s) for s in b.shapes]}
        for b in scene.bodies.values()
    ]
    d["robots"] = [_robot_to_dict(scene, r) for r in scene.robots]
    ik = {name: r.ik for name, r in scene.robots.items() if getattr(r, "ik", None) is not None}
    if ik:
        d["ik"] = ik
    d["payloads"] = [
        {"name": p.name, "robot": p.robot, "link": p.link, **_pose(p.X_LP), "shapes": [shape_to_dict(s) for s in p.shapes]}
        for p in scene.payloads.values()
    ]
    if scene.workspace is not None:
        d["workspace"] = {"lo": _l(scene.workspace.lo), "hi": _l(scene.workspace.hi)}
    d["pairs"] = {
        "exclude_adjacent": scene.exclude_adjacent,
        "disable": sorted(sorted(p) for p in scene.disabled_pairs),
    }
    # an SRDF's pairs the scene checks again (Scene.enable_pair): its SRDF, read again, would disable them
    owners = {*scene.robots, *scene.bodies, *scene.payloads,
              *(f"{r}/{ln}" for r, robot in scene.robots.items() for ln in robot.link_names)}
    enable = {frozenset(p) for src in scene._robot_sources.values() if src.get("srdf") != NO_SRDF
              for p in src.get("srdf_pairs", ()) if set(p) <= owners} - set(scene.disabled_pairs)  # a removed body's: gone
    if enable:
        d["pairs"]["enable"] = sorted(sorted(p) for p in enable)
    trajs = []
    for name, traj in scene.trajectories.items():
        spec = scene._trajectory_specs.get(name)
        if spec is not None:
            t = {"name": name, "robot": spec["robot"], "waypoints": [_l(q) for q in spec["waypoints"]],
                 "profile": spec["profile"]}
            if spec["times"] is not None:
                t["times"] = _l(spec["times"])
            if spec["description"]:
                t["description"] = spec["description"]
        else:
            t = {"name": name, "robot": traj.robot_name, "waypoints": [_l(q) for q in traj.waypoints],
                 "times": _l(traj.times), "profile": "linear"}
        trajs.append(t)
    d["trajectories"] = trajs
    d["canned_tests"] = [
        {
            "name": c.name, "description": c.description, "robot": c.robot, "threshold": float(c.threshold),
            "setup": {r: _l(q) for r, q in c.setup.items()}, "motion": _motion(c),
        }
        for c in scene.canned_tests.values()
    ]
    return d


def _motion(c) -> dict:
    """A canned test's motion as written (m, rad)."""
    if c.mode == "end_effector":
        return {"end_effector": _l(c.end_effector)}
    if c.mode == "arm_angle":
        return {"arm_angle": float(c.arm_angle)}
    return {"goal": _l(c.goal)}


def _portable(d: dict, folder: Path) -> dict:
    """``d`` with each robot's URDF and SRDF path inside ``folder`` (the saved file's) written relative to it,
    as a scene file reads it: a project folder moved whole loads again; a file elsewhere (a package's)
    stays absolute."""
    base = os.path.abspath(folder)
    for r in d.get("robots", ()):
        for key in ("urdf", "srdf"):
            v = r.get(key)
            if isinstance(v, str) and os.path.isabs(v):
                try:
                    rel = os.path.relpath(v, base)
                except ValueError:  # another drive (Windows): no relative path
                    continue
                if rel != os.pardir and not rel.startswith(os.pardir + os.sep):  # (a folder "..x" inside is inside)
                    r[key] = Path(rel).as_posix()
    return d


def save_scene(scene: Scene, path) -> Path:
    """Write ``scene`` as a YAML scene file at ``path``; returns the path.  Loads back with ``load_scene``.
    URDF and SRDF files inside the file's folder are named relative to it, others by absolute path."""
    path = Path(path)
    text = yaml.safe_dump(_portable(scene_to_dict(scene), path.parent), sort_keys=False, default_flow_style=None, width=120)
    from .._io import atomic_write

    return atomic_write(path, f"# armguard scene file, written by save_scene (SI units)\n{text}", parents=True)  # whole or not at all
