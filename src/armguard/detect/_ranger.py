"""Ranger's Detector over any backend: obstacle lists, priorities, the anytime budget, categories.

``Detector(scene, ..., backend="coal")`` (or ``$ARMGUARD_BACKEND`` / ``armguard.toml``) builds a
:class:`RangerDetector` unless the backend declares a fast path of its own
(``Backend.ranger_detector(options)``, :func:`fast_path`; the analytic backend's is its fused
numba kernel, ``armguard_analytic._engine._detector.FusedDetector``, a subclass of
:class:`armguard.detect.Detector`).  Ranger's algorithm (seed ``000``, §2-§4) is
framework code here, over the Checker interface only:

* **obstacle lists**: the Model pair rows whose sides can come within the reach margin somewhere
  inside the joint limits (:mod:`._bounds`, :mod:`._reach`); the others are never asked for;
* **lower bounds**: a pair evaluated at ``q0`` with distance ``d0`` is at least
  ``d0 - sum_j |q_j - q0_j| lever[p, j]`` away at ``q`` (signed distance is 1-Lipschitz in the
  motion of its shapes); a pair never evaluated (in this thread) bounds nothing (``-inf``), nor
  does any pair of a Checker whose distances may run long (``distances_may_run_long``: python-fcl);
* **priority**: pairs are evaluated in increasing lower bound (near last time, or moved much
  since), ties broken by the time since they were last evaluated (oldest first);
* **the anytime budget**: ``check(q, budget_us=...)`` turns the budget into a number of pairs by
  a cost model measured on this machine (µs per check plus µs per evaluated pair, exponential
  averages updated after every check, one outlier moving them at most 4x) and asks the Checker for those pairs in one
  ``pair_distances(q, pairs=rows)`` call; the report names every pair it skipped with its
  lower bound, and the status is INCOMPLETE, never CLEAR, while a skipped pair's bound does not
  prove the threshold (the analytic kernel's rule, ``armguard_analytic._engine._kernel``).  A
  check that called no backend (a budget below the check's own cost) measures no pair: its estimate
  of a check's own cost then relaxes by 10 %, never below what that check took, so that an estimate
  once above the budget does not keep every later check from calling the backend;
* **lazy**: pairs whose lower bound proves them beyond the threshold are skipped (exact status);
* a Checker whose ``pair_distances`` takes ``pairs=`` only through the framework's default (the
  whole call, then its rows: ``CheckerBase``) pays for every pair whatever the subset: a budgeted or
  lazy check over it that evaluates any pair evaluates them all;
* **categories and threshold status**: the nearest evaluated pair per category (its obstacle's face,
  edge or vertex named where that is a static polytope), the pairs within the threshold, CLEAR /
  WARNING / COLLISION / INCOMPLETE.

Per-thread state (last distances, where they were taken, when) lives in a ``threading.local``:
several threads may call one detector with the answers of single-threaded calls, provided the
Checker is itself safe across threads (every bundled one is, ``docs/backends.md``).  After a scene
edit the next call builds again on the scene's Model (a new Checker over it), as the analytic
Detector rebuilds; each build is one :class:`_Plan`, published whole, so a call or a report never
mixes two of them.
"""

from __future__ import annotations

import contextlib
import math
import threading
import time

import numpy as np

from .._errors import BackendError, DetectionError
from .._values import number, refuse_complex_or_bool
from ._bounds import pair_bounds
from ._common import check_finite_margin, check_length, check_link, scene_and_model, status_code
from ._detector import Detector
from ._extras import attach_extra
from ._report import CATEGORIES, STATUS_CODES, BatchReport, DetectionReport, NotEvaluated, PairDistances, PairResult

__all__ = ["RangerDetector", "fast_path"]

_FIRST_US_PER_PAIR = 5.0  # first guesses of the cost model, replaced by measurements
_FIRST_US_PER_CHECK = 50.0
_FLAG_SKIPPED, _FLAG_EVALUATED, _FLAG_PROVED = 0, 1, 2


