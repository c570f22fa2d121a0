"""An elevation map from sensed points: per-cell maximum height, outliers rejected, holes filled.

The JPL brief (seed ``002``) builds the terrain model "automatically from sensory data acquired
during operation" (stereo cameras).  Stereo points are noisy, have holes (occlusion shadows,
grazing angles, no texture) and a few outliers; for collision checking the map must be
*conservative*:

* a cell's height is the **maximum** of its surviving points (the terrain is at least that high);
* an outlier rule (:class:`OutlierRule`) removes points that are inconsistent with their cell,
  cells that stand alone above their neighbours on too little support and, given the sensor's
  position, points whose ray went through terrain other rays saw;
* given the sensor's position, a cell whose points lie far below the rays that crossed it
  (:class:`~armguard.terrain.Carving`: its top was not seen -- a lone point too far along its ray,
  a slot narrower than the rays' spacing) is unknown, not known too low (``_carve.py``);
* a cell with no surviving point is **unknown** and never treated as free: it is filled with a
  conservative height (``fill="neighbourhood"``: the highest known cell within ``fill_radius``
  cells, else the ceiling; ``fill="ceiling"``: the ceiling), and the map reports which cells were
  filled (:attr:`ElevationMap.filled`) so that a hit on one can be told apart.

The grid is aligned with W's x and y axes (z up); cell ``(row, col)`` covers
``x in [x0 + col * cell, x0 + (col + 1) * cell)``, ``y in [y0 + row * cell, y0 + (row + 1) * cell)``.
Below each cell the terrain is solid down to :attr:`ElevationMap.floor`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

from .._errors import TerrainError
from .._tolerance import DEFAULT_TOLERANCES
from .._values import whole_number
from ._carve import Carving, _field, ray_lows, rays_under

__all__ = ["ElevationMap", "MAX_CELLS", "OutlierRule"]

MAX_CELLS = 1 << 24
"""The most cells (4096 x 4096) a map is built with from points (:meth:`ElevationMap.from_points`,
:func:`armguard.terrain.load_terrain`): a tiny cell or a point kilometres away would otherwise ask for
gigabytes."""


def _number(value, where: str, *, positive: bool = False) -> float:
    """``value`` as a finite float (> 0 with ``positive``), else a TerrainError naming ``where``."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise TerrainError(f"{where}: expected a number, got {value!r}") from None
    if not np.isfinite(x) or (positive and x <= 0.0):
        raise TerrainError(f"{where}: expected a finite number{' > 0' if positive else ''}, got {value!r}")
    return x


_MAD_TO_SIGMA = 1.4826  # MAD of a normal distribution times this is its standard deviation


