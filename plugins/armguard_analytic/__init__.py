"""The analytic backend: the papers' exact checker, armguard's numba kernels.

The Model is compiled into flat arrays (its GeometryModel's shapes and ``Model.pairs``,
:mod:`._engine._from_model`; Pinocchio's joint tree, :meth:`armguard.model.Model.kinematic_tree`) and checked by
the fused detector kernel
(:class:`._engine._detector.FusedDetector`, which ``armguard.Detector`` builds for this backend
through ``ranger_detector``): exact signed distances for every shape pair (segment–segment
for Ranger's capsule links, point/segment–face for polytopes, GJK + EPA for hulls), the
Model's own batched forward kinematics compiled from ``pin_model`` (tested against
``pinocchio.forwardKinematics``), bounding-volume pruning and multi-threaded batches.

The engine is this package's own (:mod:`._engine`): the fused Detector (``_detector``,
``_scratch``, ``_raw``, ``_prep``), its compiled model (``_model``, ``_from_model``,
``_bvh``, ``_hulls``), the
packed buffers (``_layout``), the kernel (``_kernel``: FK, broad phase, the modes), the Checker's
entry point (``_pair_rows``), culling (``_cull``), the narrow-phase dispatch over
:mod:`armguard.geometry`'s pair kernels (``_narrow``, ``_step``), the Jacobian kernel
(``_pair_jacobian``) and the first-run warm-up (``_warm``).  The framework reaches it only
through the entry point (``AnalyticBackend.ranger_detector``, ``warm_up``, ``warm_up_leaves``,
``build``); it imports from armguard the public geometry, the Detector's framework parts
(``armguard.detect``: the base class, the result types, the reach analysis and shared checks) and
a few kernels and helpers of ``geometry``, ``kinematics`` and ``backends``.

Options: ``fidelity`` — ``"exact"`` (default), or ``"paper"``: the seeds' minimalist checkers as
the papers state them (Ranger's distances, Hermes's link–obstacle verdicts; option ``verdicts``;
see :mod:`._paper`).  Where this backend cannot hold a Model geometry exactly (a cylinder is a
circumscribed prism), ``representation`` says so.

``pair_distances(q, pairs=None)`` and ``pair_distances_many(Q, pairs=None)`` are one numba call
(:func:`._engine._pair_rows.pair_rows`) that reorders the joints, checks every selected pair
and writes the rows straight in the Model's pair order (sides exchanged where the detector holds
a pair the other way round).  Each thread has its own scratch, so threads sharing a checker get
single-threaded answers; the call releases the GIL, so they run in parallel, when it is long enough
for that to pay (:data:`._engine._scratch.GIL_RELEASE_US`, option ``release_gil``: ``"auto"``, ``True``, ``False``).

Option ``warm_start`` (``False`` by default): a call whose every joint value is within
:data:`._engine._layout.COHERENT_STEP` of the same thread's previous call starts each link-frame GJK
from the simplex that pair ended with there (a motion planner's edge check, a trajectory sampled
finely: ur3 10.3 us a call along a path of 0.01 rad steps against 14.9 us without the option,
``python -m bench robots``).  The answers are the same to ``gjk_epsilon``, but their last bits then
depend on the thread's previous call; off, the same call always gives the same bits.

``pair_distances(q, jacobian=True)`` differentiates every selected pair right after, in a second
numba call on the link poses the first left in the thread's scratch (:mod:`._jacobian`,
:mod:`._engine._pair_jacobian`); ``witness_jacobian`` (Pinocchio's joint Jacobians at the
same witness points) is kept as the slow reference.
"""

from __future__ import annotations

import math
import threading
from concurrent.futures import ThreadPoolExecutor
from typing import Mapping

import numpy as np

from armguard._errors import BackendError
from armguard.backends import (Capability, CheckerBase, PairDistances, PairDistancesMany, check_margin, check_margins,
                               check_pairs, check_q, check_Q, check_unit_circle, collides_per_pair, subset_verdicts)

