"""The backend plugins side by side: analytic vs coal vs python-fcl on the same Models.

Per model: µs per configuration for every pair's signed distance and witness points
(``checker.pair_distances(q)``), and yes/no configurations per second (``checker.collides(Q)``,
each backend's own batch path: the analytic one multi-threaded numba, coal's
``computeCollisionsInParallel`` over a GeometryPool, fcl one configuration at a time).

A second table: the analytic interface's cost around its kernel -- one ``pair_distances(q)``
against the bare compiled call it makes (the difference is the Python per call),
``pair_distances_many(Q)`` per row, the same calls from two threads sharing one checker (the
checker's GIL policy, and the GIL always released), and yes/no per thread against coal with one thread; the built-in
models, the Panda and, where example-robot-data is installed, z1 and xarm7.
"""

from __future__ import annotations

import sysconfig
import threading
import time
from pathlib import Path

import numpy as np

from .timing import fmt_ns, interleaved_thread_seconds, median_seconds, median_thread_seconds

TITLE = "Backends: analytic vs coal vs python-fcl on the same Model"

_ROBOTS = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share" / "example-robot-data" / "robots"


def _models():
    import armguard

    out = [(n, lambda n=n: armguard.load_model(n)) for n in ("ranger", "hermes", "puma560", "gmf_s480", "rover")]
    panda = _ROBOTS / "panda_description"
    if panda.is_dir():
        out.append(("panda (hulls)", lambda: armguard.load_model(panda / "urdf/panda.urdf", srdf=panda / "srdf/panda.srdf")))
    return out


def coal_core(checker):
    """``q -> None``: Pinocchio's ``computeDistances`` on the coal Checker's own geometry and requests -- every
    pair's distance and witness points computed in C++, nothing read back into Python (the Checker then reads
    each pair's result through Pinocchio's bindings, ~2 µs a pair).  Private attributes, for this figure only."""
    import pinocchio as pin

    checker.pair_distances(checker.model.neutral())
    data, gdata = checker._thread_data()
    pm, gm = checker.model.pin_model, checker.geometry_model
    return lambda q: pin.computeDistances(pm, data, gm, gdata, q)


