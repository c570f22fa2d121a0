"""The shell between a guard's outer and inner polyhedra as a tree of labelled convex cells.

Smith (Appendix A): "Further testing could be implemented by subdividing the volume between
PO(VOL) and PI(VOL) into convex subvolumes, and clipping OB against them.  The subdivision is
performed just once, when the model of VOL is defined."  This module performs it.

Level 1: one cell per outer face ``f`` — the frustum between ``f`` and the matching face of the
inner polytope.  ``PI(VOL)`` is ``PO(VOL)`` shrunk about the centre ``c`` by a factor ``s``, so
the cell is the cone from ``c`` over ``f`` cut by ``f``'s plane and the inner face's plane: a
convex polytope, and the cells tile ``PO \\ int(PI)`` exactly.

Every cell is labelled against the test object ``T`` (the guarded convex shape):

* INSIDE — every vertex of the cell is in ``T`` (within ``Tolerances.clip_plane``); ``T`` is
  convex, so the whole cell is: an obstacle meeting the cell meets ``T``;
* OUTSIDE — a plane separates the cell from ``T`` by more than ``clip_plane`` (the cell's own
  planes, the direction from ``T``'s core to the cell, or the supporting plane it was cut off
  by; ``_guard._Body.label``);
* MIXED — neither.  A MIXED cell is split (below) and its pieces labelled in turn, down to
  ``max_depth`` splits; a MIXED leaf is what leaves an answer MAYBE.

A MIXED cell is split into: (a) the part beyond the supporting plane of ``T`` whose normal
``n`` is ``T``'s surface normal where the ray from ``c`` through the cell's centroid leaves
``T`` — OUTSIDE by construction; (b) the deepest slab of the rest below a plane of normal ``n``
whose vertices all lie in ``T`` (the plane found by bisection; containment is monotone in the
plane's offset) — INSIDE; (c) the rest, bisected across its longest principal axis.  The
pieces cover the cell (they share their cutting planes), which is all a CLEAR answer needs.

Arrays are in the guard's frame ``F(VOL)``, metres.  Planes are ``[n, d]`` rows, unit outward
``n``, inside ``n . x <= d`` (as ``armguard.geometry``).
"""

from __future__ import annotations

import enum

import numpy as np

__all__ = ["CellKind", "CellTree", "build_cells"]

_SLAB_HALVINGS = 12
"""Bisection steps for the INSIDE slab's offset: it ends within 1/4096 of the deepest one."""


class CellKind(enum.IntEnum):
    """Label of a shell cell against the test object (the integer codes the kernel reads)."""

    INSIDE = 0
    OUTSIDE = 1
    MIXED = 2


class CellTree:
    """Flat arrays of the cell tree (all in ``F(VOL)``, m).

    ``planes (P, 4)``: cell ``i``'s planes are ``planes[off[i]:off[i + 1]]``; ``probe (C, 3)`` a
    point of each cell (its vertex centroid); ``kind (C,) int8`` (:class:`CellKind`);
    ``child_off (C + 1,)``/``child_idx`` the children of cell ``i``; ``roots`` the level-1
    cells; ``vertices`` a list of each cell's ``(n_i, 3)`` vertices (for plots and tests);
    ``depth (C,) int64`` the number of splits above each cell.
    """

    def __init__(self) -> None:
        self._planes: list[np.ndarray] = []
        self.vertices: list[np.ndarray] = []
        self._kind: list[int] = []
        self._children: list[list[int]] = []
        self._depth: list[int] = []
        self.roots_list: list[int] = []

    def add(self, planes: np.ndarray, vertices: np.ndarray, kind: int, depth: int) -> int:
        self._planes.append(np.asarray(planes, dtype=np.float64).reshape(-1, 4))
        self.vertices.append(np.asarray(vertices, dtype=np.float64))
        self._kind.append(int(kind))
        self._children.append([])
        self._depth.append(depth)
        return len(self._kind) - 1

    def freeze(self) -> None:
        n = len(self._kind)
        sizes = [len(p) for p in self._planes]
        self.off = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        self.planes = np.vstack(self._planes) if n else np.zeros((0, 4))
        self.probe = np.array([v.mean(axis=0) for v in self.vertices]).reshape(-1, 3)
        self.kind = np.array(self._kind, dtype=np.int8)
        self.depth = np.array(self._depth, dtype=np.int64)
        csz = [len(c) for c in self._children]
        self.child_off = np.concatenate([[0], np.cumsum(csz)]).astype(np.int64)
        self.child_idx = np.array([i for c in self._children for i in c], dtype=np.int64)
        self.roots = np.array(self.roots_list, dtype=np.int64)

    def __len__(self) -> int:
        return len(self._kind)

    def counts(self) -> dict[str, int]:
        """Leaf cells by label (a MIXED cell with children is not a leaf)."""
        out = {k.name: 0 for k in CellKind}
        for i, k in enumerate(self._kind):
            if not self._children[i]:
                out[CellKind(k).name] += 1
        return out


