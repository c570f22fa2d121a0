"""The console's view of the backend plugins: one backend's nearest pair for the active arm.

The analytic backend's panel comes from :class:`armguard.detect.Detector` (Ranger's categories,
features, the anytime budget).  Any other installed backend (``armguard.backends.available()``)
answers through its checker: :func:`readout_from_checker` takes every active pair of the model
(``model.pairs``, the order every backend answers in), keeps those with a side on the active arm,
puts that side first, and builds the same :class:`~._readout.Readout` from the smallest signed
distance, its rows in the detector's categories (``arm``, ``environment``, ``workspace``,
``payload``) whatever the backend's own pair categories.  :func:`compare_readouts` is the harness's Δd between two of them, live.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ._readout import CATEGORIES, CategoryRow, PanelStatus, Readout

__all__ = ["BackendView", "Comparison", "compare_readouts", "robot_of"]


def robot_of(owner: str) -> str | None:
    """The robot of a scene owner ``"robot/link"`` (None for bodies, payloads and the workspace)."""
    return owner.split("/", 1)[0] if "/" in owner else None


@dataclass(frozen=True)
class Comparison:
    """Two backends at the same configuration: ``delta`` = ``other.distance - primary.distance`` (m)."""

    primary: str
    other: str
    readout: Readout
    delta: float


class BackendView:
    """A checker of ``backend`` on ``model``, with the owners of its pairs for the active-arm filter."""

    def __init__(self, model, backend: str) -> None:
        from ..backends import checker

        self.model = model
        self.backend = backend
        self.checker = checker(model, backend)
        pairs = model.pairs
        self._owner_a = np.array(pairs.owner_a, dtype=object)
        self._owner_b = np.array(pairs.owner_b, dtype=object)
        held = {name: p.robot for name, p in model.scene.payloads.items()}  # a payload is its carrier arm's: its
        self._robot_a = np.array([held.get(o, robot_of(o)) for o in pairs.owner_a], dtype=object)  # pairs were
        self._robot_b = np.array([held.get(o, robot_of(o)) for o in pairs.owner_b], dtype=object)  # left out (a held
        # payload 1 m inside Hermes's tail read CLEAR on the coal and fcl panels)

    def readout(self, scene, q: dict, active: str, *, threshold: float, stopping_distance: float,
                contact: float) -> Readout:
        """The panel for ``active`` at ``q`` (robot -> joints) from this backend's pair distances."""
        q_pin = self.model.pin_q(scene.flat_q(q))
        t0 = time.perf_counter()
        pd = self.checker.pair_distances(q_pin)
        elapsed_us = (time.perf_counter() - t0) * 1e6
        on_a = self._robot_a == active
        on_b = (self._robot_b == active) & ~on_a
        keep = on_a | on_b
        rows = []
        if not np.any(keep):
            return Readout(PanelStatus.CLEAR, math.inf, "", "", "", None, None, threshold, False, (), elapsed_us,
                           backend=self.backend, stopping_distance=stopping_distance)
        d = np.asarray(pd.distance, dtype=np.float64)
        idx = np.flatnonzero(keep)
        from ..detect._reference import _CAT as _CATEGORY  # the pair categories in the detector's words

        cats = np.array([_CATEGORY.get(str(c), str(c)) for c in pd.category], dtype=object)
        order = {c: k for k, c in enumerate(CATEGORIES)}
        for cat in sorted(dict.fromkeys(cats[idx]), key=lambda c: (order.get(c, len(order)), c)):
            sel = idx[cats[idx] == cat]
            k = int(sel[np.argmin(d[sel])])
            a, b = self._sides(k, on_b[k])
            rows.append(CategoryRow(str(cat), float(d[k]), a, b))
        k = int(idx[np.argmin(d[idx])])
        a, b = self._sides(k, on_b[k])
        pa, pb = np.array(pd.p_WA[k], dtype=np.float64), np.array(pd.p_WB[k], dtype=np.float64)
        if on_b[k]:
            pa, pb = pb, pa
        dist = float(d[k])
        if dist <= max(contact, stopping_distance):
            status = PanelStatus.COLLISION
        elif dist <= threshold:
            status = PanelStatus.WARNING
        else:
            status = PanelStatus.CLEAR
        return Readout(status, dist, a, b, a, pa, pb, threshold, dist <= threshold, tuple(rows), elapsed_us,
                       backend=self.backend, owner_b=b, stopping_distance=stopping_distance)

    def _sides(self, k: int, swap: bool) -> tuple[str, str]:
        a, b = str(self._owner_a[k]), str(self._owner_b[k])
        return (b, a) if swap else (a, b)


def compare_readouts(primary: Readout, other: Readout) -> Comparison:
    """Δd of ``other`` against ``primary`` (m; ``nan`` when either has no nearest pair)."""
    if math.isfinite(primary.distance) and math.isfinite(other.distance):
        delta = other.distance - primary.distance
    else:
        delta = math.nan
    return Comparison(primary.backend, other.backend, other, delta)
