"""The public-robot table: every arm of example-robot-data and pybullet_data, as a new user meets it.

Each robot is measured in a fresh process (``python -m bench.robots NAME [N]`` prints one JSON
line), after one earlier process loaded it (so Python's bytecode and numba's kernel caches are on
disk, as after a user's first run); load times and peak memory are those of a user's next session:

* **load first**: ``armguard.load_model(name)`` in the earlier process, the first load ever (an
  empty hull cache: every mesh read and hulled, and the hulls stored);
* **load cold / warm**: ``armguard.load_model(name)`` the first time in the measured process (URDF
  parse, hulls read from the hull cache, SRDF read; numba's kernel cache on disk) and a second time;
* **peak RSS**: the process's peak resident memory after loading, building both checkers and
  checking (everything imported);
* **pairs**: active pairs with the SRDF found for it, and without any SRDF (``srdf=False``);
* **agreement**: on ``N`` random in-limit configurations, verdicts (distance ≤ 0) where analytic and
  coal differ, and the largest ``|d_analytic − d_coal|``;
* **µs / configuration**: ``checker.pair_distances(q)`` (every pair's signed distance and witness
  points) for analytic and coal: thread CPU time, median of 7 runs of ``N`` calls, the two backends'
  runs interleaved (a spell of load on the shared machine lands on both);
* **along a path**: the same, the configurations taken in order along straight joint-space segments
  between random waypoints, sampled every ``PATH_STEP`` (a motion planner's edge check, a trajectory's
  verification), the analytic backend as it is and with its option ``warm_start`` (each pair's GJK
  starts from the simplex it ended with at the previous configuration,
  ``armguard_analytic._engine._layout.COHERENT_STEP``), coal as its reference runs (no guess carried
  over: ``plugins/armguard_coal``); the path's verdicts are compared with coal's too.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

TITLE = "Public robots: load, memory, SRDF pairs, agreement and speed against coal"
PATH_STEP = 0.01
"""rad (m for a prismatic joint): the largest joint step between consecutive configurations of the path."""


def path(model, n_way: int, step: float, seed: int):
    """Configurations along straight joint-space segments (Pinocchio's ``interpolate``: continuous joints
    turn the short way) between ``n_way`` random in-limit waypoints, no joint moving more than ``step``
    between consecutive ones."""
    import numpy as np
    import pinocchio as pin

    W = model.random_q(n_way, seed)
    out = []
    for a, b in zip(W[:-1], W[1:]):
        k = max(1, int(np.ceil(np.max(np.abs(pin.difference(model.pin_model, a, b))) / step)))
        out += [pin.interpolate(model.pin_model, a, b, i / k) for i in range(k)]
    return np.array(out)


def _names() -> list[str]:
    from armguard.model import known_models

    return [m.name for m in known_models() if m.source != "built-in" and m.available]


REFERENCE_CHECKS = 3
"""Depths off by more than 1 mm a robot checked against the slow support-function reference."""


def _judge(model, q, k: int, d_a: float, d_c: float) -> tuple:
    """``(|analytic - reference|, |coal - reference|)`` of pair ``k`` at ``q`` (m): the slow
    support-function reference (``armguard.geometry._support_reference``: no GJK, no EPA) on the
    shapes as Pinocchio places them."""
    from armguard.geometry._support_reference import reference_signed_distance
    from armguard.model._shapes import placed_shapes

    ref = reference_signed_distance(*placed_shapes(model, q, model.pairs.names[k]))
    return float(abs(d_a - ref)), float(abs(d_c - ref))


def measure(name: str, n: int) -> dict:
    """One robot's row (see the module docstring); run in a fresh process."""
    import resource

    import numpy as np

    import armguard

    from .backends import coal_core
    from .timing import interleaved_thread_seconds

    t0 = time.perf_counter()
    model = armguard.load_model(name)
    cold = time.perf_counter() - t0
    t0 = time.perf_counter()
    armguard.load_model(name)
    warm = time.perf_counter() - t0
    rss_load = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    bare = armguard.load_model(name, srdf=False)
    srdf = model.srdf.file if model.srdf is not None else None
    ana, ref = armguard.checker(model, "analytic"), armguard.checker(model, "coal")
    Q = model.random_q(n, 7)
    d_a = np.array([ana.pair_distances(q).distance for q in Q])
    d_c = np.array([ref.pair_distances(q).distance for q in Q])
    verdict_a, verdict_c = (d_a <= 0).any(axis=1), (d_c <= 0).any(axis=1)
    off = ((d_a <= 0) | (d_c <= 0)) & (np.abs(d_a - d_c) > 1e-3)
    judged = [_judge(model, Q[i], k, d_a[i, k], d_c[i, k]) for i, k in np.argwhere(off)[:REFERENCE_CHECKS]]
    it = iter(range(10**9))
    core = coal_core(ref)
    t = interleaved_thread_seconds({"a": lambda: ana.pair_distances(Q[next(it) % n]),
                                    "c": lambda: ref.pair_distances(Q[next(it) % n]),
                                    "k": lambda: core(Q[next(it) % n])}, repeat=7, number=n)
    t_a, t_c, t_k = t["a"], t["c"], t["k"]
    T = path(model, 9, PATH_STEP, 11)
    ana_w = armguard.checker(model, "analytic", {"warm_start": True})
    p_a = np.array([ana_w.pair_distances(q).distance for q in T])
    p_c = np.array([ref.pair_distances(q).distance for q in T])
    it, it2, it3 = iter(range(10**9)), iter(range(10**9)), iter(range(10**9))
    tp = interleaved_thread_seconds({"w": lambda: ana_w.pair_distances(T[next(it) % len(T)]),
                                     "a": lambda: ana.pair_distances(T[next(it3) % len(T)]),
                                     "c": lambda: ref.pair_distances(T[next(it2) % len(T)])}, repeat=7, number=n)
    return {
        "name": name, "nq": int(model.nq), "cold_s": cold, "warm_s": warm,
        "rss_load_mb": rss_load, "rss_peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
        "pairs": len(model.pairs), "pairs_no_srdf": len(bare.pairs), "srdf": os.path.basename(srdf) if srdf else None,
        "n": n, "colliding": int(verdict_c.sum()), "disagree": int((verdict_a != verdict_c).sum()),
        "max_dd": float(np.max(np.abs(d_a - d_c)[(d_a > 0) & (d_c > 0)], initial=0.0)),
        "depths": int(((d_a <= 0) | (d_c <= 0)).sum()),
        "depths_off": int((((d_a <= 0) | (d_c <= 0)) & (np.abs(d_a - d_c) > 1e-3)).sum()),
        "coal_depth_max": int((d_c < -1.0).sum()),
        "ref_checked": len(judged), "ref_err_analytic": max((j[0] for j in judged), default=None),
        "ref_err_coal": max((j[1] for j in judged), default=None),
        "us_analytic": t_a * 1e6, "us_coal": t_c * 1e6, "us_coal_core": t_k * 1e6,
        "path_n": len(T), "path_disagree": int(((p_a <= 0).any(axis=1) != (p_c <= 0).any(axis=1)).sum()),
        "us_path_warm": tp["w"] * 1e6, "us_path_analytic": tp["a"] * 1e6, "us_path_coal": tp["c"] * 1e6,
    }