def fast_path(backend, backend_options):
    """The Detector class the chosen backend declares for Ranger's cycle (``ranger_detector``), or None.

    ``backend``, ``backend_options`` as ``Detector`` takes them (argument > ``$ARMGUARD_BACKEND`` >
    ``armguard.toml`` > ``"analytic"``)."""
    from ..backends import _options_file, get_backend, resolve

    name, opts = resolve(backend, backend_options)
    declare = getattr(get_backend(name), "ranger_detector", None)
    try:
        return None if declare is None else declare(opts)
    except BackendError as exc:  # an option the backend refuses: named with the file it came from, as checker() does
        source = _options_file(name, backend_options, None)
        if source is None:
            raise
        raise BackendError(f"{source}: [backend]: {exc}") from None


def _static_polytopes_b(model, pairs, rows, swap) -> tuple:
    """Per selected pair, B's shape (W) where it is a static body's polytope or cylinder, else None
    (:func:`_feature`'s shapes, as the analytic Detector's reports name)."""
    from ..geometry import Capsule, Sphere

    static = {model.geometry_name(n, i): s for n, body in model.bodies.items() for i, s in enumerate(body.shapes)
              if not isinstance(s, (Sphere, Capsule))}
    return tuple(static.get(pairs.a[k] if sw else pairs.b[k]) for k, sw in zip(rows, swap))


def _feature(plan, p: int, p_WB: np.ndarray):
    """The obstacle's face / edge / vertex at ``p_WB`` (:func:`armguard.geometry.feature_at`) where pair
    ``p``'s B is a static polytope or cylinder, else None: an annotation, never a verdict."""
    from ..geometry import feature_at

    shape = plan.b_shape[p]
    try:
        return None if shape is None else feature_at(shape, p_WB, plan.tol)
    except Exception:  # noqa: BLE001 - a point off the surface (a depth's witness), a degenerate shape
        return None


class _State:
    """One thread's memory of the pairs it evaluated (for the lower bounds and the priorities)."""

    __slots__ = ("generation", "last_d", "last_q", "has_last", "stamp", "tick")

    def __init__(self, generation: int, n_pairs: int, n_q: int) -> None:
        self.generation = generation
        self.last_d = np.zeros(n_pairs)
        self.last_q = np.zeros((n_pairs, n_q))
        self.has_last = np.zeros(n_pairs, dtype=bool)
        self.stamp = np.zeros(n_pairs, dtype=np.int64)
        self.tick = 0


class _Plan:
    """One build of a :class:`RangerDetector` (its Model and Checker, obstacle lists, pair names and
    categories), published with one assignment: a call reads it once and works on it alone, so a
    rebuild on another thread (a scene edit, ``set_active``) never mixes two builds, and a report
    keeps the names of the build that made it."""

    __slots__ = ("model", "checker", "distances", "revision", "generation", "active", "bounds", "sel", "all_rows",
                 "whole_only", "swap", "lever", "a", "b", "cat_code", "cat_masks", "margin_built", "limits", "n_q", "det",
                 "threshold", "stopping", "link_a", "b_shape", "tol")

    def with_levels(self, threshold: float, stopping: float) -> "_Plan":
        """This build with another threshold and stopping distance (within ``margin_built``): the same
        generation, so every thread's state carries over (``RangerDetector._set_limits``)."""
        new = _Plan()
        for k in _Plan.__slots__:
            setattr(new, k, getattr(self, k))
        new.threshold, new.stopping = threshold, stopping
        return new


