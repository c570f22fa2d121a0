"""Smith's 8-step procedure (Appendix A) answering INTERSECTED / CLEAR / MAYBE.

The steps, in the paper's order (the kernel is :func:`._kernels.procedure`):

1. ``REL = IVOLLOC * OBLOC`` — the relation of ``F(OB)`` to ``F(VOL)``;
2. ``D = dist(CS(VOL), REL * CS(OB))``;
3. ``D > RO(VOL) + RO(OB)``: the outer spheres do not overlap — CLEAR;
4. both ``RI`` defined and ``D < RI(VOL) + RI(OB)``: the inner spheres overlap — INTERSECTED;
5. ``COLLIDE(PO(OB), PO(VOL), REL) = no`` — CLEAR (skipped when ``PO(OB)`` is undefined);
6. ``COLLIDE(PI(OB), PI(VOL), REL) = yes`` — INTERSECTED (skipped when either is undefined);
7. ``COLLIDE(OB, PI(VOL), REL) = yes`` — INTERSECTED;
8. ``COLLIDE(OB, PO(VOL), REL) = no`` — CLEAR; else MAYBE.

The OCR of step 4 reads "D < RI (VOL) ♦ RI (OB)"; the "♦" is the "+" of step 3 (the sum of the
radii is what makes the inner balls overlap) — derived.  ``subdivide=True`` adds the
second-level tests the paper describes and SRI did not build (step 9 here): clipping ``OB``
against the labelled convex cells of the shell between ``PO(VOL)`` and ``PI(VOL)``
(:mod:`._cells`); what stays MAYBE after the depth limit is reported MAYBE.

Every definite answer is a proof about the test object (the guard's shape) given its bounding
volumes' guarantees (``PI ⊂ shape ⊂ PO``, ``RI`` ball ⊂ shape ⊂ ``RO`` ball, the same for the
obstacle), up to ``Tolerances.clip_plane``: touching counts as intersecting.  A curved obstacle
is clipped as its circumscribed polytope (:mod:`._curved`): CLEAR stays a proof about the curved
shape, INTERSECTED proves only that it comes within ``Obstacle.band`` of the test object.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np

from .._errors import ClipError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from ._guard import Guard
from ._kernels import procedure, procedure_many
from ._obstacle import Obstacle

__all__ = ["ClipStatus", "ClipResult", "ListResult", "check", "check_list", "check_many", "STEP_NAMES", "STATUS_CODES"]


class ClipStatus(enum.Enum):
    """The paper's three answers."""

    CLEAR = "clear"  # the paper's NO INTERSECTION
    INTERSECTED = "intersected"
    MAYBE = "maybe"  # the paper's MAYBE INTERSECTED


_CODES = {0: ClipStatus.CLEAR, 1: ClipStatus.INTERSECTED, 2: ClipStatus.MAYBE}

STEP_NAMES = {
    3: "outer spheres apart",
    4: "inner spheres overlap",
    5: "COLLIDE(PO(OB), PO(VOL)) = no",
    6: "COLLIDE(PI(OB), PI(VOL)) = yes",
    7: "COLLIDE(OB, PI(VOL)) = yes",
    8: "COLLIDE(OB, PO(VOL))",
    9: "second level: shell cells",
}
"""The step that decided (Appendix A numbering; 9 is the second level)."""


@dataclass(frozen=True)
class ClipResult:
    """One guard against one obstacle: ``status``; ``step`` (3–9, :data:`STEP_NAMES`)."""

    status: ClipStatus
    step: int

    @property
    def definite(self) -> bool:
        return self.status is not ClipStatus.MAYBE

    @property
    def reason(self) -> str:
        return STEP_NAMES[self.step]


@dataclass(frozen=True)
class ListResult:
    """One guard against an obstacle list ``OL``: the combined ``status``, the ``obstacle``
    index that decided it (``-1`` when CLEAR), and every obstacle's :class:`ClipResult`."""

    status: ClipStatus
    obstacle: int
    results: tuple[ClipResult, ...]


def _pose(X, what: str) -> np.ndarray:
    """``X`` as finite 4x4 rigid transforms (one, or a stack): a proper rotation (orthonormal, det +1:
    a reflection turns the guard inside out) and a last row ``0 0 0 1``; else a ClipError naming ``what``."""
    try:
        X = np.ascontiguousarray(np.eye(4) if X is None else X, dtype=np.float64)
    except (TypeError, ValueError):
        raise ClipError(f"{what}: expected finite 4x4 rigid transforms, got {type(X).__name__}") from None
    if X.ndim < 2 or X.shape[-2:] != (4, 4) or not np.all(np.isfinite(X)):
        raise ClipError(f"{what}: expected finite 4x4 rigid transforms, got shape {X.shape}")
    R = X[..., :3, :3]
    if not np.allclose(R @ np.swapaxes(R, -1, -2), np.eye(3), atol=1e-9):
        raise ClipError(f"{what}: the rotation part is not orthonormal")
    if np.any(np.linalg.det(R) < 0.0):
        raise ClipError(f"{what}: the rotation part is a reflection (det -1), not a rotation")
    if not np.allclose(X[..., 3, :], [0.0, 0.0, 0.0, 1.0], rtol=0.0, atol=1e-12):
        raise ClipError(f"{what}: the last row must be 0 0 0 1, got {X[..., 3, :].reshape(-1, 4)[0].tolist()}")
    return X


