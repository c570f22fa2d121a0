"""Every backend on the same configurations: distances, witness points, verdicts and timings.

Serially, or on Dask (a fresh ``LocalCluster(n_workers=N, threads_per_worker=1)`` or an existing
scheduler): the configurations are cut into chunks; each worker loads the model and builds its
checkers once (a per-process cache keyed by the model spec, backends and options), and answers
its chunks.  The answers do not depend on where they were computed.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass

import numpy as np

from .._errors import ArmguardError

__all__ = ["BackendAnswers", "evaluate", "build_checkers", "parse_backend_options"]

_CACHE: dict = {}


@dataclass
class BackendAnswers:
    """One backend's answers at every configuration of a ConfigSet.

    distance : (M, n) float64, m — signed, every active pair (``model.pairs`` order)
    p_WA, p_WB : (M, n, 3) float64, m — witness points in W
    verdict : (M,) bool — ``collides(Q)`` (the backend's own yes/no batch path)
    t_distances, t_verdicts : float, s — time spent in ``pair_distances`` / ``collides``, summed over chunks
    """

    distance: np.ndarray
    p_WA: np.ndarray
    p_WB: np.ndarray
    verdict: np.ndarray
    t_distances: float
    t_verdicts: float

    @property
    def us_per_config(self) -> float:
        """µs per configuration for every pair's distance and witness points."""
        return self.t_distances / max(1, len(self.verdict)) * 1e6

    @property
    def yes_no_per_s(self) -> float:
        """Configurations per second of ``collides(Q)``."""
        return len(self.verdict) / self.t_verdicts if self.t_verdicts > 0 else math.inf


def _scalar(text: str):
    """``"1"`` -> 1, ``"1e-9"`` -> 1e-9, ``"true"``/``"false"`` -> bool, anything else the string itself."""
    low = text.strip().lower()
    if low in ("true", "false"):
        return low == "true"
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def parse_backend_options(items) -> dict:
    """``["analytic.fidelity=paper", "coal.threads=1"]`` -> ``{"analytic": {"fidelity": "paper"}, "coal": {"threads": 1}}``.

    Values are numbers (int, then float), ``true``/``false``, or else strings.
    """
    out: dict = {}
    for item in items or ():
        key, sep, value = str(item).partition("=")
        backend, dot, opt = key.partition(".")
        if not sep or not dot or not backend or not opt:
            raise ArmguardError(f"--backend-option {item!r}: expected BACKEND.KEY=VALUE (e.g. analytic.fidelity=paper)")
        out.setdefault(backend.strip(), {})[opt.strip()] = _scalar(value)
    return out


def build_checkers(model, backends, options=None) -> dict:
    """``{backend: Checker}``, each warmed up (kernels compiled, batch pools built) so that timings are steady."""
    import armguard

    options = options or {}
    out = {}
    warm = np.concatenate([model.neutral()[None], model.random_q(64, 0)])
    for b in backends:
        c = armguard.checker(model, b, dict(options.get(b, {})))
        c.pair_distances(warm[0])
        c.collides(warm)
        out[b] = c
    return out


def _cached(spec: str, backends: tuple, options_json: str):
    key = (spec, backends, options_json)
    if key not in _CACHE:
        from ._models import resolve_model

        _CACHE.clear()  # one model per worker process at a time
        model = resolve_model(spec)
        _CACHE[key] = (model, build_checkers(model, backends, json.loads(options_json)))
    return _CACHE[key]


def _answer_chunk(model, checkers: dict, Q: np.ndarray) -> dict:
    """``{backend: (d (m, n), p_WA (m, n, 3), p_WB, verdict (m,), t_distances, t_verdicts)}`` for rows ``Q``."""
    n = len(model.pairs)
    m = len(Q)
    out = {}
    for b, c in checkers.items():
        d = np.empty((m, n))
        pa = np.empty((m, n, 3))
        pb = np.empty((m, n, 3))
        pd = c.pair_distances
        t0 = time.perf_counter()
        for i in range(m):
            r = pd(Q[i])
            d[i], pa[i], pb[i] = r.distance, r.p_WA, r.p_WB
        t1 = time.perf_counter()
        v = np.asarray(c.collides(Q), dtype=bool)
        t2 = time.perf_counter()
        out[b] = (d, pa, pb, v, t1 - t0, t2 - t1)
    return out


def _chunk_task(spec, backends, options_json, Q):
    model, checkers = _cached(spec, tuple(backends), options_json)
    return _answer_chunk(model, checkers, Q)


def _merge(parts: list, backends) -> dict:
    out = {}
    for b in backends:
        rows = [p[b] for p in parts]
        out[b] = BackendAnswers(np.concatenate([r[0] for r in rows]), np.concatenate([r[1] for r in rows]),
                                np.concatenate([r[2] for r in rows]), np.concatenate([r[3] for r in rows]),
                                float(sum(r[4] for r in rows)), float(sum(r[5] for r in rows)))
    return out


def evaluate(model, Q, backends, options=None, *, spec: str | None = None, workers: int | None = None,
             scheduler: str | None = None, chunk_size: int | None = None, progress=None, checkers=None) -> dict:
    """``{backend: BackendAnswers}`` at every row of ``Q`` ``(M, nq)``.

    Serially by default (``checkers``: prebuilt ones to reuse); with ``workers`` (a fresh Dask
    LocalCluster of that many single-threaded processes) or ``scheduler`` (an address), on Dask;
    the workers load the model from ``spec`` (what :func:`resolve_model` takes).  ``progress``:
    ``callable(done, total)`` after each chunk.
    """
    backends = tuple(backends)
    Q = np.ascontiguousarray(np.asarray(Q, dtype=np.float64))
    M = len(Q)
    options = options or {}
    if workers and scheduler:
        raise ArmguardError("give workers (a new LocalCluster) or scheduler (an existing cluster), not both")
    if not workers and not scheduler:
        checkers = checkers or build_checkers(model, backends, options)
        size = chunk_size or 256
        parts = []
        for s in range(0, M, size):
            parts.append(_answer_chunk(model, checkers, Q[s:s + size]))
            if progress is not None:
                progress(min(M, s + size), M)
        return _merge(parts, backends) if parts else _merge([_answer_chunk(model, checkers, Q)], backends)
    if spec is None:
        raise ArmguardError("evaluating on Dask needs the model's spec (a name or a file path the workers can load)")
    return _on_dask(str(spec), Q, backends, options, workers, scheduler, chunk_size, progress)


def _on_dask(spec, Q, backends, options, workers, scheduler, chunk_size, progress) -> dict:
    from distributed import Client, LocalCluster, as_completed

    cluster = None
    if scheduler is None:
        cluster = LocalCluster(n_workers=int(workers), processes=True, threads_per_worker=1, dashboard_address=None)
        client = Client(cluster)
    else:
        try:
            client = Client(scheduler, timeout="20s")
        except (OSError, TimeoutError) as exc:
            raise ArmguardError(f"cannot reach the Dask scheduler at {scheduler!r}: {exc}") from exc
    try:
        n_workers = max(1, len(client.scheduler_info().get("workers", {})) or int(workers or 1))
        M = len(Q)
        size = chunk_size or max(1, math.ceil(M / (4 * n_workers)))
        starts = list(range(0, M, size)) or [0]
        opts = json.dumps(options, sort_keys=True)
        futures = {client.submit(_chunk_task, spec, backends, opts, Q[s:s + size], pure=False): k
                   for k, s in enumerate(starts)}
        parts: list = [None] * len(starts)
        done = 0
        for fut in as_completed(list(futures)):
            k = futures[fut]
            parts[k] = fut.result()
            done += len(Q[starts[k]:starts[k] + size])
            if progress is not None:
                progress(done, M)
        return _merge(parts, backends)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