def split(vertices: np.ndarray, m: np.ndarray, delta: float, tiny: float, prune: bool = True):
    """Split the convex hull of ``vertices (V, 3)`` by the plane ``m . x = delta`` (unit ``m``).

    Returns ``(below, above)`` vertex sets ``(n, 3)`` (``None`` for an empty side): each side's
    vertices, plus the plane's crossings of every straddling *pair* of vertices (every edge is a
    pair, so the hull of the result is exactly that side of the hull; extra points lie inside).
    ``tiny`` (m): a side whose vertices are all within it of the plane is empty.  ``prune``
    keeps only each side's extreme points (its hull's vertices).
    """
    f = vertices @ m - delta
    lo, hi = f <= 0.0, f >= 0.0
    ia, ib = np.nonzero(f < 0.0)[0], np.nonzero(f > 0.0)[0]
    cross = np.zeros((0, 3))
    if len(ia) and len(ib):
        fa, fb = f[ia][:, None], f[ib][None, :]
        t = (fa / (fa - fb))[..., None]
        cross = (vertices[ia][:, None, :] + t * (vertices[ib][None, :, :] - vertices[ia][:, None, :])).reshape(-1, 3)
    below = np.vstack([vertices[lo], cross]) if np.any(f < -tiny) else None
    above = np.vstack([vertices[hi], cross]) if np.any(f > tiny) else None
    if prune:
        below = _dedupe(below, tiny) if below is not None else None
        above = _dedupe(above, tiny) if above is not None else None
    return below, above


def _dedupe(p: np.ndarray, tiny: float) -> np.ndarray:
    """The extreme points of ``p`` (its hull's vertices; all of ``p`` when the hull is flat)."""
    from scipy.spatial import ConvexHull, QhullError

    if len(p) < 2:
        return p
    _, idx = np.unique(np.round(p / tiny).astype(np.int64), axis=0, return_index=True)
    p = p[np.sort(idx)]
    if len(p) > 4:
        try:
            p = p[np.sort(ConvexHull(p).vertices)]
        except (QhullError, ValueError):  # flat: no interior to drop
            pass
    return p


def frustum(face_vertices: np.ndarray, plane: np.ndarray, c: np.ndarray, s: float):
    """Level-1 cell: the frustum between an outer face and its image under ``x -> c + s (x - c)``.

    ``face_vertices (m, 3)`` the face loop, ``plane (4,)`` its outward ``[n, d]``, ``c (3,)`` the
    centre (inside the polytope), ``s`` in (0, 1).  Returns ``(planes (m + 2, 4), vertices
    (2m, 3))``: the outer plane, the inner plane (flipped) and one plane through ``c`` and each
    edge, all outward.
    """
    n, d = plane[:3], float(plane[3])
    h = d - float(n @ c)
    rows = [np.r_[n, d], np.r_[-n, -(float(n @ c) + s * h)]]
    g = face_vertices.mean(axis=0)
    k = len(face_vertices)
    for i in range(k):
        a, b = face_vertices[i], face_vertices[(i + 1) % k]
        m = np.cross(a - c, b - c)
        nm = np.linalg.norm(m)
        if nm == 0.0:  # pragma: no cover - c is strictly inside, faces are non-degenerate
            continue
        m = m / nm
        if m @ (g - c) > 0.0:
            m = -m
        rows.append(np.r_[m, float(m @ c)])
    verts = np.vstack([face_vertices, c + s * (face_vertices - c)])
    return np.array(rows), verts


