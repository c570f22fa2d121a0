"""Link bounding volumes (OBBs and OBPs posed in W) packed into the terrain kernels' rows.

A link is tested as one low-resolution volume (the JPL brief: "the model for each manipulator
link is one low-resolution OBP"): an :class:`armguard.geometry.Box` (an OBB) or an
:class:`armguard.geometry.Prism` (an OBP; with an even number of sides exactly the union of
``n_sides / 2`` OBBs, :meth:`Prism.as_boxes`).  :func:`bounding_box` gives an OBB for any other
shape.  The trigonometry of a prism's boxes and the row constants are computed here, once per
query, outside the division-free kernels.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from .._errors import TerrainError
from ..geometry import Box, ConvexPolyhedron, Prism, Shape
from ._kernels import ROW

__all__ = ["bounding_box", "link_volume", "union_box", "grown", "volume_boxes", "pack_rows", "pack_obbs", "local_obbs"]


def bounding_box(shape: Shape, margin: float = 0.0) -> Box:
    """An OBB in W containing ``shape`` grown by ``margin`` (m, >= 0).

    A Box is returned as it is (grown); otherwise the axes are the principal axes of the shape's
    core points (PCA, as :func:`armguard_analytic._engine._hulls.link_obbs` does for link hulls), the box
    spans their extent along those axes, grown by the core radius and ``margin``.  The result
    contains the shape exactly (a PCA fit only affects tightness)."""
    if margin < 0.0 or not np.isfinite(margin):
        raise TerrainError(f"bounding_box: margin must be finite and >= 0, got {margin!r}")
    if isinstance(shape, Box):
        return Box(shape.center, shape.half_extents + margin, shape.rotation)
    p = np.asarray(shape.core_points, dtype=np.float64)
    mean = p.mean(axis=0)
    if len(p) >= 3:
        _, R = np.linalg.eigh(np.cov((p - mean).T))
    else:  # a point or a segment: the segment's direction and any two normals to it
        d = p[-1] - p[0]
        R = np.eye(3)
        if float(d @ d) > 0.0:
            u = d / np.linalg.norm(d)
            a = np.eye(3)[int(np.argmin(np.abs(u)))]
            v = np.cross(u, a)
            v /= np.linalg.norm(v)
            R = np.stack([u, v, np.cross(u, v)], axis=1)
    if np.linalg.det(R) < 0.0:
        R[:, 0] = -R[:, 0]
    loc = (p - mean) @ R
    lo, hi = loc.min(axis=0), loc.max(axis=0)
    c = mean + R @ (0.5 * (lo + hi))
    h = 0.5 * (hi - lo) + float(shape.core_radius) + margin
    h = np.maximum(h, np.finfo(float).eps * (1.0 + float(np.max(np.abs(p)))))
    return Box(c, h, R)


def union_box(shapes: Sequence[Shape], margin: float = 0.0) -> Box:
    """An OBB in W containing every shape of ``shapes`` grown by ``margin`` (m): the PCA box of
    all their core points grown by the largest core radius (as :func:`bounding_box`)."""
    shapes = list(shapes)
    if len(shapes) == 1:
        return bounding_box(shapes[0], margin)
    pts = np.concatenate([np.asarray(s.core_points, dtype=np.float64) for s in shapes])
    r = max(float(s.core_radius) for s in shapes)
    return bounding_box(ConvexPolyhedron(pts), margin + r) if len(pts) >= 4 else bounding_box(shapes[0], margin + r)


def link_volume(shape: Shape) -> Shape:
    """The low-resolution volume of one link shape: a Box or a Prism as it is; a ConvexPolyhedron
    that is a right prism over a regular polygon with an even number of sides (an OBP written as a
    mesh, as the rover's URDF links are) as that :class:`Prism`, grown by the round-off of the
    fit so that it contains every vertex; anything else its :func:`bounding_box`."""
    if isinstance(shape, (Box, Prism)):
        return shape
    if isinstance(shape, ConvexPolyhedron):
        pr = _as_prism(np.asarray(shape.core_points, dtype=np.float64))
        if pr is not None:
            return pr
    return bounding_box(shape)


def _as_prism(v: np.ndarray) -> Prism | None:
    """The regular even prism whose vertices are ``v (2n, 3)`` (to 1e-9 of its size), or None."""
    m = len(v)
    if m < 8 or m % 4:
        return None
    c = v.mean(axis=0)
    p = v - c
    size = float(np.max(np.linalg.norm(p, axis=1)))
    eps = 1e-9 * max(size, 1.0)
    for z in np.linalg.eigh(p.T @ p)[1].T:  # the axis is one of the principal axes
        t = p @ z
        top = t > 0.0
        if top.sum() != m // 2 or np.ptp(t[top]) > eps or np.ptp(t[~top]) > eps:
            continue
        ring = p - np.outer(t, z)
        rad = np.linalg.norm(ring, axis=1)
        n = m // 2
        if np.ptp(rad) > eps or rad[0] <= eps:
            continue
        x = ring[0] / rad[0]
        y = np.cross(z, x)
        ang = np.sort(np.mod(np.arctan2(ring[top] @ y, ring[top] @ x), 2.0 * math.pi))
        step = 2.0 * math.pi / n
        if np.max(np.abs(np.diff(np.r_[ang, ang[0] + 2.0 * math.pi]) - step)) > 1e-7:
            continue
        a0 = ang[0] + 0.5 * step  # Prism's vertices sit at (k + 1/2) step from its first face normal
        R = np.stack([math.cos(a0) * x + math.sin(a0) * y, -math.sin(a0) * x + math.cos(a0) * y, z], axis=1)
        hl = 0.5 * float(t[top].mean() - t[~top].mean())
        apo = float(rad.mean()) * math.cos(math.pi / n)
        if n % 2:
            return None
        out = Prism(c + z * 0.5 * float(t[top].mean() + t[~top].mean()), R, apo, hl, n)
        w = np.asarray(out.core_points)
        dev = float(np.max(np.min(np.linalg.norm(v[:, None, :] - w[None, :, :], axis=2), axis=1)))
        if dev > 1e-7 * max(size, 1.0):
            return None
        return Prism(out.center, R, apo + 2.0 * dev + eps, hl + 2.0 * dev + eps, n)
    return None


def grown(volume: Shape, margin: float) -> Shape:
    """``volume`` (Box or Prism) with every face pushed out by ``margin`` (m): it contains the set
    of points within ``margin`` of the original volume."""
    if margin == 0.0:
        return volume
    if isinstance(volume, Box):
        return Box(volume.center, volume.half_extents + margin, volume.rotation)
    if isinstance(volume, Prism):
        return Prism(volume.center, volume.rotation, volume.apothem + margin, volume.half_length + margin, volume.n_sides)
    raise TerrainError(f"grown: expected a Box or a Prism, got {type(volume).__name__}")


def volume_boxes(volume: Shape) -> tuple[Box, ...]:
    """The OBBs whose union a link volume is, as Boxes: a Box itself, an even Prism's
    ``as_boxes()``, an odd Prism's bounding OBB (conservative).  Any other shape:
    :class:`TerrainError` (pass :func:`bounding_box` of it)."""
    return tuple(Box(c, h, R) for c, h, R in _obbs(volume, 0.0))


def _obbs(volume: Shape, margin: float) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """``(center, half_extents, R)`` of the OBBs of ``volume`` grown by ``margin`` (m), computed
    directly (no Box construction: this runs once per link per query)."""
    if isinstance(volume, Box):
        return [(volume.center, volume.half_extents + margin, volume.rotation)]
    if isinstance(volume, Prism):
        n = volume.n_sides
        if n % 2:
            b = bounding_box(volume, margin)
            return [(b.center, b.half_extents, b.rotation)]
        a = volume.apothem + margin
        h = np.array([a, a * math.tan(math.pi / n), volume.half_length + margin])
        out = []
        for j in range(n // 2):
            t = j * 2.0 * math.pi / n
            ct, st = math.cos(t), math.sin(t)
            Rz = np.array([[ct, -st, 0.0], [st, ct, 0.0], [0.0, 0.0, 1.0]])
            out.append((volume.center, h, volume.rotation @ Rz))
        return out
    raise TerrainError(
        f"a link volume must be an armguard.geometry.Box (OBB) or Prism (OBP), got {type(volume).__name__}; "
        "use armguard.terrain.bounding_box(shape)"
    )


def pack_rows(volumes: Sequence[Shape], margin: float, eps_par: float) -> tuple[np.ndarray, np.ndarray]:
    """Kernel rows for ``volumes`` grown by ``margin`` (m): ``rows (R, 36) float64`` (layout in
    ``_kernels``) and ``rstart (K + 1,) int64`` (link ``k``'s rows are ``rstart[k]:rstart[k+1]``)."""
    parts, rstart = [], [0]
    for v in volumes:
        parts.extend(_obbs(v, margin))
        rstart.append(len(parts))
    n = len(parts)
    c = np.array([p[0] for p in parts], dtype=np.float64).reshape(n, 3)
    h = np.array([p[1] for p in parts], dtype=np.float64).reshape(n, 3)
    R = np.array([p[2] for p in parts], dtype=np.float64).reshape(n, 3, 3)
    return pack_obbs(c, h, R, eps_par), np.array(rstart, dtype=np.int64)


def local_obbs(volume: Shape) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The OBBs of ``volume`` (Box / Prism, in its own frame) as ``(c (n, 3), h0 (n, 3), g (n, 3),
    R (n, 3, 3))``: box ``i`` of the volume grown by ``m`` has half extents ``h0[i] + m * g[i]``
    (``g = 1`` for a box; ``(1, tan(pi / n), 1)`` for an even prism's boxes, whose side grows with
    the apothem)."""
    parts = _obbs(volume, 0.0)
    c = np.array([p[0] for p in parts], dtype=np.float64)
    h = np.array([p[1] for p in parts], dtype=np.float64)
    R = np.array([p[2] for p in parts], dtype=np.float64)
    g = np.ones_like(h)
    if isinstance(volume, Prism) and volume.n_sides % 2 == 0:
        g[:, 1] = math.tan(math.pi / volume.n_sides)
    return c, h, g, R


def pack_obbs(c: np.ndarray, h: np.ndarray, R: np.ndarray, eps_par: float) -> np.ndarray:
    """Kernel rows ``(n, 36)`` of OBBs with centres ``c (n, 3)`` m, half extents ``h (n, 3)`` m and
    axes ``R (n, 3, 3)`` (columns), in W."""
    n = len(c)
    rows = np.empty((n, ROW))
    rows[:, 0:3] = c
    rows[:, 3:6] = h
    rows[:, 6:15] = R.reshape(n, 9)
    Q = np.abs(rows[:, 6:15]) + eps_par
    rows[:, 15:24] = Q
    Q = Q.reshape(n, 3, 3)
    rows[:, 24:27] = np.matmul(Q, h[:, :, None])[:, :, 0]  # E_i = sum_j h_j Q_ij
    C = rows[:, 27:36].reshape(n, 3, 3)  # a view: the link's radius along e_i x B_j
    C[:, :, 0] = h[:, 1, None] * Q[:, :, 2] + h[:, 2, None] * Q[:, :, 1]
    C[:, :, 1] = h[:, 0, None] * Q[:, :, 2] + h[:, 2, None] * Q[:, :, 0]
    C[:, :, 2] = h[:, 0, None] * Q[:, :, 1] + h[:, 1, None] * Q[:, :, 0]
    return rows
