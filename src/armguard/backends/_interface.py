"""The backend plugin interface: a Backend builds a Checker for a Model.

A **Checker** answers two required queries for the Model's active pairs
(:attr:`armguard.model.Model.pairs`, in that order):

* ``pair_distances(q) -> PairDistances``: signed distance (``> 0`` apart, ``< 0``
  penetrating) and world witness points of every pair at one configuration ``q`` in
  ``pin_model``'s order ``(nq,)``; with ``jacobian=True`` also ``d(distance)/dq`` per pair
  (``.jacobian`` ``(n, nv)``, ``.smooth`` ``(n,)``; default: central differences, see
  :meth:`CheckerBase.distance_jacobian`);
* ``collides(Q) -> (M,) bool``: whether any pair is within ``margin`` (default: touching or
  penetrating, ``distance <= 0``) at each row of ``Q`` ``(M, nq)``; ``margin`` may be one per pair or
  category and ``pairs=`` a subset of the pair rows (:mod:`._margins`: the framework answers both for
  a :class:`CheckerBase` subclass from its one-margin ``collides``).

Optional fast paths have framework defaults built from those two (:class:`CheckerBase`):
``nearest(q)`` (per category, the nearest pair), ``min_distance_many(Q)``, a subset of the pairs
(``pair_distances(q, pairs=rows)``: the Model pair rows ``rows``, in that order) and a batch
(``pair_distances_many(Q, pairs=None) -> PairDistancesMany``, ``(M, n)`` distances and
``(M, n, 3)`` witness points).  A backend whose ``pair_distances`` takes no ``pairs`` gets the
default (the full result's rows).  A backend that answers verdicts only (no distances) declares
it in ``capabilities`` and the framework checks it before asking for distances.

Every Checker may be called from several threads at once, with the answers of single-threaded
calls: a backend keeps per-call or per-thread scratch (or a lock where state is unavoidable).
"""

from __future__ import annotations

import enum
import functools
import inspect
import math
from dataclasses import dataclass
from typing import Mapping, Protocol, runtime_checkable

import numpy as np

from .._errors import BackendError
from .._values import number, refuse_complex_or_bool
from ..model._joint_limits import UNIT_CIRCLE  # defined with the Model's limits (within_pin_limits tests it too)
from ._margins import check_margins, collides_per_pair, collides_subset

__all__ = ["Backend", "Checker", "CheckerBase", "PairDistances", "PairDistancesMany", "NearestPair", "Capability",
           "check_q", "check_Q", "check_pairs"]


class Capability(str, enum.Enum):
    """What a Checker can answer."""

    DISTANCES = "distances"  # signed distances with witness points (pair_distances)
    VERDICTS = "verdicts"  # collides(Q)


