"""The analytic backend's Detector: Ranger's real-time virtual sensor as one fused numba call per
check (exact, anytime, batched), a subclass of the framework's :class:`armguard.detect.Detector`."""

from __future__ import annotations

import contextlib
import math
import threading
from time import perf_counter as _perf_counter
from typing import Mapping

import numpy as np

from armguard._errors import DetectionError
from armguard._tolerance import DEFAULT_TOLERANCES, Tolerances
from armguard._values import number, refuse_complex_or_bool
from armguard.detect._common import (check_finite_margin, check_length as _check_length, check_link,
                                     require_pairs as _require_pairs, scene_and_model)
from armguard.detect._detector import Detector
from armguard.detect._extras import attach_extra
from armguard.detect._report import STATUS_CODES, BatchReport, DetectionReport, PairDistances
from armguard.geometry._pair_cylinder import SUPPORT_WORK_SIZE
from armguard.geometry._pair_epa import EPA_WORK_SIZE
from armguard.kinematics._limits import limit_error, limit_rows

from . import _kernel as kn, _scratch
from ._calls import addresses
from ._constant import CST_W, constant_pairs, constant_rows
from ._entry import detect_entry
from ._hulls import link_obbs, vertex_graphs
from ._layout import EV_W, K, SUM_SIZE, Layout
from ._model import CAT_WORKSPACE, build_model
from ._narrow import WORK_TAIL
from ._prep import _fk_blocks, _static_polytopes, _warm_option
from ._raw import _UNHELD, _Raw, _refcount
from ._row_eval import row_evaluator
from ._batch import rows
from ._built import Built
from ._scratch import _entry_point, _Scratch, median_call_us
from ._seeds import seed_tables

__all__ = ["FusedDetector"]

_CYLINDER = 4  # armguard.geometry.CoreKind.CYLINDER
_DEFAULT_NS_PER_PAIR = 200.0  # first guess of the cost model, replaced by measurements


_F64 = np.dtype(np.float64)
_MODE_EXACT = kn.MODE_EXACT


def _single(cats: np.ndarray) -> int:
    """The category shared by all of ``cats``, or -1 when they differ."""
    u = np.unique(cats)
    return int(u[0]) if len(u) == 1 else -1


