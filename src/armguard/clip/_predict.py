"""WORKMATE's collision prediction: the guard swept over the next control interval.

Smith, §VI.B: "the goal is collision prediction: The detection algorithm is applied to points
lying ahead of the manipulator on its determined path"; the controller hands the subsystem a
future point of the trajectory and the subsystem answers "before the arm gets there".  Here the
subsystem checks the volume a guard sweeps over the interval ``[X0, X1]`` (its poses in W now and
at the next set point), so a collision *between* set points is not missed.

**Motion model and bound.** Between set points the guard's centre ``CS`` moves on the straight
segment and its orientation turns at a constant rate about a fixed axis (``R(t) = R0 exp(t ω)``,
``|ω| = θ``, the angle of ``R0ᵀ R1``; the set-point interpolation of a Cartesian controller).  A
point at offset ``r`` from ``CS`` is at ``p(t) = c(t) + R(t) r``; the chord point
``(1 - t) p(0) + t p(1)`` lies in ``conv(G(0) ∪ G(1))`` and differs from ``p(t)`` by the linear
interpolation error of ``R(t) r``, at most ``t (1 - t) / 2 · max |d²/dt² R(t) r| <= θ² ρ / 8`` with
``ρ`` the largest ``|r|`` over ``PO``'s vertices.  So every intermediate guard lies in the hull
of ``PO`` at both poses with every plane pushed out by ``δ = θ² ρ / 8`` (plus ``clip_plane``).  The
swept guard's inner volumes are those of the guard at ``X1`` (a hit on them is a collision at the
set point itself); its outer sphere is ``RO + |c(1) - c(0)|`` about ``c(1)``.

A motion that leaves this model (a joint-interpolated arm between set points) needs a larger
``δ``: pass ``growth`` (m), the farthest the motion strays from the model between two set points,
added to every plane.  MAYBE over an interval is refined by halving it (``max_halvings`` times, poses
interpolated by the model, each half's planes pushed out by the whole ``growth``: the model's pose at
a half's end is not where the real motion is); what is still MAYBE stays MAYBE.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from .._errors import ClipError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from .._values import number
from ..geometry import ConvexPolyhedron
from ._cells import build_cells
from ._guard import Guard
from ._procedure import ClipStatus, _pose, check

__all__ = ["swept_guard", "rotation_growth", "Predictor", "Prediction", "interpolate_pose", "DEFAULT_MAX_HALVINGS"]

DEFAULT_MAX_HALVINGS = 3
"""Halvings of a MAYBE control interval (at most 2³ sub-intervals) before MAYBE is final."""


def rotation_growth(guard: Guard, X0, X1) -> float:
    """``δ = θ² ρ / 8`` (m): the bound of the module docstring for ``X0 -> X1`` (each 4x4)."""
    R = X0[:3, :3].T @ X1[:3, :3]
    theta = float(np.linalg.norm(Rotation.from_matrix(R).as_rotvec()))
    verts = guard.outer.vertices if guard.outer is not None else None
    if verts is None:
        raise ClipError("rotation_growth: the guard has no outer vertices (a swept guard cannot be swept again)")
    rho = float(np.max(np.linalg.norm(verts - guard.cs, axis=1)))
    return theta * theta * rho / 8.0


def interpolate_pose(X0, X1, t: float, cs) -> np.ndarray:
    """The motion model's pose ``(4, 4)`` at fraction ``t`` of ``X0 -> X1``: the point ``cs``
    (``(3,)`` m in ``F(VOL)``, the guard's ``CS``) moves linearly, the rotation is slerped."""
    cs = np.asarray(cs, dtype=np.float64)
    rots = Rotation.from_matrix(np.stack([X0[:3, :3], X1[:3, :3]]))
    R = Slerp([0.0, 1.0], rots)([t]).as_matrix()[0]
    c0, c1 = X0[:3, :3] @ cs + X0[:3, 3], X1[:3, :3] @ cs + X1[:3, 3]
    c = (1.0 - t) * c0 + t * c1
    X = np.eye(4)
    X[:3, :3] = R
    X[:3, 3] = c - R @ cs
    return X


def swept_guard(guard: Guard, X0, X1, *, growth: float = 0.0, tol: Tolerances = DEFAULT_TOLERANCES) -> Guard:
    """The guard swept from ``X0`` to ``X1`` (``F(VOL)`` in W, 4x4 each), as a Guard in W.

    ``PO`` = hull of ``PO`` at both poses, planes pushed out by :func:`rotation_growth` +
    ``growth`` + ``clip_plane``; ``PI``, ``RI``, ``CS`` = the guard's at ``X1``; ``RO`` grown by
    the centre's travel; no shell cells (MAYBE is refined in time by :class:`Predictor`)."""
    X0, X1 = _pose(X0, "X0"), _pose(X1, "X1")
    growth = number(growth, "swept_guard: growth", ClipError, low=0.0, unit=" (m)")
    if guard.outer is None:
        raise ClipError("swept_guard: the guard has no outer vertices (a swept guard cannot be swept again)")
    V = guard.outer.vertices
    pts = np.vstack([V @ X0[:3, :3].T + X0[:3, 3], V @ X1[:3, :3].T + X1[:3, 3]])
    hull = ConvexPolyhedron(pts)
    delta = rotation_growth(guard, X0, X1) + growth + tol.clip_plane
    outer = np.array(hull.planes)
    outer[:, 3] += delta
    R1, t1 = X1[:3, :3], X1[:3, 3]
    inner = np.array(guard.inner_planes).reshape(-1, 4)
    if len(inner):
        n = inner[:, :3] @ R1.T
        inner = np.hstack([n, (inner[:, 3] + n @ t1)[:, None]])
    cs0 = X0[:3, :3] @ guard.cs + X0[:3, 3]
    cs1 = R1 @ guard.cs + t1
    ro = guard.ro + float(np.linalg.norm(cs1 - cs0)) + delta
    empty = build_cells(None, hull, cs1, 1.0, 0, tol.clip_plane)
    return Guard(outer, inner, cs1, ro, guard.ri, guard.inner_scale, empty, None, None, None)


@dataclass(frozen=True)
class Prediction:
    """The answer for one control interval: ``status``; the ``guard`` and ``obstacle`` indices
    that decided it (-1 when CLEAR); ``step`` of the deciding check (3–9; 0 when CLEAR over an
    empty list); ``t`` the fraction of the interval where the deciding sub-interval ends (the
    earliest set point known to collide for a sample hit)."""

    status: ClipStatus
    guard: int = -1
    obstacle: int = -1
    step: int = 0
    t: float = 1.0


class Predictor:
    """Collision prediction along a trajectory, one control interval ahead.

    ``guards``: list of :class:`Guard` (the arm's subvolumes ``1..k``, each in its own frame);
    ``obstacles``: list of :class:`Obstacle` (in W, or pairs ``(Obstacle, X_W_OB)``).
    :meth:`predict` answers for one interval; :meth:`step` takes the next set point's poses and
    answers for the interval from the previous one — call it before commanding the motion.
    """

    def __init__(
        self,
        guards,
        obstacles,
        *,
        max_halvings: int = DEFAULT_MAX_HALVINGS,
        growth: float = 0.0,
        tol: Tolerances = DEFAULT_TOLERANCES,
    ) -> None:
        self.guards = list(guards)
        self.obstacles = [(o, np.eye(4)) if not isinstance(o, tuple) else (o[0], _pose(o[1], "X_W_OB")) for o in obstacles]
        if isinstance(max_halvings, bool) or not isinstance(max_halvings, (int, np.integer)) or max_halvings < 0:
            raise ClipError(f"Predictor: max_halvings must be an integer >= 0, got {max_halvings!r}")
        g = number(growth, "Predictor: growth", ClipError, low=0.0, unit=" (m)")
        if not self.guards:
            raise ClipError("Predictor: no guard to check")
        self.max_halvings, self.growth, self.tol = int(max_halvings), g, tol
        self._last: np.ndarray | None = None  # the stream of :meth:`step`; :meth:`run` keeps its own
        self._stream = threading.Lock()

    def _poses(self, X) -> np.ndarray:
        X = _pose(X, "poses").reshape(-1, 4, 4)
        if len(X) != len(self.guards):
            raise ClipError(f"Predictor: {len(self.guards)} guards but {len(X)} poses")
        return X

    def predict(self, X_now, X_next) -> Prediction:
        """The interval from poses ``X_now`` to ``X_next`` (``(k, 4, 4)``, one per guard)."""
        X0, X1 = self._poses(X_now), self._poses(X_next)
        worst = Prediction(ClipStatus.CLEAR)
        for gi, g in enumerate(self.guards):
            for oi, (ob, X_ob) in enumerate(self.obstacles):
                r = self._interval(g, X0[gi], X1[gi], ob, X_ob, 0.0, 1.0, 0)
                if r[0] is ClipStatus.INTERSECTED:
                    return Prediction(r[0], gi, oi, r[1], r[2])
                if r[0] is ClipStatus.MAYBE and worst.status is ClipStatus.CLEAR:
                    worst = Prediction(r[0], gi, oi, r[1], r[2])
        return worst

    def _interval(self, g, X0, X1, ob, X_ob, ta, tb, level):
        """Check ``[ta, tb]`` of ``X0 -> X1``; returns ``(status, step, t)``."""
        Xa, Xb = interpolate_pose(X0, X1, ta, g.cs), interpolate_pose(X0, X1, tb, g.cs)
        at_end = check(g, ob, Xb, X_ob, tol=self.tol)  # the set point itself, with the second level
        if at_end.status is ClipStatus.INTERSECTED:
            return ClipStatus.INTERSECTED, at_end.step, tb
        # the whole growth on every piece: its ends are the model's poses, which the real motion may be growth off
        sw = check(swept_guard(g, Xa, Xb, growth=self.growth, tol=self.tol), ob, None, X_ob, subdivide=False, tol=self.tol)
        if sw.status is not ClipStatus.MAYBE or level >= self.max_halvings:
            return sw.status, sw.step, tb
        tm = 0.5 * (ta + tb)
        first = self._interval(g, X0, X1, ob, X_ob, ta, tm, level + 1)
        if first[0] is ClipStatus.INTERSECTED:
            return first
        second = self._interval(g, X0, X1, ob, X_ob, tm, tb, level + 1)
        if second[0] is ClipStatus.INTERSECTED:
            return second
        if first[0] is ClipStatus.MAYBE:
            return first
        return second

    def step(self, X_next) -> Prediction:
        """Feed the next set point's poses ``(k, 4, 4)``; the first call only records them (there
        is no interval yet) and answers for the set point itself.

        One Predictor holds one stream of set points: threads that share it take turns (a lock),
        each step checking the interval from the set point fed just before it.  Give each stream
        its own Predictor; :meth:`predict` and :meth:`run` hold no state and may be called from
        several threads at once."""
        X1 = self._poses(X_next).copy()  # the caller may reuse its buffer for the next set point
        with self._stream:
            X0 = X1 if self._last is None else self._last
            out = self.predict(X0, X1)
            self._last = X1  # after the answer: a step that raised leaves the stream as it was
            return out

    def run(self, poses) -> list[Prediction]:
        """One answer per interval of ``poses (T, k, 4, 4)`` (``T - 1``), as :meth:`step` would give
        from a fresh stream; the stream of :meth:`step` is left as it was."""
        poses = _pose(poses, "poses")
        if poses.ndim != 4 or len(poses) < 2:
            raise ClipError(f"Predictor.run: expected poses (T, k, 4, 4) with T >= 2 set points, got shape {poses.shape}")
        X = [self._poses(p) for p in poses]
        return [self.predict(a, b) for a, b in zip(X, X[1:])]