class _Raw:
    """What a DetectionReport reads: the evaluated pairs (detector pair numbers ``idx``, in
    evaluation order) and, for the lazy and anytime modes, every pair's flag and lower bound."""

    __slots__ = ("plan", "d", "p_WA", "p_WB", "idx", "flags", "bounds", "lazy", "n_evaluated")

    def __init__(self, plan, d, p_WA, p_WB, idx, flags, bounds, lazy) -> None:
        self.plan, self.d, self.p_WA, self.p_WB, self.idx = plan, d, p_WA, p_WB, idx
        self.flags, self.bounds, self.lazy = flags, bounds, lazy
        self.n_evaluated = len(d)

    def _result(self, k: int) -> PairResult:
        plan = self.plan  # the build that made this report
        p = int(self.idx[k])
        pA, pB = self.p_WA[k].copy(), self.p_WB[k].copy()
        pA.flags.writeable = pB.flags.writeable = False
        a, b = plan.a[p], plan.b[p]
        return PairResult(float(self.d[k]), pA, pB, a, b, CATEGORIES[plan.cat_code[p]], plan.link_a[p], b,
                          _feature(plan, p, pB), p)

    def by_category(self) -> dict:
        out = {}
        cat = self.plan.cat_code[self.idx]
        for c, name in enumerate(CATEGORIES):
            ks = np.flatnonzero(cat == c)
            if ks.size:
                out[name] = self._result(int(ks[np.lexsort((self.idx[ks], self.d[ks]))[0]]))
        return out

    def within(self, threshold: float) -> tuple:
        ks = np.flatnonzero(self.d <= threshold)
        ks = ks[np.lexsort((self.idx[ks], self.d[ks]))]  # nearest first, ties by pair number
        return tuple(self._result(int(k)) for k in ks)

    def not_evaluated(self) -> tuple:
        if self.flags is None:
            return ()
        plan = self.plan
        out = [NotEvaluated(plan.a[p], plan.b[p], CATEGORIES[plan.cat_code[p]], float(self.bounds[p]), int(p))
               for p in np.flatnonzero(self.flags == _FLAG_SKIPPED)]
        if self.lazy:  # proved beyond the threshold by their bounds (the check's threshold: its build's)
            thr = max(plan.threshold, plan.stopping)
            out += [NotEvaluated(plan.a[p], plan.b[p], CATEGORIES[plan.cat_code[p]], max(float(self.bounds[p]), thr),
                                 int(p)) for p in np.flatnonzero(self.flags == _FLAG_PROVED)]
        return tuple(out)


def _with_tol(model, tol):
    """``model``, or where the Detector was given other tolerances a shallow copy of it holding them: its
    Checker then takes the Detector's joint-limit slack and contact tolerance (the analytic Detector's rule)."""
    if tol is None or tol == model.tol:
        return model
    import copy

    m = copy.copy(model)
    m.tol = tol
    return m


def _require_active_pairs(model, plan) -> None:
    """A DetectionError when the active arm has no pair with a shape the configuration moves: its checks
    could only say CLEAR without having looked (as the analytic Detector's ``require_pairs``)."""
    scene = model.scene
    if not any(scene.moves(a) or scene.moves(b) for a, b in zip(plan.a, plan.b)):
        what = ("every pair is disabled or excluded" if not plan.a else
                f"{len(plan.a)} pairs, all between fixed shapes")
        raise DetectionError(f"scene {scene.name!r} has no pair to check on arm {plan.active!r} ({what}): no verdict "
                             "can be given; enable a pair, add a body or a workspace box")


