"""What changed between two versions of a model, for ``armguard console --watch``.

:func:`describe_changes` compares the old and the new scene (and their models' active pairs,
when both have one): arms added or removed (or reset, their joints changed), joint limits
changed, the configuration clipped into new limits, the workspace box changed, shapes added,
removed, moved (the same shape elsewhere), resized (the same kind, other dimensions) or changed
(another kind or number of shapes), pairs added and removed.  :func:`carry_q` keeps the operator's configuration across the reload: a
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


_EPS = 1e-9
"""Lengths (m) and angles (rad) closer than this are the same."""


def _shape_key(shape) -> tuple:
    """``(type, radius, core points (k, 3))``: what a shape is, and where."""
    pts = np.asarray(shape.core_points, dtype=np.float64)
    return type(shape).__name__, float(getattr(shape, "radius", 0.0)), pts


def _shapes(scene, q) -> dict:
    """owner -> list of :func:`_shape_key` at ``q`` (robot -> joints)."""
    out: dict = {}
    for it in scene.shapes_at(q):
        out.setdefault(it.owner, []).append(_shape_key(it.shape))
    return out


def _compare_shape(a: tuple, b: tuple) -> str:
    """``"same"``, ``"moved"`` (a rigid motion: equal radius and core-point distances),
    ``"resized"`` (same kind and point count, other dimensions) or ``"changed"``."""
    if a[0] != b[0] or a[2].shape != b[2].shape:
        return "changed"
    if abs(a[1] - b[1]) <= _EPS and np.allclose(a[2], b[2], rtol=0.0, atol=_EPS):
        return "same"
    da = np.linalg.norm(a[2][:, None, :] - a[2][None, :, :], axis=-1)
    db = np.linalg.norm(b[2][:, None, :] - b[2][None, :, :], axis=-1)
    if abs(a[1] - b[1]) <= _EPS and np.allclose(da, db, rtol=0.0, atol=1e-7):
        return "moved"
    return "resized"


def _units(robot) -> tuple[str, ...]:
    types = getattr(robot, "joint_types", None) or ("revolute",) * robot.n_joints
    return tuple("m" if "prismatic" in str(getattr(t, "value", t)).lower() else "deg" for t in types)


def _shown(x: float, unit: str) -> str:
    if not np.isfinite(x):
        return "inf" if x > 0 else "-inf"
    return f"{np.degrees(x) if unit == 'deg' else x:.4g}"


def _joint_changes(old_scene, new_scene, q_old: dict, q_new: dict) -> list[str]:
    """Joints reset, joint limits changed and joint values clipped, per robot kept across the reload."""
    reset, limits, clipped = [], [], []
    for name, robot in new_scene.robots.items():
        old = old_scene.robots.get(name)
        if old is None:
            continue
        if tuple(old.joint_names) != tuple(robot.joint_names):
            reset.append(name)
            continue
        units = _units(robot)
        lo0, hi0, lo1, hi1 = (np.asarray(v, dtype=np.float64) for v in (old.lower, old.upper, robot.lower, robot.upper))
        for j, jn in enumerate(robot.joint_names):
            u = units[j]
            if not (np.isclose(lo0[j], lo1[j], rtol=0.0, atol=_EPS) and np.isclose(hi0[j], hi1[j], rtol=0.0, atol=_EPS)):
                limits.append(f"{name}/{jn} [{_shown(lo0[j], u)}, {_shown(hi0[j], u)}] → "
                              f"[{_shown(lo1[j], u)}, {_shown(hi1[j], u)}] {u}")
            if name in q_old and name in q_new:
                a, b = float(q_old[name][j]), float(q_new[name][j])
                if abs(a - b) > _EPS:
                    clipped.append(f"{name}/{jn} {_shown(a, u)} → {_shown(b, u)} {u}")
    out = []
    if reset:
        out.append(f"arms reset to home (their joints changed): {_names(reset)}")
    if limits:
        out.append(f"joint limits changed: {_names(limits)}")
    if clipped:
        out.append(f"configuration clipped into the new limits: {_names(clipped)}")
    return out


def _workspace_change(old_scene, new_scene) -> list[str]:
    a, b = old_scene.workspace, new_scene.workspace
    box = lambda w: (f"[{', '.join(f'{x:.4g}' for x in w.lo)}] to "  # noqa: E731
                     f"[{', '.join(f'{x:.4g}' for x in w.hi)}] m")
    if a is None and b is None:
        return []
    if a is None:
        return [f"workspace added: {box(b)}"]
    if b is None:
        return ["workspace removed"]
    if np.allclose(a.lo, b.lo, rtol=0.0, atol=_EPS) and np.allclose(a.hi, b.hi, rtol=0.0, atol=_EPS):
        return []
    return [f"workspace changed: {box(a)} → {box(b)}"]


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
    parts += _joint_changes(old_scene, new_scene, q_old, q_new)
    parts += _workspace_change(old_scene, new_scene)
    a, b = _shapes(old_scene, q_old), _shapes(new_scene, q_new)
    new_owners, gone = set(b) - set(a), set(a) - set(b)
    if new_owners:
        parts.append(f"shapes added: {_names(new_owners)}")
    if gone:
        parts.append(f"shapes removed: {_names(gone)}")
    kinds: dict = {"moved": [], "resized": [], "changed": []}
    for owner in set(a) & set(b):
        if len(a[owner]) != len(b[owner]):
            kinds["changed"].append(owner)
            continue
        seen = {_compare_shape(x, y) for x, y in zip(a[owner], b[owner])} - {"same"}
        for kind in ("changed", "resized", "moved"):  # the strongest change of the owner's shapes
            if kind in seen:
                kinds[kind].append(owner)
                break
    for kind, owners in kinds.items():
        if owners:
            parts.append(f"shapes {kind}: {_names(owners)}")
    if old_model is not None and new_model is not None:
        pa, pb = _pair_set(old_model), _pair_set(new_model)
        if pb - pa:
            parts.append(f"pairs added: {len(pb - pa)} ({_names(' / '.join(p) for p in pb - pa)})")
        if pa - pb:
            parts.append(f"pairs removed: {len(pa - pb)} ({_names(' / '.join(p) for p in pa - pb)})")
    return "; ".join(parts) if parts else "no change"
