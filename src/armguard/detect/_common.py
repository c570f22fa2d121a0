"""What both Detectors share: argument checks, Ranger's status rule, the category codes, and the
combined kinematic tree and static boxes both compile from the scene (the analytic backend's fused
Detector, :mod:`armguard_analytic._engine`, and Ranger's bounds over any backend, :mod:`._bounds`)."""

from __future__ import annotations

import math

import numpy as np

from .._errors import DetectionError
from .._values import number

__all__ = ["check_length", "check_finite_margin", "require_pairs", "status_code", "combined_tree", "cylinder_aabb",
           "CAT_ARM", "CAT_ENVIRONMENT", "CAT_WORKSPACE", "CAT_PAYLOAD", "SCENE_CATEGORY", "CYLINDER"]

ST_CLEAR, ST_WARNING, ST_COLLISION, ST_INCOMPLETE = 0, 1, 2, 3  # the analytic kernel reads these
CAT_ARM, CAT_ENVIRONMENT, CAT_WORKSPACE, CAT_PAYLOAD = 0, 1, 2, 3
SCENE_CATEGORY = {
    "arm-arm": CAT_ARM,
    "arm-vehicle": CAT_ENVIRONMENT,
    "arm-environment": CAT_ENVIRONMENT,
    "arm-payload": CAT_PAYLOAD,
    "payload-vehicle": CAT_PAYLOAD,
    "payload-environment": CAT_PAYLOAD,
    "payload-payload": CAT_PAYLOAD,
}
"""A compiled scene's pair category (``PairCategory.value``) -> the Detector's category code."""
CYLINDER = 4  # armguard.geometry.CoreKind.CYLINDER


def scene_and_model(scene_or_model, model=None) -> tuple:
    """``(scene, model)`` of a Detector's first argument: a Scene as given (``model`` as given, or
    None), or a :class:`armguard.Model`: a scene whose Model it is (``Model.scene_for``: its own
    while nothing changed there) and the Model itself (``armguard.Detector(model)``)."""
    if hasattr(scene_or_model, "pin_model") and hasattr(scene_or_model, "scene"):
        from ..model._entry import warn_edited

        warn_edited(scene_or_model, "Detector")
        return scene_or_model.scene_for(), scene_or_model if model is None else model
    if not hasattr(scene_or_model, "robots"):  # a name or None was an AttributeError ('str' has no 'robots')
        hint = f" (armguard.load_model({scene_or_model!r}))" if isinstance(scene_or_model, str) else ""
        raise DetectionError(f"Detector: expected a Scene or a Model{hint}, got {type(scene_or_model).__name__}")
    return scene_or_model, model


def check_length(value, name: str) -> float:
    """``value`` as a finite length >= 0 (m) and at most ``Tolerances.max_magnitude`` (1e9 m, as every length of a
    scene file: 1e300 printed as 300 digits), else a DetectionError naming ``name`` (text and ``True`` too:
    ``threshold="0.1"`` was read as 0.1 m, ``True`` as 1 m)."""
    from .._tolerance import DEFAULT_TOLERANCES

    return number(value, name, DetectionError, low=0.0, high=DEFAULT_TOLERANCES.max_magnitude, unit=" (m)")


def check_link(scene, link) -> str:
    """``link`` when it names a moving owner of ``scene`` (``"robot/link"`` or a payload), else a DetectionError
    listing them (``obstacle_list("nosuch")`` answered an empty list: read as "nothing near")."""
    owners = [f"{r}/{ln}" for r, robot in scene.robots.items() for ln in robot.link_names] + list(scene.payloads)
    if link not in owners:
        raise DetectionError(f"link: expected a robot link ('robot/link') or a payload of scene {scene.name!r}, "
                             f"got {link!r}; they are {owners}")
    return link


def status_code(dmin: float, lbmin: float, level: float, thr_eff: float) -> int:
    """Ranger's status from the least evaluated distance ``dmin`` and the least lower bound of the
    pairs left unevaluated ``lbmin`` (``inf``: none), as the analytic kernel decides it: COLLISION
    when an evaluated pair is within the collision ``level``; CLEAR or WARNING only when no
    unevaluated pair can be within ``thr_eff`` (WARNING also when one is within it but no
    unevaluated pair can collide); otherwise INCOMPLETE — never CLEAR by omission."""
    if dmin <= level:
        return ST_COLLISION
    if lbmin > thr_eff:
        return ST_WARNING if dmin <= thr_eff else ST_CLEAR
    if dmin <= thr_eff and lbmin > level:
        return ST_WARNING
    return ST_INCOMPLETE


