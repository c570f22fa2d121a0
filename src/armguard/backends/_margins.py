"""Margins per pair: ``collides(Q, margin=...)`` with a margin for each Model pair or category.

One margin for every pair is rarely what a planner wants: a safety distance to the vehicle and the
cell, but none between the arm's own links, some of which are never far apart (UR5's wrist 2 and
``ee_link`` are at most 19.8 mm apart: at one 2 cm margin every configuration "collides").  So
``margin`` may be

* a number (m): every pair (the default, 0: touching or penetrating);
* a mapping ``{category: m}`` over the Model's pair categories (``Model.pairs.category``:
  ``"arm-arm"``, ``"arm-vehicle"``, ``"arm-environment"``, ``"workspace"``, ``"arm-payload"``,
  ``"payload-*"``; :data:`CATEGORIES`); a category it does not name gets its ``"*"`` entry, else 0,
  and one the model has no pair in is passed over (one mapping serves several models);
* an ``(n,)`` array, one margin per Model pair (``Model.pairs`` order), e.g. from
  :func:`pair_margins` (by category, and MoveIt's padding by part).

Row ``m`` collides when some pair ``k`` has ``distance[m, k] <= margin[k]``.

Every bundled backend that answers distances (analytic, coal, fcl; clip and forbidden answer
verdicts only) answers it through :func:`collides_per_pair`, exactly, from its own
one-margin ``collides`` and its pair distances: rows colliding at the least margin collide, rows
clear at the largest are clear, and only the rows between get the distances of the pairs whose
margin is above the least.  A backend that answers verdicts only (no distances) takes one margin.
"""

from __future__ import annotations

import math
from typing import Mapping

import numpy as np

from .._errors import BackendError
from .._values import has_bool, number
from ..model._items import PairCategory

__all__ = ["CATEGORIES", "by_category", "check_margins", "collides_per_pair", "collides_subset", "pair_margins"]

#: Every pair category a Model may have (``Model.pairs.category``): a margin's mapping may name any of
#: them (one mapping serves several models: a category a model has no pair in is passed over), and
#: ``"*"`` for the categories it does not name.
CATEGORIES = tuple(c.value for c in PairCategory) + ("workspace",)
_M = " (m)"


def by_category(cats, margin: Mapping, error: type = BackendError, what: str = "margin") -> np.ndarray:
    """``margin`` ``{category: m, "*": default}`` as an array over ``cats`` (each pair's category): a category
    not named gets ``"*"``'s value, else 0; a key that is no category is ``error`` naming them all."""
    cats = np.asarray(cats, dtype=object)
    out = np.full(len(cats), number(margin.get("*", 0.0), f"{what}['*']", error, low=0.0, unit=_M))
    for key, value in margin.items():
        if key == "*":
            continue
        if key not in CATEGORIES:
            here = sorted(set(cats.tolist()))
            raise error(f"{what}: {key!r} is not a pair category; the categories: {', '.join(CATEGORIES)} (this model's: "
                        f"{', '.join(here) or 'none'}), and '*' for those not named")
        out[cats == key] = number(value, f"{what}[{key!r}]", error, low=0.0, unit=_M)
    return out


def pair_margins(model, default: float = 0.0, *, categories: Mapping | None = None,
                 padding: Mapping | None = None) -> np.ndarray:
    """An ``(n,)`` margin per Model pair: ``categories.get(pair's category, default)`` (as ``collides``'
    mapping: ``"*"`` for those not named) plus the ``padding`` of each side (MoveIt's link padding: a part
    padded by ``p`` is ``p`` further from everything).  ``padding`` is keyed by the pairs' owners
    (``Model.pairs.owner_a`` / ``owner_b``: ``"robot/link"``, a body, a payload, ``"workspace"``), by a
    link's name alone where one robot has it, or by a robot's name (each of its links).  Unknown
    categories and parts, and a part padded twice, are a BackendError naming them::

        m = armguard.backends.pair_margins(model, 0.02, categories={"arm-arm": 0.0},
                                           padding={"ur5/ee_link": 0.01})
        checker.collides(Q, margin=m)
    """
    pairs = model.pairs
    d = number(default, "default", BackendError, low=0.0, unit=_M)
    out = by_category(pairs.category, {"*": d, **(categories or {})}, what="categories")
    owner_a, owner_b = np.asarray(pairs.owner_a, dtype=object), np.asarray(pairs.owner_b, dtype=object)
    owners = sorted(set(pairs.owner_a) | set(pairs.owner_b))
    padded: dict = {}
    for key, value in (padding or {}).items():
        p = number(value, f"padding[{key!r}]", BackendError, low=0.0, unit=_M)
        hits = ([o for o in owners if o == key] or [o for o in owners if o.startswith(f"{key}/")]
                or [o for o in owners if o.rpartition("/")[2] == key])
        several = len(hits) > 1 and not all(o.startswith(f"{key}/") for o in hits)
        if not hits or several:
            why = "names no part of a pair" if not hits else f"is a link of several robots ({', '.join(hits)})"
            raise BackendError(f"padding: {key!r} {why}; the parts: {', '.join(owners[:12])}"
                               f"{', ...' if len(owners) > 12 else ''} (or a robot's name: each of its links)")
        for o in hits:
            if o in padded:
                raise BackendError(f"padding: {o!r} is padded twice ({padded[o]!r} and {key!r})")
            padded[o] = key
            with np.errstate(over="ignore"):  # a sum past the largest float: refused below
                out += p * (owner_a == o) + p * (owner_b == o)
    if not np.all(np.isfinite(out)):  # finite parts whose sum is not (1e308 twice)
        k = int(np.flatnonzero(~np.isfinite(out))[0])
        raise BackendError(f"pair_margins: the margin of pair {pairs.a[k]!r} - {pairs.b[k]!r} (its category's plus its "
                           "parts' padding) is not a finite number")
    return out