def _env(cache: str) -> dict:
    """The environment of a user's process: Python writes its bytecode caches (a shell that sets
    PYTHONDONTWRITEBYTECODE would make every first import compile its sources, seconds per process);
    the hull cache in ``cache`` (the bench's own folder, empty at its start: never the user's)."""
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    env.pop("ARMGUARD_HULL_CACHE", None)
    env["ARMGUARD_CACHE_DIR"] = cache
    return env


_FIRST = ("import time, armguard; t = time.perf_counter(); armguard.load_model({name!r}); "
          "print('first', time.perf_counter() - t)")


def _run_one(name: str, n: int, cache: str) -> dict:
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    # a first process writes the bytecode, kernel and hull caches a user's earlier runs would have
    # written; its load is the first ever (every mesh hulled)
    first = subprocess.run([sys.executable, "-c", _FIRST.format(name=name)], capture_output=True, text=True,
                           timeout=900, cwd=root, env=_env(cache))
    t_first = [float(ln.split()[1]) for ln in first.stdout.splitlines() if ln.startswith("first ")]
    proc = subprocess.run([sys.executable, "-m", "bench.robots", name, str(n)], capture_output=True, text=True,
                          timeout=900, cwd=root, env=_env(cache))
    lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("{")]
    if proc.returncode != 0 or not lines:
        tail = (proc.stderr.strip().splitlines() or ["no output"])[-1]
        return {"name": name, "error": tail[:120]}
    return {**json.loads(lines[-1]), "first_s": t_first[-1] if t_first else float("nan")}


