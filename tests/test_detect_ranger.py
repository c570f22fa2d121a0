"""Ranger's Detector over any backend (``armguard.detect._ranger``).

* The backend declares the fast path: ``analytic`` (exact) gets the fused kernel, every other
  backend Ranger's algorithm over its Checker.
* A full check with coal equals the analytic Detector's verdict and per-category distances on
  the built-in models and two public robots (panda, ur5); with python-fcl on the hull-only
  robots, where its distances match coal's.
* Budgeted and lazy checks never say CLEAR (or WARNING) where the full answer is nearer: every
  skipped pair's lower bound is below its true distance, and a skipped colliding pair is never
  hidden (a hypothesis property over configurations, motions and budgets).
* The obstacle lists drop the same pairs as the analytic Detector's, and only pairs that stay
  beyond the margin.
* One detector from 4 threads: each thread's lower bounds come from its own checks.
"""

from __future__ import annotations

import math
import threading

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

import armguard
from armguard.backends import get_backend
from armguard.detect import Detector, RangerDetector, Status
from armguard.detect._backend import CheckerDetector

MODELS = ("ranger", "hermes", "puma560", "gmf_s480", "rover", "panda", "ur5")
HULLS = {"rover", "panda", "ur5", "gmf_s480"}
THRESHOLD = 0.05
_loaded: dict = {}


def _model(name: str):
    if name not in _loaded:
        _loaded[name] = armguard.load_model(name)
    return _loaded[name]


def _configs(model, n: int, seed: int) -> np.ndarray:
    """The neutral pose and ``n`` seeded random in-limit configurations, in the scene's flat order."""
    return np.vstack([model.scene_q(model.neutral())[None, :], model.scene_q(model.random_q(n, seed))])


def _truth(det, q) -> np.ndarray:
    """Every listed pair's distance at ``q``, in the detector's pair order (one full query)."""
    return det.pair_distances(q).distance


def test_the_backend_declares_the_fast_path():
    scene = _model("hermes").scene
    fused = get_backend("analytic").ranger_detector({})
    assert issubclass(fused, Detector) and fused is not Detector and fused.__module__.startswith("armguard_analytic.")
    assert get_backend("analytic").ranger_detector({"fidelity": "paper"}) is None
    assert getattr(get_backend("coal"), "ranger_detector", None) is None
    assert type(armguard.Detector(scene)) is fused and isinstance(armguard.Detector(scene), Detector)
    coal = armguard.Detector(scene, backend="coal")
    assert isinstance(coal, RangerDetector) and CheckerDetector is RangerDetector and isinstance(coal, Detector)
    assert coal.n_pairs == armguard.Detector(scene).n_pairs == len(_model("hermes").pairs)


def test_detector_builds_the_declared_class_once_and_hands_on_anything_else(monkeypatch):
    """``armguard.detect.Detector.__new__``: a declared subclass is initialised exactly once with the
    caller's arguments (not built, then initialised again); a declared class that is not a
    subclass is called and its object returned as it is; None gives a RangerDetector."""
    import armguard.detect._ranger as ranger

    scene = _model("hermes").scene
    fused = get_backend("analytic").ranger_detector({})
    calls = []

    class Counted(fused):
        def __init__(self, *args, **kwargs):
            calls.append((args, kwargs))
            super().__init__(*args, **kwargs)

    class Other:
        def __init__(self, scene, *args, **kwargs):
            self.scene, self.args, self.kwargs = scene, args, kwargs

    declared = {"counted": Counted, "other": Other, "coal": None}
    monkeypatch.setattr(ranger, "fast_path", lambda backend, options: declared[backend])
    det = Detector(scene, 0.07, active=None, backend="counted")
    assert type(det) is Counted and det.threshold == 0.07
    assert calls == [((scene, 0.07), {"active": None, "backend": "counted"})]  # the caller's arguments, once
    other = Detector(scene, 0.07, backend="other", backend_options={"x": 1})
    assert type(other) is Other and other.args == (0.07,)
    assert other.kwargs == {"backend": "other", "backend_options": {"x": 1}}
    generic = Detector(scene, 0.07, backend="coal")
    assert type(generic) is RangerDetector and generic.threshold == 0.07 and generic.backend == "coal"