@dataclass(frozen=True)
class PairDistances:
    """Every active pair at one configuration.

    ``pairs`` ``(n, 2)`` object: GeometryObject names (side B ``"workspace"`` for the workspace
    walls); ``distance`` ``(n,) float64, m`` signed; ``p_WA``, ``p_WB`` ``(n, 3) float64, m`` the
    witness points in W on A and B, ``|p_WA - p_WB| == |distance|``; ``category`` ``(n,)`` names.

    With ``pair_distances(q, jacobian=True)``: ``jacobian`` ``(n, nv) float64, m/rad or m/m`` the
    derivative of each pair's signed distance with respect to the joint velocities (``pin_model``'s
    ``nv`` columns; a continuous joint is one column), and ``smooth`` ``(n,) bool``: whether the
    distance is differentiable there (False: touching, non-unique witness points, a switch
    between features; the row is then one of the one-sided derivatives).  Otherwise both None.
    Sign conventions: ``docs/notation.md``.
    """

    pairs: np.ndarray
    distance: np.ndarray
    p_WA: np.ndarray
    p_WB: np.ndarray
    category: tuple
    jacobian: np.ndarray | None = None
    smooth: np.ndarray | None = None

    def nearest(self) -> dict:
        """Category -> :class:`NearestPair` of the smallest distance (categories with pairs only)."""
        out = {}
        cats = np.asarray(self.category, dtype=object)
        for c in dict.fromkeys(self.category):
            idx = np.flatnonzero(cats == c)
            k = int(idx[np.argmin(self.distance[idx])])
            out[c] = NearestPair(c, self.pairs[k, 0], self.pairs[k, 1], float(self.distance[k]), self.p_WA[k].copy(),
                                 self.p_WB[k].copy(), k)
        return out

    @staticmethod
    def _unchecked(pairs, distance, p_WA, p_WB, category, jacobian=None, smooth=None,
                   _new=object.__new__) -> "PairDistances":
        """The same object as ``PairDistances(...)``, built without the frozen dataclass's
        ``__init__`` (one ``object.__setattr__`` per field): a fast backend's per-call path."""
        o = _new(PairDistances)
        d = o.__dict__
        d["pairs"], d["distance"], d["p_WA"], d["p_WB"], d["category"] = pairs, distance, p_WA, p_WB, category
        d["jacobian"], d["smooth"] = jacobian, smooth
        return o

    def take(self, rows: np.ndarray) -> "PairDistances":
        """The rows ``rows`` (int indices) of this result, in that order (fresh arrays)."""
        cat = self.category
        jac = None if self.jacobian is None else self.jacobian[rows]
        smooth = None if self.smooth is None else self.smooth[rows]
        return PairDistances(self.pairs[rows], self.distance[rows], self.p_WA[rows], self.p_WB[rows],
                             tuple(cat[int(k)] for k in rows), jac, smooth)

    def with_jacobian(self, jacobian: np.ndarray, smooth: np.ndarray) -> "PairDistances":
        """This result with ``jacobian`` and ``smooth`` set (the arrays shared, not copied)."""
        return PairDistances(self.pairs, self.distance, self.p_WA, self.p_WB, self.category, jacobian, smooth)


@dataclass(frozen=True)
class PairDistancesMany:
    """Pairs at ``M`` configurations: :class:`PairDistances` batched.

    ``pairs`` ``(n, 2)`` object, ``category`` ``(n,)`` names as in :class:`PairDistances`;
    ``distance`` ``(M, n) float64, m`` signed; ``p_WA``, ``p_WB`` ``(M, n, 3) float64, m`` the
    witness points in W.  Row ``m`` equals ``pair_distances(Q[m], pairs=...)``.
    """

    pairs: np.ndarray
    distance: np.ndarray
    p_WA: np.ndarray
    p_WB: np.ndarray
    category: tuple

    def __len__(self) -> int:
        return self.distance.shape[0]

    def row(self, m: int) -> PairDistances:
        """Configuration ``m`` as a :class:`PairDistances` (views)."""
        return PairDistances(self.pairs, self.distance[m], self.p_WA[m], self.p_WB[m], self.category)


@dataclass(frozen=True)
class NearestPair:
    """The nearest pair of one category: names, signed distance (m), witness points in W (m), row."""

    category: str
    a: str
    b: str
    distance: float
    p_WA: np.ndarray
    p_WB: np.ndarray
    index: int


def check_unit_circle(model, Q2: np.ndarray, what: str = "Q") -> None:
    """A BackendError naming the row and joint when a continuous joint's ``(cos, sin)`` in ``Q2`` ``(M, nq)``
    is off the unit circle (:data:`UNIT_CIRCLE`); part of :func:`check_q` / :func:`check_Q`, alone for a
    backend whose fast path checks the rest itself."""
    if not model.has_continuous_joints:
        return
    cq = model.continuous_q
    r = np.abs(Q2[:, cq] ** 2 + Q2[:, cq + 1] ** 2 - 1.0)
    bad = np.argwhere(r > UNIT_CIRCLE)
    if len(bad):
        m, k = int(bad[0][0]), int(cq[bad[0][1]])
        row = f" row {m}:" if what == "Q" else ""
        name = model.q_joint_names[k]
        raise BackendError(f"{what}:{row} continuous joint {name!r}: (cos, sin) = ({float(Q2[m, k]):.6g}, "
                           f"{float(Q2[m, k + 1]):.6g}) is not on the unit circle (|cos² + sin² - 1| = "
                           f"{float(r[bad[0][0], bad[0][1]]):.3g} > {UNIT_CIRCLE:g}): give (cos θ, sin θ)")