class FusedDetector(Detector):
    """Ranger's virtual sensor as one fused numba call per check: the analytic backend's
    ``ranger_detector`` (:class:`armguard.detect.Detector` builds it for ``backend="analytic"``;
    the parameters and the API are documented there).

    ``prepare`` compiles the scene once (one kinematic tree, element arrays, conservative
    per-link obstacle lists, a BVH over static obstacles, :mod:`._model`, :mod:`._layout`);
    ``check(q)`` is one numba call (:mod:`._kernel`: FK, transforms, broad and narrow phase).

    Thread safety: each thread gets its own scratch buffers (:mod:`._scratch`); the numba
    kernels release the GIL, so the checks of several threads run in parallel, except a check
    too short for handing the GIL over to pay (``releases_gil``, ``call_us``: ``_scratch.GIL_RELEASE_US``).
    """
    backend = "analytic"  # the backend whose Detector this is (RangerDetector.backend names its own)

    def __init__(self, scene, threshold: float = 0.05, *, stopping_distance: float = 0.0, active: str | None = None,
                 tol: Tolerances = DEFAULT_TOLERANCES, reach_margin: float = math.inf, backend: str | None = None,
                 backend_options=None, terrain=None, fixed_model=None) -> None:
        self.scene, _ = scene_and_model(scene)  # a Model: its scene (the Model is the scene's model of record)
        # fixed_model: compile this Model, not the scene's current one (an AnalyticChecker answers
        # for its Model, over the Model's own copy of its system, which never changes); otherwise the
        # detector follows the scene (model_of(scene), rebuilt on change)
        self._fixed_model = fixed_model
        self._threshold = _check_length(threshold, "threshold")
        self._stopping = _check_length(stopping_distance, "stopping_distance")
        self._tol = tol
        self._reach_margin = check_finite_margin(reach_margin)
        self._active = active
        self._ns_per_pair = _DEFAULT_NS_PER_PAIR
        self._ns_min = math.inf  # the least ns a pair has taken in a check (_learn's floor; inf: none yet)
        self._prepare_lock = threading.RLock()
        self._with_terrain = terrain is not None  # terrain alone is something to check
        self._warm_start = _warm_option(backend, backend_options)
        self.prepare()
        if terrain is not None:  # the terrain category: check() returns armguard.terrain's merged report
            attach_extra(self, "terrain", terrain)

    # ------------------------------------------------------------------ set-up
    def prepare(self) -> "FusedDetector":
        """(Re)compile the scene: obstacle lists, BVH, buffers.  Call after changing the scene.

        Holds the scene's lock while it reads the scene (an edit on another thread waits), and
        publishes the result with one assignment (:mod:`._built`): a call running meanwhile finishes
        on the revision it started with."""
        with self._prepare_lock, (getattr(self.scene, "lock", None) or contextlib.nullcontext()):
            self._b = self._build()
        return self

    def _build(self) -> Built:
        margin = max(self._reach_margin, self._threshold, self._stopping)
        revision = getattr(self.scene, "revision", None)  # read before compiling: a change during it is seen
        m = build_model(self.scene, active=self._active, reach_margin=margin, tol=self._tol, model=self._fixed_model)
        b = Built(self, revision, m)
        cs = m.compiled
        _require_pairs(self.scene, cs, self._active, self._with_terrain or self.terrain is not None)
        t = m.tree
        L = Layout()
        nq = max(m.n_q, 1)
        P = len(m.pair_a)
        G = cs.n_elements
        lever = np.zeros((len(m.mov_ids), nq))
        lever[:, :m.n_q] = m.lever
        # moving elements with static pairs, and the category of those pairs (-1: mixed), which
        # sets the BVH walk's cut-off (a category without pairs keeps an infinite minimum)
        with_static = np.any(m.pair_of >= 0, axis=1) if len(m.st_ids) else np.zeros(len(m.mov_ids), bool)
        st_mov = m.mov_ids[with_static]
        st_cat = np.array([_single(m.pair_cat[row[row >= 0]]) for row in m.pair_of[with_static]], dtype=np.int64)
        # the yes/no batch walks them farthest-reaching first (largest summed lever arm: the links
        # that sweep the most space meet obstacles most often), so it exits early on a likely hit;
        # the distance modes keep the kinematic order (base first), which prunes better for them
        by_reach = np.argsort(-lever.sum(axis=1)[with_static], kind="stable")
        yn_mov = np.ascontiguousarray(st_mov[by_reach], dtype=np.int64)
        yn_cat = np.ascontiguousarray(st_cat[by_reach], dtype=np.int64) if len(st_cat) else np.zeros(0, np.int64)
        L.add("MF", "X_pre", t.X_pre); L.add("MF", "axis", t.axis); L.add("MF", "X_post", t.X_post)
        L.add("MF", "offset", t.offset); L.add("MF", "term_coeff", t.term_coeff); L.add("MF", "radius", cs.elem_radius)
        L.add("MF", "verts_L", cs.verts.reshape(-1, 3)); L.add("MF", "box_L", m.box_local.reshape(-1, 15))
        vg = vertex_graphs(cs, m.fnrm_local, m.edir_local, self._tol.parallel)  # hulls' graphs; axes one per class
        L.add("MF", "obb_L", link_obbs(cs, m.elem_glink, self._tol.length))  # the yes/no cull
        L.add("MF", "fn_L", vg["fn_L"]); L.add("MF", "ed_L", vg["ed_L"])
        L.add("MF", "sph_L", cs.elem_sphere.reshape(-1, 4)); L.add("MF", "static_lo", m.static_lo.reshape(-1, 3))
        L.add("MF", "static_hi", m.static_hi.reshape(-1, 3)); L.add("MF", "bvh_lo", m.bvh.lo.reshape(-1, 3))
        L.add("MF", "bvh_hi", m.bvh.hi.reshape(-1, 3)); L.add("MF", "lever", lever)
        L.add("MF", "ws", np.concatenate([m.ws_lo, m.ws_hi]))
        qlim = limit_rows(m.lower, m.upper, self._tol.joint_limit)
        L.add("MF", "qlim", qlim)  # refused outside (kinematics._limits)
        b.static_shapes = dict(m.static_shapes)  # element number -> its shape (W), static bodies
        poly = _static_polytopes(cs, b.static_shapes)
        L.add("MF", "pv", poly["pv"]); L.add("MF", "ppl", poly["ppl"]); L.add("MF", "pbis", poly["pbis"])
        L.add("MF", "pcen", poly["pcen"])
        for name in ("gadj", "gadjs", "gtri", "gtris", "gdir", "gdirs"):
            L.add("MI", name, vg[name])
        seeds = seed_tables(t, qlim, m.elem_glink, cs.elem_core, cs.elem_vert_start, cs.verts.reshape(-1, 3), vg["gadj"],
                            vg["gadjs"], vg["gdir"], vg["gdirs"], m.pair_a, m.pair_b, m.mov_idx, self._tol.length,
                            self._tol.gjk_epsilon, self._tol.gjk_max_iterations)
        L.add("MI", "spair", seeds["spair"]); L.add("MF", "sgrid", seeds["sgrid"]); L.add("MI", "sdt", seeds["sdt"])
        cst, cst_frame = constant_pairs(t, m.elem_glink, m.pair_a, m.pair_b)  # rows filled once the buffers exist
        L.add("MI", "cst", cst); L.add("MF", "cstv", np.zeros((max(len(cst_frame), 1), CST_W)))
        rob_l, rob_j, parent_loc = _fk_blocks(t.parent, m.link_robot, [len(self.scene.robots[r].joint_names)
                                                                        for r in m.robot_names])
        for name, arr in (("parent", t.parent), ("jtype", t.jtype), ("has_post", t.has_post.astype(np.int64)),
                          ("term_start", t.term_start), ("term_joint", t.term_joint), ("glink", m.elem_glink),
                          ("core", cs.elem_core), ("vstart", cs.elem_vert_start), ("pstart", vg["pstart"]),
                          ("estart", vg["estart"]), ("mov_idx", m.mov_idx), ("st_idx", m.st_idx),
                          ("bvh_left", m.bvh.left), ("bvh_right", m.bvh.right), ("bvh_start", m.bvh.start),
                          ("bvh_count", m.bvh.count), ("bvh_items", m.bvh.items), ("pair_a", m.pair_a),
                          ("pair_b", m.pair_b), ("pair_cat", m.pair_cat),
                          ("pair_of", m.pair_of.reshape(len(m.mov_ids), max(len(m.st_ids), 1)) if len(m.st_ids) else
                           np.full((len(m.mov_ids), 1), -1)),
                          ("mov_ids", m.mov_ids), ("ped", poly["ped"]), ("poly_of", poly["poly_of"]),
                          ("pvs", poly["pvs"]), ("pps", poly["pps"]), ("pes", poly["pes"]),
                          ("all_p", np.arange(P, dtype=np.int64)),
                          ("st_mov", st_mov), ("st_cat", st_cat), ("yn_mov", yn_mov), ("yn_cat", yn_cat),
                          ("rob_l", rob_l), ("rob_j", rob_j),
                          ("parent_loc", parent_loc)):
            L.add("MI", name, arr)
        # scratch: "ev" holds the evaluated pairs' rows (one copy per report), "summary" and "ev_p"
        # are adjacent (one copy)
        stack_n = 2 * m.bvh.depth + 8
        static_mask = m.elem_glink < 0
        boxW0 = m.box_local.copy()
        vW0 = np.array(cs.verts, dtype=np.float64).reshape(-1, 3)
        sphW0 = np.array(cs.elem_sphere, dtype=np.float64).reshape(-1, 4)
        fnW0 = vg["fn_L"].copy()
        edW0 = vg["ed_L"].copy()
        del static_mask  # static elements are already in W: the scratch starts as their copy
        # room for EPA where a hull has a vertex graph, and for GJK + EPA on support functions
        # (armguard.geometry._pair_cylinder) where a cylinder is present
        # (armguard.geometry._pair_cylinder) where a cylinder is present; EPA also serves the small
        # polytopes without a graph (scanned supports: on rover's box and prisms 0.8-3 us a depth,
        # where the SAT on W points it replaces took 10 us, moving the elements included)
        has_cyl = bool(np.any(cs.elem_core == _CYLINDER))
        has_epa = len(vg["gadj"]) > 0 or bool(np.any(cs.elem_core == 3)) or int(np.count_nonzero(cs.elem_core == 2)) >= 2
        n_work = max(EPA_WORK_SIZE if has_epa else 64, SUPPORT_WORK_SIZE if has_cyl else 64) + WORK_TAIL
        for name, arr in (("Xs", np.zeros((t.n_links, 4, 4))), ("vW", vW0), ("boxW", boxW0), ("fnW", fnW0),
                          ("edW", edW0), ("sphW", sphW0), ("out9", np.zeros(9)), ("work", np.zeros(n_work)),
                          ("gap", np.zeros(stack_n)), ("ev", np.zeros((P, EV_W))),
                          ("plb", np.zeros(P)), ("last_d", np.zeros(P)), ("last_q", np.zeros((P, nq))),
                          ("best", np.zeros(4)), ("seg", np.zeros((2, 3))), ("fk_q", np.zeros(max(m.n_q, 1))),
                          ("lseed", np.zeros((P, 7))), ("coh", np.zeros(2))):
            L.add("SF", name, arr)
        for name, arr in (("summary", np.full(SUM_SIZE, -1)), ("ev_p", np.zeros(P)), ("pflag", np.zeros(P)),
                          ("stack", np.zeros(stack_n)), ("order", np.zeros(P)), ("has_last", np.zeros(P)),
                          ("stamp", np.zeros(1 + G)), ("pstamp", np.zeros(P)), ("fk_ok", np.zeros(len(rob_l) - 1))):
            L.add("SI", name, arr)
        L.scalar("n_q", m.n_q); L.scalar("n_explicit", m.n_explicit); L.scalar("n_mov", len(m.mov_ids))
        L.scalar("n_st", len(m.st_ids)); L.scalar("n_links", t.n_links)
        b.layout = L
        # SF0 / SI0: the pristine scratch every thread's own copy starts from (never passed to a kernel)
        b.H, b.MF, b.MI, b.SF0, b.SI0 = L.buffers()
        b.SF0[b.H[2 * K["coh"]]] = 1.0 if self._warm_start else 0.0  # each thread's warm starts (._layout "coh")
        b.P = P
        b.ev_off = L._shape["ev"][1]
        b.sum_off = L._shape["summary"][1]  # "ev_p" follows it
        b.all_p = L.view(b.MI, "all_p")
        b.prm = np.array([self._threshold, self._stopping, self._tol.length, self._tol.parallel,
                              self._tol.gjk_epsilon, self._tol.penetration_witness_offset])
        b.lim = (b.prm, self._threshold, self._stopping)
        b.iprm = np.array([kn.MODE_EXACT, 0, self._tol.gjk_max_iterations, 1, 0], dtype=np.int64)
        b.iprm_by_mode = {}
        for mode in (kn.MODE_EXACT, kn.MODE_LAZY, kn.MODE_ANYTIME, kn.MODE_YESNO, kn.MODE_ALL, kn.MODE_MIN):
            ip = b.iprm.copy()
            ip[0] = mode
            b.iprm_by_mode[mode] = ip
        # per-thread scratch: b.tls (a report reading the old buffers keeps them alive: nothing to copy)
        b.fn = addresses()  # the kernels' addresses in this process, the entry points' first argument
        b.q_shape = (m.n_q,)
        b.names_a = tuple(cs.owner_names[cs.elem_owner[a]] for a in m.pair_a)
        b.names_b = tuple("workspace" if e < 0 else cs.owner_names[cs.elem_owner[e]] for e in m.pair_b)
        b.links_a = tuple(m.link_names[m.elem_glink[a]] for a in m.pair_a)
        b.margin_built = margin
        constant_rows(b, cst_frame)  # the pairs whose relative pose never changes: computed once (._constant)
        b.entry, b.call_us, b.releases_gil = self._pick_entry(b)
        return b

    def _fresh(self) -> None:
        """Rebuild when the scene changed since :meth:`prepare` (a body added, a filter changed, ...).

        A query on a stale model could say CLEAR while a new body encloses a link; every query
        compares ``scene.revision`` (one attribute read) and recompiles when it moved (once, when
        several threads see it)."""
        b = self._b
        if getattr(self.scene, "revision", None) != b.revision:
            with self._prepare_lock:
                if getattr(self.scene, "revision", None) != self._b.revision:
                    self.prepare()
                b = self._b
        return b

    def _scratch(self, b: Built | None = None) -> _Scratch:
        """The calling thread's scratch of revision ``b`` (None: the current one; made on its first call)."""
        if b is None:
            b = self._b
        try:
            return b.tls.s
        except AttributeError:
            s = b.tls.s = _Scratch(b)
            return s

    # the current revision's parts, by their former names (tests read them;
    # a call reads self._b once instead, so that a rebuild meanwhile cannot mix two revisions)
    _model = property(lambda self: self._b.model)
    _layout = property(lambda self: self._b.layout)
    _H = property(lambda self: self._b.H)
    _MF = property(lambda self: self._b.MF)
    _MI = property(lambda self: self._b.MI)
    _names_a = property(lambda self: self._b.names_a)
    _names_b = property(lambda self: self._b.names_b)
    call_us = property(lambda self: self._b.call_us, doc="One exact check's measured time (µs) when prepared.")
    releases_gil = property(lambda self: self._b.releases_gil, doc="Whether ``check`` releases the GIL.")

    # the calling thread's buffers, by their former names (tests and tools read them)
    _SF = property(lambda self: self._scratch().SF)
    _SI = property(lambda self: self._scratch().SI)
    _last_raw = property(lambda self: self._scratch().last_raw)

    # ------------------------------------------------------------------ settings
    @property
    def threshold(self) -> float:
        """Detection threshold (m)."""
        return self._threshold

    @property
    def stopping_distance(self) -> float:
        """Stopping distance (m); 0 when unset."""
        return self._stopping

    @property
    def active(self) -> str | None:
        """The active robot's name, or None for all arms."""
        return self._active

    @property
    def link_names(self) -> tuple[str, ...]:
        """Global link names ``"robot/link"`` (the index space of ``PairDistances.link_a``)."""
        return self._b.model.link_names

    @property
    def n_pairs(self) -> int:
        """Number of candidate element pairs (after pair filters, active arm and obstacle lists)."""
        return self._b.P

    def set_threshold(self, threshold: float) -> None:
        self._set_limits(_check_length(threshold, "threshold"), self._stopping)

    def set_stopping_distance(self, stopping_distance: float) -> None:
        self._set_limits(self._threshold, _check_length(stopping_distance, "stopping_distance"))

    def _set_limits(self, threshold: float, stopping: float) -> None:
        """Publish a new threshold and stopping distance.  A call reads ``Built.lim`` once, passes its
        ``prm`` to the kernel and reports its values, so ``prm`` is never written after it is
        published: the new values go into a new array, published with them in one assignment (a call on another
        thread meanwhile keeps the one it started with; writing ``prm[0]`` in place could hand one call two thresholds).  A
        value beyond the margin the obstacle lists were built with rebuilds them first: until that
        build is published, calls run on the old one with the old values, never on lists too short
        for the new threshold."""
        with self._prepare_lock:
            b = self._b
            if max(threshold, stopping) > b.margin_built:
                old = self._threshold, self._stopping
                self._threshold, self._stopping = threshold, stopping
                try:
                    self.prepare()
                except BaseException:
                    self._threshold, self._stopping = old  # the build in use keeps its values
                    raise
                return
            prm = b.prm.copy()
            prm[0], prm[1] = threshold, stopping
            b.lim = (prm, threshold, stopping)  # what the calls read
            b.prm = prm
            self._threshold, self._stopping = threshold, stopping

    def set_active(self, name: str | None) -> None:
        self._switch_active(name, self._prepare_lock)

    def obstacle_list(self, link: str) -> tuple[str, ...]:
        """Owner names in the obstacle list of ``link`` (``"robot/link"``), in pair order."""
        check_link(self.scene, link)
        b = self._fresh()
        out = []
        for p in range(b.P):
            if b.links_a[p] == link and b.names_b[p] not in out:
                out.append(b.names_b[p])
        return tuple(out)

    # ------------------------------------------------------------------ queries
    def _flat_q(self, q, q1: np.ndarray) -> np.ndarray:
        """``q`` (array or mapping) written into ``q1`` ``(1, n_q)`` (a thread's scratch), checked."""
        n_q = q1.shape[1]
        if isinstance(q, np.ndarray) and q.dtype == np.float64 and q.shape == (n_q,):
            q1[0] = q
            return q1
        refuse_complex_or_bool(q, "q", DetectionError)
        if isinstance(q, Mapping):
            flat = self.scene.flat_q(q)
        else:
            try:
                flat = np.asarray(q, dtype=np.float64)
            except (TypeError, ValueError) as exc:
                raise DetectionError(f"q: expected numbers, got {q!r}") from exc
        if flat.shape != (n_q,):
            raise DetectionError(
                f"q: expected one configuration of {n_q} joints (scene.joint_names), got shape {flat.shape}"
            )
        q1[0] = flat
        return q1

    @staticmethod
    def _release_last(s: _Scratch) -> None:
        """Before a thread's scratch buffers are overwritten: let its last report copy its rows out
        if anything still refers to it (a report nobody holds needs no copy)."""
        last = s.last_raw
        if last is not None:
            s.last_raw = None
            if _refcount(last) > _UNHELD:
                last.detach()

    def _pick_entry(self, b: Built) -> tuple:
        """``(entry, call_us, releases_gil)``: ``check``'s compiled entry, releasing the GIL when one
        exact check takes at least ``GIL_RELEASE_US`` (:mod:`._scratch`; timed on a scratch of its
        own at 9 seeded in-limit configurations, so no thread's state moves)."""
        m = b.model
        s = _Scratch(b)
        free = _entry_point(*s.entry_args)
        lo, hi = np.maximum(m.lower, -np.pi), np.minimum(m.upper, np.pi)
        Q = np.random.default_rng(0).uniform(lo, hi, (9, len(lo))) if len(lo) else np.zeros((9, 0))

        def run(q):
            s.q1[0] = q
            free(*s.entry_args)

        us = median_call_us(run, Q)
        if us >= _scratch.GIL_RELEASE_US:
            return free, us, True
        return _entry_point(*s.entry_args, release_gil=False), us, False

    def _run(self, s: _Scratch, mode: int, allowance: int, lazy: bool, sel=None) -> tuple[int, int, tuple]:
        """One kernel call in ``mode`` on this thread's scratch: ``(status, evaluated pairs, lim)``,
        ``lim`` the ``Built.lim`` the call read (``_set_limits``)."""
        self._release_last(s)
        b = s.b
        lim = b.lim
        q1 = s.q1
        iprm = s.iprm_by_mode[mode]
        if mode == kn.MODE_ANYTIME:
            iprm[1] = allowance
            iprm[4] = 1 if lazy else 0
        if sel is None:  # the same argument types as check's: its bound overload, without the dispatcher
            status, n_eval, err = b.entry(b.fn, q1, b.H, b.MF, b.MI, s.SF, s.SI, lim[0], iprm, b.all_p)
        else:
            status, n_eval, err = detect_entry(b.fn, q1, b.H, b.MF, b.MI, s.SF, s.SI, lim[0], iprm, sel)
        if err:
            self._raise_kernel_error(err, q1, "Detector.check: q" if sel is None else "Detector.pair_distances: q", b=b)
        return status, n_eval, lim

    def _raise_kernel_error(self, err: int, Q: np.ndarray, where: str = "Detector.check: q", batch: bool = False,
                            b: Built | None = None) -> None:
        """The kernel's error code for ``Q`` ``(M, n_q)`` as an ArmguardError (1 non-finite, 3 outside the
        joint limits: :mod:`armguard.kinematics._limits`, 2 GJK); ``batch``: name the row; ``b``: the
        revision that ran (None: the current one)."""
        if err == 1:
            bad = np.argwhere(~np.isfinite(Q))[0]
            at = f"row {int(bad[0])}, joint {int(bad[1])}" if batch else f"joint {int(bad[1])}"  # one q: not a 2-D index
            raise DetectionError(f"{where} contains NaN or infinite values (first at {at}: {Q[tuple(bad)]})")
        if err == 3:
            m = (b or self._b).model
            exc = limit_error(where, Q if batch else Q[0], self.scene.joint_names, m.lower, m.upper,
                              self._tol.joint_limit)
            if exc is not None:
                raise exc
        raise DetectionError("a convex distance kernel did not converge (GJK iteration limit); no verdict")

    def check(self, q, *, budget_us: float | None = None, lazy: bool = False,
              jacobian: bool = False) -> DetectionReport:
        """Check configuration ``q`` (mapping robot -> joints, or flat over ``scene.joint_names``).

        ``budget_us``: time budget (µs) for the anytime mode; the budget is turned into a
        number of pair evaluations by a cost model measured on this machine (updated after
        every check), pairs are evaluated most likely first, and the report names the pairs
        left with a lower bound on their distance.  ``lazy``: skip pairs whose lower bound
        already exceeds the threshold (exact status; nearest per category exact within it).

        Cost: one numba call and two small copies (the evaluated pairs' rows); the report's
        ``PairResult`` objects are built on first access.  ``jacobian=True``: the report's
        ``jacobian`` holds each category's nearest pair's ``d(distance)/dq`` ``(pin_model.nv,)``
        and ``smooth`` flag (:mod:`armguard.detect._category_jacobian`; the Model's analytic
        Checker, one pair row each); nothing of it is computed otherwise.
        """
        if jacobian:
            return self._check_with_jacobian(q, budget_us, lazy)
        b = self._b  # one revision for the whole call (._built)
        if getattr(self.scene, "revision", None) != b.revision:  # stale model: rebuild (see _fresh)
            b = self._fresh()
        t0 = _perf_counter()  # after any rebuild: the cost model learns what a check costs, not a rebuild
        try:  # this thread's scratch (_scratch, inline)
            s = b.tls.s
        except AttributeError:
            s = self._scratch(b)
        q1 = s.q1
        if type(q) is np.ndarray and q.dtype is _F64 and q.shape == b.q_shape:
            q1[0] = q  # the common case, inline (validation of everything else in _flat_q)
        else:
            self._flat_q(q, q1)
        last = s.last_raw
        if last is not None:  # _release_last, inline
            s.last_raw = None
            if _refcount(last) > _UNHELD:
                last.detach()
            del last
        if budget_us is None and not lazy:
            args = s.entry_args
            lim = b.lim  # read once: the values this call uses and reports (_set_limits)
            if args[7] is not lim[0]:
                args = s.bind_prm(lim[0])
            status, n_eval, err = b.entry(*args)  # q1 is the array in entry_args
            if err:
                self._raise_kernel_error(err, q1, b=b)
            raw = _Raw(b, s.SF, s.SI, b.ev_off, b.sum_off, n_eval, None, None, _MODE_EXACT)
            s.last_raw = raw
            elapsed = (_perf_counter() - t0) * 1e6
            if n_eval > 0:  # _learn, inline (the exact check is the hot path): within 4x, no clamp needed
                ref = self._ns_per_pair
                x = elapsed * 1e3 / n_eval
                if 0.25 * ref <= x <= 4.0 * ref and x >= 1.0:
                    self._ns_per_pair = 0.8 * ref + 0.2 * x
                    self._ns_min = x if x < self._ns_min else self._ns_min
                else:
                    self._learn(elapsed, n_eval, None)
            return DetectionReport._from_check(STATUS_CODES[status], lim[1], lim[2], elapsed, raw)
        if budget_us is not None:
            us = number(budget_us, "budget_us", DetectionError, low=0.0, unit=" (µs)")  # not True, "5", 1e400
            n = max(0.0, us * 1e3) / self._ns_per_pair  # us * 1e3 may overflow to inf (1e306): every pair
            mode = kn.MODE_ANYTIME  # the allowance an int64 for the kernel
            status, n_eval, lim = self._run(s, mode, int(n) if n < 2.0 ** 62 else 2 ** 62, lazy)
        else:
            mode = kn.MODE_LAZY if lazy else kn.MODE_EXACT
            status, n_eval, lim = self._run(s, mode, 0, False)
        raw_buffers = (s.SF, s.SI, b.ev_off, b.sum_off)
        if mode == kn.MODE_EXACT:
            flags = bounds = None
        else:
            flags, bounds = s.pflag.copy(), s.plb.copy()
        elapsed = (_perf_counter() - t0) * 1e6
        self._learn(elapsed, n_eval, budget_us)
        raw = s.last_raw = _Raw(b, *raw_buffers, n_eval, flags, bounds, mode, max(lim[1], lim[2]))
        return DetectionReport._from_check(STATUS_CODES[status], lim[1], lim[2], elapsed, raw)

    def _learn(self, elapsed_us: float, n_eval: int, budget_us) -> None:
        """The anytime mode's cost model, an exponential average of ns per evaluated pair, after one check.  One
        outlier (a pause, a wait for the GIL) moves it at most 4x, as Ranger's detector over a Checker; a positive
        budget that fitted no pair lowers it (else one outlier could leave every later budgeted check at 0 pairs),
        not below half the least ns a pair has taken (budgets fitting no pair took it from 5213 to 0.85 ns)."""
        ref = self._ns_per_pair
        if n_eval > 0:
            x = max(elapsed_us * 1e3 / n_eval, 1.0)
            self._ns_per_pair = 0.8 * ref + 0.2 * min(max(x, 0.25 * ref), 4.0 * ref)
            self._ns_min = min(self._ns_min, x)
        elif budget_us:
            least = self._ns_min if self._ns_min < math.inf else _DEFAULT_NS_PER_PAIR  # none measured: the guess
            self._ns_per_pair = max(0.8 * ref, min(ref, 0.5 * least))

    def _check_with_jacobian(self, q, budget_us, lazy) -> DetectionReport:
        b = self._fresh()
        report = self.check(q, budget_us=budget_us, lazy=lazy)
        q_flat = self._flat_q(q, np.zeros((1, b.model.n_q)))[0]  # what check() read, in scene order
        with self._prepare_lock:
            hit = getattr(self, "_category_jac", None)
            if hit is None or hit[0] != b.revision:
                from armguard.model import model_of
                from armguard.detect._category_jacobian import CategoryJacobians

                hit = self._category_jac = (b.revision, CategoryJacobians(self._fixed_model or model_of(self.scene), "analytic"))
        return report._with_jacobian(hit[1].of(q_flat, report.by_category))

    row_evaluator = row_evaluator  # a lean pair_distances(q, robot=) for many configurations (_row_eval)

    def pair_distances(self, q, *, robot: str | None = None) -> PairDistances:
        """Every candidate pair's signed distance at ``q`` (no pruning), with witness points.

        ``robot``: only the pairs with a side on that robot (the moving robot of a trajectory: the
        other pairs do not change while it moves); None: every candidate pair.  ``pair_index``
        ``(P,)`` gives each row's pair number (``Detector`` pair order, the index space of
        ``NotEvaluated.pair_index``).  The arrays are fresh copies (a few hundred ns for ~100
        pairs), so a result stays valid after the next call.
        """
        b = self._fresh()
        sel, la, ra, lb, cat, na, nb, pidx = b.selection(robot)
        s = self._scratch(b)
        self._flat_q(q, s.q1)
        n = len(sel)
        self._run(s, kn.MODE_ALL, 0, False, sel)
        rows = s.ev[:n]
        return PairDistances(rows[:, 0].copy(), rows[:, 1:4].copy(), rows[:, 4:7].copy(), la, ra, lb, cat, na, nb,
                             b.model.link_names, pidx)

    def _many(self, Q, mode: int):
        b = self._fresh()
        n_q = b.model.n_q
        refuse_complex_or_bool(Q, "Q", DetectionError)
        try:
            Q = np.ascontiguousarray(np.asarray(Q, dtype=np.float64))
        except (TypeError, ValueError) as exc:
            raise DetectionError(f"Q: expected an (M, {n_q}) array of numbers") from exc
        if Q.ndim != 2 or Q.shape[1] != n_q:
            raise DetectionError(f"Q: expected shape (M, {n_q}), got {Q.shape}")
        lim = b.lim  # read once: the values the batch uses and reports (_set_limits)
        min_d, status, err = rows(self, b, Q, mode, lim[0])
        if err != 0:
            self._raise_kernel_error(err, Q, "Detector: Q", batch=True, b=b)
        return min_d, status, lim

    def check_many(self, Q) -> BatchReport:
        """Exact per-category nearest distances and status for each row of ``Q`` ``(M, n_q)``, in parallel."""
        min_d, status, lim = self._many(Q, kn.MODE_MIN)
        return BatchReport(min_d, status == kn.ST_COLLISION, status.astype(np.int8), lim[1], lim[2])

    def check_many_bruteforce(self, Q) -> BatchReport:
        """Like :meth:`check_many` but every candidate pair is evaluated (no bounds, no BVH).

        The all-pairs path the tests compare the pruned one against (same narrow phase)."""
        min_d, status, lim = self._many(Q, kn.MODE_ALL)
        threshold, stopping = lim[1], lim[2]
        level = max(self._tol.length, stopping)  # the contact tolerance, as the kernel
        dmin = min_d.min(axis=1)
        status = np.where(dmin <= level, kn.ST_COLLISION,
                          np.where(dmin <= max(threshold, stopping), kn.ST_WARNING, kn.ST_CLEAR))
        return BatchReport(min_d, status == kn.ST_COLLISION, status.astype(np.int8), threshold, stopping)

    def collides_many(self, Q) -> np.ndarray:
        """``(M,) bool``: collision (distance <= 0, or <= the stopping distance) per row, early exit."""
        _, status, _ = self._many(Q, kn.MODE_YESNO)
        return status == kn.ST_COLLISION

    def __repr__(self) -> str:
        return (f"Detector({self.scene.name!r}, threshold={self._threshold}, stopping_distance={self._stopping}, "
                f"active={self._active!r}, {self._b.P} pairs)")


del CAT_WORKSPACE