@pytest.mark.parametrize("name", MODELS)
def test_full_check_with_coal_equals_the_analytic_detector(name):
    model = _model(name)
    tol = 1e-5 if name in HULLS else 1e-6
    analytic = armguard.Detector(model.scene, threshold=THRESHOLD)
    coal = armguard.Detector(model.scene, threshold=THRESHOLD, backend="coal")
    assert coal.n_pairs == analytic.n_pairs
    statuses = set()
    for q in _configs(model, 4, 5):
        a, c = analytic.check(q), coal.check(q)
        assert c.not_evaluated == () and c.n_evaluated == coal.n_pairs
        da = {k: v.distance for k, v in a.by_category.items()}
        dc = {k: v.distance for k, v in c.by_category.items()}
        assert set(da) == set(dc)
        for k in da:
            assert abs(da[k] - dc[k]) <= tol, (name, k, da[k], dc[k])
        if all(abs(min(da.values()) - lv) > tol for lv in (0.0, THRESHOLD)):  # outside the contact band
            assert c.status == a.status
        statuses.add(c.status)
        wa = [r.distance for r in a.within_threshold if abs(r.distance - THRESHOLD) > tol]
        wc = [r.distance for r in c.within_threshold if abs(r.distance - THRESHOLD) > tol]
        np.testing.assert_allclose(sorted(wc), sorted(wa), rtol=0, atol=tol)
    assert Status.INCOMPLETE not in statuses


@pytest.mark.parametrize("name", ["rover", "panda", "ur5"])
def test_full_check_with_fcl_equals_the_analytic_detector(name):
    model = _model(name)
    analytic = armguard.Detector(model.scene, threshold=THRESHOLD)
    fcl = armguard.Detector(model.scene, threshold=THRESHOLD, backend="fcl")
    assert isinstance(fcl, RangerDetector) and fcl.backend == "fcl"
    for q in _configs(model, 3, 6):
        a, f = analytic.check(q), fcl.check(q)
        da = {k: v.distance for k, v in a.by_category.items()}
        df = {k: v.distance for k, v in f.by_category.items()}
        assert set(da) == set(df) and all(abs(da[k] - df[k]) <= 1e-5 for k in da)
        assert f.status == a.status


def _check_budgeted(det, q0, q1, budget, lazy) -> None:
    """A full check at ``q0`` (this thread's memory), then a budgeted one at ``q1``, held to the truth."""
    det.check(q0)
    rep = det.check(q1, budget_us=budget, lazy=lazy)
    d = _truth(det, q1)
    level, thr = max(det.model.tol.length, det.stopping_distance), max(det.threshold, det.stopping_distance)
    evaluated = {r.pair_index for r in rep.by_category.values()} | {r.pair_index for r in rep.within_threshold}
    skipped = {n.pair_index: n.lower_bound for n in rep.not_evaluated}
    assert rep.n_evaluated + len(skipped) == det.n_pairs
    assert not evaluated & set(skipped)
    for p, lb in skipped.items():  # every bound holds
        assert lb <= d[p] + 1e-9, (p, lb, d[p])
    dmin = float(d.min())
    if rep.status is Status.CLEAR:
        assert dmin > thr
    elif rep.status is Status.WARNING:
        assert level < dmin <= thr + 1e-12
    elif rep.status is Status.COLLISION:
        assert dmin <= level
    colliding_skipped = [p for p in skipped if d[p] <= level]
    if colliding_skipped:
        assert rep.status in (Status.INCOMPLETE, Status.COLLISION)
    if rep.status is not Status.INCOMPLETE:  # the categories' nearest, where decided, are the truth's evaluated ones
        for r in rep.by_category.values():
            assert r.distance == pytest.approx(d[r.pair_index], abs=1e-12)


_DETECTORS: dict = {}


def _detector(name: str, backend: str):
    key = (name, backend)
    if key not in _DETECTORS:
        _DETECTORS[key] = armguard.Detector(_model(name).scene, threshold=THRESHOLD, backend=backend)
    return _DETECTORS[key]


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(case=st.sampled_from([("hermes", "coal"), ("ur5", "coal"), ("rover", "fcl")]),
       seed=st.integers(0, 2**31 - 1), step=st.floats(0.0, 0.3), budget=st.floats(0.0, 3000.0),
       lazy=st.booleans())
@example(case=("rover", "fcl"), seed=291, step=4e-14, budget=0.0, lazy=False)  # fcl's remembered distance ran
def test_budgeted_checks_never_hide_what_they_skip(case, seed, step, budget, lazy):  # 4e-5 m long (docs/backends.md)
    det = _detector(*case)
    model = det.model
    q0 = model.scene_q(model.random_q(1, seed))[0]
    rng = np.random.default_rng(seed)
    lo = np.concatenate([r.lower for r in model.scene.robots.values()])
    hi = np.concatenate([r.upper for r in model.scene.robots.values()])
    q1 = np.clip(q0 + rng.uniform(-step, step, size=q0.shape), lo, hi)
    _check_budgeted(det, q0, q1, budget, lazy)


