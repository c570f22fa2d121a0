"""Ranger's Detector over a Checker that answers only whole calls (``armguard.detect._ranger``).

A backend whose ``pair_distances(q)`` takes no ``pairs=`` is given them by the framework
(``CheckerBase``: the whole call, then its rows), so a subset costs it every pair.  A budgeted check
over it once asked for a few rows, paid for all of them, kept those few and said INCOMPLETE on
every check; and a check that called no backend at all (a budget below the check's own cost) taught
the cost model that a check costs next to nothing, so the next budget was overrun again.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

import armguard
import armguard.backends as backends_mod
from armguard.backends import Capability, CheckerBase
from armguard.detect import Status

THRESHOLD = 0.05


class _Whole(CheckerBase):
    """coal's distances through the least a backend writes: ``pair_distances(q)``; counts its calls."""

    name = "whole_only"
    capabilities = frozenset({Capability.DISTANCES, Capability.VERDICTS})

    def __init__(self, model) -> None:
        super().__init__(model)
        self.inner = armguard.checker(model, "coal", {"threads": 1})
        self.calls = 0

    def pair_distances(self, q):
        self.calls += 1
        r = self.inner.pair_distances(q)
        return self._result(r.distance.copy(), r.p_WA.copy(), r.p_WB.copy())


@pytest.fixture
def whole_registered(monkeypatch):
    built = []

    def build(model, options=None):
        built.append(_Whole(model))
        return built[-1]

    real = backends_mod._entry_points
    fake = SimpleNamespace(load=lambda: SimpleNamespace(name="whole_only", build=build))
    monkeypatch.setattr(backends_mod, "_entry_points", lambda refresh=False: {**real(refresh), "whole_only": fake})
    return built


def test_the_framework_marks_a_pairs_argument_it_supplies():
    assert getattr(_Whole.pair_distances, "pairs_from_full", False) is True
    assert not getattr(armguard.checker(armguard.load_model("hermes"), "coal").pair_distances, "pairs_from_full", False)


def test_a_budgeted_check_over_a_whole_call_backend_evaluates_every_pair(whole_registered):
    model = armguard.load_model("hermes")
    det = armguard.Detector(model.scene, threshold=THRESHOLD, backend="whole_only")
    ref = armguard.Detector(model.scene, threshold=THRESHOLD, backend="coal")
    Q = model.scene_q(model.random_q(12, 3))
    evaluated = 0
    for q in Q:
        exact = ref.check(q)
        for budget, lazy in ((5.0, False), (50.0, False), (None, True), (5.0, True)):
            rep = det.check(q, budget_us=budget, lazy=lazy)
            if rep.n_evaluated:  # whatever it asked, it paid for (and kept) every pair
                evaluated += 1
                assert rep.n_evaluated == det.n_pairs and rep.not_evaluated == ()
                assert rep.status is exact.status
                assert rep.nearest.distance == pytest.approx(exact.nearest.distance, abs=1e-9)
            else:  # a budget that allows no pair: no backend call, nothing hidden
                assert rep.status in (Status.INCOMPLETE, exact.status)
    assert evaluated >= len(Q)  # the lazy checks at least


def test_a_check_that_calls_no_backend_relaxes_the_cost_model_without_calling_it(whole_registered):
    """A check that calls no backend measures nothing: the estimate of a check's own cost relaxes (10 % a check),
    never below what such a check costs, and no backend is called for it."""
    model = armguard.load_model("hermes")
    det = armguard.Detector(model.scene, threshold=THRESHOLD, backend="whole_only")
    q = model.scene_q(model.random_q(1, 5))[0]
    det.check(q)
    det._us_per_check = 1e4  # an estimate far above any budget below
    calls = whole_registered[-1].calls
    expected = 1e4
    for _ in range(20):
        rep = det.check(q, budget_us=0.0)
        assert rep.n_evaluated == 0
        # the rule, from each check's own measured cost (a loaded machine's pause makes one check slow:
        # 1908 us once under xdist, above 1e4 x 0.9^20, and the estimate rightly stays there)
        expected = max(0.9 * expected, rep.elapsed_us)
        assert det._us_per_check == pytest.approx(expected, rel=1e-9)
    assert whole_registered[-1].calls == calls  # no backend call
    assert 0.0 < det._us_per_check < 1e4 * 0.9  # it relaxed (a check that calls nothing costs far below 9 ms)


def test_a_budget_below_the_first_estimate_is_not_stuck_there():
    """The cost model starts at 50 us a check: a 40 us budget once left every check of a fresh Detector
    unevaluated for good (nothing called the backend to correct the estimate)."""
    model = armguard.load_model("hermes")
    det = armguard.Detector(model.scene, threshold=THRESHOLD, backend="coal")
    Q = model.scene_q(model.random_q(100, 9))
    det._us_per_check = 10_000.0  # as after a slow first check: 10x the budget
    # a budget well above what a check that calls no backend costs on a loaded machine (60 us once was not:
    # the estimate relaxes no lower than that cost, and stayed above 60 us in a loaded CI run)
    evaluated = sum(det.check(q, budget_us=1000.0).n_evaluated > 0 for q in Q)
    assert evaluated >= 10, evaluated  # (0 of 100 while the estimate could only be taught by a call)


@pytest.mark.parametrize("backend", ["analytic", "coal"])
def test_a_budget_that_is_no_number_of_microseconds_is_refused_naming_it(backend):
    """True and "5" were taken as budgets (1 and 5 µs); 10**400, a complex number and a one-element
    array raised a bare OverflowError or TypeError that did not name budget_us."""
    model = armguard.load_model("hermes")
    det = armguard.Detector(model, threshold=THRESHOLD, backend=backend)
    q = model.scene_q(model.random_q(1, 3))[0]
    for bad in (True, "5", 10**400, 1 + 2j, np.array([5.0]), -1.0, float("nan"), float("inf")):
        with pytest.raises(armguard.DetectionError, match="budget_us: expected a finite number >= 0"):
            det.check(q, budget_us=bad)
    assert det.check(q, budget_us=np.float64(5.0)).status in set(armguard.Status)
