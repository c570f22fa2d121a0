"""Free space along the sensor's rays: which rays contradict the map, and how high each cell may be.

A stereo point ``p`` seen from the sensor at ``o`` says two things: the terrain reaches ``p``, and
the segment from ``o`` to ``p`` crossed free space (light travelled along it).  The elevation map
(:class:`~armguard.terrain.ElevationMap`, a solid column per cell) uses the first; this module the
second, for two checks the points alone cannot make:

* **A ray under seen terrain** (stage 3 of :class:`~armguard.terrain.OutlierRule`): a ray that
  crosses a cell more than ``OutlierRule.ray`` below that cell's lowest point went through the
  ground that other rays saw; its point lies beyond a surface (a stereo mismatch that put it too
  far) and is dropped (its cell is then unknown, never lower than its points were).  A point too far along its ray lands *below* the terrain of its cell: the
  per-cell maximum keeps such a cell known, and too low, where it is the cell's only point.
* **A cell whose top was not seen** (:class:`Carving`): a cell's column can reach no higher than
  the rays that crossed it without stopping.  A cell whose surviving points lie far below that
  bound (``Carving.gap``) holds something between them and the rays that no ray met -- a point too
  far along its ray alone in its cell, a slot or a pole narrower than the rays' spacing -- and is
  treated as unseen (a hole, filled, never below its points).  Where no ray crossed a cell (the
  far edge of what the camera saw, a face seen at the image's border) nothing bounds it: its
  points' height stands, as without the sensor's position.

The segment used stops short of its point by ``margin + range_margin * range**2`` (the depth noise
of stereo grows with the square of the range): the last stretch of a noisy ray proves nothing.
A cell's bound is the ``votes``-th lowest crossing (not the lowest: one stray ray does not carve a
cell).  The walk over the cells is Amanatides & Woo's grid traversal (1987) of the segment's
projection on the grid, after Liang & Barsky's clip (1984) to the grid's rectangle; within a cell
the segment's lowest point is at its entry or its exit (a segment is straight).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from .._errors import TerrainError

__all__ = ["Carving", "ray_lows", "rays_under"]


def _field(obj, cls: str, name: str, low, integer: bool, inf_ok: bool) -> None:
    """``obj.name`` checked: an int >= ``low`` (``integer``), else a number >= ``low`` (> 0 where
    ``low`` is 0.0 and ``inf_ok``: a tolerance), ``inf`` only with ``inf_ok``; else a TerrainError."""
    v = getattr(obj, name)
    if integer:
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < low:
            raise TerrainError(f"{cls}.{name}: expected an integer >= {low}, got {v!r}")
        return
    try:
        x = float(v)
    except (TypeError, ValueError):
        raise TerrainError(f"{cls}.{name}: expected a number, got {v!r}") from None
    ok = (x > low if inf_ok else x >= low) and (np.isfinite(x) or (inf_ok and x == np.inf))
    if isinstance(v, bool) or not ok:
        what = "> 0 (inf: off)" if inf_ok else f">= {low:g}, finite"
        raise TerrainError(f"{cls}.{name}: expected a number {what}, got {v!r}")


@dataclass(frozen=True)
class Carving:
    """How :meth:`ElevationMap.from_points` reads the rays' free space (given a sensor position).

    Attributes
    ----------
    margin : float, m
        Each ray's segment stops this far before its point (besides ``range_margin``).
    range_margin : float, 1/m
        ... and ``range_margin * range**2`` more (``0.006``: three times the depth noise
        ``0.002 z**2`` of the shipped clouds, ``reference/terrain/README.md``).
    votes : int
        A cell's bound is the ``votes``-th lowest crossing of it (``inf`` with fewer crossings).
    gap : float, m
        A cell whose highest point lies more than ``gap`` below its bound was not seen on top: it is
        treated as unseen (filled, and never lower than its highest point).
    """

    margin: float = 0.05
    range_margin: float = 0.006
    votes: int = 2
    gap: float = 0.15

    def __post_init__(self) -> None:
        for name, low, ints, inf_ok in (("margin", 0.0, False, False), ("range_margin", 0.0, False, False),
                                        ("votes", 1, True, False), ("gap", 0.0, False, True)):
            _field(self, "Carving", name, low, ints, inf_ok)


@njit(cache=True)
def _clip(ax, ay, dx, dy, x_lo, y_lo, x_hi, y_hi):  # pragma: no cover - compiled
    """Liang & Barsky: the parameter range ``[t0, t1]`` of ``a + t d`` (t in [0, 1]) inside the
    rectangle, ``t0 > t1`` when none."""
    t0, t1 = 0.0, 1.0
    for p, q in ((-dx, ax - x_lo), (dx, x_hi - ax), (-dy, ay - y_lo), (dy, y_hi - ay)):
        if p == 0.0:
            if q < 0.0:
                return 1.0, 0.0
        else:
            r = q / p
            if p < 0.0:
                t0 = max(t0, r)
            else:
                t1 = min(t1, r)
    return t0, t1


@njit(cache=True, inline="always")
def _axis(o, d, lo, i, cell):  # pragma: no cover - compiled
    """Along one grid axis: the step (+1, -1, 0), the parameter of the first cell boundary crossed
    from cell ``i`` and the parameter between boundaries (Amanatides & Woo's tMax, tDelta)."""
    if d > 0.0:
        return 1, (lo + (i + 1) * cell - o) / d, cell / d
    if d < 0.0:
        return -1, (lo + i * cell - o) / d, -cell / d
    return 0, np.inf, np.inf


@njit(cache=True)
def _walk(o, p, stop, x0, y0, cell, nx, ny, rows, cols, zmins):  # pragma: no cover - compiled
    """The cells the segment from ``o`` towards ``p`` (stopped ``stop`` m before ``p``) crosses, in
    order: fills ``rows``, ``cols`` and the segment's lowest height in each, returns how many."""
    vx, vy, vz = p[0] - o[0], p[1] - o[1], p[2] - o[2]
    length = np.sqrt(vx * vx + vy * vy + vz * vz)
    if not length > stop:
        return 0
    s = (length - stop) / length
    dx, dy, dz = vx * s, vy * s, vz * s
    t, t1 = _clip(o[0], o[1], dx, dy, x0, y0, x0 + nx * cell, y0 + ny * cell)
    if not t < t1:
        return 0
    x, y = o[0] + t * dx, o[1] + t * dy
    col = min(max(int(np.floor((x - x0) / cell)), 0), nx - 1)
    row = min(max(int(np.floor((y - y0) / cell)), 0), ny - 1)
    step_x, t_x, dt_x = _axis(o[0], dx, x0, col, cell)
    step_y, t_y, dt_y = _axis(o[1], dy, y0, row, cell)
    n = 0
    while n < len(rows):
        t_out = min(t_x, t_y, t1)
        rows[n], cols[n] = row, col
        zmins[n] = o[2] + min(t * dz, t_out * dz)  # the lower of the entry and the exit
        n += 1
        if t_out >= t1:
            break
        if t_x <= t_y:
            col += step_x
            t_x += dt_x
        else:
            row += step_y
            t_y += dt_y
        if col < 0 or col >= nx or row < 0 or row >= ny:
            break
        t = t_out
    return n


@njit(cache=True)
def _rays_under(o, pts, stops, x0, y0, cell, nx, ny, hmax, tol):  # pragma: no cover - compiled
    n_pts = pts.shape[0]
    out = np.zeros(n_pts, np.bool_)
    cap = nx + ny + 4
    rows, cols, zmins = np.empty(cap, np.int64), np.empty(cap, np.int64), np.empty(cap)
    for i in range(n_pts):
        k = _walk(o[i], pts[i], stops[i], x0, y0, cell, nx, ny, rows, cols, zmins)
        for j in range(k):
            if zmins[j] < hmax[rows[j], cols[j]] - tol:
                out[i] = True
                break
    return out


@njit(cache=True)
def _ray_lows(o, pts, stops, use, x0, y0, cell, nx, ny, lows):  # pragma: no cover - compiled
    cap = nx + ny + 4
    rows, cols, zmins = np.empty(cap, np.int64), np.empty(cap, np.int64), np.empty(cap)
    votes = lows.shape[0]
    for i in range(pts.shape[0]):
        if not use[i]:
            continue
        k = _walk(o[i], pts[i], stops[i], x0, y0, cell, nx, ny, rows, cols, zmins)
        for j in range(k):
            r, c, z = rows[j], cols[j], zmins[j]
            if z < lows[votes - 1, r, c]:  # insert into the sorted `votes` lowest of the cell
                m = votes - 1
                while m > 0 and lows[m - 1, r, c] > z:
                    lows[m, r, c] = lows[m - 1, r, c]
                    m -= 1
                lows[m, r, c] = z


def _stops(o: np.ndarray, pts: np.ndarray, carving: Carving) -> np.ndarray:
    rng2 = np.einsum("ij,ij->i", pts - o, pts - o)
    return carving.margin + carving.range_margin * rng2


def rays_under(o_W, points_W, grid, hmax, tol: float, carving: Carving) -> np.ndarray:
    """``(N,) bool``: the points whose ray (from ``o_W (N, 3)``, stopped as ``carving`` says)
    crosses a cell more than ``tol`` below ``hmax (ny, nx)`` (the cells' lowest points; ``-inf``:
    no point there, never crossed under).
    ``grid``: ``(x0, y0, cell, nx, ny)``."""
    x0, y0, cell, nx, ny = grid
    o, p = np.ascontiguousarray(o_W, np.float64), np.ascontiguousarray(points_W, np.float64)
    if len(p) == 0:
        return np.zeros(0, bool)
    return _rays_under(o, p, _stops(o, p, carving), float(x0), float(y0), float(cell), int(nx), int(ny),
                       np.ascontiguousarray(hmax, np.float64), float(tol))


def ray_lows(o_W, points_W, use, grid, carving: Carving) -> np.ndarray:
    """``(ny, nx)`` m: per cell, the ``carving.votes``-th lowest height at which a used ray
    crossed it (``inf`` where fewer did): the column of that cell is no higher."""
    x0, y0, cell, nx, ny = grid
    votes = int(carving.votes)
    lows = np.full((votes, int(ny), int(nx)), np.inf)
    o, p = np.ascontiguousarray(o_W, np.float64), np.ascontiguousarray(points_W, np.float64)
    if len(p):
        _ray_lows(o, p, _stops(o, p, carving), np.ascontiguousarray(use, np.bool_), float(x0), float(y0),
                  float(cell), int(nx), int(ny), lows)
    return lows[votes - 1]
