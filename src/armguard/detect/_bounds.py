"""Ranger's bounds over a Model's pair rows, for the Detector over any backend.

The generic Detector (:mod:`._ranger`) asks a Checker for the distances of Model pair rows
(``checker.pair_distances(q, pairs=rows)``); what it needs beyond the distances comes from the
Model alone, here, in the scene's flat joint order (``scene.joint_names``, the Detector's ``q``):

* per pair row, which side moves (a static side goes on B, as the Detector reports pairs),
  its Detector category and the robots of its sides (the active-arm filter);
* the *obstacle lists*: a pair whose sides' reach spheres stay farther apart than the reach
  margin at every configuration inside the joint limits is dropped (:mod:`._reach`, Ranger's
  obstacle lists built automatically);
* per pair, the summed lever arms of its two sides ``(n_q,)``, so that
  ``d(q') >= d(q) - sum_j |q_j - q'_j| lever[p, j]`` (:mod:`._reach`): the anytime lower bound.

The rows follow :meth:`armguard.model.Model._compute_pairs` (the compiled scene's element pairs,
then one workspace row per moving element), so element ``e`` of a row is the compiled scene's.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass

import numpy as np

from ._common import CAT_WORKSPACE
from ._common import CYLINDER as _CYLINDER
from ._common import SCENE_CATEGORY as _SCENE_CAT
from ._common import cylinder_aabb as _cylinder_aabb
from ._reach import chain_bounds

__all__ = ["PairBounds", "pair_bounds"]


@dataclass(frozen=True)
class PairBounds:
    """The checked Model pair rows and their bounds (see the module docstring).

    ``rows`` ``(P,) int64`` Model pair rows kept (active arm, obstacle lists), in Model order;
    ``swap`` ``(P,) bool`` the Model's side A is the static one (the Detector reports it on B);
    ``category`` ``(P,) int64`` Detector category codes (:data:`._report.CATEGORIES`);
    ``lever`` ``(P, n_q) float64`` summed lever arms of both sides (m per rad, 1 per m; inf on a
    chain with an unlimited prismatic joint); ``n_dropped`` pairs left out by the reach analysis.
    """

    rows: np.ndarray
    swap: np.ndarray
    category: np.ndarray
    lever: np.ndarray
    n_dropped: int


def _elements(cs) -> list[tuple[int, int, int]]:
    """``(element a, element b or -1 for the workspace, detector category)`` per Model pair row."""
    from ..model._compile import PAIR_CATEGORIES

    out = []
    for p in range(len(cs.pair_a)):
        cat = _SCENE_CAT[PAIR_CATEGORIES[int(cs.pair_category[p])].value]
        for k in range(int(cs.pair_elem_start[p]), int(cs.pair_elem_start[p + 1])):
            out.append((int(cs.elem_pair_a[k]), int(cs.elem_pair_b[k]), cat))
    if cs.has_workspace:
        for e in range(cs.n_elements):
            if int(cs.elem_robot[e]) >= 0:
                out.append((e, -1, CAT_WORKSPACE))
    return out


def pair_bounds(model, *, active: str | None, reach_margin: float) -> PairBounds:
    """The pair rows of ``model`` a Detector checks, with their lever arms (module docstring)."""
    from ..model._compile import compile_scene

    scene = model.scene_for()  # the Model's own copy of the system it holds (a fresh one if that was edited)
    lock = getattr(scene, "lock", None)
    with lock if lock is not None else contextlib.nullcontext():  # that scene, read whole
        cs = compile_scene(scene)
        robot_names = tuple(cs.robot_names)
        lower = np.concatenate([scene.robots[r].lower for r in robot_names]) if robot_names else np.zeros(0)
        upper = np.concatenate([scene.robots[r].upper for r in robot_names]) if robot_names else np.zeros(0)
    tree, link_off, _ = model.kinematic_tree(robot_names)  # compiled from pin_model, the Robots' layout
    n_q = len(lower)
    moving = np.asarray(cs.elem_kind) != 0
    G = cs.n_elements
    glink = (np.where(moving, link_off[np.maximum(cs.elem_robot, 0)] + cs.elem_link, -1) if G and len(link_off)
             else np.full(G, -1, np.int64))
    mov_ids = np.flatnonzero(moving & (glink >= 0))
    cb = chain_bounds(tree, lower, upper, glink[mov_ids], np.asarray(cs.elem_sphere)[mov_ids].reshape(-1, 4),
                      np.clip(np.zeros(n_q), lower, upper))
    # per element: lever arms, reach sphere (a static element: its bounding sphere, no lever)
    lever = np.zeros((G, n_q))
    centre = np.zeros((G, 3))
    radius = np.zeros(G)
    lever[mov_ids] = cb.lever
    centre[mov_ids], radius[mov_ids] = cb.reach_center, cb.reach_radius
    lo, hi = np.zeros((G, 3)), np.zeros((G, 3))  # a static element's box in W (as the analytic Detector's)
    for g in np.setdiff1d(np.arange(G), mov_ids):
        if cs.elem_core[g] == _CYLINDER:
            lo[g], hi[g] = _cylinder_aabb(cs.elem_box_center[g], cs.elem_box_axes[g], cs.elem_box_half[g])
        else:
            V = cs.verts[cs.elem_vert_start[g]:cs.elem_vert_start[g + 1]]
            lo[g], hi[g] = V.min(axis=0) - cs.elem_radius[g], V.max(axis=0) + cs.elem_radius[g]
    active_id = robot_names.index(active) if active is not None else -1
    owner_robot = np.asarray(cs.owner_robot)
    elem_owner = np.asarray(cs.elem_owner)
    rows, swap, cat, lev = [], [], [], []
    dropped = 0
    for r, (a, b, c) in enumerate(_elements(cs)):
        ra = int(owner_robot[elem_owner[a]])
        rb = int(owner_robot[elem_owner[b]]) if b >= 0 else -1
        if active_id >= 0 and ra != active_id and rb != active_id:
            continue
        ma, mb = bool(moving[a]), b >= 0 and bool(moving[b])
        elem_swapped = b >= 0 and not ma
        if elem_swapped:  # the moving side on A
            a, b, ma, mb = b, a, mb, ma
        if b < 0:  # the workspace walls: the reach sphere's least clearance to them
            gap = float(np.min(np.concatenate([cs.workspace_hi - centre[a], centre[a] - cs.workspace_lo]))) - radius[a]
        elif mb:  # two reach spheres
            gap = float(np.linalg.norm(centre[a] - centre[b])) - radius[a] - radius[b]
        else:  # a reach sphere and a static box
            gap = float(np.linalg.norm(np.maximum(np.maximum(lo[b] - centre[a], 0.0), centre[a] - hi[b]))) - radius[a]
        if gap > reach_margin:
            dropped += 1
            continue
        rows.append(r)
        swap.append(bool(elem_swapped))
        cat.append(c)
        lev.append(lever[a] + (lever[b] if b >= 0 else 0.0))
    return PairBounds(np.asarray(rows, dtype=np.int64), np.asarray(swap, dtype=bool), np.asarray(cat, dtype=np.int64),
                      np.asarray(lev, dtype=np.float64).reshape(len(rows), n_q), dropped)