def run(quick: bool) -> str:
    import shutil
    import tempfile

    n = 50 if quick else 300
    rows = ["| robot | nq | load first | load cold | load warm | peak RSS | SRDF | pairs (no SRDF) | colliding / "
            "disagree (of N) | max \\|Δd\\| apart | depths off > 1 mm | analytic | coal | coal / analytic "
            "| coal's C++ core | core / analytic "
            "| along a path: analytic | analytic, `warm_start` | coal | coal / analytic (`warm_start`) | disagree (path) |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    cache = tempfile.mkdtemp(prefix="armguard-bench-cache-")
    try:
        results = []
        for name in _names():
            results.append(_run_one(name, n, cache))
            print(f"  {name}: {results[-1]}", file=sys.stderr, flush=True)
    finally:
        shutil.rmtree(cache, ignore_errors=True)
    for r in results:
        name = r["name"]
        if "error" in r:
            rows.append(f"| {name} | — | error: {r['error']} ||||||||||")
            continue
        rows.append(
            f"| {name} | {r['nq']} | {r['first_s']:.2f} s | {r['cold_s']:.2f} s | {r['warm_s']:.2f} s "
            f"| {r['rss_peak_mb']:.0f} MB "
            f"| {r['srdf'] or '—'} | {r['pairs']} ({r['pairs_no_srdf']}) | {r['colliding']} / {r['disagree']} "
            f"| {r['max_dd']:.1e} m | {r['depths_off']} of {r['depths']}"
            + (f" (coal < -1 m: {r['coal_depth_max']})" if r['coal_depth_max'] else "")
            + (f"; reference ({r['ref_checked']} checked): analytic off ≤ {r['ref_err_analytic']:.0e} m, coal "
               f"≤ {r['ref_err_coal']:.0e} m" if r.get("ref_checked") else "")
            + f" | {r['us_analytic']:.1f} µs | {r['us_coal']:.1f} µs "
            f"| {r['us_coal'] / r['us_analytic']:.1f}× "
            f"| {r['us_coal_core']:.1f} µs | {r['us_coal_core'] / r['us_analytic']:.1f}× "
            f"| {r['us_path_analytic']:.1f} µs | {r['us_path_warm']:.1f} µs | {r['us_path_coal']:.1f} µs "
            f"| {r['us_path_coal'] / r['us_path_analytic']:.1f}× ({r['us_path_coal'] / r['us_path_warm']:.1f}×) "
            f"| {r['path_disagree']} of {r['path_n']} |")
    note = (f"\n\nN = {n} random in-limit configurations per robot (seeded). Each robot runs in its own process "
            "with numba's kernel cache already compiled (`make run` or one earlier bench). *load first* is the very "
            "first `load_model` of the robot (an empty hull cache: every mesh read and hulled, in an earlier "
            "process); *load cold* is a user's next first `load_model` in a new process (hulls read from the hull "
            "cache, `docs/models.md`), *load warm* a second one in the same process; *peak RSS* includes Python, "
            "numpy, Pinocchio, coal and the compiled kernels. *analytic*, *coal*: `pair_distances(q)` over the N "
            "configurations, thread CPU time, median of 7 runs, the two backends' runs interleaved; *coal* is coal "
            "through armguard's coal Checker from Python: Pinocchio's `computeDistances` (every pair's distance and "
            "witness points, in C++) and then reading each pair's result through Pinocchio's Python bindings (about "
            "2 µs a pair, most of the coal figure); *coal's C++ core* is that `computeDistances` call alone, the "
            "results left unread (what a C++ caller of coal pays; the analytic figure includes its Python call and "
            "its arrays). *along a path*: "
            f"the same, over configurations in order along straight joint-space segments between 9 random waypoints, "
            f"no joint moving more than {PATH_STEP} rad (m) a step (a planner's edge check), {n} calls a run; with the "
            "option `warm_start` the analytic backend starts each pair's GJK from the simplex it ended with at the "
            "previous configuration (answers the same to `gjk_epsilon`, their last bits then depending on the "
            "previous call: off by default); coal runs as its reference (no guess carried over, `plugins/armguard_coal`); "
            "*disagree (path)*: configurations of the path where the warm-started verdict differs from coal's. "
            "*colliding*: configurations coal finds in contact; "
            "*disagree*: configurations where the analytic verdict differs from coal's. *max |Δd| apart*: over "
            "pairs both backends find apart. *depths off*: pairs in contact (for either backend) whose penetration "
            "depths differ by more than 1 mm, of all pairs in contact; up to 3 of them a robot are checked against the slow "
            "support-function reference (`armguard.geometry._support_reference`: no GJK, no EPA), with each side's "
            "largest error. coal's depth comes from EPA, which is not exact on cylinders (panda_collision's "
            "cylinders and spheres: the *depths off* column gives each side's error against the reference; "
            "`bench/robots.py`).")
    return "\n".join(rows) + note


if __name__ == "__main__":
    print(json.dumps(measure(sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 300)))
