"""Jogging the tool in tool, base, world or an object's coordinates (WORKMATE, Smith 1986, seed 004:
"jogging the tool in tool, base or object coordinates").

A jog is one step along or about one axis of a frame ``F``: a translation ``s`` along F's axis
``k`` moves the tool origin by ``s R_WF e_k``; a turn ``θ`` about F's axis ``k`` turns the tool
about that direction through the tool origin (the tool point stays put):
``R_WE' = R_WF Rot(e_k, θ) R_WF^T R_WE``.  In tool coordinates (``F = E``, the tool now) this is
``X_WE' = X_WE Trans(s e_k)`` and ``X_WE' = X_WE Rot(e_k, θ)``.  The new pose is reached through the
arm's inverse kinematics seeded at the current joints (:meth:`ConsoleState._solve_ik`); no
solution leaves the arm where it was, with the reason.
"""

from __future__ import annotations

import math

import numpy as np

from ._parse import ConsoleInputError, parse_number

__all__ = ["JOG_AXES", "FIXED_FRAMES", "MAX_STEP_MM", "MAX_TURN_DEG", "jogged_pose", "jog_frames", "frame_pose",
           "jog", "parse_step_mm", "parse_turn_deg"]

JOG_AXES = ("x", "y", "z")
FIXED_FRAMES = ("world", "base", "tool")
"""The frames every console offers; then every static body's frame (an object)."""
MAX_STEP_MM = 500.0
"""Largest jog step (mm): more is a typing error, not a jog."""
MAX_TURN_DEG = 90.0
"""Largest jog turn (deg)."""


def _rot(axis: int, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    R = np.eye(3)
    R[i, i], R[i, j], R[j, i], R[j, j] = c, -s, s, c
    return R


def jogged_pose(X_WE, X_WF, axis: int, *, translate: float = 0.0, turn: float = 0.0) -> np.ndarray:
    """``X_WE'`` (4, 4): the tool pose ``X_WE`` moved ``translate`` m along, then turned ``turn`` rad
    about, axis ``axis`` (0, 1, 2: x, y, z) of frame ``X_WF`` (the turn about the tool origin)."""
    X_WE = np.asarray(X_WE, dtype=np.float64)
    R_WF = np.asarray(X_WF, dtype=np.float64)[:3, :3]
    out = np.array(X_WE)
    out[:3, 3] = X_WE[:3, 3] + translate * R_WF[:, axis]
    out[:3, :3] = R_WF @ _rot(axis, turn) @ R_WF.T @ X_WE[:3, :3]
    return out


def jog_frames(state, cell=None) -> tuple[str, ...]:
    """The frames offered: world, base, tool, then the cell's objects (or the scene's static bodies)."""
    bodies = tuple(cell.objects) if cell is not None else tuple(state.scene.bodies)
    return FIXED_FRAMES + tuple(b for b in bodies if b not in FIXED_FRAMES)


def frame_pose(state, frame: str, cell=None, robot: str | None = None) -> np.ndarray:
    """``X_WF`` (4, 4) of ``frame`` for the arm ``robot`` (default: the active arm) now: ``world``; ``base`` (the
    arm's mount); ``tool`` (its tool pose now); an object: the cell's frame for it (the nominal layout or its
    calibration) or, without a cell, its shapes' bounding-box centre with W's axes."""
    name = state.snapshot().active if robot is None else robot
    robot = state.scene.robots[name]
    if frame == "world":
        return np.eye(4)
    if frame == "base":
        return np.array(robot.X_WB, dtype=np.float64)
    if frame == "tool":
        return np.array(state.ee_pose(name))
    if cell is not None and frame in cell.objects:
        return np.array(cell.objects[frame], dtype=np.float64)
    if frame in state.scene.bodies:
        from ..program import object_frame

        return object_frame(state.scene.bodies[frame].shapes)
    raise ConsoleInputError(f"jog frame: unknown frame {frame!r}; frames are {list(jog_frames(state, cell))}")


def parse_step_mm(text) -> float:
    """A jog step typed in mm: (0, MAX_STEP_MM]; returns m."""
    return parse_number(text, "jog step", lo=0.0, hi=MAX_STEP_MM, unit="mm", open_lo=True) * 1e-3


def parse_turn_deg(text) -> float:
    """A jog turn typed in deg: (0, MAX_TURN_DEG]; returns rad."""
    return math.radians(parse_number(text, "jog turn", lo=0.0, hi=MAX_TURN_DEG, unit="deg", open_lo=True))


def jog(state, frame: str, axis: str, *, translate: float = 0.0, turn: float = 0.0, cell=None) -> np.ndarray:
    """Jog the active arm's tool ``translate`` m along / ``turn`` rad about ``axis`` (``"x"``,
    ``"y"``, ``"z"``) of ``frame`` through its inverse kinematics; returns the new joints.  An
    unreachable pose raises ConsoleInputError and leaves the arm where it was."""
    if axis not in JOG_AXES:
        raise ConsoleInputError(f"jog: unknown axis {axis!r}; axes are {list(JOG_AXES)}")
    k = JOG_AXES.index(axis)
    for name, v in (("step", translate), ("turn", turn)):
        if not math.isfinite(v):
            raise ConsoleInputError(f"jog {name}: {v} is not finite; arm kept where it was")
    with state._lock:
        X_WF = frame_pose(state, frame, cell)
        name = state._active
        robot = state._robot(name)
        q0 = state._q[name]
        X_new = jogged_pose(robot.link_pose(q0), X_WF, k, translate=translate, turn=turn)
        q = state._solve_ik(robot, X_new, q0)
        state._q[name] = q
        hand = state._arm_moved(name)
        what = (f"{translate * 1e3:+g} mm along" if translate else f"{math.degrees(turn):+g} deg about")
        state._changed("; ".join(x for x in (f"jog: tool {what} {frame} {axis}", hand) if x))
        return q.copy()
