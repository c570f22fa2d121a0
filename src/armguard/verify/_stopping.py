"""Stopping distance and discretisation error (Hermes, ``001_…`` §3 and §4).

Hermes grows every obstacle by the *stopping distance* — the distance the arm needs to
brake — so that "two objects are defined to be in collision if and only if their relative
distance is less than the stopping distance".  The stopping distance "is treated as a
stepwise function of speed and load of the arm.  Letting the maximum value of the stopping
distance be 100 mm ... and using 10 ranges, the error due to this contribution can be
assumed, in the worst case, as 10 mm" (§4).  :class:`StoppingDistance` is that step
function; :func:`discretisation_error` is Hermes eq. (4-2), ``Ed = v / f``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._errors import VerificationError
from .._values import number

__all__ = ["StoppingDistance", "discretisation_error", "check_stopping_distance"]


def _finite_nonneg(x, name: str) -> float:
    return number(x, name, VerificationError, low=0.0)


@dataclass(frozen=True)
class StoppingDistance:
    """A stopping distance as a step function of speed and payload mass (Hermes §4).

    Attributes
    ----------
    speed_edges : (n_speed + 1,) float64, m/s
        Increasing bin edges from 0; a speed ``v`` falls in bin ``k`` when
        ``speed_edges[k] <= v <= speed_edges[k + 1]`` (the upper edge belongs to the lower bin,
        so a bin's value covers its whole closed range).  Speeds above the last edge raise.
    mass_edges : (n_mass + 1,) float64, kg
        Increasing payload-mass bin edges from 0, same rule.
    table : (n_speed, n_mass) float64, m
        Stopping distance per bin; must not decrease with speed or mass (checked), so the
        value for the largest speed and mass an interval reaches bounds the whole interval.
    """

    speed_edges: tuple[float, ...]
    mass_edges: tuple[float, ...]
    table: tuple[tuple[float, ...], ...]

    def __post_init__(self) -> None:
        se = np.asarray(self.speed_edges, dtype=np.float64)
        me = np.asarray(self.mass_edges, dtype=np.float64)
        tb = np.asarray(self.table, dtype=np.float64)
        for name, e in (("speed_edges", se), ("mass_edges", me)):
            if e.ndim != 1 or len(e) < 2 or not np.all(np.isfinite(e)) or e[0] != 0.0 or np.any(np.diff(e) <= 0):
                raise VerificationError(f"StoppingDistance.{name}: expected increasing finite edges starting at 0, got {e.tolist()}")
        if tb.shape != (len(se) - 1, len(me) - 1):
            raise VerificationError(f"StoppingDistance.table: expected shape {(len(se) - 1, len(me) - 1)}, got {tb.shape}")
        if not np.all(np.isfinite(tb)) or np.any(tb < 0):
            raise VerificationError("StoppingDistance.table: expected finite distances >= 0 (m)")
        if np.any(np.diff(tb, axis=0) < 0) or np.any(np.diff(tb, axis=1) < 0):
            raise VerificationError("StoppingDistance.table: must not decrease with speed or with mass")
        object.__setattr__(self, "speed_edges", tuple(float(x) for x in se))
        object.__setattr__(self, "mass_edges", tuple(float(x) for x in me))
        object.__setattr__(self, "table", tuple(tuple(float(x) for x in row) for row in tb))

    @classmethod
    def hermes(cls, max_speed: float, max_distance: float = 0.1, n_ranges: int = 10, max_mass: float | None = None,
               at_rest: float = 0.0) -> "StoppingDistance":
        """Hermes's rule: ``n_ranges`` equal speed ranges up to ``max_speed`` (m/s), each given the
        stopping distance of its top, ``max_distance * (k + 1) / n_ranges`` (m): 10 ranges up to
        100 mm by default, so the step error is at most ``max_distance / n_ranges`` = 10 mm.

        ``max_mass`` (kg): one mass range ``[0, max_mass]`` (inf when not given: mass-independent).
        ``at_rest`` (m/s): speeds up to it stop in no distance (a first range ``[0, at_rest]`` with
        stopping distance 0; it must lie inside the first range): an arm at rest is not charged
        the first range's distance.
        """
        vmax = _finite_nonneg(max_speed, "max_speed")
        dmax = _finite_nonneg(max_distance, "max_distance")
        rest = _finite_nonneg(at_rest, "at_rest")
        if vmax <= 0.0 or int(n_ranges) != n_ranges or n_ranges < 1:
            raise VerificationError("StoppingDistance.hermes: need max_speed > 0 and an integer n_ranges >= 1")
        if rest >= vmax / n_ranges:
            raise VerificationError(f"StoppingDistance.hermes: at_rest {rest:.6g} m/s must be below the first range's "
                                    f"top {vmax / n_ranges:.6g} m/s")
        edges = tuple(vmax * k / n_ranges for k in range(n_ranges)) + (vmax,)  # the top is max_speed itself
        # (vmax * n / n rounds a last bit below vmax for ~6 % of speeds: the table refused the speed it was made for)
        table = tuple((dmax * (k + 1) / n_ranges,) for k in range(n_ranges))
        if rest > 0.0:
            edges = (0.0, rest) + edges[1:]
            table = ((0.0,),) + table
        m = 1e300 if max_mass is None else _finite_nonneg(max_mass, "max_mass")
        return cls(edges, (0.0, m), table)

    @staticmethod
    def _bin(edges: tuple[float, ...], x: float, name: str) -> int:
        # a value over the last edge by rounding (64 units in its last place) is in the last range: the
        # speed a table was made for, found again on another split of the trajectory, came out one
        # unit above it (``verify --speed-dependent`` refused 5 of 14 plain moves)
        if x > edges[-1] + 64.0 * math.ulp(edges[-1]):
            raise VerificationError(f"StoppingDistance: {name} {x!r} is above the table's last edge {edges[-1]!r}")
        k = int(np.searchsorted(np.asarray(edges), x, side="left")) - 1
        return min(max(k, 0), len(edges) - 2)

    def at(self, speed: float, mass: float = 0.0) -> float:
        """Stopping distance (m) at ``speed`` (m/s, of the fastest point of the arm) and payload ``mass`` (kg)."""
        v = _finite_nonneg(speed, "speed")
        m = _finite_nonneg(mass, "mass")
        return self.table[self._bin(self.speed_edges, v, "speed")][self._bin(self.mass_edges, m, "mass")]

    @property
    def max_distance(self) -> float:
        """The largest stopping distance in the table (m)."""
        return self.table[-1][-1]

    def to_dict(self) -> dict:
        return {"speed_edges": list(self.speed_edges), "mass_edges": list(self.mass_edges), "table": [list(r) for r in self.table]}


def check_stopping_distance(value) -> "float | StoppingDistance":
    """Coerce a stopping distance argument: a finite float >= 0 (m) or a :class:`StoppingDistance`."""
    if isinstance(value, StoppingDistance):
        return value
    from .._tolerance import DEFAULT_TOLERANCES

    return number(value, "stopping_distance", VerificationError, low=0.0, high=DEFAULT_TOLERANCES.max_magnitude,
                  unit=" (m)")


def discretisation_error(speed, frequency):
    """Hermes eq. (4-2): ``Ed = v / f``, the distance the fastest point of the arm moves between
    two checks.  ``speed`` (m/s, broadcastable), ``frequency`` (Hz, > 0) -> Ed (m).

    The paper quotes ``v`` in mm/s and Ed in mm; the ratio is the same in any length unit.
    """
    v = np.asarray(speed, dtype=np.float64)
    f = float(frequency)
    if not np.all(np.isfinite(v)) or np.any(v < 0):
        raise VerificationError("discretisation_error: speed must be finite and >= 0")
    if not math.isfinite(f) or f <= 0.0:
        raise VerificationError(f"discretisation_error: frequency must be finite and > 0, got {f}")
    return v / f
