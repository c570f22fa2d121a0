"""The public-robot table: every arm of example-robot-data and pybullet_data, as a new user meets it.

Each robot is measured in a fresh process (``python -m bench.robots NAME [N]`` prints one JSON
line), after one earlier process loaded it (so Python's bytecode and numba's kernel caches are on
disk, as after a user's first run); load times and peak memory are those of a user's next session:

* **load cold / warm**: ``armguard.load_model(name)`` the first time in the process (URDF parse,
  meshes read and hulled, SRDF read; numba's kernel cache already on disk) and a second time;
* **peak RSS**: the process's peak resident memory after loading, building both checkers and
  checking (everything imported);
* **pairs**: active pairs with the SRDF found for it, and without any SRDF (``srdf=False``);
* **agreement**: on ``N`` random in-limit configurations, verdicts (distance ≤ 0) where analytic and
  coal differ, and the largest ``|d_analytic − d_coal|``;
* **µs / configuration**: ``checker.pair_distances(q)`` (every pair's signed distance and witness
  points) for analytic and coal, median of 5 runs.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

TITLE = "Public robots: load, memory, SRDF pairs, agreement and speed against coal"


def _names() -> list[str]:
    from armguard.model import known_models

    return [m.name for m in known_models() if m.source != "built-in" and m.available]


def measure(name: str, n: int) -> dict:
    """One robot's row (see the module docstring); run in a fresh process."""
    import resource

    import numpy as np

    import armguard

    from .timing import median_seconds

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
    it = iter(range(10**9))
    t_a = median_seconds(lambda: ana.pair_distances(Q[next(it) % n]), repeat=5, number=max(1, n // 5))
    t_c = median_seconds(lambda: ref.pair_distances(Q[next(it) % n]), repeat=5, number=max(1, n // 5))
    return {
        "name": name, "nq": int(model.nq), "cold_s": cold, "warm_s": warm,
        "rss_load_mb": rss_load, "rss_peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
        "pairs": len(model.pairs), "pairs_no_srdf": len(bare.pairs), "srdf": os.path.basename(srdf) if srdf else None,
        "n": n, "colliding": int(verdict_c.sum()), "disagree": int((verdict_a != verdict_c).sum()),
        "max_dd": float(np.max(np.abs(d_a - d_c), initial=0.0)),
        "us_analytic": t_a * 1e6, "us_coal": t_c * 1e6,
    }


def _env() -> dict:
    """The environment of a user's process: Python writes its bytecode caches (a shell that sets
    PYTHONDONTWRITEBYTECODE would make every first import compile its sources, seconds per process)."""
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    return env


def _run_one(name: str, n: int) -> dict:
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    # a first process writes the bytecode and kernel caches a user's earlier runs would have written
    subprocess.run([sys.executable, "-c", f"import armguard; armguard.load_model({name!r})"], capture_output=True,
                   timeout=900, cwd=root, env=_env())
    proc = subprocess.run([sys.executable, "-m", "bench.robots", name, str(n)], capture_output=True, text=True,
                          timeout=900, cwd=root, env=_env())
    lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("{")]
    if proc.returncode != 0 or not lines:
        tail = (proc.stderr.strip().splitlines() or ["no output"])[-1]
        return {"name": name, "error": tail[:120]}
    return json.loads(lines[-1])


def run(quick: bool) -> str:
    n = 50 if quick else 300
    rows = ["| robot | nq | load cold | load warm | peak RSS | SRDF | pairs (no SRDF) | colliding / disagree "
            "(of N) | max \\|Δd\\| | analytic | coal | coal / analytic |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for name in _names():
        r = _run_one(name, n)
        print(f"  {name}: {r}", file=sys.stderr, flush=True)
        if "error" in r:
            rows.append(f"| {name} | — | error: {r['error']} |||||||||")
            continue
        rows.append(
            f"| {name} | {r['nq']} | {r['cold_s']:.2f} s | {r['warm_s']:.2f} s | {r['rss_peak_mb']:.0f} MB "
            f"| {r['srdf'] or '—'} | {r['pairs']} ({r['pairs_no_srdf']}) | {r['colliding']} / {r['disagree']} "
            f"| {r['max_dd']:.1e} m | {r['us_analytic']:.1f} µs | {r['us_coal']:.1f} µs "
            f"| {r['us_coal'] / r['us_analytic']:.1f}× |")
    note = (f"\n\nN = {n} random in-limit configurations per robot (seeded). Each robot runs in its own process "
            "with numba's kernel cache already compiled (`make run` or one earlier bench), so *load cold* is a "
            "user's first `load_model` in a new process and *peak RSS* includes Python, numpy, Pinocchio, coal "
            "and the compiled kernels. *colliding*: configurations coal finds in contact; *disagree*: "
            "configurations where the analytic verdict differs from coal's.")
    return "\n".join(rows) + note


if __name__ == "__main__":
    print(json.dumps(measure(sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 300)))
