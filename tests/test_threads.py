"""Checkers and Detectors shared by several threads answer as single-threaded calls do.

Each test runs 4 threads over the same random configurations at once (a barrier starts them
together, every thread walks the list in its own order) and compares every answer exactly with
the single-threaded ones computed first.  Also: ``pair_distances(q, pairs=rows)`` equals the full
result's rows, and ``pair_distances_many(Q)`` equals ``pair_distances`` row by row.
"""

from __future__ import annotations

import math
import sys
import sysconfig
import threading
from pathlib import Path

import numpy as np
import pytest

import armguard
from armguard import BackendError
from armguard.backends import PairDistancesMany

N_THREADS = 4
ROBOTS = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share" / "example-robot-data" / "robots"


def _in_threads(fn, items, n_threads: int = N_THREADS) -> list[list]:
    """``fn(item)`` for every item on each of ``n_threads`` threads at once; per thread, the answers
    in ``items``' order (each thread visits them in its own shuffled order)."""
    barrier = threading.Barrier(n_threads)
    out: list = [None] * n_threads
    errors: list = []

    def run(t: int) -> None:
        order = np.random.default_rng(t).permutation(len(items))
        got = [None] * len(items)
        try:
            barrier.wait()
            for k in order:
                got[k] = fn(items[k])
        except BaseException as exc:  # noqa: BLE001 - reported below, in the test's thread
            errors.append(exc)
        out[t] = got

    threads = [threading.Thread(target=run, args=(t,)) for t in range(n_threads)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    if errors:
        raise errors[0]
    return out


def _pd_tuple(r) -> tuple:
    return r.distance.copy(), r.p_WA.copy(), r.p_WB.copy(), tuple(map(tuple, r.pairs)), tuple(r.category)


def _assert_same_pd(got, want) -> None:
    for g, w in zip(got, want):
        np.testing.assert_array_equal(g[0], w[0])
        np.testing.assert_array_equal(g[1], w[1])
        np.testing.assert_array_equal(g[2], w[2])
        assert g[3:] == w[3:]


@pytest.fixture(scope="module")
def ranger():
    return armguard.load_model("ranger")


@pytest.fixture(scope="module")
def panda():
    return armguard.load_model(ROBOTS / "panda_description/urdf/panda.urdf", srdf=ROBOTS / "panda_description/srdf/panda.srdf")


# ---------------------------------------------------------------- pair_distances from 4 threads
@pytest.mark.parametrize("backend, model_name, n", [("analytic", "ranger", 200), ("analytic", "panda", 120),
                                                    ("coal", "ranger", 60), ("coal", "panda", 30),
                                                    ("fcl", "ranger", 12)])
def test_pair_distances_from_threads_equal_single_threaded(backend, model_name, n, request):
    model = request.getfixturevalue(model_name)
    c = armguard.checker(model, backend)
    Q = model.random_q(n, 11)
    want = [_pd_tuple(c.pair_distances(q)) for q in Q]
    for got in _in_threads(lambda q: _pd_tuple(c.pair_distances(q)), list(Q)):
        _assert_same_pd(got, want)


def test_paper_fidelity_from_threads_equal_single_threaded(ranger):
    c = armguard.checker(ranger, "analytic", {"fidelity": "paper"})
    Q = ranger.random_q(60, 12)
    want = [_pd_tuple(c.pair_distances(q)) for q in Q]
    for got in _in_threads(lambda q: _pd_tuple(c.pair_distances(q)), list(Q)):
        _assert_same_pd(got, want)
    Qs = [Q[k:k + 5] for k in range(0, len(Q), 5)]
    want_c = [c.collides(x) for x in Qs]
    for got in _in_threads(lambda x: c.collides(x), Qs):
        for g, w in zip(got, want_c):
            np.testing.assert_array_equal(g, w)


@pytest.mark.parametrize("backend", ["analytic", "coal"])
def test_subsets_and_batches_from_threads(backend, ranger):
    c = armguard.checker(ranger, backend)
    rng = np.random.default_rng(5)
    n = len(ranger.pairs)
    Q = ranger.random_q(40, 13)
    jobs = [(q, rng.choice(n, size=int(rng.integers(1, n)), replace=False)) for q in Q]
    want = [_pd_tuple(c.pair_distances(q, pairs=idx)) for q, idx in jobs]
    for got in _in_threads(lambda job: _pd_tuple(c.pair_distances(job[0], pairs=job[1])), jobs):
        _assert_same_pd(got, want)
    blocks = [Q[k:k + 8] for k in range(0, len(Q), 8)]
    want_m = [c.pair_distances_many(x) for x in blocks]
    for got in _in_threads(lambda x: c.pair_distances_many(x), blocks):
        for g, w in zip(got, want_m):
            np.testing.assert_array_equal(g.distance, w.distance)
            np.testing.assert_array_equal(g.p_WA, w.p_WA)
            np.testing.assert_array_equal(g.p_WB, w.p_WB)


@pytest.mark.parametrize("backend", ["analytic", "coal"])
def test_collides_from_threads(backend, panda):
    c = armguard.checker(panda, backend, {"threads": 2} if backend == "coal" else None)
    Q = panda.random_q(400, 14)
    blocks = [Q[k:k + 100] for k in range(0, len(Q), 100)]  # coal: batches of >= 64 use its pool
    want = [c.collides(x) for x in blocks]
    assert 0 < sum(int(w.sum()) for w in want) < len(Q)  # both answers occur
    for got in _in_threads(lambda x: c.collides(x), blocks):
        for g, w in zip(got, want):
            np.testing.assert_array_equal(g, w)


@pytest.mark.parametrize("backend", ["analytic", "fcl"])
def test_one_row_collides_from_threads(backend):
    """``collides`` a row at a time from several threads: the analytic backend's one-row path (the
    thread's own outputs) and compiled conversion of kinova's continuous joints, python-fcl's early
    exit under its lock; every thread's verdicts equal the single-threaded ones, at two margins."""
    kinova = armguard.load_model("kinova")
    c = armguard.checker(kinova, backend)
    Q = kinova.random_q(12 if backend == "fcl" else 120, 29)
    jobs = [(Q[m:m + 1], margin) for m in range(len(Q)) for margin in (0.0, 0.05)]
    want = [c.collides(x, margin=mg) for x, mg in jobs]
    assert 0 < sum(int(w[0]) for w in want) < len(jobs)  # both answers occur
    for got in _in_threads(lambda job: c.collides(job[0], margin=job[1]), jobs):
        for g, w in zip(got, want):
            np.testing.assert_array_equal(g, w)


def test_clip_verdicts_from_threads(ranger):
    c = armguard.checker(ranger, "clip")
    Q = ranger.random_q(80, 15)
    blocks = [Q[k:k + 10] for k in range(0, len(Q), 10)]
    want = [c.check_pairs(x).codes for x in blocks]
    for got in _in_threads(lambda x: c.check_pairs(x).codes, blocks):
        for g, w in zip(got, want):
            np.testing.assert_array_equal(g, w)


def test_forbidden_verdicts_from_threads(tmp_path_factory):
    from armguard.cspace import ForbiddenMap

    model = armguard.load_model("hermes")
    fmap = ForbiddenMap.build(model, out=tmp_path_factory.mktemp("fb") / "hermes.agmap", resolution=math.radians(15.0),
                              stopping_distance=0.1, max_depth=2)
    c = armguard.checker(model, "forbidden", {"map": str(fmap.path)})
    Q = model.random_q(200, 16)
    blocks = [Q[k:k + 20] for k in range(0, len(Q), 20)]
    want = [c.verdicts(x).status for x in blocks]
    for got in _in_threads(lambda x: c.verdicts(x).status, blocks):
        for g, w in zip(got, want):
            np.testing.assert_array_equal(g, w)


# ---------------------------------------------------------------- the Detector from 4 threads
def _report_tuple(rep) -> tuple:
    cats = {k: (v.distance, v.a, v.b, tuple(v.p_WA), tuple(v.p_WB)) for k, v in rep.by_category.items()}
    return rep.status, cats, tuple((r.distance, r.a, r.b) for r in rep.within_threshold)


def test_detector_check_from_threads(ranger):
    det = armguard.Detector(ranger.scene, threshold=0.1)
    Q = ranger.scene_q(ranger.random_q(200, 17))
    want = [_report_tuple(det.check(q)) for q in Q]
    assert len({w[0] for w in want}) > 1  # more than one status among them
    for got in _in_threads(lambda q: _report_tuple(det.check(q)), list(Q)):
        assert got == want


def test_detector_held_reports_from_threads(ranger):
    """A report held while the same thread checks again still says what it said."""
    det = armguard.Detector(ranger.scene, threshold=0.1)
    Q = ranger.scene_q(ranger.random_q(60, 18))
    want = [_report_tuple(det.check(q)) for q in Q]

    def held_then_more(q):
        rep = det.check(q)
        det.check(Q[0])  # overwrites this thread's scratch
        det.pair_distances(q)
        return _report_tuple(rep)

    for got in _in_threads(held_then_more, list(Q)):
        assert got == want


def test_a_report_read_on_another_thread_while_the_checking_thread_goes_on(ranger):
    """A control loop publishes its latest report and a UI thread reads it: the UI's read and the control
    thread's copy before its next check raced (the control thread's ``check`` raised TypeError about once
    in 10^4 cycles; a copy half overwritten was possible).  Every report read equals the one-thread answer
    for its configuration, and neither thread raises."""
    import time

    det = armguard.Detector(ranger.scene, threshold=0.1)
    Q = ranger.scene_q(ranger.random_q(50, 19))
    want = [_report_tuple(det.check(q)) for q in Q]
    latest, errors, seen, stop = [None], [], [0], threading.Event()

    def control():
        k = 0
        while not stop.is_set():
            try:
                latest[0] = (k % len(Q), det.check(Q[k % len(Q)]))
            except Exception as exc:  # noqa: BLE001 - recorded, asserted below
                errors.append(("control", exc))
                return
            k += 1

    def ui():
        while not stop.is_set():
            got = latest[0]
            if got is None:
                continue
            try:
                if _report_tuple(got[1]) != want[got[0]]:
                    errors.append(("ui", f"configuration {got[0]}: another answer"))
                    return
                seen[0] += 1
            except Exception as exc:  # noqa: BLE001 - recorded, asserted below
                errors.append(("ui", exc))
                return

    old = sys.getswitchinterval()
    sys.setswitchinterval(1e-5)
    try:
        threads = [threading.Thread(target=f) for f in (control, ui)]
        for t in threads:
            t.start()
        time.sleep(3.0)
        stop.set()
        for t in threads:
            t.join()
    finally:
        sys.setswitchinterval(old)
    assert not errors and seen[0] > 100, (errors[:3], seen[0])


def test_detector_batches_and_pair_distances_from_threads(ranger):
    det = armguard.Detector(ranger.scene, threshold=0.1)
    Q = ranger.scene_q(ranger.random_q(120, 19))
    blocks = [Q[k:k + 30] for k in range(0, len(Q), 30)]
    want = [(det.check_many(x).min_distance, det.collides_many(x)) for x in blocks]
    for got in _in_threads(lambda x: (det.check_many(x).min_distance, det.collides_many(x)), blocks):
        for g, w in zip(got, want):
            np.testing.assert_array_equal(g[0], w[0])
            np.testing.assert_array_equal(g[1], w[1])
    want_pd = [det.pair_distances(q).distance for q in Q]
    for got in _in_threads(lambda q: det.pair_distances(q).distance, list(Q)):
        for g, w in zip(got, want_pd):
            np.testing.assert_array_equal(g, w)


# ---------------------------------------------------------------- pairs= and pair_distances_many
@pytest.mark.parametrize("backend", ["analytic", "coal", "fcl"])
def test_pairs_subset_is_the_full_results_rows(backend, ranger):
    c = armguard.checker(ranger, backend)
    n = len(ranger.pairs)
    rng = np.random.default_rng(21)
    for q in ranger.random_q(4, 22):
        full = c.pair_distances(q)
        for idx in (rng.permutation(n)[: n // 3], np.array([n - 1, 0, n - 1, 2]), np.arange(n)[::-1],
                    np.zeros(0, np.int64), np.concatenate([np.arange(n), np.arange(n)])):
            sub = c.pair_distances(q, pairs=idx)
            np.testing.assert_array_equal(sub.distance, full.distance[idx])
            np.testing.assert_array_equal(sub.p_WA, full.p_WA[idx])
            np.testing.assert_array_equal(sub.p_WB, full.p_WB[idx])
            assert sub.pairs.tolist() == full.pairs[idx].tolist()
            assert tuple(sub.category) == tuple(full.category[int(k)] for k in idx)
        sub = c.pair_distances(q, pairs=[3, 1])  # a list works too
        np.testing.assert_array_equal(sub.distance, full.distance[[3, 1]])


@pytest.mark.parametrize("backend", ["analytic", "coal", "fcl"])
def test_many_equals_row_by_row(backend, ranger):
    c = armguard.checker(ranger, backend)
    Q = ranger.random_q(6 if backend == "fcl" else 40, 23)
    many = c.pair_distances_many(Q)
    assert isinstance(many, PairDistancesMany) and len(many) == len(Q)
    assert many.distance.shape == (len(Q), len(ranger.pairs)) and many.p_WA.shape == (len(Q), len(ranger.pairs), 3)
    for m, q in enumerate(Q):
        r = c.pair_distances(q)
        np.testing.assert_array_equal(many.distance[m], r.distance)
        np.testing.assert_array_equal(many.p_WA[m], r.p_WA)
        np.testing.assert_array_equal(many.p_WB[m], r.p_WB)
        np.testing.assert_array_equal(many.row(m).distance, r.distance)
    assert many.pairs.tolist() == r.pairs.tolist() and tuple(many.category) == tuple(r.category)
    idx = np.array([5, 2, 7])
    sub = c.pair_distances_many(Q, pairs=idx)
    np.testing.assert_array_equal(sub.distance, many.distance[:, idx])
    np.testing.assert_array_equal(sub.p_WB, many.p_WB[:, idx])
    assert c.pair_distances_many(Q[:0]).distance.shape == (0, len(ranger.pairs))


def test_analytic_many_split_over_threads_equals_row_by_row(panda):
    c = armguard.checker(panda, "analytic")
    Q = panda.random_q(1100, 24)  # enough rows for several worker threads
    many = c.pair_distances_many(Q)
    for m in range(0, len(Q), 97):
        r = c.pair_distances(Q[m])
        np.testing.assert_array_equal(many.distance[m], r.distance)
        np.testing.assert_array_equal(many.p_WA[m], r.p_WA)


@pytest.mark.parametrize("backend", ["analytic", "coal", "fcl"])
def test_bad_pairs_and_bad_q_are_errors(backend, ranger):
    c = armguard.checker(ranger, backend)
    q = ranger.random_q(1, 25)[0]
    n = len(ranger.pairs)
    for bad in ([n], [-1], np.array([True, False]), [[0, 1]], [0.5], "ab"):
        with pytest.raises(BackendError, match="pairs"):
            c.pair_distances(q, pairs=bad)
        with pytest.raises(BackendError, match="pairs"):
            c.pair_distances_many(q[None], pairs=bad)
    bad_q = q.copy()
    bad_q[0] = np.nan
    with pytest.raises(BackendError, match="NaN"):
        c.pair_distances(bad_q)
    with pytest.raises(BackendError, match="NaN"):
        c.pair_distances_many(np.stack([q, bad_q]))
    with pytest.raises(BackendError, match="shape"):
        c.pair_distances(q[:-1])


def test_any_float_q_layout_is_accepted(ranger):
    c = armguard.checker(ranger, "analytic")
    Q = ranger.random_q(3, 26)
    want = c.pair_distances(Q[1]).distance
    ro = Q[1].copy()
    ro.flags.writeable = False
    for q in (ro, np.asfortranarray(Q.T)[:, 1], Q[1].tolist(), Q[1:2].reshape(-1)):
        np.testing.assert_array_equal(c.pair_distances(q).distance, want)


@pytest.mark.parametrize("backend", ["clip"])
def test_verdict_backends_refuse_distances(backend, ranger):
    c = armguard.checker(ranger, backend)
    q = ranger.random_q(1, 27)[0]
    for call in (lambda: c.pair_distances(q), lambda: c.pair_distances(q, pairs=[0]),
                 lambda: c.pair_distances_many(q[None]), lambda: c.pair_distances_many(q[None], pairs=[0])):
        with pytest.raises(BackendError, match="does not answer distances"):
            call()


# ---------------------------------------------------------------- the GIL policy (analytic)
@pytest.mark.parametrize("release_gil", [True, False])
def test_both_gil_policies_answer_alike_from_threads(release_gil, ranger):
    """Holding the GIL (short calls) or releasing it, 4 threads get the single-threaded answers,
    and both policies the same answers."""
    c = armguard.checker(ranger, "analytic", {"release_gil": release_gil})
    assert c.releases_gil is release_gil
    other = armguard.checker(ranger, "analytic", {"release_gil": not release_gil})
    Q = ranger.random_q(60, 31)
    want = [_pd_tuple(c.pair_distances(q)) for q in Q]
    _assert_same_pd([_pd_tuple(other.pair_distances(q)) for q in Q], want)
    for got in _in_threads(lambda q: _pd_tuple(c.pair_distances(q)), list(Q)):
        _assert_same_pd(got, want)
    many = c.pair_distances_many(ranger.random_q(600, 32))  # split over worker threads: these release it
    np.testing.assert_array_equal(many.distance[599], c.pair_distances(ranger.random_q(600, 32)[599]).distance)


def test_gil_policy_goes_by_the_measured_call(monkeypatch, ranger):
    """``"auto"``: the GIL is released when a call takes at least ``GIL_RELEASE_US`` (the Checker's
    call plan and the fused Detector each time their own call)."""
    from armguard_analytic._engine import _scratch

    for limit, released in ((0.0, True), (math.inf, False)):
        monkeypatch.setattr(_scratch, "GIL_RELEASE_US", limit)
        c = armguard.checker(ranger, "analytic")
        assert c.releases_gil is released
        assert 0.0 < c._plan().call_us < 1e6
        det = armguard.Detector(ranger.scene, threshold=0.1)
        assert det.releases_gil is released and 0.0 < det.call_us < 1e6
        Q = ranger.scene_q(ranger.random_q(40, 33))
        want = [_report_tuple(det.check(q)) for q in Q]
        for got in _in_threads(lambda q: _report_tuple(det.check(q)), list(Q)):
            assert got == want


def test_release_gil_option_is_checked(ranger):
    assert armguard.checker(ranger, "analytic", {"release_gil": "auto"}).releases_gil in (True, False)
    with pytest.raises(BackendError, match="release_gil"):
        armguard.checker(ranger, "analytic", {"release_gil": "sometimes"})


# ---------------------------------------------------------------- warm starts (analytic option)
def test_warm_starts_from_threads_answer_as_one_thread(panda):
    """Option ``warm_start``: each thread keeps its own previous simplices, so 4 threads walking one
    path in small steps on one shared checker (each from its own start, so each thread's previous call
    is its own) get the distances of a plain checker to 1e-9 m, its verdicts, and pair names."""
    import pinocchio as pin

    c = armguard.checker(panda, "analytic", {"warm_start": True})
    plain = armguard.checker(panda, "analytic")
    a, b = panda.random_q(2, 41)
    path = [pin.interpolate(panda.pin_model, a, b, t) for t in np.linspace(0.0, 1.0, 160)]
    want = [_pd_tuple(plain.pair_distances(q)) for q in path]
    barrier = threading.Barrier(N_THREADS)
    out: list = [None] * N_THREADS

    def walk(t: int) -> None:
        barrier.wait()
        out[t] = [(k, _pd_tuple(c.pair_distances(path[k]))) for k in np.roll(np.arange(len(path)), 40 * t)]

    threads = [threading.Thread(target=walk, args=(t,)) for t in range(N_THREADS)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    for got in out:
        assert got is not None and len(got) == len(path)
        for k, g in got:
            np.testing.assert_allclose(g[0], want[k][0], atol=1e-9, rtol=0)
            clear = np.abs(want[k][0]) > 1e-9
            assert np.array_equal(g[0][clear] <= 0.0, want[k][0][clear] <= 0.0) and g[3:] == want[k][3:]


_WARNING_FILTERS_SCRIPT = """
import sys, threading, warnings
import armguard
sys.setswitchinterval(1e-6)  # threads switch as often as they can: the old per-call filters' race shows
model = armguard.load_model("ranger")
checker = armguard.checker(model, "coal")
q = model.neutral()
seen = []
warnings.showwarning = lambda message, *a, **k: seen.append(str(message))
before = list(warnings.filters)
for _ in range(40):  # 40 rounds of 8 new threads: each thread's first call makes its GeometryData
    barrier = threading.Barrier(8)
    def first_call():
        barrier.wait()
        checker.pair_distances(q)
    threads = [threading.Thread(target=first_call) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
print(sum("enable_cached_gjk_guess" in m for m in seen), list(warnings.filters) == before)
"""


def test_coal_first_calls_from_threads_leave_the_warning_filters_alone():
    """Each thread's first call makes its own GeometryData and turns coal's cached GJK guess off through
    a setter coal deprecates.  That warning was once silenced by a ``warnings.catch_warnings()`` per
    call: from threads at once they restored one another's filters, letting the warnings through and
    leaving filters behind.  In a process that shows every DeprecationWarning (``-W always``), 40
    rounds of 8 threads' first calls now show none of it and leave the filters as they were."""
    import subprocess
    import sys

    proc = subprocess.run([sys.executable, "-W", "always::DeprecationWarning", "-c", _WARNING_FILTERS_SCRIPT],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stdout.split() == ["0", "True"], proc.stdout


@pytest.mark.skipif(not hasattr(__import__("os"), "sched_setaffinity"), reason="no CPU affinity on this platform")
def test_batches_spread_over_the_cores_the_process_may_use():
    """A process pinned to one core (a control loop's, a container's share): batches used every core of the
    machine (``os.cpu_count()``), over the core set aside for control.  They now read the CPU affinity."""
    import subprocess
    import sys as _sys

    code = ("import os; os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]}); import armguard; "
            "from armguard_analytic._engine._scratch import CPUS; "
            "c = armguard.checker(armguard.load_model('puma560'), 'coal'); print(CPUS, c.threads)")
    out = subprocess.run([_sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.split()[-2:] == ["1", "1"], out.stdout