class RangerDetector(Detector):
    """Ranger's Detector over a backend's Checker (see the module docstring); a subclass of
    :class:`armguard.detect.Detector` with its API.  ``reach_margin`` (m, default ``inf``: every pair) as there."""

    def __init__(self, scene, threshold: float = 0.05, *, stopping_distance: float = 0.0, active: str | None = None,
                 backend: str | None = None, backend_options=None, model=None, tol=None,
                 reach_margin: float | None = None, terrain=None) -> None:
        from ..model import model_of

        scene, model = scene_and_model(scene, model)
        self.scene = scene
        self._threshold = check_length(threshold, "threshold")
        self._stopping = check_length(stopping_distance, "stopping_distance")
        self._reach_margin = check_finite_margin(math.inf if reach_margin is None else reach_margin)
        self._backend_args = (backend, backend_options)
        self._tol_given = tol
        self._us_per_pair = _FIRST_US_PER_PAIR
        self._us_per_check = _FIRST_US_PER_CHECK
        self._tls = threading.local()
        self._lock = threading.RLock()
        self._generation = 0
        self._active = None
        self.terrain = None
        self._terrain_given = terrain is not None  # attached after the first build: pairs on no arm then allowed
        if active is not None and active not in scene.robots:
            raise DetectionError(f"active: unknown robot {active!r}; robots are {list(scene.robots)}")
        self._active = active
        self._plan = None
        lock = getattr(scene, "lock", None)
        with lock if lock is not None else contextlib.nullcontext():  # the revision the Model is of
            revision = getattr(scene, "revision", None)
            model = model if model is not None else model_of(scene)
        self._build(model, revision)
        if terrain is not None:  # the terrain category, composed outside the backend
            attach_extra(self, "terrain", terrain)

    def _require_distances(self, what: str, plan: _Plan | None = None) -> None:
        if not (plan or self._plan).distances:
            from .._errors import BackendError

            raise BackendError(f"backend {self.backend!r} answers verdicts only (no distances), so it has no {what}; "
                               "use collides_many(Q) with it, or a backend that answers distances")

    # ------------------------------------------------------------------ settings
    threshold = property(lambda self: self._plan.threshold, doc="Detection threshold (m).")
    stopping_distance = property(lambda self: self._plan.stopping, doc="Stopping distance (m); 0 when unset.")
    active = property(lambda self: self._active, doc="The active robot's name, or None for all arms.")

    # the current build's parts (a call reads self._fresh() once instead)
    model = property(lambda self: self._plan.model,
                     doc="The Model this detector checks (the scene's, built again after an edit).")
    checker = property(lambda self: self._plan.checker, doc="The backend's Checker over :attr:`model`.")
    backend = property(lambda self: self._plan.checker.name, doc="The backend's name.")
    _tol = property(lambda self: self._tol_given if self._tol_given is not None else self._plan.model.tol)
    _sel = property(lambda self: self._plan.sel)

    @property
    def n_pairs(self) -> int:
        """Number of candidate pairs (after pair filters, active arm and obstacle lists)."""
        return len(self._fresh().sel)

    @property
    def link_names(self) -> tuple:
        return tuple(f"{r}/{ln}" for r, robot in self.scene.robots.items() for ln in robot.link_names)

    def set_threshold(self, threshold: float) -> None:
        self._set_limits(check_length(threshold, "threshold"), self._stopping)

    def set_stopping_distance(self, stopping_distance: float) -> None:
        self._set_limits(self._threshold, check_length(stopping_distance, "stopping_distance"))

    def _set_limits(self, threshold: float, stopping: float) -> None:
        """Publish a new threshold and stopping distance with the build they go with: a call reads
        ``_plan`` once and takes both from it, so it never pairs one threshold with obstacle lists
        built for a smaller one, nor reports a threshold it did not use.  Beyond the margin the
        lists were built with, they are built again first."""
        with self._lock:
            old = self._threshold, self._stopping
            self._threshold, self._stopping = threshold, stopping
            plan = self._plan
            if max(threshold, stopping) > plan.margin_built:
                try:
                    self._build(plan.model, plan.revision)
                except BaseException:
                    self._threshold, self._stopping = old  # the plan in use keeps its values
                    raise
            else:
                self._plan = plan.with_levels(threshold, stopping)

    def set_active(self, name: str | None) -> None:
        self._switch_active(name, self._lock)

    def prepare(self) -> "RangerDetector":
        """(Re)build the obstacle lists and bounds; forget every thread's last distances."""
        plan = self._plan
        self._build(plan.model, plan.revision)  # the same Model: a scene edit since is still seen (_fresh)
        return self

    def _build(self, model, revision) -> _Plan:
        """A new build on ``model`` (the Checker made again when the Model is another), published
        with one assignment (:class:`_Plan`); ``revision``: the scene's revision ``model`` is of."""
        from ..backends import Capability, checker

        with self._lock:
            old = self._plan
            plan = _Plan()
            plan.det = self
            plan.revision = revision
            plan.model = model
            plan.checker = old.checker if old is not None and old.model is model else \
                checker(_with_tol(model, self._tol_given), *self._backend_args)
            plan.distances = Capability.DISTANCES in plan.checker.capabilities
            margin = max(self._reach_margin, self._threshold, self._stopping)
            plan.active = self._active
            b = pair_bounds(model, active=plan.active, reach_margin=margin)
            pairs = model.pairs
            plan.bounds = b
            plan.sel = b.rows
            plan.all_rows = len(b.rows) == len(pairs)  # every Model row, in order: ask without pairs=
            # a subset costs the backend its whole call (the framework's pairs=): a budgeted or lazy
            # check then evaluates every pair, as it pays for them anyway
            plan.whole_only = bool(getattr(plan.checker.pair_distances, "pairs_from_full", False))
            plan.swap = b.swap
            plan.lever = b.lever
            oa, ob = pairs.owner_a, pairs.owner_b
            plan.a = tuple(ob[k] if s else oa[k] for k, s in zip(b.rows, b.swap))
            plan.b = tuple(oa[k] if s else ob[k] for k, s in zip(b.rows, b.swap))
            plan.link_a = tuple(self._carrier(a) or a for a in plan.a)  # a payload's: the link carrying it
            plan.b_shape = _static_polytopes_b(model, pairs, b.rows, b.swap)
            plan.tol = self._tol_given or model.tol
            if plan.active is not None and not getattr(self, "_terrain_given", False) and self.terrain is None:
                _require_active_pairs(model, plan)
            plan.cat_code = b.category
            plan.cat_masks = tuple(b.category == c for c in range(len(CATEGORIES)))
            plan.margin_built = margin
            plan.threshold, plan.stopping = self._threshold, self._stopping
            robots = [r for _, r in model._robots]  # the robots the Model moves, in its joint order
            slack = (self._tol_given or model.tol).joint_limit
            plan.limits = ((np.concatenate([r.lower for r in robots]) - slack,
                            np.concatenate([r.upper for r in robots]) + slack) if robots else (np.zeros(0), np.zeros(0)))
            plan.n_q = int(plan.limits[0].shape[0])
            self._generation += 1
            plan.generation = self._generation
            self._plan = plan
        return plan

    def _fresh(self) -> _Plan:
        """The current build, made again first when the scene changed since (a body added, a pair
        filter set...: the scene's Model then, and a Checker over it), as the analytic Detector does."""
        plan = self._plan
        if getattr(self.scene, "revision", None) == plan.revision:
            return plan
        from ..model import model_of

        lock = getattr(self.scene, "lock", None)
        with self._lock:
            plan = self._plan
            if getattr(self.scene, "revision", None) == plan.revision:
                return plan
            if lock is not None:  # the scene's lock after this detector's (the order the analytic Detector takes them)
                with lock:
                    revision = self.scene.revision
                    model = model_of(self.scene)
            else:
                revision = getattr(self.scene, "revision", None)
                model = model_of(self.scene)
            return self._build(model, revision)

    def obstacle_list(self, link: str) -> tuple[str, ...]:
        """Owner names in the obstacle list of ``link`` (``"robot/link"``), in pair order."""
        check_link(self.scene, link)
        plan = self._fresh()
        return tuple(dict.fromkeys(b for a, b in zip(plan.a, plan.b) if a == link))

    def _payload_of(self, owner: str):
        p = self.scene.payloads.get(owner)
        return None if p is None else p.robot

    # ------------------------------------------------------------------ evaluation
    def _state(self, plan: _Plan) -> _State:
        s = getattr(self._tls, "s", None)
        if s is None or s.generation != plan.generation:
            s = self._tls.s = _State(plan.generation, len(plan.sel), plan.n_q)
        return s

    def _query(self, plan: _Plan, q_flat: np.ndarray, which: np.ndarray | None):
        """Distances and witness points (moving side on A) of detector pairs ``which`` (None: all)."""
        self._require_distances("per-pair distances (check, pair_distances, check_many)", plan)
        q_pin = plan.model.pin_q(q_flat)
        if which is None and plan.all_rows:
            r = plan.checker.pair_distances(q_pin)
            swap = plan.swap
        else:
            rows = plan.sel if which is None else plan.sel[which]
            swap = plan.swap if which is None else plan.swap[which]
            r = plan.checker.pair_distances(q_pin, pairs=rows)
        d = np.asarray(r.distance, dtype=np.float64)
        if np.isnan(d).any():  # never a verdict from a NaN
            raise DetectionError(f"backend {plan.checker.name!r} answered a NaN distance; no verdict")
        sw = swap[:, None]
        return d, np.where(sw, r.p_WB, r.p_WA), np.where(sw, r.p_WA, r.p_WB)

    def _flat(self, q, plan: _Plan, entry: str = "Detector.check") -> np.ndarray:
        refuse_complex_or_bool(q, "q", DetectionError)
        try:
            q = self.scene.flat_q(q)
        except Exception as exc:  # noqa: BLE001 - one error type at the boundary
            raise DetectionError(f"q: {exc}") from None
        q = np.asarray(q, dtype=np.float64)
        if not np.all(np.isfinite(q)):
            raise DetectionError(f"q: contains NaN or infinite values: {q.tolist()}")
        lo, hi = plan.limits
        if q.shape != lo.shape or not (np.all(q >= lo) and np.all(q <= hi)):  # the Model's error, naming the joint
            _with_tol(plan.model, self._tol).check_limits(q, entry)
        return q

    def _levels(self, plan: _Plan) -> tuple[float, float]:
        """(collision level, effective threshold) of build ``plan``, as the analytic kernel's."""
        return max(self._tol.length, plan.stopping), max(plan.threshold, plan.stopping)

    def lower_bounds(self, q) -> np.ndarray:
        """``(P,)`` this thread's lower bound on every pair's distance at ``q`` (m; ``-inf``: never evaluated)."""
        plan = self._fresh()
        return self._lower_bounds(plan, self._state(plan), self._flat(q, plan))

    def _lower_bounds(self, plan: _Plan, s: _State, q: np.ndarray) -> np.ndarray:
        if getattr(plan.checker, "distances_may_run_long", False):  # python-fcl: a remembered distance may
            return np.full(len(s.last_d), -math.inf)  # exceed the exact one (4e-5 m at the same q): no bound
        dq = np.abs(q[None, :] - s.last_q)
        moved = np.where(dq > 0.0, dq * plan.lever, 0.0).sum(axis=1)  # 0 * inf lever: no motion
        return np.where(s.has_last, s.last_d - moved, -math.inf)

    def check(self, q, *, budget_us: float | None = None, lazy: bool = False,
              jacobian: bool = False) -> DetectionReport:
        """Check ``q`` (mapping robot -> joints, or flat over ``scene.joint_names``): see the module
        docstring for ``budget_us`` (µs) and ``lazy``; ``jacobian=True`` as the analytic Detector's
        (:mod:`._category_jacobian`, this detector's Checker, the nearest pair's Model row)."""
        if jacobian:
            plan = self._fresh()
            report = self._check(plan, q, budget_us, lazy)
            rows = {c: int(plan.sel[r.pair_index]) for c, r in report.by_category.items() if r.pair_index >= 0}
            hit = getattr(self, "_category_jac", None)
            if hit is None or hit[0] is not plan.model:
                from ._category_jacobian import CategoryJacobians

                hit = self._category_jac = (plan.model, CategoryJacobians(plan.model, checker=plan.checker))
            return report._with_jacobian(hit[1].of(self._flat(q, plan), report.by_category, rows))
        return self._check(self._fresh(), q, budget_us, lazy)

    def _check(self, plan: _Plan, q, budget_us, lazy) -> DetectionReport:
        t0 = time.perf_counter()
        if budget_us is not None:
            number(budget_us, "budget_us", DetectionError, low=0.0, unit=" (µs)")  # not True, "5", 1e400
        q = self._flat(q, plan)
        s = self._state(plan)
        level, thr = self._levels(plan)
        P = len(plan.sel)
        if budget_us is None and not lazy:  # exact: every listed pair
            which = np.arange(P)
            d, pA, pB = self._query(plan, q, None)
            flags = bounds = None
            lbmin = math.inf
        else:
            bounds = self._lower_bounds(plan, s, q)
            order = np.lexsort((s.stamp, bounds))  # increasing bound, then longest unevaluated first
            flags = np.full(P, _FLAG_SKIPPED, dtype=np.int8)
            if lazy:
                proved = bounds > thr
                flags[proved] = _FLAG_PROVED
                order = order[~proved[order]]
            if budget_us is not None:
                order = order[:self._allowance(float(budget_us))]
            which = np.sort(order)  # the Checker answers in Model order
            whole = plan.whole_only and len(which) > 0  # any subset costs the whole call: every pair, then
            if whole:
                which = np.arange(P)
            flags[which] = _FLAG_EVALUATED
            d, pA, pB = self._query(plan, q, None if whole else which) if len(which) else \
                (np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3)))
            skipped = bounds[flags == _FLAG_SKIPPED]
            lbmin = float(skipped.min()) if skipped.size else math.inf
        s.tick += 1
        s.last_d[which], s.last_q[which], s.has_last[which], s.stamp[which] = d, q, True, s.tick
        status = STATUS_CODES[status_code(float(d.min(initial=math.inf)), lbmin, level, thr)]
        elapsed = (time.perf_counter() - t0) * 1e6
        if len(d):
            self._learn(elapsed, len(d))
        else:  # no backend call: nothing measured, but an estimate above the budget must not stick (no check
            # would ever call the backend to correct it): it relaxes 10 % a check, never below this check's cost
            self._us_per_check = max(0.9 * self._us_per_check, elapsed)
        raw = _Raw(plan, d, pA, pB, which, flags, bounds, lazy)
        return DetectionReport._from_check(status, plan.threshold, plan.stopping, elapsed, raw)

    def _allowance(self, budget_us: float) -> int:
        """How many pairs the cost model says fit in ``budget_us`` besides the check's own cost."""
        return int(min(max(0.0, budget_us - self._us_per_check) // self._us_per_pair, 2.0 ** 62))

    def _learn(self, elapsed_us: float, n: int) -> None:
        """Update the cost model ``elapsed = per_check + n per_pair`` with one check (benign races:
        threads share it, each update is two float stores)."""
        clamp = lambda x, ref: min(max(x, 0.25 * ref), 4.0 * ref)  # noqa: E731 - one outlier moves it at most 4x
        if n >= 4:
            per_pair = (elapsed_us - self._us_per_check) / n
            self._us_per_pair = 0.8 * self._us_per_pair + 0.2 * clamp(max(per_pair, 1e-3), self._us_per_pair)
        fixed = elapsed_us - n * self._us_per_pair
        self._us_per_check = 0.8 * self._us_per_check + 0.2 * clamp(max(fixed, 1e-3), self._us_per_check)

    def pair_distances(self, q, *, robot: str | None = None) -> PairDistances:
        """Every checked pair's signed distance (rows: one per shape pair), as the analytic detector's."""
        plan = self._fresh()
        d, pA, pB = self._query(plan, self._flat(q, plan, "Detector.pair_distances"), None)
        names = self.link_names
        li = {n: i for i, n in enumerate(names)}
        rid = {r: i for i, r in enumerate(self.scene.robots)}
        link_a = np.array([li.get(a, li.get(self._carrier(a), -1)) for a in plan.a], dtype=np.int64)
        robot_a = np.array([rid.get(a.split("/", 1)[0], rid.get(self._payload_of(a), -1)) for a in plan.a], dtype=np.int64)
        link_b = np.array([li.get(b, li.get(self._carrier(b), -1)) for b in plan.b], dtype=np.int64)
        idx = np.arange(len(d), dtype=np.int64)
        if robot is not None:
            if robot not in rid:
                raise DetectionError(f"robot: unknown robot {robot!r}; robots are {list(rid)}")
            on = robot_a == rid[robot]
            on |= np.array([rid.get(b.split("/", 1)[0], rid.get(self._payload_of(b), -2)) == rid[robot] for b in plan.b])
            idx = np.flatnonzero(on)
        ro = np.ascontiguousarray
        return PairDistances(d[idx].copy(), pA[idx].copy(), pB[idx].copy(), ro(link_a[idx]), ro(robot_a[idx]),
                             ro(link_b[idx]), ro(plan.cat_code[idx]), tuple(plan.a[i] for i in idx),
                             tuple(plan.b[i] for i in idx), names, ro(idx))

    def _carrier(self, owner: str):
        p = self.scene.payloads.get(owner)
        return None if p is None else f"{p.robot}/{p.link}"

    def _rows(self, Q, plan: _Plan) -> np.ndarray:
        n = plan.n_q
        refuse_complex_or_bool(Q, "Q", DetectionError)
        try:
            Q = np.asarray(Q, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise DetectionError(f"Q: expected an (M, {n}) array of numbers") from exc
        if Q.ndim != 2 or Q.shape[1] != n:
            raise DetectionError(f"Q: expected shape (M, {n}), got {Q.shape}")
        if not np.all(np.isfinite(Q)):
            bad = np.argwhere(~np.isfinite(Q))[0]
            raise DetectionError(f"Detector: Q contains NaN or infinite values (first at row {int(bad[0])}, joint "
                                 f"{int(bad[1])}: {Q[tuple(bad)]})")
        lo, hi = plan.limits  # the Detector's joint-limit slack, as check's
        for i in np.flatnonzero(~((Q >= lo) & (Q <= hi)).all(axis=1)):  # the Model's error, naming the joint
            _with_tol(plan.model, self._tol).check_limits(Q[i], f"Detector: Q[{i}]")
        return Q

    def check_many(self, Q) -> BatchReport:
        """Per-category nearest distances and status for each row of ``Q`` ``(M, n_q)`` (the
        Checker's ``pair_distances_many`` over the listed pairs)."""
        plan = self._fresh()
        self._require_distances("per-pair distances (check_many)", plan)
        Q = self._rows(Q, plan)
        M = len(Q)
        min_d = np.full((M, len(CATEGORIES)), np.inf)
        if M and len(plan.sel):
            Q_pin = plan.model.pin_q(Q)
            many = (plan.checker.pair_distances_many(Q_pin) if plan.all_rows
                    else plan.checker.pair_distances_many(Q_pin, pairs=plan.sel))
            D = np.asarray(many.distance, dtype=np.float64).reshape(M, len(plan.sel))
            if np.isnan(D).any():
                raise DetectionError(f"backend {plan.checker.name!r} answered a NaN distance; no verdict")
            for c, mask in enumerate(plan.cat_masks):
                if mask.any():
                    min_d[:, c] = D[:, mask].min(axis=1)
        level, thr = self._levels(plan)
        dmin = min_d.min(axis=1)
        status = np.where(dmin <= level, 2, np.where(dmin <= thr, 1, 0)).astype(np.int8)
        return BatchReport(min_d, status == 2, status, plan.threshold, plan.stopping)

    check_many_bruteforce = check_many

    def collides_many(self, Q) -> np.ndarray:
        """``(M,) bool``: collision (distance <= 0, or <= the stopping distance) per row (the backend's batch)."""
        plan = self._fresh()
        Q = self._rows(Q, plan)
        if plan.active is None and plan.all_rows:  # at check()'s collision level (its contact tolerance); a
            # verdicts-only backend answers contact alone (clip: margin 0, its uncertain answers counted as contact)
            margin = self._levels(plan)[0] if plan.distances else plan.stopping
            return plan.checker.collides(plan.model.pin_q(Q), margin=margin)
        self._require_distances("active-arm batches (collides_many with active= checks the whole Model)", plan)
        return self.check_many(Q).collision

    def __repr__(self) -> str:
        return (f"Detector({self.scene.name!r}, backend={self.backend!r}, threshold={self._threshold}, "
                f"stopping_distance={self._stopping}, active={self._active!r}, {len(self._plan.sel)} pairs)")
