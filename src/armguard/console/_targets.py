"""Typed Cartesian targets and workspace corners of :class:`~._state.ConsoleState`.

Mixed into the state (its lock, scene, arms, ``_changed`` and ``_rebuild_detector``).  Every
value an operator types into these fields is checked here like a joint value (a number per axis,
finite, within :data:`MAX_COORDINATE` m or :data:`MAX_ANGLE_DEG` deg) and kept in the state
only when good; the page shows what the state holds, so a refused entry leaves the box showing
the value in force.

**Cartesian target**: the tool pose the *move tool* command goes to.  Until the operator types
one it is the active arm's tool pose now; a typed target holds until the arm moves or another arm
becomes active (then it follows the tool again).

**Workspace corners**: a box is applied only by :meth:`TargetsMixin.apply_workspace` (both
corners typed or the box in force, the upper above the lower on every axis) and removed only by
:meth:`TargetsMixin.remove_workspace`; a scene without a box shows none (empty corners).  A
refused box puts the corners back to the box in force.
"""

from __future__ import annotations

import math

import numpy as np

from ._parse import ConsoleInputError, parse_numbers

__all__ = ["TargetsMixin", "MAX_COORDINATE", "MAX_ANGLE_DEG", "AXES"]

MAX_COORDINATE = 100.0
"""Largest |coordinate| (m) of a typed target or workspace corner: more is a typing error."""
MAX_ANGLE_DEG = 180.0
"""Largest |roll|, |pitch|, |yaw| (deg) of a typed target orientation."""
AXES = ("x", "y", "z")


def _checked(values: np.ndarray, field: str, names, bound: float, unit: str) -> np.ndarray:
    for name, v in zip(names, values):
        if abs(v) > bound:
            raise ConsoleInputError(f"{field} {name}: {v:g} {unit} is outside [{-bound:g}, {bound:g}] {unit}; "
                                    "value kept unchanged")
    return values


def parse_point(text, field: str) -> np.ndarray:
    """Three coordinates (m) typed as ``"x, y, z"``: (3,) float64, each finite and within ±MAX_COORDINATE."""
    p = parse_numbers(text, field, 3, unit="m", names=AXES)
    return _checked(p, field, AXES, MAX_COORDINATE, "m")


def parse_rpy_deg(text, field: str) -> np.ndarray:
    """Roll, pitch, yaw typed in degrees: (3,) float64 rad, each finite and within ±MAX_ANGLE_DEG."""
    names = ("roll", "pitch", "yaw")
    a = parse_numbers(text, field, 3, unit="deg", names=names)
    return np.radians(_checked(a, field, names, MAX_ANGLE_DEG, "deg"))


