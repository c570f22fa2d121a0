"""The Detector's result types: status, per-pair results, the per-check report and batch arrays.

Everything here is immutable.  ``DetectionReport`` keeps the kernel's raw output arrays and
builds its ``PairResult`` views on first access, so that a ``check`` call costs one numba call
and a few attribute stores; what it reports does not depend on whether a view was built.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

__all__ = [
    "Status",
    "Category",
    "CATEGORIES",
    "PairResult",
    "NotEvaluated",
    "DetectionReport",
    "BatchReport",
    "PairDistances",
]


class Status(enum.Enum):
    """The overall verdict of a check, Ranger's green / yellow / red plus "could not finish"."""

    CLEAR = "clear"
    WARNING = "warning"
    COLLISION = "collision"
    INCOMPLETE = "incomplete"


# integer codes used by the kernels, in this order (BatchReport.status holds them)
STATUS_CODES = (Status.CLEAR, Status.WARNING, Status.COLLISION, Status.INCOMPLETE)


class Category(str, enum.Enum):
    """Ranger's result categories (its three plus the payload): the keys of ``by_category``.

    * ``arm``: arm–arm, other arms and the arm's own non-adjacent links (pair filters honoured);
    * ``environment``: arm–bodies (vehicle and environment bodies: faces, edges);
    * ``workspace``: arm–walls of the workspace bounding box (distance to the walls, inside > 0);
    * ``payload``: arm–payload and payload–everything.
    """

    ARM = "arm"
    ENVIRONMENT = "environment"
    WORKSPACE = "workspace"
    PAYLOAD = "payload"


CATEGORIES = ("arm", "environment", "workspace", "payload")
"""The category names in code order (0..3), the column order of ``BatchReport.min_distance``."""


_new = object.__new__


def _ro(a: np.ndarray) -> np.ndarray:
    a.flags.writeable = False
    return a


@dataclass(frozen=True)
class PairResult:
    """The signed distance of one evaluated pair, with witness points and names.

    ``distance`` (m) > 0 separated, <= 0 touching / penetrating; ``p_WA`` on the arm side A,
    ``p_WB`` on the obstacle side B, each ``(3,) float64, m`` in W, ``|p_WA - p_WB| = |distance|``.
    ``a`` / ``b`` are owner names (``"left_arm/link4"``, ``"vehicle"``, ``"workspace"``,
    ``"payload:tool"``); ``link`` is A's link name, ``obstacle`` is B's owner name;
    ``feature`` is the obstacle's face / edge / vertex nearest to ``p_WB``
    (from :func:`armguard.geometry.feature_at`) where the obstacle is a static polytope, else ``None``
    (the analytic Detector's annotation: a Detector over another backend's Checker gives ``None``).
    A payload's pair names the payload in ``a`` and the link carrying it in ``link``.
    """

    distance: float
    p_WA: np.ndarray
    p_WB: np.ndarray
    a: str
    b: str
    category: str
    link: str
    obstacle: str
    feature: Any = None
    pair_index: int = -1

    def to_dict(self) -> dict:
        """JSON-ready dictionary (lists of floats, the feature as ``Feature.to_dict`` data)."""
        feat = None if self.feature is None else self.feature.to_dict()
        return {
            "distance": self.distance,
            "category": self.category,
            "a": self.a,
            "b": self.b,
            "link": self.link,
            "obstacle": self.obstacle,
            "feature": feat,
            "p_WA": [float(x) for x in self.p_WA],
            "p_WB": [float(x) for x in self.p_WB],
        }


@dataclass(frozen=True)
class NotEvaluated:
    """A pair the anytime check did not evaluate: ``lower_bound`` (m) <= its distance now.

    The bound is the larger of (a) its last evaluated distance minus how far its links can have
    moved since (joint displacement times lever arm, summed over the chain) and (b) the
    distance between its bounding volumes at this configuration (``-inf`` if they overlap).
    """

    a: str
    b: str
    category: str
    lower_bound: float
    pair_index: int = -1


