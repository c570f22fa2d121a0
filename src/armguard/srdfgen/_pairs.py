"""The link pairs of a collision matrix, their joints and lever arms.

:func:`pair_setup` takes a :class:`armguard.Model` and lists every pair of links of one robot
that both carry geometry, with

* ``adjacent``: joined by one joint, or through links without geometry (the Scene's own rule,
  :meth:`armguard.scene.Scene.allowed_pairs`; MoveIt's *Adjacent*);
* ``joints``: the flat scene joints that change the pair's relative pose -- every joint but those
  that move only the links' common ancestor (and with it both links rigidly);
* ``weight`` ``(len(joints),) m/rad``: ``lever_A[j] + lever_B[j]``, the certified verifier's
  lever-arm rows (:class:`armguard.verify._oracle.ClearanceModel`, from
  :func:`armguard.verify._motion.chain_bounds`): over a box of half-widths ``h`` about ``c``
  the pair's signed distance is at least ``d(c) - h . weight``.

A joint that moves the common ancestor moves both links by the same rigid motion unless it
also drives an edge between the ancestor and a link (a coupled joint): the angular-rate and
prismatic rows of :class:`~armguard.verify._motion.ChainBounds` then differ between the link and
the ancestor, and the joint is kept.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from .._errors import VerificationError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances

__all__ = ["LinkPair", "PairSetup", "pair_setup", "matrix_scene"]


@dataclass(frozen=True)
class LinkPair:
    """One link pair: URDF link names (as an SRDF names them), scene owners, adjacency, its joints (flat scene indices) and lever weights."""

    robot: str
    link1: str
    link2: str
    owner1: str
    owner2: str
    adjacent: bool
    joints: tuple
    weight: np.ndarray


@dataclass(frozen=True)
class PairSetup:
    """The pairs of a model, the scene they were taken from, its home (flat scene q) and joint limits."""

    scene: object
    pairs: tuple
    home: np.ndarray
    lower: np.ndarray
    upper: np.ndarray


def matrix_scene(scene, *, adjacent: bool = False):
    """A copy of ``scene`` that checks every own-link pair of every robot (the adjacent ones too when
    ``adjacent``) and nothing else (no bodies, payloads, workspace walls, listed self pairs or disabled pairs)."""
    sub = scene.copy()
    for key in list(sub.disabled_pairs):
        a, b = tuple(key)
        sub.enable_pair(a, b)
    for r in sub.robots:
        sub.set_self_pairs(r, None)
    sub.exclude_adjacent = not adjacent
    if sub.workspace is not None:
        sub.clear_workspace()
    for cp in sub.allowed_pairs():
        ra, rb = cp.a.split("/", 1)[0], cp.b.split("/", 1)[0]
        if getattr(cp.category, "value", cp.category) != "arm-arm" or ra != rb:
            sub.disable_pair(cp.a, cp.b)
    return sub


def _limits(scene) -> tuple[np.ndarray, np.ndarray]:
    """Flat joint limits; an unbounded revolute joint (continuous) is searched over one turn."""
    lo, hi = [], []
    for robot in scene.robots.values():
        lo.extend(np.asarray(robot.lower, dtype=np.float64))
        hi.extend(np.asarray(robot.upper, dtype=np.float64))
    lo, hi = np.array(lo), np.array(hi)
    lo = np.where(np.isfinite(lo), lo, -np.pi)
    hi = np.where(np.isfinite(hi), hi, np.pi)
    return lo, hi


def _urdf_link(model, owner: str) -> str:
    """The URDF link (Pinocchio frame) of scene owner ``owner`` -- the name an SRDF uses (a built-in
    model's links carry its robot's prefix, ``puma560_link1``, where the scene says ``puma560/link1``)."""
    go = model.collision_model.geometryObjects[model.geometry_index(model.geometry_name(owner, 0))]
    return model.pin_model.frames[go.parentFrame].name


def pair_setup(model, tol: Tolerances = DEFAULT_TOLERANCES) -> PairSetup:
    """Every own-link pair of ``model``'s robots with geometry (see the module docstring)."""
    from ..model import kinematics_of
    from ..verify._motion import chain_bounds, relative_joints
    from ..verify._oracle import ClearanceModel

    scene = model.scene_for()  # the Model as made (model.scene may have been edited since)
    work = matrix_scene(scene, adjacent=True)  # adjacent pairs too: listed, and disabled as Adjacent
    if not work.allowed_pairs():
        raise VerificationError(f"model {model.name!r}: no two links with geometry on one robot: no collision matrix to make")
    cm = ClearanceModel(work, source="reference", tol=tol)
    lever = {o: cm.lever[i] for i, o in enumerate(cm.parts)}
    offsets, k = {}, 0
    for name, robot in work.robots.items():
        offsets[name] = k
        k += len(robot.joint_names)
    kin = kinematics_of(model)  # the lever arms measured on the Model's kinematics (pin_model)
    bounds = {name: chain_bounds(robot, tol, fk=functools.partial(kin.robot_link_poses, name)) for name, robot in work.robots.items()}
    pairs = []
    for cp in work.allowed_pairs():
        r, la = cp.a.split("/", 1)
        _, lb = cp.b.split("/", 1)
        robot = work.robots[r]
        keep = relative_joints(robot, bounds[r], la, lb)
        flat = tuple(offsets[r] + j for j in keep)
        w = lever[cp.a][list(flat)] + lever[cp.b][list(flat)]
        adjacent = work._adjacent(r, la, lb)
        pairs.append(LinkPair(r, _urdf_link(model, cp.a), _urdf_link(model, cp.b), cp.a, cp.b, bool(adjacent), flat,
                              np.ascontiguousarray(w)))
    lo, hi = _limits(work)
    home = np.asarray(work.flat_q(work.default_q()), dtype=np.float64)
    return PairSetup(work, tuple(pairs), home, lo, hi)
