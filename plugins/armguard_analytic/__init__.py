"""The analytic backend: the papers' exact checker, armguard's numba kernels.

The Model's scene is compiled into flat arrays and checked by the fused detector kernel
(:class:`armguard.Detector`): exact signed distances for every shape pair (segment–segment
for Ranger's capsule links, point/segment–face for polytopes, GJK + EPA for hulls), the
Model's own batched forward kinematics compiled from ``pin_model`` (tested against
``pinocchio.forwardKinematics``), bounding-volume pruning and multi-threaded batches.

Options: ``fidelity`` — ``"exact"`` (default), or ``"paper"``: the seeds' minimalist checkers as
the papers state them (Ranger's distances, Hermes's link–obstacle verdicts; option ``verdicts``;
see :mod:`._paper`).  Where this backend cannot hold a Model geometry exactly (a cylinder is a
circumscribed prism), ``representation`` says so.
"""

from __future__ import annotations

import math
from typing import Mapping

import numpy as np

from armguard._errors import BackendError
from armguard.backends import Capability, CheckerBase, check_q, check_Q

__all__ = ["AnalyticBackend", "AnalyticChecker"]

_FIDELITIES = ("exact", "paper")


class AnalyticChecker(CheckerBase):
    """A Checker over the fused numba detector (see the module docstring)."""

    name = "analytic"
    capabilities = frozenset({Capability.DISTANCES, Capability.VERDICTS})

    def __init__(self, model, options: Mapping | None = None) -> None:
        super().__init__(model)
        opts = dict(options or {})
        self.fidelity = str(opts.pop("fidelity", "exact"))
        if self.fidelity not in _FIDELITIES:
            raise BackendError(f"analytic: fidelity {self.fidelity!r} is not one of {list(_FIDELITIES)}")
        if self.fidelity != "exact":
            raise BackendError(f"analytic: fidelity {self.fidelity!r} is built by AnalyticBackend().build (armguard.checker)")
        if opts:
            raise BackendError(f"analytic: unknown options {sorted(opts)}; options are ['fidelity']")
        self.representation = dict(model.notes)
        self._detectors: dict = {}
        self._map = None

    # ---------------------------------------------------------------- detectors
    def detector(self, stopping_distance: float = 0.0):
        """The armguard Detector of the Model's scene (every pair kept), one per stopping distance."""
        from armguard.detect import Detector

        key = float(stopping_distance)
        det = self._detectors.get(key)
        if det is None:
            det = self._detectors[key] = Detector(self.model.scene, threshold=0.0, stopping_distance=key,
                                                  reach_margin=math.inf)
        return det

    def _order(self):
        """For each Model pair row, its detector pair (a gather index), and the Model rows whose
        detector pair has A and B the other way round."""
        det = self.detector()
        if self._map is not None and self._map[0] == det._revision:
            return self._map[1:]
        m = det._model
        cs = m.compiled
        model = self.model

        def gname(e: int) -> str:
            if e < 0:
                return "workspace"
            o = int(cs.elem_owner[e])
            return model.geometry_name(cs.owner_names[o], e - int(cs.owner_elem_start[o]))

        pairs = model.pairs
        row = {(a, b): k for k, (a, b) in enumerate(zip(pairs.a, pairs.b))}
        P = len(m.pair_a)
        dest = np.empty(P, np.int64)
        swap = np.zeros(P, bool)
        for p in range(P):
            na, nb = gname(int(m.pair_a[p])), gname(int(m.pair_b[p]))
            if (na, nb) in row:
                dest[p] = row[(na, nb)]
            elif (nb, na) in row:
                dest[p], swap[p] = row[(nb, na)], True
            else:
                raise BackendError(f"analytic: the detector checks pair ({na}, {nb}) that the Model does not list")
        if P != len(pairs) or len(np.unique(dest)) != P:
            raise BackendError(f"analytic: the detector checks {P} pairs, the Model lists {len(pairs)}")
        inv = np.empty(P, np.int64)
        inv[dest] = np.arange(P)
        self._map = (det._revision, inv, np.sort(dest[swap]))
        return self._map[1:]

    # ---------------------------------------------------------------- the interface
    def pair_distances(self, q):
        q = check_q(self.model, q)
        det = self.detector()
        r = det.pair_distances(self.model.scene_q(q))
        inv, sw = self._order()
        d, p_WA, p_WB = r.distance[inv], r.p_WA[inv], r.p_WB[inv]  # gathers into the Model's order
        if sw.size:
            p_WA[sw], p_WB[sw] = p_WB[sw], p_WA[sw].copy()
        return self._result(d, p_WA, p_WB)

    def collides(self, Q, *, margin: float = 0.0) -> np.ndarray:
        Q = check_Q(self.model, Q)
        if not (margin >= 0.0 and math.isfinite(margin)):
            raise BackendError(f"margin: expected a finite length >= 0, got {margin!r}")
        return self.detector(margin).collides_many(self.model.scene_q(Q))

    def min_distance_many(self, Q) -> np.ndarray:
        Q = check_Q(self.model, Q)
        return self.detector().check_many(self.model.scene_q(Q)).min_distance.min(axis=1)


class AnalyticBackend:
    """Entry point ``analytic`` of the group ``armguard.backends``."""

    name = "analytic"

    def build(self, model, options: Mapping | None = None):
        if str(dict(options or {}).get("fidelity", "exact")) == "paper":
            from ._paper import PaperChecker

            return PaperChecker(model, options)
        return AnalyticChecker(model, options)