@dataclass(frozen=True)
class DetectionReport:
    """The result of :meth:`Detector.check` at one configuration.

    ``status``: CLEAR (every distance > threshold), WARNING (some pair within the threshold),
    COLLISION (some distance <= 0, or <= ``stopping_distance`` when that is set > 0),
    INCOMPLETE (a time budget ran out before the unevaluated pairs' lower bounds could prove
    the threshold holds: never CLEAR by omission).
    ``nearest``: the overall nearest evaluated pair, or None when no pair was evaluated (a scene
    without pairs, or a budgeted or lazy check whose lower bounds decided it alone: CLEAR with
    ``nearest`` None is then a proof, ``not_evaluated`` holds every pair with its bound);
    ``by_category``: the nearest evaluated pair per category (keys among ``"arm",
    "environment", "workspace", "payload"``; a category none of whose pairs was evaluated is absent);
    ``within_threshold``: every evaluated pair with distance <= threshold, nearest first;
    ``not_evaluated``: pairs skipped by the budget or by the lazy mode, with lower bounds;
    ``elapsed_us``: wall time of the check (µs); ``threshold``, ``stopping_distance`` (m);
    ``jacobian``: None unless ``check(q, jacobian=True)`` asked for it, then ``{category:
    CategoryJacobian}`` (:mod:`._category_jacobian`): the nearest pair's ``d(distance)/dq`` ``(nv,)``
    per category (Pinocchio's velocity order) and its ``smooth`` flag.
    """

    status: Status
    threshold: float
    stopping_distance: float
    elapsed_us: float
    _raw: Any = field(repr=False, compare=False)
    jacobian: Any = field(default=None, repr=False, compare=False)

    @cached_property
    def by_category(self) -> dict[str, PairResult]:
        return self._raw.by_category()

    @cached_property
    def nearest(self) -> PairResult | None:
        cats = self.by_category
        if not cats:
            return None
        return min(cats.values(), key=lambda r: r.distance)

    @cached_property
    def within_threshold(self) -> tuple[PairResult, ...]:
        return self._raw.within(self.threshold)

    @cached_property
    def not_evaluated(self) -> tuple[NotEvaluated, ...]:
        return self._raw.not_evaluated()

    @classmethod
    def _from_check(cls, status: Status, threshold: float, stopping_distance: float, elapsed_us: float,
                    raw: Any) -> "DetectionReport":
        """The report of one check without the frozen dataclass's ``__init__`` (five
        ``object.__setattr__`` calls, ~0.5 µs of a ~4 µs check): the same fields, set once
        (item stores, ~0.15 µs cheaper than ``__dict__.update`` with keywords)."""
        r = _new(cls)
        d = r.__dict__
        d["status"] = status
        d["threshold"] = threshold
        d["stopping_distance"] = stopping_distance
        d["elapsed_us"] = elapsed_us
        d["_raw"] = raw
        return r

    @property
    def n_evaluated(self) -> int:
        """How many narrow-phase pair distances this check computed."""
        return self._raw.n_evaluated

    def _with_jacobian(self, jacobian: dict) -> "DetectionReport":
        """This report with ``jacobian`` set (set once, before the report is handed out)."""
        self.__dict__["jacobian"] = jacobian
        return self

    def to_dict(self) -> dict:
        """JSON-ready dictionary of the whole report (``jacobian`` only when it was asked for; a pair's
        ``lower_bound`` that is not finite, ``-inf`` when never evaluated, is ``None``: strict JSON has no infinity)."""
        out = self._to_dict()
        if self.jacobian is not None:
            out["jacobian"] = {k: {"jacobian": [float(x) for x in v.jacobian], "smooth": v.smooth, "row": v.row}
                               for k, v in self.jacobian.items()}
        return out

    def _to_dict(self) -> dict:
        return {
            "status": self.status.value,
            "threshold": self.threshold,
            "stopping_distance": self.stopping_distance,
            "elapsed_us": self.elapsed_us,
            "nearest": None if self.nearest is None else self.nearest.to_dict(),
            "by_category": {k: v.to_dict() for k, v in self.by_category.items()},
            "within_threshold": [r.to_dict() for r in self.within_threshold],
            "not_evaluated": [
                {"a": n.a, "b": n.b, "category": n.category,
                 "lower_bound": n.lower_bound if math.isfinite(n.lower_bound) else None}  # strict JSON: null, no bound
                for n in self.not_evaluated
            ],
        }


@dataclass(frozen=True)
class BatchReport:
    """:meth:`Detector.check_many` over M configurations.

    ``min_distance``: ``(M, 4) float64, m``, the nearest distance per category in the order
    ``CATEGORIES`` = ("arm", "environment", "workspace", "payload"), ``inf`` where the scene has
    no pair of that category; ``collision``: ``(M,) bool``; ``status``: ``(M,) int8`` codes,
    index into ``STATUS`` (0 clear, 1 warning, 2 collision).
    """

    min_distance: np.ndarray
    collision: np.ndarray
    status: np.ndarray
    threshold: float
    stopping_distance: float

    STATUS = STATUS_CODES

    def statuses(self) -> list[Status]:
        """The status codes as :class:`Status` members."""
        return [STATUS_CODES[int(s)] for s in self.status]


@dataclass(frozen=True)
class PairDistances:
    """Every checked pair's signed distance at one configuration (for conservative advancement).

    ``distance`` ``(P,) float64, m``; ``p_WA``, ``p_WB`` ``(P, 3) float64, m`` in W;
    ``link_a`` ``(P,) int64`` global link index of side A (into ``link_names``), ``robot_a``
    ``(P,) int64`` its robot index; ``link_b`` ``(P,) int64`` global link index of side B, -1 when
    B is static (a body or the workspace walls); ``category`` ``(P,) int64`` code into
    ``CATEGORIES``; ``owner_a`` / ``owner_b`` ``(P,)`` owner names; ``link_names`` the global link
    names ``"robot/link"``; ``pair_index`` ``(P,) int64`` each row's pair number in the detector
    (rows follow it in increasing order; all pairs, or those of one robot).  The index arrays may be
    shared between calls (the fused detector's are, read-only; the generic detector makes them per
    call): do not write into them.  The distance and witness arrays are fresh per call.
    """

    distance: np.ndarray
    p_WA: np.ndarray
    p_WB: np.ndarray
    link_a: np.ndarray
    robot_a: np.ndarray
    link_b: np.ndarray
    category: np.ndarray
    owner_a: tuple
    owner_b: tuple
    link_names: tuple
    pair_index: np.ndarray | None = None