@dataclass(frozen=True)
class OutlierRule:
    """The outlier rule of :meth:`ElevationMap.from_points`, two stages (three given the sensor's position).

    1. **Per cell, robust z-score** (Iglewicz & Hoaglin's modified z-score): in a cell with at
       least ``min_points`` points, a point is rejected when
       ``|z - median| > k * max(1.4826 * MAD, sigma_min)`` (MAD: the median absolute deviation of
       the cell's heights).  Cells with fewer points are kept whole (nothing to judge them by).  A
       point *above* its cell's median is kept all the same where the cells around support it as
       stage 2 counts support (``spike_support`` points of the other cells within
       ``spike_radius`` at least ``z - spike`` high): the few points of a rock's top in a cell
       that is mostly the ground beside it are the terrain, and the cell's height (its maximum).
    2. **Unsupported points**: a point at height ``z`` is dropped when fewer than
       ``spike_support`` points (itself included) within ``spike_radius`` cells of its cell
       (Chebyshev distance, its own cell included; points after stage 1) are at least as high as
       ``z - spike``.  Ground has neighbours at its height, a real rock has flanks and many
       points; a stereo mismatch floating above the ground (or a pair of them) has neither.  A cell
       left without points becomes unknown (and is filled like any hole).  The price: a real spike
       seen by one or two points only is dropped too (``spike = inf`` keeps it).
    3. **Rays under seen terrain** (only given the sensor's position, ``from_points(sensor_W=...)``):
       a point is dropped when its ray crosses a cell more than ``ray`` below that cell's *lowest*
       point (after stages 1 and 2): it went through the ground other rays saw, so the point lies
       too far along it (``_carve.py``).  The lowest point, not the highest: a ray may pass beside
       a post in a cell, never under the ground all round it.  A cell that loses a point to stage 3
       is unknown, and filled no lower than its points were (a real point behind a post that
       stage 3 drops all the same costs the cell its "known", never its height).

    ``k = inf``, ``spike = inf`` or ``ray = inf`` disables a stage (with ``spike = inf`` stage 1
    judges both sides of the median alone).

    Attributes
    ----------
    k : float, dimensionless
        Robust z-score above which a point is an outlier (3.5, Iglewicz & Hoaglin).
    min_points : int
        Points a cell needs before stage 1 judges it.
    sigma_min : float, m
        Floor on the robust spread, so that a flat, noise-free cell does not reject its own
        millimetre-level noise.
    spike : float, m
        Stage 2: how far below a point its supporting points may be.
    spike_support : int
        Stage 2: the supporting points a point needs (itself included).
    spike_radius : int, cells
        Stage 2's neighbourhood (2: the 5 x 5 cells around; sparse far-range data needs more than
        the 8 adjacent cells to find its neighbours).
    ray : float, m
        Stage 3: how far below a cell's highest point a ray may cross it.
    """

    k: float = 3.5
    min_points: int = 5
    sigma_min: float = 0.01
    spike: float = 0.15
    spike_support: int = 3
    spike_radius: int = 2
    ray: float = 0.15

    def __post_init__(self) -> None:
        for name, low, ints, inf_ok in (("k", 0.0, False, True), ("min_points", 1, True, False),
                                        ("sigma_min", 0.0, False, False), ("spike", 0.0, False, True),
                                        ("spike_support", 1, True, False), ("spike_radius", 0, True, False),
                                        ("ray", 0.0, False, True)):
            _field(self, "OutlierRule", name, low, ints, inf_ok)


