"""The backend plugin interface: a Backend builds a Checker for a Model.

A **Checker** answers two required queries for the Model's active pairs
(:attr:`armguard.model.Model.pairs`, in that order):

* ``pair_distances(q) -> PairDistances``: signed distance (``> 0`` apart, ``< 0``
  penetrating) and world witness points of every pair at one configuration ``q`` in
  ``pin_model``'s order ``(nq,)``;
* ``collides(Q) -> (M,) bool``: whether any pair is within ``margin`` (default: touching or
  penetrating, ``distance <= 0``) at each row of ``Q`` ``(M, nq)``.

Optional fast paths have framework defaults built from those two (:class:`CheckerBase`):
``nearest(q)`` (per category, the nearest pair) and ``min_distance_many(Q)``.  A backend that
answers verdicts only (no distances) declares it in ``capabilities`` and the framework checks
it before asking for distances.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import Mapping, Protocol, runtime_checkable

import numpy as np

from .._errors import BackendError

__all__ = ["Backend", "Checker", "CheckerBase", "PairDistances", "NearestPair", "Capability", "check_q", "check_Q"]


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
    """

    pairs: np.ndarray
    distance: np.ndarray
    p_WA: np.ndarray
    p_WB: np.ndarray
    category: tuple

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


def check_q(model, q) -> np.ndarray:
    """``q`` as a finite ``(nq,)`` float64 array in ``pin_model``'s order, else a BackendError."""
    try:
        q = np.asarray(q, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise BackendError(f"q: expected {model.nq} numbers, got {q!r}") from exc
    if q.shape != (model.nq,):
        raise BackendError(f"q: expected shape ({model.nq},) in pin_model's order {list(model.joint_names)}, got {q.shape}")
    if not np.all(np.isfinite(q)):
        raise BackendError(f"q: contains NaN or infinite values: {q.tolist()}")
    return q


def check_Q(model, Q) -> np.ndarray:
    """``Q`` as a finite C-contiguous ``(M, nq)`` float64 array, else a BackendError."""
    try:
        Q = np.ascontiguousarray(np.asarray(Q, dtype=np.float64))
    except (TypeError, ValueError) as exc:
        raise BackendError(f"Q: expected an (M, {model.nq}) array of numbers") from exc
    if Q.ndim != 2 or Q.shape[1] != model.nq:
        raise BackendError(f"Q: expected shape (M, {model.nq}), got {Q.shape}")
    if not np.all(np.isfinite(Q)):
        bad = np.argwhere(~np.isfinite(Q))[0]
        raise BackendError(f"Q contains NaN or infinite values (first at {tuple(int(x) for x in bad)})")
    return Q


@runtime_checkable
class Checker(Protocol):
    """What every backend's checker answers (see the module docstring)."""

    name: str
    model: object
    capabilities: frozenset

    def pair_distances(self, q) -> PairDistances: ...

    def collides(self, Q, *, margin: float = 0.0) -> np.ndarray: ...


@runtime_checkable
class Backend(Protocol):
    """A plugin: ``name`` and ``build(model, options) -> Checker``."""

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

    def __init__(self, model) -> None:
        self.model = model
        pairs = model.pairs
        self._pairs = pairs.names
        self._category = pairs.category

    def _require(self, cap: Capability) -> None:
        if cap not in self.capabilities:
            raise BackendError(f"backend {self.name!r} does not answer {cap.value} (it answers "
                               f"{sorted(c.value for c in self.capabilities)})")

    def pair_distances(self, q) -> PairDistances:  # pragma: no cover - required of subclasses
        raise NotImplementedError

    def collides(self, Q, *, margin: float = 0.0) -> np.ndarray:
        """Default: ``min(pair_distances(q).distance) <= margin`` row by row."""
        self._require(Capability.DISTANCES)
        Q = check_Q(self.model, Q)
        return np.array([bool(np.min(self.pair_distances(q).distance, initial=np.inf) <= margin) for q in Q])

    def nearest(self, q) -> dict:
        """Category -> :class:`NearestPair` at ``q`` (default: from :meth:`pair_distances`)."""
        self._require(Capability.DISTANCES)
        return self.pair_distances(q).nearest()

    def min_distance_many(self, Q) -> np.ndarray:
        """``(M,)`` the smallest signed distance over all pairs at each row (default: row by row)."""
        self._require(Capability.DISTANCES)
        Q = check_Q(self.model, Q)
        return np.array([float(np.min(self.pair_distances(q).distance, initial=np.inf)) for q in Q])

    def _result(self, d, p_WA, p_WB) -> PairDistances:
        return PairDistances(self._pairs, d, p_WA, p_WB, self._category)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.model.name!r}, {len(self._category)} pairs)"