def _plane_tolerance(tol: Tolerances, *poses) -> float:
    """``Tolerances.clip_plane`` widened by the rounding of ``REL = IVOLLOC * OBLOC`` far from the origin
    (about 1e-16 of the poses' translations: at 1e8 m, 19 of 89 pairs penetrating by 10 nm were CLEAR
    under the fixed 1 nm).  Wider only errs towards INTERSECTED."""
    far = max((float(np.max(np.abs(X[..., :3, 3]), initial=0.0)) for X in poses), default=0.0)
    return tol.clip_plane + 16.0 * np.finfo(np.float64).eps * far


def check(
    guard: Guard,
    obstacle: Obstacle,
    X_W_VOL=None,
    X_W_OB=None,
    *,
    subdivide: bool = True,
    tol: Tolerances = DEFAULT_TOLERANCES,
) -> ClipResult:
    """Appendix A for one guard ``VOL`` posed at ``X_W_VOL`` (4x4, ``F(VOL)`` in W; default
    identity) and one obstacle posed at ``X_W_OB`` (``OBLOC``; default identity)."""
    if not isinstance(guard, Guard) or not isinstance(obstacle, Obstacle):
        raise ClipError(f"check: expected a Guard and an Obstacle, got {type(guard).__name__} and {type(obstacle).__name__}")
    Xv, Xo = _pose(X_W_VOL, "X_W_VOL"), _pose(X_W_OB, "X_W_OB")
    s, k = procedure(guard.pack(), Xv, obstacle.pack(), Xo, _plane_tolerance(tol, Xv, Xo), subdivide)
    return ClipResult(_CODES[int(s)], int(k))


def check_list(
    guard: Guard,
    obstacles,
    X_W_VOL=None,
    X_W_OB=None,
    *,
    subdivide: bool = True,
    tol: Tolerances = DEFAULT_TOLERANCES,
) -> ListResult:
    """The paper's loop over an obstacle list ``OL`` ("NEXTOB: if no more obstacles return NO
    INTERSECTION").  The paper returns at the first MAYBE; here the loop goes on after a MAYBE,
    so a later obstacle's INTERSECTED is not hidden behind it (INTERSECTED > MAYBE > CLEAR), and
    returns at the first INTERSECTED as the paper does.  ``X_W_OB`` is one pose for all, or a
    list of one pose per obstacle."""
    obstacles = list(obstacles)
    poses = [X_W_OB] * len(obstacles) if X_W_OB is None or np.ndim(X_W_OB) == 2 else list(X_W_OB)
    if len(poses) != len(obstacles):
        raise ClipError(f"check_list: {len(obstacles)} obstacles but {len(poses)} poses")
    results, first_maybe = [], -1
    for i, (ob, X) in enumerate(zip(obstacles, poses)):
        r = check(guard, ob, X_W_VOL, X, subdivide=subdivide, tol=tol)
        results.append(r)
        if r.status is ClipStatus.INTERSECTED:
            return ListResult(ClipStatus.INTERSECTED, i, tuple(results))
        if r.status is ClipStatus.MAYBE and first_maybe < 0:
            first_maybe = i
    if first_maybe >= 0:
        return ListResult(ClipStatus.MAYBE, first_maybe, tuple(results))
    return ListResult(ClipStatus.CLEAR, -1, tuple(results))


def check_many(
    guard: Guard,
    obstacle: Obstacle,
    X_W_VOL,
    X_W_OB=None,
    *,
    subdivide: bool = True,
    tol: Tolerances = DEFAULT_TOLERANCES,
) -> tuple[np.ndarray, np.ndarray]:
    """Appendix A for ``M`` guard poses ``X_W_VOL (M, 4, 4)`` against one posed obstacle, in
    one compiled loop.  Returns ``(status (M,) int8, step (M,) int8)``: status codes 0 CLEAR,
    1 INTERSECTED, 2 MAYBE (:data:`STATUS_CODES`)."""
    X = _pose(X_W_VOL, "X_W_VOL").reshape(-1, 4, 4)
    status = np.empty(len(X), dtype=np.int8)
    step = np.empty(len(X), dtype=np.int8)
    Xo = _pose(X_W_OB, "X_W_OB")
    procedure_many(guard.pack(), X, obstacle.pack(), Xo, _plane_tolerance(tol, X, Xo), subdivide, status, step)
    return status, step


STATUS_CODES = {v: k for k, v in _CODES.items()}
"""``ClipStatus -> int8`` code used by :func:`check_many`."""