@dataclass(frozen=True, eq=False)
class ElevationMap:
    """A height grid in W (see the module docstring for the cell layout).

    Attributes
    ----------
    heights : (ny, nx) float64, m
        Terrain height of each cell (z in W): the max of its points, or the fill of an unknown cell.
    origin : (2,) float64, m
        ``(x0, y0)``: W coordinates of the corner of cell ``(0, 0)``.
    cell : float, m
        Side of a (square) cell.
    known : (ny, nx) bool
        Cells with at least one surviving point and, given the sensor's position, no ray crossing
        them more than ``Carving.gap`` above their highest point (their top was seen).
    counts : (ny, nx) int64
        Surviving points per cell.
    floor : float, m
        The terrain is solid from ``floor`` up to each cell's height.
    rejected : int
        Points removed by the outlier rule (stage 1 points plus the points of stage 2 cells).
    invalid : int
        Input points dropped as non-finite (NaN or inf: a depth image's holes).
    upper : (ny, nx) float64 or None, m
        Given the sensor's position, the height no cell's column can exceed (the rays that crossed
        it, :class:`~armguard.terrain.Carving`; ``inf`` where too few did); else None.
    """

    heights: np.ndarray
    origin: np.ndarray
    cell: float
    known: np.ndarray
    counts: np.ndarray = field(repr=False)
    floor: float
    rejected: int = 0
    invalid: int = 0
    upper: np.ndarray | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        h = np.asarray(self.heights, dtype=np.float64)
        if h.ndim != 2 or h.size == 0 or not np.all(np.isfinite(h)):
            raise TerrainError(f"ElevationMap.heights: expected a finite (ny, nx) array, got shape {h.shape}")
        big = DEFAULT_TOLERANCES.max_magnitude
        if float(np.abs(h).max()) > big:
            raise TerrainError(f"ElevationMap.heights: {float(np.abs(h).max()):.6g} m is beyond the largest magnitude a "
                               f"map holds ({big:g} m, Tolerances.max_magnitude)")
        object.__setattr__(self, "cell", _number(self.cell, "ElevationMap.cell (m)", positive=True))
        try:
            o = np.asarray(self.origin, dtype=np.float64)
        except (TypeError, ValueError):
            o = np.zeros(0)
        if o.shape != (2,) or not np.all(np.isfinite(o)) or float(np.abs(o).max()) > big:
            raise TerrainError(f"ElevationMap.origin: expected (x0, y0), two finite numbers (m, W), got {self.origin!r}")
        object.__setattr__(self, "origin", o)
        object.__setattr__(self, "floor", _number(self.floor, "ElevationMap.floor (m)"))
        if abs(self.floor) > big:
            raise TerrainError(f"ElevationMap.floor: {self.floor:.6g} m is beyond the largest magnitude a map holds "
                               f"({big:g} m, Tolerances.max_magnitude)")
        if self.floor > float(h.min()):
            raise TerrainError(f"ElevationMap.floor {self.floor!r} must be finite and <= the lowest height {h.min():.6g}")
        extra = () if self.upper is None else (("upper", self.upper),)
        for name, a in (("known", self.known), ("counts", self.counts)) + extra:
            if np.shape(a) != h.shape:
                raise TerrainError(f"ElevationMap.{name}: shape {np.shape(a)} != heights {h.shape}")
        arrays = (("heights", h, np.float64), ("origin", self.origin, np.float64), ("known", self.known, bool),
                  ("counts", self.counts, np.int64)) + tuple((n, a, np.float64) for n, a in extra)
        for name, a, dt in arrays:
            a = np.array(a, dtype=dt)
            a.flags.writeable = False
            object.__setattr__(self, name, a)
        object.__setattr__(self, "cell", float(self.cell))
        object.__setattr__(self, "floor", float(self.floor))

    # ----------------------------------------------------------------------------- properties
    @property
    def shape(self) -> tuple[int, int]:
        """``(ny, nx)``: rows (y) and columns (x)."""
        return self.heights.shape  # type: ignore[return-value]

    @property
    def filled(self) -> np.ndarray:
        """``(ny, nx) bool``: the unknown cells, which hold a conservative fill height."""
        return ~self.known

    def cell_bounds(self, row: int, col: int) -> tuple[np.ndarray, np.ndarray]:
        """``(lo, hi)``, each ``(3,) m`` in W: the solid column of cell ``(row, col)``."""
        x0, y0 = self.origin
        lo = np.array([x0 + col * self.cell, y0 + row * self.cell, self.floor])
        hi = np.array([lo[0] + self.cell, lo[1] + self.cell, self.heights[row, col]])
        return lo, hi

    def cell_of(self, xy_W) -> tuple[np.ndarray, np.ndarray]:
        """Row and column indices ``(int64 arrays)`` of the cells holding points ``xy_W (N, 2+) m``
        (clipped to the grid)."""
        xy = np.asarray(xy_W, dtype=np.float64).reshape(-1, np.shape(xy_W)[-1])
        ny, nx = self.shape
        col = np.clip(np.floor((xy[:, 0] - self.origin[0]) / self.cell), 0, nx - 1).astype(np.int64)
        row = np.clip(np.floor((xy[:, 1] - self.origin[1]) / self.cell), 0, ny - 1).astype(np.int64)
        return row, col

    # ----------------------------------------------------------------------------- constructors
    @classmethod
    def from_heights(cls, heights, cell: float, origin=(0.0, 0.0), *, floor: float | None = None,
                     known=None) -> "ElevationMap":
        """A map from a height grid ``heights (ny, nx) m`` (e.g. a generated terrain's ground truth),
        every cell known unless ``known (ny, nx) bool`` says otherwise.  ``floor`` (m): default one
        cell side below the lowest height."""
        h = np.asarray(heights, dtype=np.float64)
        if h.ndim != 2 or h.size == 0:
            raise TerrainError(f"from_heights: expected a (ny, nx) array, got shape {h.shape}")
        cell = _number(cell, "from_heights: cell (m)", positive=True)
        k = np.ones(h.shape, bool) if known is None else np.asarray(known, bool)
        fl = float(h.min()) - cell if floor is None else _number(floor, "from_heights: floor (m)")
        return cls(h, origin, cell, k, k.astype(np.int64), fl)

    @classmethod
    def from_points(cls, points_W, cell: float, *, bounds=None, rule: OutlierRule = OutlierRule(),
                    fill: str = "neighbourhood", fill_radius: int = 2, ceiling: float | None = None,
                    floor: float | None = None, sensor_W=None, carving: Carving = Carving()) -> "ElevationMap":
        """The conservative elevation map of a point cloud.

        Parameters
        ----------
        points_W : (N, 3) float64, m
            Sensed points in W (z up); rows with a NaN or inf are dropped (counted in ``invalid``).
        cell : float, m
            Cell side.
        bounds : (4,) float, m, optional
            ``(x_min, y_min, x_max, y_max)`` of the grid in W; points outside are dropped.  Default:
            the points' extent.
        rule : OutlierRule
            The outlier rule (see :class:`OutlierRule`).
        fill : {"neighbourhood", "ceiling"}
            How unknown cells are filled: the highest known cell within ``fill_radius`` cells
            (Chebyshev distance), falling back to the ceiling where none is; or the ceiling.
        ceiling : float, m, optional
            Fill height where no neighbour informs; default the highest known cell.
        floor : float, m, optional
            Bottom of the terrain columns; default one cell side below the lowest cell.
        sensor_W : (3,) or (N, 3) float, m, optional
            Where the points were seen from (the camera's optical centre in W; one row per point
            for a cloud merged from several poses).  Enables stage 3 of the outlier rule and the
            free-space bound (:class:`Carving`, :attr:`upper`).  A wrong position proves free space
            that is not: give it only for the pose the points were taken from.
        carving : Carving
            How the rays' free space is read (with ``sensor_W``).
        """
        cell = _number(cell, "from_points: cell (m)", positive=True)
        if fill not in ("neighbourhood", "ceiling"):
            raise TerrainError(f"from_points: fill must be 'neighbourhood' or 'ceiling', got {fill!r}")
        fill_radius = whole_number(fill_radius, "from_points: fill_radius (cells)", TerrainError, low=0)
        try:
            p = np.asarray(points_W, dtype=np.float64)
        except (TypeError, ValueError):
            raise TerrainError(f"from_points: points_W: expected (N, 3) numbers (m, W), got {type(points_W).__name__}") from None
        if p.ndim != 2 or p.shape[1] != 3:
            raise TerrainError(f"from_points: points_W must be (N, 3), got shape {p.shape}")
        finite = np.all(np.isfinite(p), axis=1)
        invalid = int(np.count_nonzero(~finite))
        p = p[finite]
        o = _sensor(sensor_W, finite)
        if bounds is None:
            if len(p) == 0:
                raise TerrainError("from_points: no finite points and no bounds")
            x_min, y_min = p[:, 0].min(), p[:, 1].min()
            x_max, y_max = p[:, 0].max(), p[:, 1].max()
        else:
            b = list(bounds) if np.ndim(bounds) == 1 else []
            if len(b) != 4:
                raise TerrainError(f"from_points: bounds: expected (x_min, y_min, x_max, y_max), got {bounds!r}")
            x_min, y_min, x_max, y_max = (_number(v, "from_points: bounds (m)") for v in b)
            if not (x_max > x_min and y_max > y_min):
                raise TerrainError(f"from_points: empty bounds {bounds!r}")
        nx = max(1, int(min(np.ceil((x_max - x_min) / cell), 2.0**62)))
        ny = max(1, int(min(np.ceil((y_max - y_min) / cell), 2.0**62)))
        if nx * ny > MAX_CELLS:
            raise TerrainError(f"from_points: a {cell:.6g} m cell over {x_max - x_min:.6g} m x {y_max - y_min:.6g} m makes "
                               f"{nx} x {ny} cells, more than MAX_CELLS = {MAX_CELLS} (a larger cell, or bounds "
                               "cropped to the workspace)")
        col = np.floor((p[:, 0] - x_min) / cell).astype(np.int64)
        row = np.floor((p[:, 1] - y_min) / cell).astype(np.int64)
        col = np.where(p[:, 0] == x_max, nx - 1, col)  # the far edge belongs to the last cell
        row = np.where(p[:, 1] == y_max, ny - 1, row)
        inside = (col >= 0) & (col < nx) & (row >= 0) & (row < ny)
        at = np.flatnonzero(inside)  # the points in the grid, by their index in p
        cid, z = (row * nx + col)[inside], p[inside, 2]
        keep = _robust_keep(cid, z, nx, ny, rule)
        at, cid, z = at[keep], cid[keep], z[keep]
        drop = _spikes(cid, z, nx, ny, rule)
        at, cid, z = at[~drop], cid[~drop], z[~drop]
        grid = (x_min, y_min, cell, nx, ny)
        # what the points alone give (stages 1 and 2): with the sensor's position a cell may only lose its
        # "known", or rise; the fill of the holes reads these heights
        pointed = np.bincount(cid, minlength=nx * ny).reshape(ny, nx) > 0
        hmax = _hmax(cid, z, nx, ny)
        upper, unseen = None, np.zeros((ny, nx), bool)
        if o is not None:
            use = np.ones(len(p), bool)
            use[np.flatnonzero(inside)] = False
            use[at] = True  # the points outside the grid and the survivors: their rays cross it
            if np.isfinite(rule.ray):
                use &= ~rays_under(o, p, grid, _hlow(cid, z, nx, ny), rule.ray, carving)
                ok = use[at]
                unseen.flat[cid[~ok]] = True  # a cell that lost a point to stage 3
                at, cid, z = at[ok], cid[ok], z[ok]
            upper = ray_lows(o, p, use, grid, carving)
            unseen |= pointed & np.isfinite(upper) & (upper - hmax > carving.gap)  # no ray bound: no evidence
        rejected = int(np.count_nonzero(inside)) - len(at)
        counts = np.bincount(cid, minlength=nx * ny).reshape(ny, nx)
        known = pointed & ~unseen
        if not known.any():
            if ceiling is None and pointed.any():
                raise TerrainError(f"from_points: no cell was seen on top: the {len(at)} points left in the grid lie "
                                   f"more than Carving.gap = {carving.gap:g} m below the rays that crossed their cells, "
                                   "or their cells lost a point to a ray under the ground (OutlierRule.ray); give a "
                                   "ceiling to fill the map, or check sensor_W (where the points were seen from)")
            if ceiling is None:
                raise TerrainError(f"from_points: no cell has a surviving point (the outlier rule rejected all "
                                   f"{int(np.count_nonzero(inside))} points in the grid: a point is kept with at least "
                                   f"{rule.spike_support} points, itself included, as high within {rule.spike_radius} "
                                   "cells); give a ceiling to fill the map, or a denser cloud")
        top = float(hmax[pointed].max()) if pointed.any() else None
        if ceiling is not None:
            ceiling = _number(ceiling, "from_points: ceiling (m)")
            if top is not None and ceiling < top:  # unknown cells would be pits below seen ground: never free
                raise TerrainError(f"from_points: ceiling {ceiling!r} m is below the highest point seen ({top!r} m): "
                                   "an unknown cell filled there would be lower than terrain the sensor saw; give a "
                                   "ceiling at least that high, or none (the highest point)")
        top = ceiling if top is None else top
        ceil_h = top if ceiling is None else ceiling
        heights = np.where(known, hmax, ceil_h)
        if fill == "neighbourhood" and pointed.any() and fill_radius > 0:
            win = 2 * int(fill_radius) + 1
            neigh = ndimage.maximum_filter(np.where(pointed, hmax, -np.inf), size=win, mode="constant", cval=-np.inf)
            heights = np.where(known, hmax, np.where(np.isfinite(neigh), neigh, ceil_h))
        heights = np.where(unseen, np.maximum(heights, hmax), heights)  # unseen on top: never below its points
        fl = float(heights.min()) - cell if floor is None else _number(floor, "from_points: floor (m)")
        return cls(heights, np.array([x_min, y_min]), float(cell), known, counts, fl, rejected, invalid, upper)


