"""The grid of a forbidden-values map: (joint 1, joint 2) cells grouped in substructures, joint-3 quanta.

Hermes (``001_…``, "Forbidden Values Method") discretises the first two joints (1° over joint 1 in
[0, 360°], joint 2 in [−30°, 210°]) and groups the cells in substructures of 10° × 10°; each
cell holds the ranges of joint 3.  Here:

* cell ``(i1, i2)`` is the closed joint-space rectangle
  ``[lo_1 + i1 s_1, lo_1 + (i1 + 1) s_1] × [lo_2 + i2 s_2, lo_2 + (i2 + 1) s_2]`` (rad), clipped to
  the joint limits; ``s_1 = s_2`` is the map's ``resolution``;
* joint 3 is quantised in bins ``b`` of width ``s_3`` (``j3_resolution``, rad) from ``lo_3``;
  intervals are stored as bin numbers (integers, like Hermes's angular values);
* substructure ``(k1, k2)`` holds cells ``i1 in [k1 c_1, (k1 + 1) c_1)``, ``i2 in [k2 c_2, ...)``
  with ``c`` the cells per substructure (``round(cell / resolution)``, at least 1).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._errors import ForbiddenMapError

__all__ = ["MAX_BINS", "MAX_MAP_BINS", "MapGrid", "parse_angle"]

#: the most joint-3 bins (stored as uint16 bin numbers)
MAX_BINS = 65535
#: the most bins of a whole map (joint-1 cells x joint-2 cells x joint-3 bins): 2^30, a 1 GiB mask
#: (a 0.0001 deg resolution asked numpy for 298 GiB and ended in a MemoryError)
MAX_MAP_BINS = 1 << 30
_COUNT_SLACK = 1e-9  # relative: (hi - lo) / step within this of an integer counts as that integer


def parse_angle(text) -> float:
    """An angle in rad from ``"1deg"``, ``"1°"``, ``"0.0175rad"`` or a number (rad)."""
    if isinstance(text, (int, float, np.floating, np.integer)):
        return float(text)
    s = str(text).strip().lower()
    try:
        for suffix, scale in (("deg", math.pi / 180.0), ("°", math.pi / 180.0), ("rad", 1.0)):
            if s.endswith(suffix):
                return float(s[: -len(suffix)]) * scale
        return float(s)
    except ValueError:
        raise ForbiddenMapError(f"cannot read the angle {text!r}: expected e.g. '1deg', '0.5°', '0.01rad' or a number of rad") from None


def _count(span: float, step: float) -> int:
    x = span / step
    return max(1, int(math.ceil(x - _COUNT_SLACK * max(1.0, x))))


@dataclass(frozen=True)
class MapGrid:
    """The discretisation of a map (immutable; all angles in rad).

    Attributes
    ----------
    lower, upper : (3,) float64, rad
        Joint limits of joints 1, 2, 3.
    step : (3,) float64, rad
        Cell width of joints 1 and 2 (the resolution) and the joint-3 quantum.
    counts : (3,) int64
        ``n1, n2`` cells and ``n3`` joint-3 bins.
    per_sub : (2,) int64
        Cells of joints 1, 2 per substructure.
    n_sub : (2,) int64
        Substructures along joints 1, 2.
    """

    lower: np.ndarray
    upper: np.ndarray
    step: np.ndarray
    counts: np.ndarray
    per_sub: np.ndarray
    n_sub: np.ndarray

    @classmethod
    def create(cls, lower, upper, resolution: float, j3_resolution: float, cell) -> "MapGrid":
        """The grid over ``[lower, upper]`` ``(3,)`` rad at ``resolution`` (rad) with substructures of ``cell`` ``(2,)`` rad."""
        lo = np.asarray(lower, dtype=np.float64).reshape(3)
        hi = np.asarray(upper, dtype=np.float64).reshape(3)
        if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)) and np.all(hi > lo)):
            raise ForbiddenMapError(f"the three joints need finite limits with upper > lower, got {lo} .. {hi}")
        res = parse_angle(resolution)
        r3 = parse_angle(j3_resolution)
        cell = np.broadcast_to(np.asarray([parse_angle(c) for c in np.atleast_1d(cell)], dtype=np.float64), (2,))
        for name, v in (("resolution", res), ("j3_resolution", r3), ("cell", float(cell.min()))):
            if not (math.isfinite(v) and v > 0.0):
                raise ForbiddenMapError(f"{name}: expected a positive angle (rad), got {v}")
        step = np.array([res, res, r3])
        counts = np.array([_count(hi[k] - lo[k], step[k]) for k in range(3)], dtype=np.int64)
        if counts[2] > MAX_BINS:
            raise ForbiddenMapError(f"j3_resolution {r3} rad gives {counts[2]} joint-3 bins; at most {MAX_BINS}")
        total = int(counts[0]) * int(counts[1]) * int(counts[2])
        if total > MAX_MAP_BINS:
            raise ForbiddenMapError(f"resolution {math.degrees(res):.6g} deg and j3_resolution {math.degrees(r3):.6g} deg give "
                                    f"{counts[0]} x {counts[1]} x {counts[2]} = {total:.3g} bins, more than {MAX_MAP_BINS} "
                                    "(MAX_MAP_BINS): a coarser resolution")
        # cells per substructure, at most the grid's (a cell of 1e300 deg was INT64_MIN cells, a map that did not load)
        per_sub = np.minimum(np.maximum(1.0, np.rint(cell / res)), np.maximum(counts[:2], 1)).astype(np.int64)
        n_sub = -(-counts[:2] // per_sub)
        return cls(lo, hi, step, counts, per_sub, n_sub)

    # ------------------------------------------------------------------ derived
    @property
    def n_cells(self) -> int:
        return int(self.counts[0] * self.counts[1])

    @property
    def n_substructures(self) -> int:
        return int(self.n_sub[0] * self.n_sub[1])

    def sub_cells(self, s: int) -> tuple[int, int, int, int]:
        """Cell ranges ``(i1a, i1b, i2a, i2b)`` (end exclusive) of substructure number ``s`` (row-major over (k1, k2))."""
        k1, k2 = divmod(int(s), int(self.n_sub[1]))
        c1, c2 = int(self.per_sub[0]), int(self.per_sub[1])
        return (k1 * c1, min((k1 + 1) * c1, int(self.counts[0])), k2 * c2, min((k2 + 1) * c2, int(self.counts[1])))

    def sub_of(self, i1: int, i2: int) -> int:
        """Substructure number holding cell ``(i1, i2)``."""
        return int(i1 // self.per_sub[0]) * int(self.n_sub[1]) + int(i2 // self.per_sub[1])

    def cell_of(self, q) -> tuple[int, int, int] | None:
        """``(i1, i2, b)`` of the configuration ``q`` ``(3,)`` rad, or None outside the joint limits."""
        q = np.asarray(q, dtype=np.float64).reshape(3)
        if not np.all((q >= self.lower) & (q <= self.upper)):
            return None
        idx = np.minimum(np.floor((q - self.lower) / self.step).astype(np.int64), self.counts - 1)
        return int(idx[0]), int(idx[1]), int(idx[2])

    def bin_edges(self) -> np.ndarray:
        """``(n3 + 1,) float64, rad``: joint-3 bin edges (the last clipped to the upper limit)."""
        e = self.lower[2] + self.step[2] * np.arange(self.counts[2] + 1)
        return np.minimum(e, self.upper[2])

    def to_json(self) -> dict:
        return {"lower": self.lower.tolist(), "upper": self.upper.tolist(), "step": self.step.tolist(),
                "counts": self.counts.tolist(), "per_sub": self.per_sub.tolist(), "n_sub": self.n_sub.tolist()}

    @classmethod
    def from_json(cls, d: dict) -> "MapGrid":
        try:
            g = cls(np.array(d["lower"], dtype=np.float64), np.array(d["upper"], dtype=np.float64),
                    np.array(d["step"], dtype=np.float64), np.array(d["counts"], dtype=np.int64),
                    np.array(d["per_sub"], dtype=np.int64), np.array(d["n_sub"], dtype=np.int64))
        except (KeyError, TypeError, ValueError) as exc:
            raise ForbiddenMapError(f"the map's grid record is invalid: {exc}") from None
        fields = (g.lower, g.upper, g.step, g.counts, g.per_sub, g.n_sub)
        if any(a.shape != (3,) for a in fields[:4]) or any(a.shape != (2,) for a in fields[4:]):
            raise ForbiddenMapError("the map's grid record is invalid: lower, upper, step, counts of 3 joints and "
                                    "per_sub, n_sub of 2 expected")
        if not (np.all(np.isfinite(g.lower)) and np.all(np.isfinite(g.upper)) and np.all(np.isfinite(g.step))
                and np.all(g.step > 0) and np.all(g.upper >= g.lower) and np.all(g.counts >= 1)
                and np.all(g.per_sub >= 1) and np.all(g.n_sub >= 1)):
            raise ForbiddenMapError("the map's grid record is invalid: finite limits with upper >= lower, steps > 0 "
                                    f"and counts >= 1 expected, got {g.to_json()}")
        return g