__all__ = ["AnalyticBackend", "AnalyticChecker"]

_FIDELITIES = ("exact", "paper")
_F64 = np.dtype(np.float64)
_I64 = np.dtype(np.int64)
_ND = np.ndarray
_new_result = PairDistances._unchecked


class _Fast:
    """What one ``pair_distances`` call needs, prepared once per scene revision: the detector's
    buffers of that revision (held here, so a later rebuild of the detector cannot mix with them),
    the gather map, the compiled entry point, and per-thread scratch copied from the pristine one."""

    __slots__ = ("revision", "det", "b", "head", "sel", "swap", "gmap", "n", "names", "category", "q_shape", "entry",
                 "entry_free", "fn", "call_us", "releases_gil", "args", "SF0", "SI0", "n_q", "tls", "subsets", "jac")

    def __init__(self, checker: "AnalyticChecker", release_gil: bool | None = None) -> None:
        from ._engine import _kernel as kn
        from ._engine._calls import addresses
        from ._engine._pair_rows import pair_rows, pair_rows_held
        from ._engine._scratch import GIL_RELEASE_US, compiled, median_call_us

        model = checker.model
        det = checker.detector()
        b = det._fresh()  # one revision of the detector throughout (its ._engine._built)
        self.revision = b.revision
        self.det, self.b = det, b
        inv, swap_rows = checker._order(b)
        n = len(inv)
        swap = np.zeros(n, np.int64)
        swap[swap_rows] = 1
        qidx = np.asarray(model.q_index, dtype=np.int64)
        circ = np.asarray(model._circular, dtype=np.int64)
        # gmap (kernel pair_rows): [nq, n_q, n_circ, n_sel, qidx, circ, sel, swap]
        self.head = np.concatenate([[model.nq, len(qidx), len(circ), n], qidx, circ]).astype(np.int64)
        self.sel, self.swap = inv.astype(np.int64), swap
        self.gmap = np.ascontiguousarray(np.concatenate([self.head, self.sel, self.swap]))
        self.n = n
        pairs = model.pairs
        self.names, self.category = pairs.names, pairs.category
        self.q_shape = (model.nq,)
        self.args = (b.H, b.MF, b.MI, b.prm, b.iprm_by_mode[kn.MODE_ALL])
        self.SF0, self.SI0, self.n_q = b.SF0, b.SI0, b.model.n_q
        if checker._warm_start:  # every thread's scratch starts with warm starts on (._engine._layout "coh")
            from ._engine._layout import K

            self.SF0 = b.SF0.copy()
            self.SF0[b.H[2 * K["coh"]]] = 1.0
        self.tls = threading.local()
        self.subsets: dict = {}  # idx.tobytes() -> (n, gmap, names, category): a repeated subset is planned once
        self.jac = None  # the Jacobian kernel's arrays (._jacobian.JacobianPlan), made on the first jacobian=True
        # the compiled overload for exactly these argument types, called without the dispatcher
        # (see ._engine._scratch._entry_point); built on a scratch of its own
        SF, SI, q1 = self.new_scratch()
        q = np.ascontiguousarray(model.neutral(), dtype=np.float64)
        H, MF, MI, prm, iprm = self.args
        out = (np.empty(n), np.empty((n, 3)), np.empty((n, 3)))
        self.fn = addresses()  # the fused kernel's addresses in this process (._engine._entry)
        call = (self.fn, q, 0, 1, self.gmap, H, MF, MI, SF, SI, prm, iprm, q1, *out)
        self.entry_free = compiled(pair_rows, call)  # releases the GIL (pair_distances_many's workers)
        Q = np.ascontiguousarray(model.random_q(9, 0), dtype=np.float64)
        self.call_us = median_call_us(lambda q: self.entry_free(self.fn, q, *call[2:]), Q)
        if release_gil is None:  # the GIL policy (._engine._scratch.GIL_RELEASE_US)
            release_gil = self.call_us >= GIL_RELEASE_US
        self.releases_gil = bool(release_gil)
        self.entry = self.entry_free if self.releases_gil else compiled(pair_rows_held, call)

    def new_scratch(self) -> tuple:
        """``(SF, SI, q1)``: scratch for one thread or one worker, from the pristine buffers."""
        return self.SF0.copy(), self.SI0.copy(), np.zeros((1, self.n_q))

    def scratch(self) -> tuple:
        """The calling thread's scratch (made on its first call)."""
        try:
            return self.tls.s
        except AttributeError:
            s = self.tls.s = self.new_scratch()
            return s

    def subset(self, idx: np.ndarray) -> np.ndarray:
        """The kernel's ``gmap`` for the Model rows ``idx``."""
        head = self.head.copy()
        head[3] = len(idx)
        return np.concatenate([head, self.sel[idx], self.swap[idx]])

    def subset_plan(self, idx: np.ndarray) -> tuple:
        """``(n, gmap, names, category)`` for the checked Model rows ``idx`` (at most ``n`` of
        them), kept for the next call with the same rows (at most 256 subsets are kept)."""
        key = idx.tobytes()
        plan = self.subsets.get(key)
        if plan is None:
            cat = self.category
            names = self.names[idx]
            names.flags.writeable = False  # handed to every result of this subset
            plan = (len(idx), self.subset(idx), names, tuple(cat[int(k)] for k in idx))
            if len(self.subsets) >= 256:
                self.subsets.clear()
            self.subsets[key] = plan
        return plan