def _sensor(sensor_W, finite: np.ndarray) -> np.ndarray | None:
    """``(n, 3)``: each finite point's sensor position, from ``(3,)`` or ``(N, 3)``; None without one."""
    if sensor_W is None:
        return None
    try:
        o = np.asarray(sensor_W, dtype=np.float64)
    except (TypeError, ValueError):
        o = np.zeros((0, 0))
    if o.shape == (3,):
        o = np.broadcast_to(o, (len(finite), 3))
    if o.shape != (len(finite), 3) or not np.all(np.isfinite(o)):
        raise TerrainError(f"from_points: sensor_W: expected (3,) or ({len(finite)}, 3) finite numbers (m, W: where "
                           f"the points were seen from), got shape {np.shape(sensor_W)}")
    return np.ascontiguousarray(o[finite])


def _hlow(cid: np.ndarray, z: np.ndarray, nx: int, ny: int) -> np.ndarray:
    """``(ny, nx)``: the lowest point of each cell, ``-inf`` where none (no ray is under it)."""
    h = np.full(nx * ny, np.inf)
    np.minimum.at(h, cid, z)
    h[h == np.inf] = -np.inf
    return h.reshape(ny, nx)


def _hmax(cid: np.ndarray, z: np.ndarray, nx: int, ny: int) -> np.ndarray:
    """``(ny, nx)``: the highest point of each cell, ``-inf`` where none."""
    h = np.full(nx * ny, -np.inf)
    np.maximum.at(h, cid, z)
    return h.reshape(ny, nx)