def check_margin(margin) -> float:
    """``collides``'s ``margin`` as a finite float >= 0 (m), else a BackendError naming it: NaN and a
    negative margin made ``min(d) <= margin`` false everywhere (clear at a collision), ``True`` read as
    1 m, text a raw TypeError.  A plain float in range passes at the cost of one type test."""
    if type(margin) is float and 0.0 <= margin < math.inf:
        return margin
    return number(margin, "margin", BackendError, low=0.0, unit=" (m)")


def check_q(model, q) -> np.ndarray:
    """``q`` as a finite ``(nq,)`` float64 array in ``pin_model``'s order (a continuous joint's ``(cos, sin)``
    on the unit circle, :data:`UNIT_CIRCLE`), else a BackendError; a joint outside its limits is a
    :class:`~armguard.JointLimitError` (``Model.check_pin_limits``), the rule of every backend."""
    refuse_complex_or_bool(q, "q", BackendError)
    try:
        q = np.asarray(q, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise BackendError(f"q: expected {model.nq} numbers, got {q!r}") from exc
    if q.shape != (model.nq,):
        raise BackendError(f"q: expected shape ({model.nq},), {model.q_layout(q.shape[-1] if q.ndim else None)}, got {q.shape}")
    if not np.all(np.isfinite(q)):
        raise BackendError(f"q: contains NaN or infinite values: {q.tolist()}")
    check_unit_circle(model, q[None], "q")
    model.check_pin_limits(q, "q")
    return q


def check_Q(model, Q) -> np.ndarray:
    """``Q`` as a finite C-contiguous ``(M, nq)`` float64 array (continuous joints on the unit circle, as
    :func:`check_q`), else a BackendError."""
    refuse_complex_or_bool(Q, "Q", BackendError)
    try:
        Q = np.ascontiguousarray(np.asarray(Q, dtype=np.float64))
    except (TypeError, ValueError) as exc:
        raise BackendError(f"Q: expected an (M, {model.nq}) array of numbers") from exc
    if Q.ndim != 2 or Q.shape[1] != model.nq:
        width = Q.shape[-1] if Q.ndim else None
        raise BackendError(f"Q: expected shape (M, {model.nq}), each row {model.q_layout(width)}, got {Q.shape}")
    if not np.all(np.isfinite(Q)):
        bad = np.argwhere(~np.isfinite(Q))[0]
        raise BackendError(f"Q contains NaN or infinite values (first at {tuple(int(x) for x in bad)})")
    check_unit_circle(model, Q, "Q")
    model.check_pin_limits(Q, "Q")
    return Q


def check_pairs(model, pairs) -> np.ndarray:
    """``pairs`` as a 1-D int64 array of Model pair rows (each in ``[0, n)``), else a BackendError."""
    n = len(model.pairs)
    if isinstance(pairs, np.ndarray) and pairs.dtype == np.int64 and pairs.ndim == 1:
        idx = pairs
    else:
        try:
            arr = np.asarray(pairs)
        except (TypeError, ValueError) as exc:
            raise BackendError(f"pairs: expected an array of Model pair rows, got {pairs!r}") from exc
        if arr.dtype == bool or arr.ndim != 1 or (arr.size and not np.issubdtype(arr.dtype, np.integer)):
            raise BackendError(f"pairs: expected a 1-D array of integer Model pair rows, got dtype {arr.dtype}, "
                               f"shape {arr.shape}")
        idx = arr.astype(np.int64)
    if idx.size and (idx.min() < 0 or idx.max() >= n):
        bad = int(idx[(idx < 0) | (idx >= n)][0])
        raise BackendError(f"pairs: row {bad} is not a Model pair row (the Model lists {n} pairs, rows 0..{n - 1})")
    return np.ascontiguousarray(idx)


@runtime_checkable
class Checker(Protocol):
    """What every backend's checker answers (see the module docstring)."""

    name: str
    model: object
    capabilities: frozenset

    def pair_distances(self, q, *, pairs=None, jacobian: bool = False) -> PairDistances: ...

    def pair_distances_many(self, Q, *, pairs=None) -> PairDistancesMany: ...

    def collides(self, Q, *, margin: float | Mapping | np.ndarray = 0.0, pairs=None) -> np.ndarray: ...


@runtime_checkable
class Backend(Protocol):
    """A plugin: ``name`` and ``build(model, options) -> Checker``.

    Optional methods the framework looks for (``getattr``; a backend without them loses nothing):

    * ``ranger_detector(options)``: the Detector class for Ranger's cycle with this backend, or None
      (the declared fast path, :func:`armguard.detect._ranger.fast_path`);
    * ``warm_up(scene)`` (or ``warm_up(scene, wait=None)``): compile (or load from numba's cache)
      the backend's kernels on ``scene`` before a command's real work (:mod:`armguard.cli._compile`,
      for the default backend); ``wait(name)``, given while a second process compiles, blocks until
      that process has compiled kernel ``name`` of the ``after`` list;
    * ``warm_up_leaves()``: ``(main, side)`` or ``(main, side, after)``, tuples of ``(module,
      function, signature codes)``: leaf kernels worth compiling ahead of ``warm_up``, ``side`` in a
      second process at once, ``after`` in that process once the first has compiled ``main``
      (codes as :func:`armguard.cli._compile.signature` reads them).
    """

    name: str

    def build(self, model, options: Mapping | None = None) -> Checker: ...


class CheckerBase:
    """Framework defaults for the optional fast paths, from the two required queries.

    Subclasses set ``name``, ``model``, ``capabilities`` and implement ``pair_distances`` (when
    they answer distances) and ``collides``; ``representation`` maps GeometryObject names to a
    note where the backend cannot hold the model's exact shape.
    """

    name = "base"
    capabilities: frozenset = frozenset({Capability.DISTANCES, Capability.VERDICTS})
    representation: Mapping = {}
    # True where pair_distances(q, jacobian=True) differentiates every row in the distance pass, at
    # a cost near the distances' (the analytic backend's kernel): a caller wanting the Jacobians of
    # a few rows then asks for all of them; otherwise it asks distance_jacobian for those rows only
    jacobian_with_distances: bool = False
    # True where a separated pair's distance may come out longer than the exact one (an early-stopping
    # GJK): such a distance bounds nothing from below, so Ranger's Detector over the backend takes no
    # lower bound from its memory (armguard.detect._ranger)
    distances_may_run_long: bool = False
    # True where the class's own collides takes margins per pair or category (check_margins,
    # collides_per_pair): the framework then leaves it unwrapped (the wrapper's call costs ~90 ns)
    own_pair_margins: bool = False

    def __init_subclass__(cls, **kwargs) -> None:
        super().__init_subclass__(**kwargs)
        own = cls.__dict__.get("pair_distances")
        if own is not None and "pairs" not in inspect.signature(own).parameters:
            own = cls.pair_distances = _with_pairs(own)
        if own is not None and "jacobian" not in inspect.signature(own).parameters:
            cls.pair_distances = _with_jacobian(own)
        own = cls.__dict__.get("collides")
        if own is not None:  # (own_pair_margins: read from the class body that defines this collides)
            wrapped = _with_pair_margins(own, bool(cls.__dict__.get("own_pair_margins", False)))
            if wrapped is not own:
                cls.collides = wrapped

    def __init__(self, model) -> None:
        self.model = model
        pairs = model.pairs
        self._pairs = pairs.names
        self._category = pairs.category

    def _require(self, cap: Capability) -> None:
        if cap not in self.capabilities:
            raise BackendError(f"backend {self.name!r} does not answer {cap.value} (it answers "
                               f"{sorted(c.value for c in self.capabilities)})")

    def pair_distances(self, q, *, pairs=None, jacobian: bool = False) -> PairDistances:
        """Required of a backend answering distances; here: refuse (no distances)."""
        self._require(Capability.DISTANCES)
        raise NotImplementedError(f"{type(self).__name__} declares distances but does not implement pair_distances")

    def pair_distances_many(self, Q, *, pairs=None) -> PairDistancesMany:
        """Default: :meth:`pair_distances` row by row, stacked (``pairs``: Model pair rows, as there)."""
        self._require(Capability.DISTANCES)
        Q = check_Q(self.model, Q)
        idx = None if pairs is None else check_pairs(self.model, pairs)
        n = len(self._category) if idx is None else len(idx)
        M = len(Q)
        d = np.empty((M, n))
        p_WA = np.empty((M, n, 3))
        p_WB = np.empty((M, n, 3))
        names, cat = self._subset(idx)
        for m in range(M):
            r = self.pair_distances(Q[m], pairs=idx)
            d[m], p_WA[m], p_WB[m] = r.distance, r.p_WA, r.p_WB
        return PairDistancesMany(names, d, p_WA, p_WB, cat)

    def _subset(self, idx) -> tuple:
        """The ``(pairs, category)`` fields of a result holding Model rows ``idx`` (None: all)."""
        if idx is None:
            return self._pairs, self._category
        cat = self._category
        return self._pairs[idx], tuple(cat[int(k)] for k in idx)

    def collides(self, Q, *, margin: float = 0.0, pairs=None) -> np.ndarray:
        """Default: some pair's ``pair_distances(q).distance <= margin`` row by row (``margin``: one for
        every pair, or one per pair or category, :mod:`._margins`; ``pairs``: only those Model pair rows)."""
        self._require(Capability.DISTANCES)
        margin = check_margins(self.model, margin)
        if pairs is not None:
            return collides_subset(self, check_Q(self.model, Q), margin, check_pairs(self.model, pairs))
        Q = check_Q(self.model, Q)
        return np.array([bool(np.any(self.pair_distances(q).distance <= margin)) for q in Q], dtype=bool)

    def nearest(self, q) -> dict:
        """Category -> :class:`NearestPair` at ``q`` (default: from :meth:`pair_distances`)."""
        self._require(Capability.DISTANCES)
        return self.pair_distances(q).nearest()

    def min_distance_many(self, Q) -> np.ndarray:
        """``(M,)`` the smallest signed distance over all pairs at each row (default: row by row)."""
        self._require(Capability.DISTANCES)
        Q = check_Q(self.model, Q)
        return np.array([float(np.min(self.pair_distances(q).distance, initial=np.inf)) for q in Q], dtype=np.float64)

    def distance_jacobian(self, q, result: PairDistances, idx=None) -> tuple:
        """``(jacobian (n, nv), smooth (n,) bool)`` of ``result`` (this checker's distances of the
        Model rows ``idx`` at the checked ``q``).  Default: central differences of
        :meth:`pair_distances` along each velocity direction (``Tolerances.jacobian_step``;
        ``2 nv`` more queries); ``smooth`` is False where the forward and backward differences
        disagree (``Tolerances.jacobian_kink``) or the pair touches, and there the row is the
        forward difference (a one-sided derivative).  A backend with witness points overrides it."""
        from ._jacobian import finite_difference_rows

        tol = self.model.tol
        rows, kink = finite_difference_rows(self, q, idx, step=tol.jacobian_step)
        smooth = ~kink & (np.abs(result.distance) > tol.length)
        if not np.all(smooth):
            fwd, _ = finite_difference_rows(self, q, idx, step=tol.jacobian_step, one_sided=True)
            rows[~smooth] = fwd[~smooth]
        return rows, smooth

    def witness_jacobian(self, q, result: PairDistances, idx=None) -> tuple:
        """:meth:`distance_jacobian` from the witness points (equation (1) of
        :mod:`armguard.backends._jacobian`: Pinocchio's joint Jacobians, one product for all
        pairs; touching pairs by forward differences), for a backend whose witness points are
        exact and whose links move as ``pin_model`` says: set ``distance_jacobian = witness_jacobian``."""
        from ._jacobian import WitnessJacobian, finite_difference_rows

        wj = self.__dict__.get("_witness")
        if wj is None:
            wj = self._witness = WitnessJacobian(self.model, self.model.tol)
        tol = self.model.tol

        def refine(rows):
            sub = rows if idx is None else idx[rows]
            return finite_difference_rows(self, q, sub, step=tol.jacobian_step, one_sided=True)[0]

        return wj.rows(q, result, idx, refine=refine)

    def result(self, d, p_WA, p_WB) -> PairDistances:
        """The :class:`PairDistances` of a full answer: ``d (n,)``, ``p_WA``/``p_WB (n, 3)`` in the order of
        ``model.pairs``, with the Model's pair names and categories."""
        return PairDistances(self._pairs, d, p_WA, p_WB, self._category)

    _result = result  # the name the bundled backends use

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.model.name!r}, {len(self._category)} pairs)"


