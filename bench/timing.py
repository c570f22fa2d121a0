"""Small timing helpers shared by the benchmarks: medians of repeated runs."""

from __future__ import annotations

import statistics
import time
from typing import Callable


def median_seconds(fn: Callable[[], object], *, repeat: int = 7, number: int = 1) -> float:
    """Median over ``repeat`` runs of the time per call of ``fn`` (called ``number`` times per run)."""
    fn()  # warm-up (JIT compilation, caches)
    samples = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        samples.append((time.perf_counter() - t0) / number)
    return statistics.median(samples)


def median_thread_seconds(fn: Callable[[], object], *, repeat: int = 7, number: int = 1) -> float:
    """Median over ``repeat`` runs of the thread CPU time (``time.thread_time``) per call of ``fn``
    (``number`` calls a run): what one core spends, less sensitive to a shared machine's load."""
    fn()  # warm-up (JIT compilation, caches)
    samples = []
    for _ in range(repeat):
        t0 = time.thread_time()
        for _ in range(number):
            fn()
        samples.append((time.thread_time() - t0) / number)
    return statistics.median(samples)


def interleaved_thread_seconds(fns: dict[str, Callable[[], object]], *, repeat: int = 7,
                               number: int = 1, reduce: Callable = statistics.median) -> dict[str, float]:
    """:func:`median_thread_seconds` of each of ``fns`` (name -> call), their runs interleaved (run
    ``r`` of every call, then run ``r + 1``): a spell of load on a shared machine lands on all of
    them, not on whichever was being timed then, so their ratios hold where each time alone moves.
    ``reduce=min``: the best run of each instead (``timeit``'s advice for a cost of the code itself:
    the slower runs measure the machine's other load)."""
    for fn in fns.values():
        fn()  # warm-up (JIT compilation, caches)
    samples: dict[str, list[float]] = {k: [] for k in fns}
    for _ in range(repeat):
        for k, fn in fns.items():
            t0 = time.thread_time()
            for _ in range(number):
                fn()
            samples[k].append((time.thread_time() - t0) / number)
    return {k: reduce(v) for k, v in samples.items()}


def fmt_ns(seconds: float) -> str:
    """Format a duration given in seconds as ns / µs / ms."""
    ns = seconds * 1e9
    if ns < 1e3:
        return f"{ns:.0f} ns"
    if ns < 1e6:
        return f"{ns / 1e3:.2f} µs"
    return f"{ns / 1e6:.2f} ms"


def json_of_process(args: list, *, cwd: str, env: dict | None = None, timeout: float = 900) -> dict:
    """Run ``args`` (a benchmark's measuring process) and return the last JSON line it printed, or
    ``{"error": <its stderr's last line>}`` when it failed or printed none."""
    import json
    import subprocess

    proc = subprocess.run(args, capture_output=True, text=True, cwd=cwd, env=env, timeout=timeout)
    lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("{")]
    if proc.returncode != 0 or not lines:
        return {"error": ((proc.stderr.strip().splitlines() or ["no output"])[-1])[:120]}
    return json.loads(lines[-1])
