"""The terrain as a multi-resolution pyramid of OBBs, tested coarse-to-fine (the JPL brief, seed ``002``).

"At the highest level of the pyramid (coarsest resolution) there is a single terrain OBB that
encloses all of the sensed data points [...] each level is characterized by twice the horizontal
spatial resolution of the level above it [...] If no collisions between any of the OBPs and the
coarsest-resolution terrain OBB are detected, then there is no need for further computation [...]
This process continues to successively finer levels of resolution until the finest resolution is
reached or no more collisions are detected."  (Leger, NPO-30356, Figure 2.)

Level ``L - 1`` (the finest) has one box per map cell: the cell's solid column, from the map's
floor to the cell's height.  Each level above merges 2 x 2 blocks of the level below (a block at
the grid's edge may hold fewer), its box tight on the blocks' heights (top: their highest cell;
bottom: the floor) and grown by ``Tolerances.terrain_margin`` per level so that round-off cannot
make a parent miss what a child hits.  Level 0 is one box over the whole map.  The terrain boxes
are axis-aligned in W (the map's grid is), so each test is the 15-axis SAT specialised to an
axis-aligned box, with no division, square root or transcendental (``_kernels``).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from .._errors import TerrainError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from ..geometry import Box, Shape, distance
from ._kernels import descend, flat_hits
from ._map import ElevationMap
from ._volumes import pack_rows

__all__ = ["TerrainPyramid", "TerrainStatus", "TerrainResult", "PyramidLevel"]

_MAX_LINKS = 63  # links per kernel call: one bit each in an int64 mask


class TerrainStatus(enum.Enum):
    """Verdict of a terrain check."""

    HIT = "hit"  # a finest-level box (exact mode: a cell column, by exact distance) is within reach
    CLEAR = "clear"  # proven clear: some level's boxes miss every link (exact mode: every candidate too)


@dataclass(frozen=True)
class PyramidLevel:
    """One level of the pyramid: ``boxes (ny * nx, 6) float64, m`` rows ``[c_W (3), h (3)]`` in
    row-major ``(ny, nx)`` order, a view into the pyramid's flat array; ``block`` the cells per box
    side (``2 ** (L - 1 - level)``)."""

    ny: int
    nx: int
    block: int
    boxes: np.ndarray = field(repr=False)


@dataclass(frozen=True)
class TerrainResult:
    """The outcome of :meth:`TerrainPyramid.check`.

    Attributes
    ----------
    status : TerrainStatus
    level : int
        The level that decided: the finest level (``n_levels - 1``) for HIT (and for an exact-mode
        CLEAR whose candidates were all refuted there), else the deepest level reached, where every
        box tested missed.
    boxes_tested : int
        Terrain boxes visited (each tested against the links that hit its parent).
    tests : int
        Box-versus-link-volume tests run (an OBP counts once).
    tests_per_level : (n_levels,) int64
    cells_hit : (m, 2) int64
        ``(row, col)`` of the finest-level boxes hit by at least one link volume.
    links_hit : (K,) bool
        Links whose volume hits some finest-level box.
    hit_unknown : bool
        Some hit cell is an unknown (filled) cell of the map.
    min_distance : float or None, m
        Exact mode only: the least exact signed distance between a link's shape and a hit cell's
        column (``inf`` if no cell was a candidate).  It is the terrain distance whenever it is at
        most ``clearance``; otherwise the terrain is farther than ``clearance`` from every link.
    nearest : (int, int, int) or None
        Exact mode: ``(link, row, col)`` of that minimum.
    truncated : bool
        ``first=True`` stopped at the first finest-level hit (``cells_hit`` holds only it).
    link_known, link_unknown : (K,) float64 or None, m
        Exact mode only: per link, the least exact distance to a candidate cell that is known
        (seen) / unknown (filled), ``inf`` where the link has no such candidate.  A link's terrain
        distance is the smaller of the two whenever that is at most ``clearance``.
    cell_known, cell_unknown : (K, 2) int64 or None
        Exact mode: ``(row, col)`` of those minima (``-1`` where none).
    cell_links : (m, K) bool or None
        Which links hit each cell of ``cells_hit`` (None from :meth:`TerrainPyramid.check_flat`).
    """

    status: TerrainStatus
    level: int
    boxes_tested: int
    tests: int
    tests_per_level: np.ndarray = field(repr=False)
    cells_hit: np.ndarray = field(repr=False)
    links_hit: np.ndarray = field(repr=False)
    hit_unknown: bool = False
    min_distance: float | None = None
    nearest: tuple[int, int, int] | None = None
    truncated: bool = False
    link_known: np.ndarray | None = field(default=None, repr=False)
    link_unknown: np.ndarray | None = field(default=None, repr=False)
    cell_known: np.ndarray | None = field(default=None, repr=False)
    cell_unknown: np.ndarray | None = field(default=None, repr=False)
    cell_links: np.ndarray | None = field(default=None, repr=False)


class TerrainPyramid:
    """The OBB pyramid of an :class:`ElevationMap` (see the module docstring).

    Attributes
    ----------
    map : ElevationMap
    levels : list[PyramidLevel]
        ``levels[0]`` one box over the map, ``levels[-1]`` one box per cell.
    boxes : (total, 6) float64, m
        Every level's boxes concatenated (level 0 first), as the kernels take them.
    offsets : (n_levels + 1,) int64
        Level ``l`` is ``boxes[offsets[l]:offsets[l + 1]]``.
    """

    def __init__(self, elevation: ElevationMap, *, tol: Tolerances = DEFAULT_TOLERANCES) -> None:
        if not isinstance(elevation, ElevationMap):
            raise TerrainError(f"TerrainPyramid: expected an ElevationMap, got {type(elevation).__name__}")
        self.map = elevation
        self.tol = tol
        h = elevation.heights
        ny, nx = h.shape
        c, (x0, y0), fl = elevation.cell, elevation.origin, elevation.floor
        n_levels = 1 + int(np.ceil(np.log2(max(nx, ny)))) if max(nx, ny) > 1 else 1
        tops = [h]  # finest first while building
        while tops[-1].shape != (1, 1):
            t = tops[-1]
            py, px = (-t.shape[0]) % 2, (-t.shape[1]) % 2
            t = np.pad(t, ((0, py), (0, px)), constant_values=-np.inf)
            tops.append(t.reshape(t.shape[0] // 2, 2, t.shape[1] // 2, 2).max(axis=(1, 3)))
        assert len(tops) == n_levels
        levels, parts = [], []
        for depth, top in enumerate(tops):  # depth 0: the finest
            b = 2**depth
            ly, lx = top.shape
            iy, ix = np.meshgrid(np.arange(ly), np.arange(lx), indexing="ij")
            xlo, xhi = x0 + c * ix * b, x0 + c * np.minimum((ix + 1) * b, nx)
            ylo, yhi = y0 + c * iy * b, y0 + c * np.minimum((iy + 1) * b, ny)
            grow = depth * tol.terrain_margin
            box = np.stack([0.5 * (xlo + xhi), 0.5 * (ylo + yhi), 0.5 * (fl + top),
                            0.5 * (xhi - xlo) + grow, 0.5 * (yhi - ylo) + grow, 0.5 * (top - fl) + grow], axis=-1)
            parts.append(box.reshape(-1, 6))
            levels.append((ly, lx, b))
        parts.reverse()
        levels.reverse()
        self.boxes = np.ascontiguousarray(np.concatenate(parts), dtype=np.float64)
        self.offsets = np.cumsum([0] + [len(p) for p in parts]).astype(np.int64)
        self.level_nx = np.array([lv[1] for lv in levels], np.int64)
        self.level_ny = np.array([lv[0] for lv in levels], np.int64)
        self.levels = [PyramidLevel(ly, lx, b, self.boxes[self.offsets[i]:self.offsets[i + 1]])
                       for i, (ly, lx, b) in enumerate(levels)]
        self.boxes.flags.writeable = False

    @property
    def n_levels(self) -> int:
        return len(self.levels)

    def __repr__(self) -> str:
        ny, nx = self.map.shape
        return f"TerrainPyramid({ny}x{nx} cells of {self.map.cell:g} m, {self.n_levels} levels, {len(self.boxes)} boxes)"

    def cell_box(self, row: int, col: int) -> Box:
        """The exact solid column of cell ``(row, col)`` as an :class:`armguard.geometry.Box`
        (a zero-height column gets the thickness ``Tolerances.length``)."""
        lo, hi = self.map.cell_bounds(row, col)
        half = np.maximum(0.5 * (hi - lo), self.tol.length)
        return Box(0.5 * (lo + hi), half)

    # ----------------------------------------------------------------------------- queries
    def check(self, volumes: Sequence[Shape], *, shapes: Sequence[Shape] | None = None, exact: bool = False,
              clearance: float = 0.0, first: bool = False) -> TerrainResult:
        """Coarse-to-fine check of link volumes against the terrain.

        Parameters
        ----------
        volumes : sequence of Box / Prism, posed in W (m)
            One low-resolution bounding volume per link (OBB or OBP; see
            :func:`armguard.terrain.bounding_box` for other shapes).
        shapes : sequence of Shape, optional
            Exact mode: each link's exact shape in W, contained in its volume (default: the volumes).
        exact : bool
            Confirm the finest-level hits with :func:`armguard.geometry.distance` between the link's
            shape and the cell's column, and return the least distance.
        clearance : float, m, >= 0
            Volumes are grown by this much, so the verdict is "within ``clearance``"; in exact mode
            HIT means some exact distance is at most ``clearance``.
        first : bool
            Stop at the first finest-level hit (the fastest yes/no; not with ``exact``).
        """
        vols, K = list(volumes), len(volumes)
        if K == 0:
            raise TerrainError("check: no link volumes")
        clearance = _clearance(clearance, "check")
        if exact and first:
            raise TerrainError("check: exact mode needs every finest-level hit; drop first=True")
        if shapes is not None and len(shapes) != K:
            raise TerrainError(f"check: {len(shapes)} shapes for {K} volumes")
        rows, rstart = pack_rows(vols, clearance, self.tol.parallel)
        return self._result(*self._descend(rows, rstart, K, first), K, exact,
                            vols if shapes is None else list(shapes), clearance)

    def check_packed(self, rows: np.ndarray, rstart: np.ndarray, *, first: bool = False) -> TerrainResult:
        """:meth:`check` (not exact) of volumes already packed into kernel rows: ``rows (R, 36)
        float64`` and ``rstart (K + 1,) int64`` as :func:`armguard.terrain._volumes.pack_rows` makes
        them (a caller that poses the same links at many configurations fills them itself)."""
        K = len(rstart) - 1
        if K <= 0:
            raise TerrainError("check_packed: no link volumes")
        return self._result(*self._descend(rows, rstart, K, first), K, False, None, 0.0)

    def _descend(self, rows, rstart, K, first):
        per_level = np.zeros(self.n_levels, np.int64)
        cells, masks, visited, deepest, truncated = [], [], 0, 0, False
        for lo in range(0, K, _MAX_LINKS):
            hi = min(K, lo + _MAX_LINKS)
            rs = rstart[lo:hi + 1]
            mask0 = np.int64((1 << (hi - lo)) - 1)
            cap = 256
            while True:
                oc, om, pl = np.empty(cap, np.int64), np.empty(cap, np.int64), np.zeros(self.n_levels, np.int64)
                n, v, d = descend(self.boxes, self.offsets, self.level_nx, self.level_ny, rows[rs[0]:],
                                  rs - rs[0], mask0, first, oc, om, pl)
                if n <= cap:
                    break
                cap = int(n)
            per_level += pl
            visited += int(v)
            deepest = max(deepest, int(d))
            cells.append(oc[:n])
            masks.append(_shift_masks(om[:n], lo, K))
            if first and n:
                truncated = True
                break
        return cells, masks, per_level, visited, deepest, truncated

    def check_flat(self, volumes: Sequence[Shape], *, clearance: float = 0.0) -> TerrainResult:
        """Brute-force reference: every finest-level box against every link volume (no pyramid)."""
        vols, K = list(volumes), len(volumes)
        if K == 0:
            raise TerrainError("check_flat: no link volumes")
        clearance = _clearance(clearance, "check_flat")
        rows, rstart = pack_rows(vols, clearance, self.tol.parallel)
        lo_b, hi_b = int(self.offsets[-2]), int(self.offsets[-1])
        cells, masks, tests = [], [], 0
        for lo in range(0, K, _MAX_LINKS):
            hi = min(K, lo + _MAX_LINKS)
            rs = rstart[lo:hi + 1]
            mask0 = np.int64((1 << (hi - lo)) - 1)
            cap = 256
            while True:
                oc, om = np.empty(cap, np.int64), np.empty(cap, np.int64)
                n, t = flat_hits(self.boxes, lo_b, hi_b, rows[rs[0]:], rs - rs[0], mask0, oc, om)
                if n <= cap:
                    break
                cap = int(n)
            tests += int(t)
            cells.append(oc[:n])
            masks.append(_shift_masks(om[:n], lo, K))
        per_level = np.zeros(self.n_levels, np.int64)
        per_level[-1] = tests
        res = self._result(cells, masks, per_level, 0, self.n_levels - 1, False, K, False, vols, clearance)
        return TerrainResult(res.status, self.n_levels - 1, hi_b - lo_b, tests, per_level, res.cells_hit,
                             res.links_hit, res.hit_unknown)

    # ----------------------------------------------------------------------------- assembly
    def _result(self, cells, masks, per_level, visited, deepest, truncated, K, exact, shapes, clearance):
        nx = self.map.shape[1]
        if len(cells) == 1:  # one chunk of links: the descent visits each finest cell at most once
            uniq, per_cell = cells[0], masks[0]
        else:  # a cell may be hit in several chunks
            cell = np.concatenate(cells)
            uniq, inv = np.unique(cell, return_inverse=True)
            per_cell = np.zeros((len(uniq), K), bool)
            np.logical_or.at(per_cell, inv, np.concatenate(masks, axis=0))
        rc = np.empty((len(uniq), 2), np.int64)
        rc[:, 0], rc[:, 1] = np.divmod(uniq, nx)
        links_hit = per_cell.any(axis=0)
        hit_unknown = bool(len(uniq)) and not bool(self.map.known.ravel()[uniq].all())
        last = self.n_levels - 1
        if not exact:
            status = TerrainStatus.HIT if len(uniq) else TerrainStatus.CLEAR
            level = last if len(uniq) else deepest
            return TerrainResult(status, level, visited, int(per_level.sum()), per_level, rc, links_hit,
                                 hit_unknown, truncated=truncated, cell_links=per_cell)
        known = self.map.known.ravel()[uniq]
        ld = np.full((2, K), np.inf)  # per link: least distance to a known (0) / an unknown (1) candidate
        lcell = np.full((2, K, 2), -1, np.int64)
        best, nearest = np.inf, None
        for ci, (r, c) in enumerate(rc):
            box = self.cell_box(int(r), int(c))
            u = 0 if known[ci] else 1
            for k in np.flatnonzero(per_cell[ci]):
                d = distance(shapes[k], box).distance
                if d < ld[u, k]:
                    ld[u, k] = d
                    lcell[u, k] = (r, c)
                if d < best:
                    best, nearest = float(d), (int(k), int(r), int(c))
        status = TerrainStatus.HIT if best <= clearance else TerrainStatus.CLEAR
        level = last if len(uniq) else deepest
        return TerrainResult(status, level, visited, int(per_level.sum()), per_level, rc, links_hit, hit_unknown,
                             best, nearest, truncated, ld[0], ld[1], lcell[0], lcell[1], per_cell)


def _shift_masks(m: np.ndarray, lo: int, K: int) -> np.ndarray:
    """``(n, K) bool`` from the chunk's int64 bit masks (chunk links ``lo, lo + 1, ...``)."""
    out = np.zeros((len(m), K), bool)
    nb = min(_MAX_LINKS, K - lo)
    out[:, lo:lo + nb] = (m[:, None] >> np.arange(nb, dtype=np.int64)) & 1
    return out


def _clearance(value, where: str) -> float:
    """``value`` as a finite clearance >= 0 (m); else a TerrainError naming ``where`` (text was a raw TypeError)."""
    try:
        c = float(value)
    except (TypeError, ValueError):
        c = float("nan")
    if isinstance(value, bool) or not (np.isfinite(c) and c >= 0.0):
        raise TerrainError(f"{where}: clearance must be a finite length >= 0 (m), got {value!r}")
    return c