def require_pairs(scene, cs, active, with_terrain: bool) -> None:
    """A DetectionError when nothing would be checked (no pair, or none on the ``active`` arm), or
    nothing the configuration moves (every pair between two fixed shapes, and no workspace box
    around a moving one): the detector would otherwise say CLEAR, the same at every configuration,
    without having looked at the arm."""
    if with_terrain:
        return
    pa, pb = np.asarray(cs.pair_a, np.int64), np.asarray(cs.pair_b, np.int64)
    keep = np.ones(len(pa), bool)
    if active is not None and len(pa):
        r = list(cs.robot_names).index(active) if active in cs.robot_names else -1
        keep = (cs.owner_robot[pa] == r) | (cs.owner_robot[pb] == r)
    moves = np.array([scene.moves(o) for o in cs.owner_names], bool)
    n_all = int(np.count_nonzero(keep))
    n_moving = int(np.count_nonzero(keep & (moves[pa] | moves[pb]))) if len(pa) else 0
    box = bool(cs.has_workspace) and bool(moves.any())  # the box holds every moving robot shape
    if n_moving == 0 and not box:
        on = f" on arm {active!r}" if active is not None else ""
        what = (" (every pair is disabled or excluded)" if n_all == 0 else
                f" with a shape the configuration moves ({n_all} pairs, all between fixed shapes)")
        raise DetectionError(f"scene {scene.name!r} has no pair to check{on}{what}: "
                             "no verdict can be given; enable a pair, add a body or a workspace box")


def _c(a, dtype=np.float64):
    return np.ascontiguousarray(np.asarray(a, dtype=dtype))


def cylinder_aabb(c: np.ndarray, R: np.ndarray, half: np.ndarray):
    """``(lo, hi)`` (3,) m: the axis-aligned box of the cylinder with centre ``c``, axes ``R`` (the axis
    as third column) and ``half = (r, r, h)``: along axis ``k`` the extent is ``h |a_k| + r sqrt(1 -
    a_k^2)`` (as :meth:`armguard.geometry.Cylinder.aabb`), grown by a rounding margin so it contains
    the cylinder as the kernels evaluate it."""
    a = R[:, 2]
    e = half[2] * np.abs(a) + half[0] * np.sqrt(np.maximum(0.0, 1.0 - a * a))
    e = e + 1e-12 * (float(np.max(np.abs(c))) + float(np.max(half)) + 1.0)
    return c - e, c + e


def combined_tree(scene, robot_names):
    """All robots' FlatTrees as one tree over global links (parents and joint terms shifted).

    Built from the Robots (``robot.flat_tree``): what Ranger's bounds over any backend
    (:mod:`._bounds`) use.  The analytic backend's engine compiles the same layout from the
    scene's Model instead (``Model.kinematic_tree``, ``armguard.model._tree``) and is tested against this.
    """
    from ..kinematics._fk import FlatTree

    parts = {k: [] for k in ("parent", "X_pre", "axis", "jtype", "X_post", "has_post", "offset", "term_joint", "term_coeff")}
    term_start = [0]
    link_off, joint_off = [], []
    nl = nj = 0
    for r in robot_names:
        robot = scene.robots[r]
        t = getattr(robot, "flat_tree", None) or robot._tree
        link_off.append(nl)
        joint_off.append(nj)
        parts["parent"].append(np.where(t.parent >= 0, t.parent + nl, -1))
        for k in ("X_pre", "axis", "jtype", "X_post", "has_post", "offset", "term_coeff"):
            parts[k].append(np.asarray(getattr(t, k)))
        parts["term_joint"].append(np.asarray(t.term_joint) + nj)
        term_start.extend((np.asarray(t.term_start[1:]) + term_start[-1]).tolist())
        nl += t.n_links
        nj += len(robot.joint_names)
    cat = lambda k, shape, dt: _c(np.concatenate(parts[k]) if parts[k] else np.zeros(shape), dt)  # noqa: E731
    tree = FlatTree(
        parent=cat("parent", (0,), np.int64),
        X_pre=cat("X_pre", (0, 4, 4), np.float64),
        axis=cat("axis", (0, 3), np.float64),
        jtype=cat("jtype", (0,), np.int64),
        X_post=cat("X_post", (0, 4, 4), np.float64),
        has_post=cat("has_post", (0,), np.bool_),
        offset=cat("offset", (0,), np.float64),
        term_start=_c(term_start, np.int64),
        term_joint=cat("term_joint", (0,), np.int64),
        term_coeff=cat("term_coeff", (0,), np.float64),
    )
    return tree, np.asarray(link_off, dtype=np.int64), np.asarray(joint_off, dtype=np.int64)


def check_finite_margin(reach_margin) -> float:
    """``reach_margin`` as a float >= 0 (``inf`` keeps every pair)."""
    try:
        x = float(reach_margin)
    except (TypeError, ValueError) as exc:
        raise DetectionError(f"reach_margin: expected a number of metres, got {reach_margin!r}") from exc
    if math.isnan(x) or x < 0.0:
        raise DetectionError(f"reach_margin: must be >= 0 (or inf), got {x}")
    return x
