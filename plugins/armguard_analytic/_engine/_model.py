"""Compile a scene for the fused detector: one kinematic tree, element arrays, pair lists, BVH.

Built on :func:`armguard.scene.compile_scene` (elements in their own frames, owner pairs with
their categories); this module adds what the detector needs on top of it:

* one flattened kinematic tree over the links of *all* robots (global link index =
  robot's offset + link index), so one FK call serves the scene, compiled from the scene's
  Model (:func:`armguard.model.model_of` with ``geometry=False``: its Pinocchio joint tree,
  placements and mimic couplings, :meth:`armguard.model.Model.kinematic_tree`, which Ranger's
  bounds over the other backends use too); the Robots' own trees
  (:func:`armguard.detect._common.combined_tree`) are the slow reference the tests hold it to;
* element frames as link numbers (-1 for static bodies), edge directions and face normals
  in the element frame, static elements' AABBs (a cylinder's exact one, see
  :func:`armguard.detect._common.cylinder_aabb`) and a :class:`BVH` over them;
* the candidate pairs: element pairs of :meth:`Scene.allowed_pairs` mapped to the four
  categories, plus one workspace pair per moving element, filtered by the active arm and by
  the conservative obstacle lists (:mod:`armguard.detect._reach`);
* per moving element, lever arms for the anytime lower bounds.
"""

from __future__ import annotations

import numpy as np

from armguard._errors import DetectionError
from armguard.detect._common import (CAT_ARM, CAT_ENVIRONMENT, CAT_PAYLOAD, CAT_WORKSPACE, CYLINDER as _CYLINDER,
                                     SCENE_CATEGORY as _SCENE_CAT, cylinder_aabb as _cylinder_aabb)
from armguard.detect._reach import chain_bounds

from ._bvh import build_bvh
from ._from_model import compile_model_parts

__all__ = ["DetectModel", "build_model", "compile_for_engine", "engine_tree", "CAT_ARM", "CAT_ENVIRONMENT", "CAT_WORKSPACE", "CAT_PAYLOAD"]


def _c(a, dtype=np.float64):
    return np.ascontiguousarray(np.asarray(a, dtype=dtype))


class DetectModel:
    """The detector's compiled scene (read-only arrays; see the module docstring).

    Element arrays are indexed like ``compiled.elem_*``; ``elem_glink`` ``(G,)`` is the global
    link of a moving element (-1 static).  ``pair_a``, ``pair_b`` ``(P,) int64`` element numbers
    (``pair_b = -1``: the workspace walls), ``pair_cat`` ``(P,)`` category codes; pairs are
    ordered explicit first (moving-moving and workspace, ``n_explicit`` of them), then
    moving-static.  ``pair_of`` ``(n_moving, n_static) int64`` maps a (moving, static) element
    couple to its pair number (-1: not a candidate).  ``static_shapes``: static element number ->
    its shape in W; ``source``: ``"model"`` (:func:`._from_model.compile_model`) or ``"scene"``
    (:func:`armguard.scene.compile_scene`).
    """


_DERIVE_BUDGET = 50_000_000
"""Above this ``derive_cost`` (~0.1 s of Pinocchio's pair-map copies) the engine compiles an edited
scene with ``compile_scene`` instead of deriving its Model (many bodies added: the scaling bench's
10 000 boxes); both give the same arrays (tests/test_engine_from_model.py, test_model_derive.py)."""


def _model_of_geometry(scene):
    """The scene's Model, its GeometryModel holding exactly the scene's shapes (``model_of``: the
    Model the scene was loaded as, or one derived from it after bodies or payloads changed); None
    (compile the Scene) for a scene without robots that no Model was made for, or when deriving
    would add more objects than Pinocchio adds cheaply (:data:`_DERIVE_BUDGET`)."""
    from armguard.model import model_of
    from armguard.model._derive import derive_cost

    if not scene.robots and getattr(scene, "_model_of_record", None) is None:
        return None
    kin = model_of(scene, geometry=False) if scene.robots else scene._model_of_record
    if kin.is_model_of(scene):
        return kin
    if derive_cost(kin, scene) > _DERIVE_BUDGET:
        return None
    model = model_of(scene)
    return model if model.is_model_of(scene) else None


