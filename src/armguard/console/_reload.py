"""What changed between two versions of a model, for ``armguard console --watch``.

:func:`describe_changes` compares the old and the new scene (and their models' active pairs,
when both have one): pairs added and removed, shapes moved, reshaped, added or removed, arms
added or removed.  :func:`carry_q` keeps the operator's configuration across the reload: a
robot whose joint names are unchanged keeps its joint values (clipped into the new limits),
any other robot starts at the new model's home.
"""

from __future__ import annotations

import numpy as np

__all__ = ["describe_changes", "carry_q", "MAX_NAMED"]

MAX_NAMED = 4
"""Names listed per kind of change before "and N more"."""


def _names(items) -> str:
    items = sorted(items)
    head = ", ".join(items[:MAX_NAMED])
    return head + (f" and {len(items) - MAX_NAMED} more" if len(items) > MAX_NAMED else "")


def _shape_key(shape) -> tuple:
    pts = np.round(np.asarray(shape.core_points, dtype=np.float64), 9)
    return type(shape).__name__, float(round(getattr(shape, "radius", 0.0), 9)), pts.shape, pts.tobytes()


def _shapes(scene, q) -> dict:
    """owner -> list of (type, radius, points) at ``q`` (robot -> joints)."""
    out: dict = {}
    for it in scene.shapes_at(q):
        out.setdefault(it.owner, []).append(_shape_key(it.shape))
    return out


def _pair_set(model) -> set:
    if model is None:
        return set()
    p = model.pairs
    return {tuple(sorted((str(a), str(b)))) for a, b in zip(p.owner_a, p.owner_b)}


def carry_q(old_q: dict, old_scene, new_scene) -> dict:
    """The configuration to keep after a reload: robot -> (n_joints,) float64 in the new scene."""
    q = {k: np.array(v, dtype=np.float64) for k, v in new_scene.default_q().items()}
    for name, robot in new_scene.robots.items():
        old = old_scene.robots.get(name)
        if old is None or tuple(old.joint_names) != tuple(robot.joint_names) or name not in old_q:
            continue
        q[name] = np.clip(np.asarray(old_q[name], dtype=np.float64), np.asarray(robot.lower), np.asarray(robot.upper))
    return q


def describe_changes(old_scene, new_scene, q_old: dict, q_new: dict, old_model=None, new_model=None) -> str:
    """One line saying what the reload changed (``"no change"`` when nothing did)."""
    parts = []
    added_r = set(new_scene.robots) - set(old_scene.robots)
    removed_r = set(old_scene.robots) - set(new_scene.robots)
    if added_r:
        parts.append(f"arms added: {_names(added_r)}")
    if removed_r:
        parts.append(f"arms removed: {_names(removed_r)}")
    a, b = _shapes(old_scene, q_old), _shapes(new_scene, q_new)
    new_owners, gone = set(b) - set(a), set(a) - set(b)
    if new_owners:
        parts.append(f"shapes added: {_names(new_owners)}")
    if gone:
        parts.append(f"shapes removed: {_names(gone)}")
    moved, reshaped = [], []
    for owner in set(a) & set(b):
        if a[owner] == b[owner]:
            continue
        same_kind = len(a[owner]) == len(b[owner]) and all(
            x[:3] == y[:3] for x, y in zip(a[owner], b[owner]))
        (moved if same_kind else reshaped).append(owner)
    if moved:
        parts.append(f"shapes moved: {_names(moved)}")
    if reshaped:
        parts.append(f"shapes changed: {_names(reshaped)}")
    if old_model is not None and new_model is not None:
        pa, pb = _pair_set(old_model), _pair_set(new_model)
        if pb - pa:
            parts.append(f"pairs added: {len(pb - pa)} ({_names(' / '.join(p) for p in pb - pa)})")
        if pa - pb:
            parts.append(f"pairs removed: {len(pa - pb)} ({_names(' / '.join(p) for p in pa - pb)})")
    return "; ".join(parts) if parts else "no change"
