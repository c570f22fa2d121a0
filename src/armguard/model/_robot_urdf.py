"""Robots from URDF files, through Pinocchio (the model of record).

``Robot.from_urdf(path)`` (``robot_from_urdf``) is the one arm of :func:`armguard.load_model` of
that file: Pinocchio
parses the URDF (mimic joints included) and builds its collision geometry; armguard's Robot
keeps its own batched FK compiled from Pinocchio's joint placements.  See
:mod:`armguard.model` for the checks (a file that does not parse, a missing mesh, a dropped
collision element: an error naming the file and element) and for the shapes (capsules, boxes,
spheres, exact cylinders, and meshes as their convex hulls).

It lives here, not in :mod:`armguard.kinematics` (one layer down, where ``Robot`` is): this
package registers it there on import (:func:`armguard.kinematics._robot.register_urdf_reader`),
so ``Robot.from_urdf`` works without kinematics importing upwards.
"""

from __future__ import annotations

from pathlib import Path

from .._errors import SceneFileError

__all__ = ["robot_from_urdf", "robot_home_from_urdf", "robot_parts_from_urdf"]


def robot_from_urdf(path, *, name=None, X_WB=None, load_collision=True, mesh_dir=None, srdf=None):
    """The Robot of the URDF file ``path`` (its one arm); ``X_WB`` (4, 4) mounts its root link in W.

    ``name`` defaults to the URDF's robot name; ``mesh_dir`` is searched for mesh files too; ``srdf``
    as :func:`armguard.load_model`'s (None: found beside the URDF; a path; False: none).
    """
    return robot_home_from_urdf(path, name=name, X_WB=X_WB, load_collision=load_collision, mesh_dir=mesh_dir,
                                srdf=srdf)[0]


def robot_home_from_urdf(path, *, name=None, X_WB=None, load_collision=True, mesh_dir=None, srdf=None):
    """``(robot, home)``: :func:`robot_from_urdf`'s Robot and its home as :func:`armguard.load_model` takes it
    (the SRDF's home state, else zero clipped to the limits), ``(n_joints,)`` rad / m."""
    return robot_parts_from_urdf(path, name=name, X_WB=X_WB, load_collision=load_collision, mesh_dir=mesh_dir,
                                 srdf=srdf)[:2]


def robot_parts_from_urdf(path, *, name=None, X_WB=None, load_collision=True, mesh_dir=None, srdf=None):
    """``(robot, home, disabled, srdf_file, groups)``: :func:`robot_home_from_urdf`'s two, the pairs of the
    robot's links its SRDF disables as :func:`armguard.load_model` applies them (``(link1, link2)`` names: a
    pair of links one owner merges, or of links the URDF lacks in an SRDF of a larger robot, is not among
    them), that SRDF's path (None: none) and its groups and states in scene names (``._srdf.scene_srdf``;
    None without groups)."""
    from ._load import model_from_urdf
    from ._srdf import scene_srdf

    file = str(path)
    if not Path(file).is_file():
        raise SceneFileError(file, "", "file not found")
    model = model_from_urdf(file, srdf=srdf, package_dirs=[mesh_dir] if mesh_dir is not None else ())
    robots = list(model.scene.robots.values())
    if len(robots) != 1:
        raise SceneFileError(file, "robot", f"expected one arm, found {[r.name for r in robots]}; "
                             "use armguard.load_model for a system of several arms")
    robot = robots[0]
    home = model.scene.home(robot.name)
    own = f"{robot.name}/"
    disabled = sorted(tuple(sorted(n[len(own):] for n in p)) for p in model.scene.disabled_pairs
                      if all(n.startswith(own) for n in p))
    if not load_collision:
        robot = robot.with_link_shapes({ln: () for ln in robot.link_names})
    if X_WB is not None:
        robot = robot.with_base(X_WB)
    if name is not None:
        robot = robot.with_name(name)
    return robot, home, disabled, None if model.srdf is None else model.srdf.file, scene_srdf(model, robot.name)