class AnalyticChecker(CheckerBase):
    """A Checker over the fused numba detector (see the module docstring)."""

    name = "analytic"
    capabilities = frozenset({Capability.DISTANCES, Capability.VERDICTS})
    jacobian_with_distances = True  # the Jacobian kernel runs right after the distances
    own_pair_margins = True  # collides takes margins per pair itself (no framework wrapper on the fast path)

    def __init__(self, model, options: Mapping | None = None) -> None:
        super().__init__(model)
        opts = dict(options or {})
        self.fidelity = str(opts.pop("fidelity", "exact"))
        if self.fidelity not in _FIDELITIES:
            raise BackendError(f"analytic: fidelity {self.fidelity!r} is not one of {list(_FIDELITIES)}")
        if self.fidelity != "exact":
            raise BackendError(f"analytic: fidelity {self.fidelity!r} is built by AnalyticBackend().build (armguard.checker)")
        gil = opts.pop("release_gil", "auto")
        if gil not in ("auto", None, True, False):
            raise BackendError(f"analytic: release_gil {gil!r} is not one of ['auto', True, False]")
        self._release_gil = None if gil in ("auto", None) else bool(gil)
        from ._engine._prep import warm_start_option

        self._warm_start = warm_start_option(opts.pop("warm_start", False))
        if opts:
            raise BackendError(f"analytic: unknown options {sorted(opts)}; options are ['fidelity', 'release_gil', "
                               "'warm_start']")
        self.representation = dict(model.notes)
        self._detector = None
        self._nq = model.nq
        # collides: Pinocchio's rows as they are, gathered (a column take), or converted (continuous joints)
        self._scene_order = model.q_in_scene_order
        self._q_take = None if model.has_continuous_joints else model.q_index
        self._q_circ = None  # collides with continuous joints: (qidx, circ, the compiled conversion), on first use
        self._yesno_rows = None  # set with the first detector (:meth:`detector`)
        self._map = None
        self._fast = None
        self._lock = threading.RLock()  # building a detector or the call plan: once, whichever thread asks

    # ---------------------------------------------------------------- detectors
    def detector(self):
        """The fused Detector of the Model (every pair kept, threshold and stopping distance 0): it compiles
        this Model, also after its scene moved on to a derived one (``armguard.model.model_of``).  One for
        every margin of :meth:`collides`: its obstacle lists keep every pair (``reach_margin`` inf), so a
        margin is only the kernel's stopping-distance parameter (a detector per margin cost 32 ms and
        5 MB on panda, 1.1 s and 35 MB on so101, each kept)."""
        det = self._detector
        if det is None:
            from ._engine._batch import yesno_rows
            from ._engine._detector import FusedDetector

            self._yesno_rows = yesno_rows  # collides' path (the engine is imported on first use)
            with self._lock:
                det = self._detector
                if det is None:
                    det = self._detector = FusedDetector(self.model._spec, threshold=0.0, stopping_distance=0.0,
                                                         reach_margin=math.inf, fixed_model=self.model)
        return det

    def _order(self, b=None):
        """For each Model pair row, its detector pair (a gather index), and the Model rows whose
        detector pair has A and B the other way round, in the detector's revision ``b`` (None: its
        current one)."""
        if b is None:
            b = self.detector()._fresh()
        if self._map is not None and self._map[0] == b.revision:
            return self._map[1:]
        m = b.model
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
        self._map = (b.revision, inv, np.sort(dest[swap]))
        return self._map[1:]

    # ---------------------------------------------------------------- the interface
    def _plan(self) -> _Fast:
        """The call plan for the scene's current revision (rebuilt, once, when it moved)."""
        f = self._fast
        if f is not None and f.revision == self.model._spec.revision:
            return f
        with self._lock:
            f = self._fast
            if f is None or f.revision != self.model._spec.revision:
                f = self._fast = _Fast(self, self._release_gil)
                self._pairs, self._category = f.names, f.category
        return f

    @property
    def releases_gil(self) -> bool:
        """Whether ``pair_distances(q)`` releases the GIL: option ``release_gil`` (``"auto"``, the
        default: when one call takes at least ``_engine._scratch.GIL_RELEASE_US``, measured once per scene revision)."""
        return self._plan().releases_gil

    def _q(self, q) -> np.ndarray:
        """``q`` checked, as a fresh writeable C-contiguous float64 array (the kernel's argument type)."""
        return np.array(check_q(self.model, q), dtype=np.float64, order="C")

    def _kernel_error(self, f: _Fast, err: int, Q: np.ndarray, batch: bool):
        e, m = err % 4, err // 4
        if batch:  # the framework's own checks first: their errors name the row (non-finite, circle, limits)
            check_Q(self.model, Q)
        else:
            check_q(self.model, Q[m])
        f.det._raise_kernel_error(e, self.model.scene_q(Q[m:m + 1]), "Detector.pair_distances: q", b=f.b)

    def pair_distances(self, q, *, pairs=None, jacobian: bool = False):
        f = self._fast
        if f is None or f.revision != self.model._spec.revision:
            f = self._plan()
        if type(q) is not _ND or q.dtype is not _F64 or q.shape != f.q_shape or not q.flags.carray:
            q = self._q(q)
        if pairs is None:
            n, gmap, names, cat = f.n, f.gmap, f.names, f.category
            idx = None
        else:
            plan = f.subsets.get(pairs.tobytes()) if type(pairs) is _ND and pairs.dtype is _I64 and pairs.ndim == 1 else None
            if plan is None:  # a subset not seen before (checked, then planned once)
                idx = check_pairs(self.model, pairs)
                if len(idx) > f.n:  # more rows than the scratch holds (repeated rows): the full result's rows
                    return self.pair_distances(q, jacobian=jacobian).take(idx)
                plan = f.subset_plan(idx)
            else:
                idx = pairs
            n, gmap, names, cat = plan
        try:  # this thread's scratch (f.scratch, inline)
            SF, SI, q1 = f.tls.s
        except AttributeError:
            SF, SI, q1 = f.scratch()
        d, p_WA, p_WB = np.empty(n), np.empty((n, 3)), np.empty((n, 3))
        H, MF, MI, prm, iprm = f.args
        err = f.entry(f.fn, q, 0, 1, gmap, H, MF, MI, SF, SI, prm, iprm, q1, d, p_WA, p_WB)
        if err:
            self._kernel_error(f, err, q[None], False)
        if not jacobian:
            return _new_result(names, d, p_WA, p_WB, cat)
        return _new_result(names, d, p_WA, p_WB, cat, *self._jacobian_rows(f, q, idx, SF, d, p_WA, p_WB))

    def _jacobian_rows(self, f: _Fast, q, idx, SF, d, p_WA, p_WB) -> tuple:
        """``(jacobian, smooth)`` of the Model rows ``idx`` (None: all) at ``q``, whose distances and
        witness points are ``d``, ``p_WA``, ``p_WB``, with the link poses the kernel left in ``SF``
        (this thread's scratch, checked at ``q`` last): the Jacobian kernel, then forward
        differences for the touching pairs (as :meth:`CheckerBase.witness_jacobian`)."""
        jp = f.jac or self._jacobian_plan(f)
        n = len(d)
        jac, smooth = np.empty((n, jp.nv)), np.empty(n, np.bool_)
        H, MF, MI = f.args[:3]
        from armguard.backends._jacobian import cores_meet, finite_difference_rows

        touch = jp.entry(H, MF, MI, SF, jp.rows_of(idx), jp.vcol, jp.gF, jp.gI, jp.V, *jp.graph, jp.tol, d, p_WA,
                         p_WB, jac, smooth)
        meet = cores_meet(self.model, d, idx, jp.tol_length)  # two round shapes whose cores meet: a kink
        if touch or meet.any():
            smooth[meet] = False
            touching = np.flatnonzero((np.abs(d) <= jp.tol_length) | meet)
            sub = touching if idx is None else idx[touching]
            jac[touching] = finite_difference_rows(self, q, sub, step=self.model.tol.jacobian_step, one_sided=True)[0]
        return jac, smooth

    def _jacobian_plan(self, f: _Fast):
        """The Jacobian kernel's arrays for the call plan ``f`` (made once, whichever thread asks)."""
        with self._lock:
            if f.jac is None:
                from ._jacobian import JacobianPlan

                f.jac = JacobianPlan(self, f)
        return f.jac

    def distance_jacobian(self, q, result: PairDistances, idx=None) -> tuple:
        """``(jacobian (n, nv), smooth (n,))`` of ``result`` (this checker's distances of the Model
        rows ``idx`` at ``q``): the link poses at ``q`` (the kernel's forward kinematics alone), then
        the Jacobian kernel on ``result``'s witness points."""
        f = self._plan()
        q = self._q(q)
        idx = None if idx is None else check_pairs(self.model, idx)
        n = f.n if idx is None else len(idx)
        if len(result.distance) != n:
            raise BackendError(f"distance_jacobian: {len(result.distance)} distances for {n} Model rows")
        try:
            SF, SI, q1 = f.tls.s
        except AttributeError:
            SF, SI, q1 = f.scratch()
        jp = f.jac or self._jacobian_plan(f)
        H, MF, MI, prm, iprm = f.args
        e = np.empty(0)
        err = f.entry(f.fn, q, 0, 1, jp.zero_gmap, H, MF, MI, SF, SI, prm, iprm, q1, e, e.reshape(0, 3), e.reshape(0, 3))
        if err:
            self._kernel_error(f, err, q[None], False)
        c = np.ascontiguousarray
        return self._jacobian_rows(f, q, idx, SF, c(result.distance, dtype=np.float64), c(result.p_WA, dtype=np.float64),
                                   c(result.p_WB, dtype=np.float64))

    witness_jacobian = CheckerBase.witness_jacobian  # the slow reference: Pinocchio's joint Jacobians at the same witnesses

    def pair_distances_many(self, Q, *, pairs=None) -> PairDistancesMany:
        """Every pair (or the Model rows ``pairs``) at each row of ``Q`` ``(M, nq)``; rows split over
        threads (one numba call each, the GIL released) when there are many.

        Row by row, every pair at each.  The other order, each pair over every row (measured with the
        kernel's one-pair subsets over 200 random rows), took the pairs per row 18.8 us against 18.5
        on ur3, 26.7 against 28.1 on kinova and 63.1 against 73.5 on so101 (hulls of 800-4,262
        vertices, which then stay in the caches), before the forward kinematics it would repeat for
        every pair; not kept."""
        from ._engine._pair_rows import pair_rows
        from ._engine._scratch import row_threads

        f = self._plan()
        Q = check_Q(self.model, Q)
        if not Q.flags.writeable:
            Q = Q.copy()
        if pairs is None:
            n, gmap, (names, cat) = f.n, f.gmap, (f.names, f.category)
        else:
            idx = check_pairs(self.model, pairs)
            if len(idx) > f.n:  # more rows than the scratch holds (repeated rows): the unique rows, then theirs
                u, back = np.unique(idx, return_inverse=True)
                r = self.pair_distances_many(Q, pairs=u)
                return PairDistancesMany(r.pairs[back], r.distance[:, back], r.p_WA[:, back], r.p_WB[:, back],
                                         tuple(r.category[int(k)] for k in back))
            n, gmap, (names, cat) = len(idx), f.subset(idx), self._subset(idx)
        M = len(Q)
        d, p_WA, p_WB = np.empty((M, n)), np.empty((M, n, 3)), np.empty((M, n, 3))
        Qf, df, pAf, pBf = Q.reshape(-1), d.reshape(-1), p_WA.reshape(-1, 3), p_WB.reshape(-1, 3)
        H, MF, MI, prm, iprm = f.args
        n_threads = row_threads(M)
        bounds = [(M * k) // n_threads for k in range(n_threads + 1)]
        entry = pair_rows if not M else f.entry if n_threads == 1 else f.entry_free

        def work(k: int) -> int:
            SF, SI, q1 = f.scratch() if n_threads == 1 else f.new_scratch()  # each worker its own
            return int(entry(f.fn, Qf, bounds[k], bounds[k + 1], gmap, H, MF, MI, SF, SI, prm, iprm, q1, df, pAf, pBf))

        if M == 0:
            errs = [0]
        elif n_threads == 1:
            errs = [work(0)]
        else:
            with ThreadPoolExecutor(n_threads) as ex:
                errs = list(ex.map(work, range(n_threads)))
        bad = [e for e in errs if e]
        if bad:
            self._kernel_error(f, min(bad, key=lambda e: e // 4), Q, True)
        return PairDistancesMany(names, d, p_WA, p_WB, cat)

    def collides(self, Q, *, margin: float = 0.0, pairs=None) -> np.ndarray:
        """Yes/no per row of ``Q`` ``(M, nq)``: the fused kernel's early-exit mode, straight on ``Q``
        when it is already a C-contiguous float64 array of the right width (the kernel itself refuses
        a non-finite row, then :func:`check_Q` names it), the joints reordered only where Pinocchio's
        order is not the scene's."""
        model = self.model
        if pairs is not None:  # those pairs only: from their distances (the fused kernel answers every pair)
            return subset_verdicts(self, Q, margin, pairs)
        margin = check_margin(margin) if type(margin) is float else check_margins(model, margin)
        if type(margin) is not float:  # a margin per pair: decided from this checker's own answers
            return collides_per_pair(self, check_Q(model, Q), margin)
        if type(Q) is not _ND or Q.dtype is not _F64 or Q.ndim != 2 or Q.shape[1] != self._nq or not Q.flags.carray:
            Q = check_Q(model, Q)
            if not Q.flags.writeable:  # a read-only array would compile the kernel again, for that type
                Q = Q.copy()
        if self._scene_order:
            Qs = Q
        elif self._q_take is not None:
            Qs = Q.take(self._q_take, axis=1)
        else:  # each (cos, sin) of a continuous joint checked, then read as its angle (compiled)
            qidx, circ, scene_rows = self._q_circ or self._circ_plan()
            Qs = np.empty((len(Q), len(qidx)))
            bad = scene_rows(Q, qidx, circ, Qs)
            if bad >= 0:
                check_unit_circle(model, Q)  # the row and joint named
                raise BackendError(f"Q: row {bad}: a continuous joint's (cos, sin) is not on the unit circle")
        det = self.detector()
        hit, err = self._yesno_rows(det, Qs, margin)
        if err != 0:
            check_Q(model, Q)  # a non-finite row: the same error as every backend's
            det._raise_kernel_error(err, Qs, "Detector: Q", batch=True)
        return hit

    def _circ_plan(self) -> tuple:
        """``(qidx, circ, scene_rows)`` of :meth:`collides` on a model with continuous joints
        (:func:`._engine._pair_rows.scene_rows`, the joint map of ``pair_distances``' kernel)."""
        from ._engine._pair_rows import scene_rows

        m = self.model
        self._q_circ = plan = (np.ascontiguousarray(m.q_index, dtype=np.int64),
                               np.ascontiguousarray(m._circular, dtype=np.int64), scene_rows)
        return plan

    def min_distance_many(self, Q) -> np.ndarray:
        Q = check_Q(self.model, Q)
        return self.detector().check_many(self.model.scene_q(Q)).min_distance.min(axis=1)


class AnalyticBackend:
    """Entry point ``analytic`` of the group ``armguard.backends``."""

    name = "analytic"

    def ranger_detector(self, options: Mapping | None = None):
        """The declared fast path of ``armguard.Detector``: Ranger's cycle as one fused numba call
        (:class:`._engine._detector.FusedDetector`, a subclass of :class:`armguard.detect.Detector`)
        in the exact fidelity; None (Ranger's algorithm over this backend's Checker) in the paper
        fidelity."""
        opts = dict(options or {})
        fidelity = str(opts.get("fidelity", "exact"))
        if fidelity not in _FIDELITIES:  # before the option names, which depend on it
            raise BackendError(f"analytic: fidelity {fidelity!r} is not one of {list(_FIDELITIES)}")
        exact = fidelity == "exact"
        known = ["fidelity", "release_gil", "warm_start"] if exact else ["fidelity", "verdicts"]  # as the Checker's
        unknown = sorted(set(opts) - set(known))
        if unknown:  # a typo ("warm_strat") would else leave the option off without a word
            raise BackendError(f"analytic: unknown options {unknown}; options are {known}"
                               + ("" if exact else " (fidelity 'paper')"))
        if not exact:
            return None
        from ._engine._detector import FusedDetector

        return FusedDetector

    def warm_up(self, scene, wait=None) -> None:
        """Compile (or load from numba's cache) the fused Detector's and the Checker's kernels on
        ``scene`` (the framework's first-run warm-up, :mod:`armguard.cli._compile`); ``wait(name)``
        blocks until the framework's second process has compiled kernel ``name``."""
        from ._engine._warm import warm_up

        warm_up(scene, wait)

    def warm_up_leaves(self) -> tuple:
        """``(main, side, after)``: the fused kernel's leaf kernels to compile ahead, in two processes,
        and the kernels above them the second process compiles next (:mod:`._engine._warm`)."""
        from ._engine._warm import LEAVES_AFTER, LEAVES_MAIN, LEAVES_SIDE

        return LEAVES_MAIN, LEAVES_SIDE, LEAVES_AFTER

    def build(self, model, options: Mapping | None = None):
        if str(dict(options or {}).get("fidelity", "exact")) == "paper":
            from ._paper import PaperChecker

            return PaperChecker(model, options)
        return AnalyticChecker(model, options)