class TargetsMixin:
    """The Cartesian target and the workspace box's corners as typed by the operator."""

    _target = None  # (p_WE (3,), rpy (3,) rad, active, q of the active arm when typed) or None
    _ws_draft = (None, None)  # typed corners (3,) m, not yet applied

    # ------------------------------------------------------------------ Cartesian target
    def _target_now(self):
        """``(p_WE (3,) m, rpy (3,) rad, typed)``: the typed target while it holds, else the tool pose now."""
        from ..kinematics._frames import xyz_rpy_from_pose

        t = self._target
        if t is not None and t[2] == self._active and np.array_equal(t[3], self._q[self._active]):
            return t[0].copy(), t[1].copy(), True
        xyz, rpy = xyz_rpy_from_pose(self._robot(self._active).link_pose(self._q[self._active]))
        return np.asarray(xyz, dtype=np.float64), np.asarray(rpy, dtype=np.float64), False

    def target(self):
        """``(p_WE (3,) m, rpy (3,) rad, typed)`` the *move tool* command goes to."""
        with self._lock:
            return self._target_now()

    def _set_target(self, p=None, rpy=None, message: str = "") -> None:
        with self._lock:
            p0, rpy0, _ = self._target_now()
            self._target = (p0 if p is None else p, rpy0 if rpy is None else rpy, self._active,
                            self._q[self._active].copy())
            self._changed(message)

    def set_target_position(self, text) -> np.ndarray:
        """The target position ``"x, y, z"`` (m, in W); returns it.  Nothing moves until :meth:`move_to_target`."""
        p = parse_point(text, "target position")
        self._set_target(p=p, message="target position: " + ", ".join(f"{v:g}" for v in p) + " m (move tool to go)")
        return p

    def set_target_rpy(self, text) -> np.ndarray:
        """The target orientation ``"roll, pitch, yaw"`` (deg); returns it in rad."""
        rpy = parse_rpy_deg(text, "target roll pitch yaw")
        self._set_target(rpy=rpy, message="target orientation: " + ", ".join(f"{math.degrees(v):g}" for v in rpy)
                         + " deg (move tool to go)")
        return rpy

    def reset_target(self) -> None:
        """The target follows the tool pose now again."""
        with self._lock:
            self._target = None
            self._changed("target = tool pose now")

    def move_to_target(self) -> np.ndarray:
        """Move the active arm's tool to the target (:meth:`move_ee`); returns the new joints."""
        with self._lock:
            p, rpy, _ = self._target_now()
            return self.move_ee(p, rpy)

    # ------------------------------------------------------------------ workspace box
    def workspace_corners(self):
        """``(lower, upper)`` as the corner fields show them: each (3,) m, the typed corner, else
        the box in force's, else None (no box)."""
        with self._lock:
            ws = self._scene.workspace
            out = []
            for k, typed in enumerate(self._ws_draft):
                if typed is not None:
                    out.append(typed.copy())
                elif ws is not None:
                    out.append(np.array(ws.lo if k == 0 else ws.hi, dtype=np.float64))
                else:
                    out.append(None)
            return tuple(out)

    def set_workspace_corner(self, which: str, text) -> np.ndarray:
        """Type the ``"lower"`` or ``"upper"`` corner ``"x, y, z"`` (m); applied by :meth:`apply_workspace`."""
        if which not in ("lower", "upper"):
            raise ConsoleInputError(f"workspace corner: expected 'lower' or 'upper', got {which!r}")
        p = parse_point(text, f"workspace {which} corner")
        with self._lock:
            draft = list(self._ws_draft)
            draft[0 if which == "lower" else 1] = p
            self._ws_draft = tuple(draft)
            self._changed(f"workspace {which} corner: " + ", ".join(f"{v:g}" for v in p) + " m (apply limits to use)")
        return p

    def apply_workspace(self) -> None:
        """Apply the corners (:meth:`workspace_corners`) as the workspace box; a refusal puts them back."""
        with self._lock:
            lo, hi = self.workspace_corners()
            try:
                if lo is None or hi is None:
                    missing = " and ".join(n for n, c in (("lower", lo), ("upper", hi)) if c is None)
                    raise ConsoleInputError(f"workspace: no box to apply: type the {missing} corner first "
                                            "(x, y, z in m)")
                self.set_workspace(lo, hi)
            except ConsoleInputError:
                self._ws_draft = (None, None)
                self._version += 1
                raise
            self._ws_draft = (None, None)

    def remove_workspace(self) -> None:
        """Remove the workspace box (the scene then has none; the corners show empty)."""
        with self._lock:
            if self._scene.workspace is None:
                raise ConsoleInputError("workspace: there is no box to remove")
            old = self._scene.workspace
            self._scene.clear_workspace()
            try:
                self._rebuild_detector()
                self._refresh_model()
            except Exception:
                self._scene.set_workspace(old.lo, old.hi)
                self._rebuild_detector()
                raise
            self._ws_draft = (None, None)
            self._changed("workspace box removed")

    def _refresh_model(self) -> None:
        """The Model (and the other backends' checkers on it) after an edit of the scene's workspace box: the
        coal and fcl panels measured the old box (a violated new box read clear; the comparison a false delta)."""
        if self._model is None:
            return
        from ..model import model_of

        self._model = model_of(self._scene)
        self._views = {}

    def set_workspace(self, lo, hi) -> None:
        """Workspace bounding-box limits ``lo``, ``hi`` (3 numbers each, m; hi > lo on every axis)."""
        lo_v = parse_point(lo, "workspace lower corner")
        hi_v = parse_point(hi, "workspace upper corner")
        if np.any(hi_v <= lo_v):
            raise ConsoleInputError(
                f"workspace: the upper corner must exceed the lower one on every axis, got lower {lo_v.tolist()} "
                f"upper {hi_v.tolist()} m; limits kept unchanged"
            )
        with self._lock:
            old = self._scene.workspace
            self._scene.set_workspace(lo_v, hi_v)
            try:
                self._rebuild_detector()
                self._refresh_model()
            except Exception:
                if old is None:
                    self._scene.clear_workspace()
                else:
                    self._scene.set_workspace(old.lo, old.hi)
                self._rebuild_detector()
                raise
            self._ws_draft = (None, None)
            self._changed("workspace: " + ", ".join(f"{v:g}" for v in lo_v) + " to "
                          + ", ".join(f"{v:g}" for v in hi_v) + " m")
