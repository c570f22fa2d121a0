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


def _limits(scene, home: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Flat joint limits to search; a revolute joint allowed more than one turn (continuous, UR's +-2 pi, limits
    written in degrees) is searched over one turn about its home: every pose it takes within its limits is one
    it takes there (the links' poses repeat every turn), unless a coupling names it (a mimic joint following it
    at another rate does not repeat)."""
    from ..kinematics import JointType

    lo, hi, turns = [], [], []
    for robot in scene.robots.values():
        lo.extend(np.asarray(robot.lower, dtype=np.float64))
        hi.extend(np.asarray(robot.upper, dtype=np.float64))
        coupled = {src for c in robot.couplings for src in c.terms}
        turns.extend(t is JointType.REVOLUTE and j not in coupled for j, t in zip(robot.joint_names, robot.joint_types))
    lo, hi, turns = np.array(lo), np.array(hi), np.array(turns, dtype=bool)
    wide = turns & ~(hi - lo <= 2.0 * np.pi)  # (an infinite limit too)
    start = np.clip(home - np.pi, np.where(np.isfinite(lo), lo, -np.inf), np.where(np.isfinite(hi), hi - 2.0 * np.pi, np.inf))
    lo = np.where(wide, start, lo)
    hi = np.where(wide, start + 2.0 * np.pi, hi)
    return np.where(np.isfinite(lo), lo, -np.pi), np.where(np.isfinite(hi), hi, np.pi)


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
    home = np.asarray(work.flat_q(work.default_q()), dtype=np.float64)
    lo, hi = _limits(work, home)
    return PairSetup(work, tuple(pairs), home, lo, hi)
