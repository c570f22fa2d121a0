"""One revision of a fused Detector's compiled scene, published whole.

:meth:`FusedDetector.prepare` builds every buffer, table and name a call reads into one
:class:`Built` and stores it with a single attribute assignment (``FusedDetector._b``).  A call
reads that attribute once and takes everything from the object it got: the model buffers, the
offsets of the outputs in the scratch, the pair names, the thread-local scratch made from them.
So a scene edit, and the rebuild it starts on another thread, can never hand one call the buffers
of one revision and the offsets or scratch of the next (numba does not check bounds: such a mix
reads past a buffer's end), and a report keeps answering with the names of the revision that
made it.
"""

from __future__ import annotations

import threading
from typing import TYPE_CHECKING

import numpy as np

from armguard._errors import DetectionError
from armguard.detect._report import CATEGORIES, PairResult

if TYPE_CHECKING:
    from ._detector import FusedDetector

__all__ = ["Built"]


def _readonly(a: np.ndarray) -> np.ndarray:
    a.flags.writeable = False
    return a


class Built:
    """Everything one revision's calls read (see the module docstring).  Made by
    :meth:`FusedDetector.prepare`; nothing here changes after it is published except ``lim`` (``(prm,
    threshold, stopping distance)``, what a call reads once) and ``prm``, replaced (never written) by
    ``set_threshold`` (``FusedDetector._set_limits``), the per-thread scratch in ``tls`` and the
    ``pair_distances`` selection cache."""

    __slots__ = ("det", "revision", "model", "layout", "H", "MF", "MI", "SF0", "SI0", "P", "ev_off", "sum_off",
                 "all_p", "prm", "lim", "iprm", "iprm_by_mode", "tls", "fn", "entry", "call_us", "releases_gil", "q_shape",
                 "names_a", "names_b", "links_a", "static_shapes", "margin_built", "pd_cache")

    def __init__(self, det: "FusedDetector", revision, model) -> None:
        self.det = det
        self.revision = revision
        self.model = model
        self.tls = threading.local()
        self.pd_cache: dict = {}

    # ------------------------------------------------------------------ names and rows
    def pair_names(self, p: int) -> tuple[str, str]:
        return self.names_a[p], self.names_b[p]

    def pair_result(self, p: int, d: float, p_WA: np.ndarray, p_WB: np.ndarray) -> PairResult:
        m = self.model
        b = int(m.pair_b[p])
        feature = None
        shape = self.static_shapes.get(b) if b >= 0 else None
        if shape is not None and m.compiled.elem_core[b] >= 2:
            from armguard.geometry import feature_at

            try:
                feature = feature_at(shape, p_WB, self.det._tol)
            except Exception:  # noqa: BLE001 - a feature is an annotation, never a verdict
                feature = None
        p_WA.flags.writeable = False
        p_WB.flags.writeable = False
        cat = CATEGORIES[int(m.pair_cat[p])]
        return PairResult(d, p_WA, p_WB, self.names_a[p], self.names_b[p], cat, self.links_a[p], self.names_b[p],
                          feature, p)

    def selection(self, robot: str | None) -> tuple:
        """Pair numbers checked by ``pair_distances(q, robot=robot)`` and their static columns (cached)."""
        hit = self.pd_cache.get(robot)
        if hit is not None:
            return hit
        m = self.model
        if robot is None:
            sel = np.arange(self.P, dtype=np.int64)
        else:
            if robot not in m.robot_names:
                raise DetectionError(f"robot: unknown robot {robot!r}; robots are {list(m.robot_names)}")
            r = m.robot_names.index(robot)
            cs = m.compiled
            on_a = cs.elem_robot[m.pair_a] == r
            on_b = np.where(m.pair_b >= 0, cs.elem_robot[np.maximum(m.pair_b, 0)], -1) == r
            sel = np.flatnonzero(on_a | on_b).astype(np.int64)
        la = m.elem_glink[m.pair_a[sel]]
        pb = m.pair_b[sel]
        lb = np.where(pb >= 0, m.elem_glink[np.maximum(pb, 0)], -1)
        ro = lambda a: _readonly(np.ascontiguousarray(a))  # noqa: E731
        hit = (np.ascontiguousarray(sel), ro(la), ro(m.link_robot[la] if len(la) else la.copy()), ro(lb),
               ro(m.pair_cat[sel]), tuple(self.names_a[p] for p in sel), tuple(self.names_b[p] for p in sel),
               ro(sel.copy()))
        self.pd_cache[robot] = hit
        return hit