def _principal_axis(v: np.ndarray) -> np.ndarray:
    x = v - v.mean(axis=0)
    _, _, vt = np.linalg.svd(x, full_matrices=False)
    return vt[0]


def build_cells(body, outer, c: np.ndarray, s: float, max_depth: int, tol: float) -> CellTree:
    """The cell tree of the shell between ``outer`` (a ConvexPolyhedron in ``F(VOL)``) and its
    shrink by ``s`` about ``c``, labelled against ``body`` (a ``_guard._Body``); ``tol`` is
    ``Tolerances.clip_plane`` (m).  ``s >= 1`` gives an empty tree (no shell)."""
    tree = CellTree()
    if s < 1.0:
        for f, face in enumerate(outer.faces):
            planes, verts = frustum(outer.vertices[face], outer.planes[f], c, s)
            i = _labelled(tree, body, planes, verts, 0, tol)
            tree.roots_list.append(i)
            _refine(tree, body, i, c, max_depth, tol)
    tree.freeze()
    return tree


def _labelled(tree: CellTree, body, planes, verts, depth: int, tol: float, kind: int | None = None) -> int:
    if kind is None:
        kind = body.label(verts, planes, tol)
    return tree.add(planes, verts, kind, depth)


def _refine(tree: CellTree, body, i: int, c: np.ndarray, max_depth: int, tol: float) -> None:
    if tree._kind[i] != CellKind.MIXED or tree._depth[i] >= max_depth:
        return
    planes, verts, depth = tree._planes[i], tree.vertices[i], tree._depth[i] + 1
    tiny = tol
    kids: list[int] = []
    rest_p, rest_v = planes, verts
    u = verts.mean(axis=0) - c
    if np.linalg.norm(u) > tiny:
        n = body.normal_toward(u / np.linalg.norm(u))
        h = body.support(n) + tol
        # (a) beyond the supporting plane n . x = h(n): OUTSIDE by construction
        below, above = split(rest_v, n, h, tiny)
        if above is not None:
            kids.append(_labelled(tree, body, np.vstack([rest_p, np.r_[-n, -h]]), above, depth, tol, CellKind.OUTSIDE))
        if below is None:
            rest_v = None
        else:
            rest_p, rest_v = np.vstack([rest_p, np.r_[n, h]]), below
        # (b) the deepest slab below a plane of normal n whose vertices are all inside T
        if rest_v is not None:
            lo, hi = float(np.min(rest_v @ n)), h
            best = None
            for _ in range(_SLAB_HALVINGS):
                mid = 0.5 * (lo + hi)
                sub, _ = split(rest_v, n, mid, tiny, prune=False)  # extra inner points: same label
                if sub is not None and body.all_inside(sub, tol):
                    best, lo = (mid, sub), mid
                else:
                    hi = mid
            if best is not None:
                tau, _ = best
                sub, _ = split(rest_v, n, tau, tiny)
                kids.append(_labelled(tree, body, np.vstack([rest_p, np.r_[n, tau]]), sub, depth, tol, CellKind.INSIDE))
                _, top = split(rest_v, n, tau, tiny)
                if top is None:
                    rest_v = None
                else:
                    rest_p, rest_v = np.vstack([rest_p, np.r_[-n, -tau]]), top
    # (c) bisect the rest across its longest principal axis
    if rest_v is not None:
        if len(rest_v) >= 4:
            a = _principal_axis(rest_v)
            mid = float(rest_v.mean(axis=0) @ a)
            lo_v, hi_v = split(rest_v, a, mid, tiny)
            parts = [(np.vstack([rest_p, np.r_[a, mid]]), lo_v), (np.vstack([rest_p, np.r_[-a, -mid]]), hi_v)]
        else:  # pragma: no cover - a cell of volume has at least four vertices
            parts = [(rest_p, rest_v)]
        for p, v in parts:
            if v is not None:
                kids.append(_labelled(tree, body, p, v, depth, tol))
    tree._children[i] = kids
    for k in kids:
        _refine(tree, body, k, c, max_depth, tol)