def _robust_keep(cid: np.ndarray, z: np.ndarray, nx: int, ny: int, rule: OutlierRule) -> np.ndarray:
    """Stage 1 of :class:`OutlierRule`: a keep mask over the points (vectorised per cell)."""
    n = len(z)
    keep = np.ones(n, bool)
    if n == 0 or not np.isfinite(rule.k):
        return keep
    order = np.lexsort((z, cid))
    c_s, z_s = cid[order], z[order]
    starts = np.flatnonzero(np.r_[True, c_s[1:] != c_s[:-1]])
    cnt = np.diff(np.r_[starts, n])
    lo_mid, hi_mid = starts + (cnt - 1) // 2, starts + cnt // 2
    med = 0.5 * (z_s[lo_mid] + z_s[hi_mid])
    grp = np.repeat(np.arange(len(starts)), cnt)
    dev = np.abs(z_s - med[grp])
    order2 = np.lexsort((dev, grp))
    dev_s = dev[order2]
    mad = 0.5 * (dev_s[lo_mid] + dev_s[hi_mid])
    scale = np.maximum(_MAD_TO_SIGMA * mad, rule.sigma_min)
    judged = cnt[grp] >= rule.min_points
    bad_sorted = judged & (dev > rule.k * scale[grp])
    keep[order[bad_sorted]] = False
    if np.isfinite(rule.spike):  # a high point the other cells around support is terrain (a rock's top)
        high = order[bad_sorted & (z_s > med[grp])]
        if len(high):
            others = _support(cid, z, nx, ny, rule, own=False, at=high)
            keep[high[others >= rule.spike_support]] = True
    return keep