def _with_jacobian(own):
    """A backend's ``pair_distances(q, pairs=...)`` given the framework's ``jacobian=``
    (:meth:`CheckerBase.distance_jacobian`)."""

    @functools.wraps(own)
    def pair_distances(self, q, *, pairs=None, jacobian: bool = False) -> PairDistances:
        r = own(self, q, pairs=pairs)
        if not jacobian:
            return r
        q = check_q(self.model, q)
        idx = None if pairs is None else check_pairs(self.model, pairs)
        return r.with_jacobian(*self.distance_jacobian(q, r, idx))

    return pair_distances


class _Unset:
    def __repr__(self) -> str:
        return "0.0"


_UNSET = _Unset()  # collides' margin not given: the backend's own default (the contract's 0) applies


def _collides_signature(Q, *, margin: float = 0.0, pairs=None) -> np.ndarray: ...


_SIGNATURE = inspect.signature(_collides_signature)


def _with_pair_margins(own, own_margins: bool = False):
    """A backend's one-margin ``collides`` given the framework's margins per pair or category
    (:func:`._margins.collides_per_pair`, exact from the backend's own answers) and ``pairs=``
    (:func:`subset_verdicts`), unless it takes them itself (``own_pair_margins``; a ``pairs``
    parameter): ``own`` is then returned unwrapped.  A float goes straight through (one type test);
    a margin not given is not passed (the backend's default applies: the contract's 0, which the
    conformance suite checks)."""
    takes_pairs = "pairs" in inspect.signature(own).parameters
    if own_margins and takes_pairs:
        return own

    @functools.wraps(own)
    def collides(self, Q, *, margin=_UNSET, pairs=None) -> np.ndarray:
        if pairs is not None and not takes_pairs:
            return subset_verdicts(self, Q, 0.0 if margin is _UNSET else margin, pairs)
        extra = {} if pairs is None else {"pairs": pairs}
        if margin is _UNSET:
            return own(self, Q, **extra)
        if own_margins or type(margin) is float:
            return own(self, Q, margin=margin, **extra)
        m = check_margins(self.model, margin)
        if type(m) is float:
            return own(self, Q, margin=m, **extra)
        if pairs is not None:  # a margin per pair on a subset: from the pairs' distances
            return subset_verdicts(self, Q, m, pairs)
        return collides_per_pair(self, check_Q(self.model, Q), m)

    collides.__signature__ = _SIGNATURE.replace(parameters=[inspect.Parameter("self", inspect.Parameter.POSITIONAL_OR_KEYWORD),
                                                            *_SIGNATURE.parameters.values()])
    return collides