def check_margins(model, margin):
    """``margin`` as a float (one margin for every pair, the fast path: a plain float in range costs one
    type test) or a read-only ``(n,)`` float64 array over ``model.pairs`` (a mapping by category, or an
    array); per-pair margins that are all equal become that float.  Anything else is a BackendError
    naming what was expected: NaN or a negative margin made ``d <= margin`` false everywhere."""
    if type(margin) is float and 0.0 <= margin < math.inf:
        return margin
    n = len(model.pairs)
    forms = f"a number (m), a mapping by pair category or an array of {n} numbers (one per Model pair, Model.pairs order)"
    if isinstance(margin, Mapping):
        out = by_category(model.pairs.category, margin)
    else:
        if isinstance(margin, (list, tuple)) and has_bool(margin):  # numpy reads True among numbers as 1 (m)
            raise BackendError(f"margin: expected {forms}, got a boolean in the list")
        try:
            arr = np.asarray(margin)
        except (TypeError, ValueError):  # a ragged list
            raise BackendError(f"margin: expected {forms}, got {margin!r}") from None
        if arr.ndim == 0:
            if arr.dtype == bool or arr.dtype.kind not in "fiu":
                raise BackendError(f"margin: expected {forms}, got {margin!r}")
            return number(margin, "margin", BackendError, low=0.0, unit=_M)
        if arr.shape != (n,) or arr.dtype == bool or arr.dtype.kind not in "fiu":
            raise BackendError(f"margin: expected {forms}, got dtype {arr.dtype}, shape {arr.shape}")
        out = arr.astype(np.float64)
        bad = np.flatnonzero(~np.isfinite(out) | (out < 0.0))
        if bad.size:
            k = int(bad[0])
            raise BackendError(f"margin[{k}] (pair {model.pairs.a[k]!r} - {model.pairs.b[k]!r}): expected a finite "
                               f"number >= 0 (m), got {float(out[k])!r}")
    if not n or np.all(out == out[0]):  # one margin after all (or no pair for one to apply to)
        return float(out[0]) if n else 0.0
    out.flags.writeable = False
    return out


def collides_per_pair(checker, Q: np.ndarray, margins: np.ndarray) -> np.ndarray:
    """``(M,) bool``: some pair ``k`` with ``distance <= margins[k]``, from ``checker``'s one-margin
    ``collides`` and its ``pair_distances_many`` (``Q`` already checked, ``margins`` from
    :func:`check_margins`).  Exact: a row colliding at the least margin collides at its pair's own, a
    row clear at the largest is clear at every pair's own; the rows between are decided pair by pair
    on the distances of the pairs whose margin is above the least (the others are already clear)."""
    caps = getattr(checker, "capabilities", None)  # (Capability is a str enum: its members equal their values)
    if caps is not None and not any(c == "distances" for c in caps):
        raise BackendError(f"{type(checker).__name__}: a margin per pair needs pair distances; this backend "
                           "answers verdicts only: give one margin")
    lo, hi = float(margins.min()), float(margins.max())
    out = np.array(checker.collides(Q, margin=lo), dtype=bool)  # a copy: the backend's array may be read-only
    rest = np.flatnonzero(~out)
    if rest.size:
        near = rest[checker.collides(Q[rest], margin=hi)]
        if near.size:
            idx = np.flatnonzero(margins > lo)
            d = checker.pair_distances_many(Q[near], pairs=idx).distance
            out[near] = np.any(d <= margins[idx], axis=1)
    return out


def collides_subset(checker, Q: np.ndarray, margins, idx: np.ndarray) -> np.ndarray:
    """``(M,) bool``: some pair of the Model pair rows ``idx`` within its margin (``margins``: a float or the
    ``(n,)`` array of :func:`check_margins`), from ``checker``'s ``pair_distances_many(Q, pairs=idx)``
    (``collides(Q, pairs=idx)``: a planner's allowed-collision changes without a new Model; no pair: False)."""
    if not idx.size or not len(Q):
        return np.zeros(len(Q), dtype=bool)
    m = margins if type(margins) is float else margins[idx]
    return np.any(checker.pair_distances_many(Q, pairs=idx).distance <= m, axis=1)