def run(quick: bool) -> str:
    import armguard

    n_pd = 50 if quick else 300
    n_yn = 2000 if quick else 20000
    rows = ["| model | pairs | analytic distances | coal distances | fcl distances | analytic yes/no | coal yes/no "
            "| fcl yes/no | coal / analytic (distances, yes/no) |",
            "|---|---|---|---|---|---|---|---|---|"]
    for name, load in _models():
        m = load()
        Q = m.random_q(n_pd, 1)
        Qy = m.random_q(n_yn, 2)
        t_pd, t_yn = {}, {}
        for b in ("analytic", "coal", "fcl"):
            c = armguard.checker(m, b)
            it = iter(range(10**9))
            t_pd[b] = median_seconds(lambda c=c: c.pair_distances(Q[next(it) % len(Q)]), repeat=5, number=len(Q) // 5)
            Qb = Qy if b != "fcl" else Qy[: max(50, len(Qy) // 50)]
            t_yn[b] = median_seconds(lambda c=c, Qb=Qb: c.collides(Qb), repeat=3) / len(Qb)
        rows.append(
            f"| {name} | {len(m.pairs)} | {fmt_ns(t_pd['analytic'])} | {fmt_ns(t_pd['coal'])} | {fmt_ns(t_pd['fcl'])} "
            f"| {1 / t_yn['analytic'] / 1e3:.0f} k/s | {1 / t_yn['coal'] / 1e3:.0f} k/s | {1 / t_yn['fcl'] / 1e3:.1f} k/s "
            f"| {t_pd['coal'] / t_pd['analytic']:.1f}×, {t_yn['coal'] / t_yn['analytic']:.1f}× |")
    note = (f"\n\nDistances: one `pair_distances(q)` per configuration ({n_pd} random in-limit configurations, "
            f"median of 5 runs), every active pair with witness points, from Python: coal's figure is mostly the "
            "reading of its results through Pinocchio's Python bindings (its C++ core alone: the next table). Yes/no: "
            f"`collides(Q)` on {n_yn} configurations (fcl on a fiftieth of them; its `collides` computes each pair's "
            "distance, with nearest points, until the first within the margin). coal's reference runs GJK without guesses "
            "carried between configurations (see `plugins/armguard_coal`).")
    return "\n".join(rows) + note + "\n\n" + interface_rows(quick)


def _hull_robots():
    """Robots with convex-hull collision geometry (pybullet's KUKA iiwa, example-robot-data's Panda)."""
    import armguard

    out = []
    try:
        import pybullet_data

        iiwa = Path(pybullet_data.getDataPath()) / "kuka_iiwa" / "model.urdf"
        if iiwa.is_file():
            out.append(("kuka_iiwa (hulls)", lambda: armguard.load_model(iiwa)))
    except ImportError:  # pragma: no cover - pybullet is a test extra
        pass
    panda = _ROBOTS / "panda_description"
    if panda.is_dir():
        out.append(("panda (hulls)", lambda: armguard.load_model(panda / "urdf/panda.urdf", srdf=panda / "srdf/panda.srdf")))
    return out


def _public_robots():
    """Public robots of the interface table (example-robot-data's z1: cylinders against dense gripper
    hulls; xarm7: dense meshes; kinova: continuous joints, given as (cos, sin)), where installed."""
    import armguard
    from armguard.model import known_models

    have = {m.name for m in known_models() if m.available}
    return [(n, lambda n=n: armguard.load_model(n)) for n in ("z1", "xarm7", "kinova") if n in have]


def _two_threads(fn, n: int) -> float:
    """Wall seconds for ``n`` calls ``fn(i)`` split over two threads sharing everything."""
    barrier = threading.Barrier(3)

    def run(lo: int, hi: int) -> None:
        barrier.wait()
        for i in range(lo, hi):
            fn(i)

    ts = [threading.Thread(target=run, args=(0, n // 2)), threading.Thread(target=run, args=(n // 2, n))]
    for t in ts:
        t.start()
    barrier.wait()
    t0 = time.perf_counter()
    for t in ts:
        t.join()
    return time.perf_counter() - t0


def _no_kernel(*args) -> int:
    return 0


def _python_seconds(call, owner, name: str, args: tuple) -> float:
    """The Python of ``call()`` without its kernel: ``owner.name`` (the compiled kernel it calls)
    swapped for a Python function that returns at once, less that function's own call on ``args``
    (the kernel's arguments); the best of 21 interleaved runs of 500 calls each: a cost of the code,
    not of the machine's load."""
    kernel = getattr(owner, name)
    setattr(owner, name, _no_kernel)
    try:
        t = interleaved_thread_seconds({"call": call, "nop": lambda: _no_kernel(*args)}, repeat=21, number=500,
                                       reduce=min)
    finally:
        setattr(owner, name, kernel)
    return max(t["call"] - t["nop"], 0.0)


def _wrapper_seconds(a, f, q) -> float:
    """The Python of one ``pair_distances(q)`` call (:func:`_python_seconds`, the plan's compiled entry
    swapped).  (The difference of the call and the bare kernel call, two noisy times of tens of µs,
    moved by ±3 µs from run to run.)"""
    args = (f.fn, q, 0, 1, f.gmap, *f.args[:3], *f.scratch()[:2], *f.args[3:], f.scratch()[2], q, q, q)
    return _python_seconds(lambda: a.pair_distances(q), f, "entry", args)


def _collides_python_seconds(a, Q) -> float:
    """The Python of one ``collides(Q)`` call (:func:`_python_seconds`, the fused kernel's
    ``detect_rows`` swapped)."""
    from armguard_analytic._engine import _kernel as kn

    det = a.detector()
    b = det._fresh()
    SF, SI, ip = det._scratch(b).batch_buffers(kn.MODE_YESNO)
    args = (Q, 0, len(Q), b.H, b.MF, b.MI, SF, SI, b.prm, ip, b.all_p, Q, Q, b.fn)
    return _python_seconds(lambda: a.collides(Q), kn, "detect_rows", args)


def collides_rows(quick: bool) -> str:
    """``collides(Q)`` on one configuration: the call, its Python, coal's call."""
    import armguard

    n_q = 40 if quick else 200
    rows = ["| model | analytic `collides(Q)`, one row | Python per call | coal `collides(Q)`, one row | coal / analytic |",
            "|---|---|---|---|---|"]
    for name, load in _models() + _public_robots():
        m = load()
        Q = [np.ascontiguousarray(q[None]) for q in m.random_q(n_q, 5)]
        a, c = armguard.checker(m, "analytic"), armguard.checker(m, "coal", {"threads": 1})
        t_py = _collides_python_seconds(a, Q[0])
        it = iter(range(10**9))
        t = interleaved_thread_seconds({"a": lambda: a.collides(Q[next(it) % n_q]),
                                        "c": lambda: c.collides(Q[next(it) % n_q])}, repeat=7, number=n_q)
        rows.append(f"| {name} | {fmt_ns(t['a'])} | {fmt_ns(t_py)} | {fmt_ns(t['c'])} | {t['c'] / t['a']:.1f}× |")
    note = ("\n\nThread CPU time, medians of 7 interleaved runs over random in-limit configurations, one `(1, nq)` row "
            "per call. The Python per call is `collides` with the fused kernel's `detect_rows` swapped for a Python "
            "function that returns at once (less that function's call; best of 21 interleaved runs of 500 calls, "
            "as for `pair_distances`): the argument checks, the joint reordering where Pinocchio's order is not "
            "the scene's (ranger: a column take; kinova: its continuous joints' (cos, sin) checked and read as "
            "angles, compiled), the thread's scratch and the verdict array.")
    return "\n".join(rows) + note


def interface_rows(quick: bool) -> str:
    """The analytic interface around its kernel (see the module docstring)."""
    import armguard

    n_q = 40 if quick else 200
    rows = ["| model | pairs | analytic `pair_distances` | bare kernel call | Python per call | `pair_distances_many` "
            "per row | coal `pair_distances` | coal / analytic | coal's C++ core | core / analytic | 2 threads, one "
            "checker (speed-up; GIL) | 2 threads, GIL always released |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for name, load in _models() + _public_robots():
        m = load()
        Q = m.random_q(n_q, 3)
        a, c = armguard.checker(m, "analytic"), armguard.checker(m, "coal")
        f = a._plan()  # the call plan: the compiled entry and its arguments (private, for this figure only)
        SF, SI, q1 = f.scratch()
        H, MF, MI, prm, iprm = f.args
        out = (np.empty(f.n), np.empty((f.n, 3)), np.empty((f.n, 3)))
        it = iter(range(10**9))
        core = coal_core(c)
        t = interleaved_thread_seconds({
            "full": lambda: a.pair_distances(Q[next(it) % n_q]),
            "bare": lambda: f.entry(f.fn, Q[next(it) % n_q], 0, 1, f.gmap, H, MF, MI, SF, SI, prm, iprm, q1, *out),
            "coal": lambda: c.pair_distances(Q[next(it) % n_q]),
            "core": lambda: core(Q[next(it) % n_q])}, repeat=7, number=n_q)
        t_full, t_bare, t_coal, t_core = t["full"], t["bare"], t["coal"], t["core"]
        t_wrap = _wrapper_seconds(a, f, Q[0])
        t_many = median_thread_seconds(lambda: a.pair_distances_many(Q[:100]), repeat=5) / min(100, n_q)
        n2 = 20 * n_q
        one = median_seconds(lambda: [a.pair_distances(Q[i % n_q]) for i in range(n2)], repeat=3)
        two = float(np.median([_two_threads(lambda i: a.pair_distances(Q[i % n_q]), n2) for _ in range(3)]))
        free = armguard.checker(m, "analytic", {"release_gil": True})
        one_f = median_seconds(lambda: [free.pair_distances(Q[i % n_q]) for i in range(n2)], repeat=3)
        two_f = float(np.median([_two_threads(lambda i: free.pair_distances(Q[i % n_q]), n2) for _ in range(3)]))
        gil = "released" if a.releases_gil else "held"
        rows.append(f"| {name} | {len(m.pairs)} | {fmt_ns(t_full)} | {fmt_ns(t_bare)} | {fmt_ns(t_wrap)} "
                    f"| {fmt_ns(t_many)} | {fmt_ns(t_coal)} | {t_coal / t_full:.1f}× | {fmt_ns(t_core)} "
                    f"| {t_core / t_full:.1f}× | {one / two:.2f}× ({gil}) "
                    f"| {one_f / two_f:.2f}× |")
    from armguard_analytic._engine._scratch import GIL_RELEASE_US

    yn = ["| hull robot | pairs | analytic yes/no per thread | coal yes/no, 1 thread | analytic / coal |", "|---|---|---|---|---|"]
    n_yn = 200 if quick else 2000
    for name, load in _hull_robots():
        m = load()
        Q = m.random_q(n_yn, 4)
        a, c = armguard.checker(m, "analytic"), armguard.checker(m, "coal", {"threads": 1})
        blocks = [Q[k:k + 200] for k in range(0, n_yn, 200)]  # 200 rows: the analytic batch stays on one thread
        t = interleaved_thread_seconds({"a": lambda: [a.collides(b) for b in blocks],
                                        "c": lambda: [c.collides(b) for b in blocks]}, repeat=3)
        t_a, t_c = t["a"] / n_yn, t["c"] / n_yn
        yn.append(f"| {name} | {len(m.pairs)} | {1 / t_a / 1e3:.0f} k/s | {1 / t_c / 1e3:.1f} k/s | {t_c / t_a:.1f}× |")
    note = ("\n\nThread CPU time (`time.thread_time`, medians) for the per-call figures, the runs of analytic, its bare "
            "kernel call and coal interleaved (so is each yes/no pair of figures); the bare kernel call is "
            "`pair_rows` through its compiled entry point with preallocated outputs (numba's unboxing of its "
            "arguments included); the Python per call is `pair_distances` with that entry point swapped for a Python "
            "function that returns at once (less that function's call; best of 21 interleaved runs of 500 calls, as "
            "`timeit` advises for a cost of the code: slower runs measure the machine's other load): validation, the "
            "plan and scratch lookups, three output arrays and the result. coal `pair_distances` is coal through "
            "armguard's coal Checker from Python: Pinocchio's `computeDistances` and then every pair's result read "
            "through Pinocchio's Python bindings (about 2 µs a pair, most of the figure); *coal's C++ core* is that "
            "`computeDistances` call alone (every pair's distance and witnesses computed in C++, nothing read back): "
            "what a C++ caller of coal pays, against armguard's whole Python call. Two threads: wall time of "
            f"{20 * n_q} calls on one thread over the same calls split between two threads sharing one checker "
            "(2.0× is perfect scaling; a shared machine's load lowers it), with the checker's own GIL policy (it holds "
            f"the GIL when one call takes under {GIL_RELEASE_US:g} µs: handing it to the other thread and back costs more than such a "
            "call) and with the GIL always released (option `release_gil=True`). Yes/no per thread: `collides` on blocks "
            "of 200 configurations (one analytic worker thread; coal built with `threads=1`).")
    return "\n".join(rows) + "\n\n" + "\n".join(yn) + note + "\n\n" + collides_rows(quick)