def subset_verdicts(checker, Q, margin, pairs) -> np.ndarray:
    """``collides(Q, margin=margin, pairs=pairs)`` from ``checker``'s pair distances of those rows
    (:func:`._margins.collides_subset`), every argument checked first; a verdicts-only backend refuses it."""
    if Capability.DISTANCES not in getattr(checker, "capabilities", frozenset({Capability.DISTANCES})):
        raise BackendError(f"{type(checker).__name__}: collides(pairs=...) needs pair distances; this backend answers "
                           "verdicts only (of every pair)")
    model = checker.model
    m = check_margins(model, margin)
    idx = check_pairs(model, pairs)
    return collides_subset(checker, check_Q(model, Q), m, idx)


def _with_pairs(full):
    """``pair_distances(q)`` of a backend given the framework's ``pairs=`` (the full result's rows)."""

    @functools.wraps(full)
    def pair_distances(self, q, *, pairs=None) -> PairDistances:
        if pairs is None:
            return full(self, q)
        self._require(Capability.DISTANCES)
        idx = check_pairs(self.model, pairs)  # refused before any work
        return full(self, q).take(idx)

    # a subset costs the whole call here: Ranger's Detector then evaluates every pair (armguard.detect._ranger)
    pair_distances.pairs_from_full = True
    return pair_distances