@pytest.mark.parametrize("backend", ["coal", "fcl"])
def test_a_zero_budget_evaluates_nothing_and_says_so(backend):
    model = _model("rover")
    det = armguard.Detector(model.scene, threshold=THRESHOLD, backend=backend)
    q = _configs(model, 1, 7)[1]
    rep = det.check(q, budget_us=0.0)  # no memory yet: every bound is -inf
    assert rep.status is Status.INCOMPLETE and rep.n_evaluated == 0
    assert len(rep.not_evaluated) == det.n_pairs and all(n.lower_bound == -math.inf for n in rep.not_evaluated)
    det.check(q)
    again = det.check(q, budget_us=0.0)  # same q: each bound is the distance itself
    d = _truth(det, q)
    if backend == "fcl":  # its distances may run long: none bounds anything, the check stays incomplete
        assert again.status is Status.INCOMPLETE and all(n.lower_bound == -math.inf for n in again.not_evaluated)
    else:
        assert {n.pair_index: n.lower_bound for n in again.not_evaluated} == {p: d[p] for p in range(det.n_pairs)}
        if det.check(q).status is Status.CLEAR:  # the bounds alone prove it
            assert again.status is Status.CLEAR
    with pytest.raises(armguard.ArmguardError):
        det.check(q, budget_us=float("nan"))


@pytest.mark.parametrize("backend", ["analytic", "coal"])
def test_a_budget_beyond_every_pair_checks_every_pair(backend):
    """A finite budget too large for an int64 of pairs (1e30 us) is every pair: the exact check's
    answer, not an OverflowError."""
    model = _model("rover")
    det = armguard.Detector(model.scene, threshold=THRESHOLD, backend=backend)
    q = _configs(model, 1, 7)[1]
    exact = det.check(q)
    for budget in (1e30, 1e306, 1.7e308):  # 1e306 us is inf ns: NaN pairs, once
        rep = det.check(q, budget_us=budget)
        assert rep.n_evaluated == det.n_pairs and rep.status is exact.status
        assert rep.nearest.distance == exact.nearest.distance


def test_obstacle_lists_as_the_analytic_detectors():
    model = _model("ranger")
    margin = 0.1
    analytic = armguard.Detector(model.scene, threshold=THRESHOLD, reach_margin=margin, active="left_arm")
    coal = armguard.Detector(model.scene, threshold=THRESHOLD, reach_margin=margin, active="left_arm", backend="coal")
    assert coal.n_pairs == analytic.n_pairs < len(model.pairs)
    for link in ("left_arm/link2", "left_arm/link5"):
        assert set(coal.obstacle_list(link)) == set(analytic.obstacle_list(link))
    # the dropped rows stay beyond the margin
    kept = set(coal._sel.tolist())
    dropped = np.array([k for k in range(len(model.pairs)) if k not in kept
                        and ("left_arm/" in model.pairs.owner_a[k] or "left_arm/" in model.pairs.owner_b[k])])
    checker = armguard.checker(model, "coal")
    for q in model.random_q(5, 8):
        if len(dropped):
            assert checker.pair_distances(q, pairs=dropped).distance.min() > margin
    for q in _configs(model, 3, 9):
        assert coal.check(q).status == analytic.check(q).status


def test_each_thread_bounds_from_its_own_checks():
    model = _model("hermes")
    det = armguard.Detector(model.scene, threshold=THRESHOLD, backend="coal")
    Q = _configs(model, 8, 10)

    def run(t: int, out: dict, barrier) -> None:
        barrier.wait()
        got = []
        for k in range(len(Q)):
            q = Q[(k + t) % len(Q)]
            det.check(q)
            rep = det.check(q, budget_us=0.0)  # bounds from this thread's own last check at q
            got.append({n.pair_index: n.lower_bound for n in rep.not_evaluated})
        out[t] = got

    out: dict = {}
    barrier = threading.Barrier(4)
    threads = [threading.Thread(target=run, args=(t, out, barrier)) for t in range(4)]
    [th.start() for th in threads]
    [th.join() for th in threads]
    for t in range(4):
        for k, got in enumerate(out[t]):
            d = _truth(det, Q[(k + t) % len(Q)])
            assert got == {p: d[p] for p in range(det.n_pairs)}


def test_outside_the_limits_is_refused_and_the_memory_kept():
    model = _model("hermes")
    det = armguard.Detector(model.scene, threshold=THRESHOLD, backend="coal")
    q = _configs(model, 1, 11)[1]
    det.check(q)
    hi = np.concatenate([r.upper for r in model.scene.robots.values()])
    j = int(np.flatnonzero(np.isfinite(hi))[0])
    bad = q.copy()
    bad[j] = hi[j] + 1e-3
    with pytest.raises(armguard.JointLimitError):
        det.check(bad, budget_us=0.0)
    with pytest.raises(armguard.ArmguardError):
        det.check(np.full_like(q, np.nan))
    d = _truth(det, q)
    again = det.check(q, budget_us=0.0)
    assert {n.pair_index: n.lower_bound for n in again.not_evaluated} == {p: d[p] for p in range(det.n_pairs)}