def _spikes(cid: np.ndarray, z: np.ndarray, nx: int, ny: int, rule: OutlierRule) -> np.ndarray:
    """Stage 2 of :class:`OutlierRule`: a drop mask over the points.  The points are sorted by the
    key ``cell + (z - z_min) / span`` (``span`` > the height range, so each cell's heights map into
    ``[cell, cell + 1)`` in order); the points of a cell at least as high as a threshold are then
    a range of that sorted key, counted by two binary searches per neighbouring cell."""
    n = len(z)
    if not np.isfinite(rule.spike) or n == 0:
        return np.zeros(n, bool)
    return _support(cid, z, nx, ny, rule) < rule.spike_support


def _support(cid: np.ndarray, z: np.ndarray, nx: int, ny: int, rule: OutlierRule, *, own: bool = True,
             at: np.ndarray | None = None) -> np.ndarray:
    """Per point (or per point of ``at``, indices), how many points within ``spike_radius`` cells are
    at least ``z - spike`` high (its own cell's with ``own``, itself included)."""
    z_min = float(z.min())
    span = 2.0 * (float(z.max()) - z_min + rule.spike) + 1.0
    key = np.sort(cid + (z - z_min) / span)
    sel = np.arange(len(z)) if at is None else at
    row, col = np.divmod(cid[sel], nx)
    lo_key = (np.maximum(z[sel] - rule.spike, z_min) - z_min) / span
    support = np.zeros(len(sel), np.int64)
    rad = max(int(rule.spike_radius), 0)
    for dy in range(-rad, rad + 1):
        for dx in range(-rad, rad + 1):
            if not own and dx == 0 and dy == 0:
                continue
            r, c = row + dy, col + dx
            ok = (r >= 0) & (r < ny) & (c >= 0) & (c < nx)
            nb = (r * nx + c)[ok]
            support[ok] += np.searchsorted(key, nb + 1.0, side="left") - np.searchsorted(key, nb + lo_key[ok], side="left")
    return support