def compile_for_engine(scene, model=None) -> tuple:
    """``(compiled, static_shapes, source)``: the element arrays and pairs of ``model`` when given,
    else of the scene's Model (``source == "model"``) or, for a scene without one, of the Scene."""
    if model is None:
        model = _model_of_geometry(scene)
    if model is not None:
        cs, static_shapes = compile_model_parts(model)
        return cs, static_shapes, "model"
    from armguard.scene import compile_scene

    static_shapes = dict(enumerate(s for body in scene.bodies.values() for s in body.shapes))
    return compile_scene(scene), static_shapes, "scene"


def engine_tree(scene, robot_names, *, model=None):
    """``(tree, link_off, joint_off)``: the kinematic tree of the scene's Model
    (:meth:`armguard.model.Model.kinematic_tree`, compiled from its Pinocchio model once per
    robot set; ``model`` when it moves the scene's robots, else ``model_of(scene, geometry=False)``)."""
    from armguard.model import model_of
    from armguard.model._tree import pin_tree

    if not robot_names:  # nothing moves: no Model needed
        return pin_tree(None, ())
    if model is None or not model.moves_robots_of(scene):
        model = model_of(scene, geometry=False)
    return model.kinematic_tree(tuple(robot_names))


def build_model(scene, *, active: str | None, reach_margin: float, tol, model=None) -> DetectModel:
    """Compile ``scene`` for the detector (explicit, repeatable; the scene is unchanged): its Model
    (``armguard.model.model_of``), or ``model`` as it is (an AnalyticChecker answers for its Model,
    also after the scene moved on to a derived one)."""
    cs, m_static, source = compile_for_engine(scene, model)
    m = DetectModel()
    m.compiled, m.static_shapes, m.source = cs, m_static, source
    robot_names = tuple(cs.robot_names)
    if active is not None and active not in robot_names:
        raise DetectionError(f"active: unknown robot {active!r}; robots are {list(robot_names)}")
    m.robot_names = robot_names
    if model is not None:
        scene = model  # its robots and kinematics (the scene's while it moves them)
    tree, link_off, joint_off = engine_tree(scene, robot_names, model=model)
    m.tree, m.link_off, m.joint_off = tree, link_off, joint_off
    m.link_names = tuple(f"{r}/{ln}" for r in robot_names for ln in scene.robots[r].link_names)
    m.link_robot = _c([i for i, r in enumerate(robot_names) for _ in scene.robots[r].link_names], np.int64)
    m.n_q = int(sum(len(scene.robots[r].joint_names) for r in robot_names))
    lower = np.concatenate([scene.robots[r].lower for r in robot_names]) if robot_names else np.zeros(0)
    upper = np.concatenate([scene.robots[r].upper for r in robot_names]) if robot_names else np.zeros(0)
    m.lower, m.upper = _c(lower), _c(upper)

    G = cs.n_elements
    moving = cs.elem_kind != 0  # links and payloads
    if G and len(link_off):
        glink = np.where(moving, link_off[np.maximum(cs.elem_robot, 0)] + cs.elem_link, -1)
    else:  # no element, or no robot (every element static: nothing moves, nothing to check)
        glink = np.full(G, -1, np.int64)
    m.elem_glink = _c(glink, np.int64)
    m.elem_is_payload = _c(cs.elem_kind == 2, np.bool_)
    mov_ids = np.flatnonzero(moving)
    st_ids = np.flatnonzero(~moving)
    m.mov_ids, m.st_ids = _c(mov_ids, np.int64), _c(st_ids, np.int64)
    mov_idx = np.full(G, -1, np.int64)
    mov_idx[mov_ids] = np.arange(len(mov_ids))
    st_idx = np.full(G, -1, np.int64)
    st_idx[st_ids] = np.arange(len(st_ids))
    m.mov_idx, m.st_idx = mov_idx, st_idx

    # element-frame data the kernel moves: face normals (from planes), edge directions
    m.fnrm_local = _c(cs.planes[:, :3]) if len(cs.planes) else np.zeros((0, 3))
    if len(cs.edges):
        e = cs.verts[cs.edges[:, 1]] - cs.verts[cs.edges[:, 0]]
        n = np.linalg.norm(e, axis=1)
        e = np.where(n[:, None] > tol.length, e / np.where(n > 0, n, 1.0)[:, None], 0.0)
        m.edir_local = _c(e)
    else:
        m.edir_local = np.zeros((0, 3))
    box = np.zeros((G, 15))
    box[:, 0:3] = cs.elem_box_center
    box[:, 3:6] = cs.elem_box_half
    box[:, 6:15] = np.asarray(cs.elem_box_axes).reshape(G, 9)
    m.box_local = _c(box)

    # static AABBs (W) and the BVH over them
    slo = np.zeros((len(st_ids), 3))
    shi = np.zeros((len(st_ids), 3))
    for k, g in enumerate(st_ids):
        if cs.elem_core[g] == _CYLINDER:  # the exact box of a cylinder (its core points are a larger prism)
            slo[k], shi[k] = _cylinder_aabb(cs.elem_box_center[g], cs.elem_box_axes[g], cs.elem_box_half[g])
            continue
        V = cs.verts[cs.elem_vert_start[g]:cs.elem_vert_start[g + 1]]
        r = cs.elem_radius[g]
        slo[k] = V.min(axis=0) - r
        shi[k] = V.max(axis=0) + r
    m.static_lo, m.static_hi = _c(slo), _c(shi)
    m.bvh = build_bvh(m.static_lo, m.static_hi)

    # reach spheres and lever arms of the moving elements
    q_ref = np.clip(np.zeros(m.n_q), m.lower, m.upper)
    sph = cs.elem_sphere[mov_ids] if len(mov_ids) else np.zeros((0, 4))
    cb = chain_bounds(tree, m.lower, m.upper, glink[mov_ids], sph, q_ref)
    m.reach_center, m.reach_radius = cb.reach_center, cb.reach_radius
    m.lever = _c(cb.lever)

    # candidate pairs
    owner_robot = cs.owner_robot
    active_id = robot_names.index(active) if active is not None else -1
    from armguard.scene import PAIR_CATEGORIES

    def in_reach_static(ma: int, s: int) -> bool:
        c, rr = m.reach_center[ma], m.reach_radius[ma]
        gap = float(np.linalg.norm(np.maximum(np.maximum(slo[s] - c, 0.0), c - shi[s]))) - rr
        return not gap > reach_margin

    def in_reach_moving(ma: int, mb: int) -> bool:
        gap = float(np.linalg.norm(m.reach_center[ma] - m.reach_center[mb])) - m.reach_radius[ma] - m.reach_radius[mb]
        return not gap > reach_margin

    explicit, static_pairs, dropped = [], [], 0
    for k in range(len(cs.pair_a)):
        oa, ob = int(cs.pair_a[k]), int(cs.pair_b[k])
        if active_id >= 0 and owner_robot[oa] != active_id and owner_robot[ob] != active_id:
            continue
        cat = _SCENE_CAT[PAIR_CATEGORIES[int(cs.pair_category[k])].value]
        for e in range(cs.pair_elem_start[k], cs.pair_elem_start[k + 1]):
            ga, gb = int(cs.elem_pair_a[e]), int(cs.elem_pair_b[e])
            if mov_idx[ga] < 0:  # keep the moving element on side A
                ga, gb = gb, ga
            if mov_idx[gb] >= 0:
                if in_reach_moving(mov_idx[ga], mov_idx[gb]):
                    explicit.append((ga, gb, cat))
                else:
                    dropped += 1
            elif in_reach_static(mov_idx[ga], st_idx[gb]):
                static_pairs.append((ga, gb, cat))
            else:
                dropped += 1
    m.has_workspace = bool(cs.has_workspace)
    m.ws_lo, m.ws_hi = _c(cs.workspace_lo), _c(cs.workspace_hi)
    if cs.has_workspace:
        for g in mov_ids:
            if active_id >= 0 and cs.elem_robot[g] != active_id:
                continue
            c, rr = m.reach_center[mov_idx[g]], m.reach_radius[mov_idx[g]]
            gap = float(np.min(np.concatenate([m.ws_hi - c, c - m.ws_lo]))) - rr
            if not gap > reach_margin:
                explicit.append((int(g), -1, CAT_WORKSPACE))
            else:
                dropped += 1
    pairs = explicit + static_pairs
    m.n_explicit = len(explicit)
    m.n_dropped = dropped
    m.pair_a = _c([p[0] for p in pairs], np.int64)
    m.pair_b = _c([p[1] for p in pairs], np.int64)
    m.pair_cat = _c([p[2] for p in pairs], np.int64)
    pair_of = np.full((len(mov_ids), len(st_ids)), -1, np.int64)
    for k in range(m.n_explicit, len(pairs)):
        pair_of[mov_idx[pairs[k][0]], st_idx[pairs[k][1]]] = k
    m.pair_of = pair_of
    m.has_category = tuple(bool(np.any(m.pair_cat == c)) for c in range(4))
    m.reach_margin = reach_margin
    return m
