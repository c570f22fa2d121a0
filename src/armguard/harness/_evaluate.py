"""Every backend on the same configurations: distances, witness points, verdicts and timings.

Serially, or on Dask (a fresh ``LocalCluster(n_workers=N, threads_per_worker=1)`` or an existing
scheduler): the configurations are cut into chunks; each worker loads the model and builds its
checkers once (a per-process cache keyed by the model spec, backends and options), and answers
its chunks.  The answers do not depend on where they were computed.

Every answer is checked where the harness receives it (after the timed calls): a distance or witness
point that is NaN or infinite, an array of another shape or type, verdict codes other than CLEAR /
COLLISION / UNDECIDED are a :class:`~armguard.BackendError` naming the backend, the configuration
(``#k``) and its ``q`` (and the pair), not a comparison of a wrong answer nor a crash further on.
"""

from __future__ import annotations

import json
import math
import time
import uuid
from dataclasses import dataclass

import numpy as np

from .._errors import ArmguardError, BackendError
from ..backends import option_value

__all__ = ["BackendAnswers", "evaluate", "build_checkers", "parse_backend_options", "answers_distances", "verdict_detail",
           "combine_codes", "checked_distances", "check_finite", "checked_verdicts", "CLEAR", "COLLISION", "UNDECIDED"]

_CACHE: dict = {}


@dataclass
class BackendAnswers:
    """One backend's answers at every configuration of a ConfigSet.

    distance : (M, n) float64, m — signed, every active pair (``model.pairs`` order); None for a
        verdicts-only backend (no ``Capability.DISTANCES``)
    p_WA, p_WB : (M, n, 3) float64, m — witness points in W; None for a verdicts-only backend
    verdict : (M,) bool — ``collides(Q)`` (the backend's own yes/no batch path)
    t_distances, t_verdicts : float, s — time spent in ``pair_distances`` / ``collides``, summed over chunks
    verdicts_only : bool — the backend answers verdicts only (the fields below describe them)
    codes : (M,) int8 or None — the backend's three-valued verdict where it has one (:data:`CLEAR`,
        :data:`COLLISION`, :data:`UNDECIDED`: clip's MAYBE, forbidden's MAP_FORBIDDEN)
    codes_first : (M,) int8 or None — the same before a second level (clip: the 8 steps alone)
    pair_codes, pair_codes_first : (M, n) int8 or None — per active pair (clip's ``check_pairs``)
    map_forbidden : (M,) bool or None — forbidden: the map refused joints 1–3 (``MAP_FORBIDDEN``)
    t_detail : float, s — time spent in the three-valued query (not part of the yes/no rate)
    """

    distance: np.ndarray | None
    p_WA: np.ndarray | None
    p_WB: np.ndarray | None
    verdict: np.ndarray
    t_distances: float
    t_verdicts: float
    verdicts_only: bool = False
    codes: np.ndarray | None = None
    codes_first: np.ndarray | None = None
    pair_codes: np.ndarray | None = None
    pair_codes_first: np.ndarray | None = None
    map_forbidden: np.ndarray | None = None
    t_detail: float = 0.0

    @property
    def us_per_config(self) -> float:
        """µs per configuration for every pair's distance and witness points; for a verdicts-only
        backend, of its ``collides(Q)`` batch (its only answer)."""
        t = self.t_verdicts if self.verdicts_only else self.t_distances
        return t / max(1, len(self.verdict)) * 1e6

    @property
    def yes_no_per_s(self) -> float:
        """Configurations per second of ``collides(Q)``."""
        return len(self.verdict) / self.t_verdicts if self.t_verdicts > 0 else math.inf


CLEAR, COLLISION, UNDECIDED = 0, 1, 2
"""Three-valued verdict codes: proven clear, definite collision, undecided (counted as a collision
by ``collides``): clip's CLEAR / INTERSECTED / MAYBE, forbidden's FREE / COLLISION / MAP_FORBIDDEN."""

_NAMES = {"CLEAR": CLEAR, "FREE": CLEAR, "INTERSECTED": COLLISION, "COLLISION": COLLISION, "MAYBE": UNDECIDED,
          "MAP_FORBIDDEN": UNDECIDED}


def answers_distances(checker) -> bool:
    """Whether ``checker`` declares ``Capability.DISTANCES`` (a Checker without ``capabilities`` is taken to)."""
    from ..backends import Capability

    caps = getattr(checker, "capabilities", None)
    return caps is None or Capability.DISTANCES in caps


def _codes_of(values) -> np.ndarray:
    """``(M,) int8`` codes from an array of enum members (by name: ClipStatus, CombinedStatus) or names."""
    out = np.empty(len(values), dtype=np.int8)
    for i, v in enumerate(values):
        name = str(getattr(v, "name", v)).upper()
        if name not in _NAMES:
            raise ArmguardError(f"three-valued verdict {v!r}: expected one of {sorted(_NAMES)}")
        out[i] = _NAMES[name]
    return out


class AnswerContractError(BackendError):
    """An answer of another shape or type than the interface's: the backend is broken, and a comparison
    stops at it (a refusal or a non-finite value at one configuration leaves that one out instead)."""


def verdict_detail(checker, Q, *, backend: str | None = None, where: str | None = None) -> dict:
    """A verdicts-only backend's three-valued answers at ``Q`` ``(m, nq)``, where it exposes them.

    ``check_pairs(Q, subdivide=True)`` (clip: per-pair codes after the 8 steps and with the second
    level) or ``verdicts(Q)`` (forbidden: a batch with ``status`` codes; or an array of statuses);
    ``{}`` for a backend with neither.  Keys: ``codes``, and ``codes_first``, ``pair_codes``,
    ``pair_codes_first`` (``check_pairs``) or ``map_forbidden`` (a CombinedBatch); see :class:`BackendAnswers`.
    Codes of another shape than ``(m, n)`` / ``(m,)``, or other than CLEAR, COLLISION, UNDECIDED, are a
    BackendError naming ``backend`` (default: the checker's name) and ``where`` (the configurations).
    """
    backend = backend or str(getattr(checker, "name", type(checker).__name__))
    where = where or f"{len(Q)} configurations"
    model = getattr(checker, "model", None)
    n = len(model.pairs) if model is not None and hasattr(model, "pairs") else None
    if hasattr(checker, "check_pairs"):
        try:
            b = checker.check_pairs(Q, subdivide=True)
        except TypeError:
            b = checker.check_pairs(Q)
        pc = _codes_array(backend, "pair_codes", getattr(b, "pair_codes", None), (len(Q), n), where)
        first = pc if getattr(b, "pair_codes_8", None) is None else \
            _codes_array(backend, "pair_codes_8", b.pair_codes_8, (len(Q), n), where)
        return {"codes": combine_codes(pc, len(Q)), "codes_first": combine_codes(first, len(Q)), "pair_codes": pc,
                "pair_codes_first": first}
    if not hasattr(checker, "verdicts"):
        return {}
    v = checker.verdicts(Q)
    status = np.asarray(getattr(v, "status", v), dtype=object)
    if status.shape != (len(Q),):
        raise AnswerContractError(f"backend {backend!r} answered verdicts of shape {status.shape} at {where}, expected ({len(Q)},)")
    try:
        if hasattr(v, "collision"):  # armguard.cspace.CombinedBatch: int codes of CombinedStatus
            from ..cspace import CombinedStatus

            status = np.asarray([CombinedStatus(int(s)) for s in status], dtype=object)
        codes = _codes_of(status)
    except (ValueError, TypeError, ArmguardError) as exc:  # a code or name that is no verdict
        raise AnswerContractError(f"backend {backend!r} answered a verdict that is none at {where}: {exc}") from None
    out = {"codes": codes}
    if hasattr(v, "collision"):
        out["map_forbidden"] = codes == UNDECIDED
    return out


def _codes_array(backend: str, what: str, a, shape: tuple, where: str) -> np.ndarray:
    """``a`` as ``int8`` codes CLEAR / COLLISION / UNDECIDED of ``shape`` (``(m, None)``: any pair count),
    else the BackendError of ``backend``'s answer ``what``."""
    try:
        arr = np.asarray(a)
    except (TypeError, ValueError):
        arr = np.asarray(None)
    if arr.dtype == bool or not np.issubdtype(arr.dtype, np.integer):
        raise AnswerContractError(f"backend {backend!r} answered {what} of "
                           f"{type(a).__name__ if a is None else f'dtype {arr.dtype}'} at {where}, expected integer codes")
    if arr.ndim != 2 or any(want is not None and got != want for got, want in zip(arr.shape, shape)):
        raise AnswerContractError(f"backend {backend!r} answered {what} of shape {arr.shape} at {where}, expected "
                           f"{tuple('n' if x is None else x for x in shape)}")
    ok = (arr == CLEAR) | (arr == COLLISION) | (arr == UNDECIDED)
    if not ok.all():
        bad = sorted({int(x) for x in arr[~ok]})[:5]
        raise AnswerContractError(f"backend {backend!r} answered {what} codes {bad} at {where}, expected {CLEAR} (clear), "
                           f"{COLLISION} (collision) or {UNDECIDED} (undecided)")
    return arr.astype(np.int8, copy=False)


def combine_codes(pair_codes: np.ndarray, m: int | None = None) -> np.ndarray:
    """``(M, k) int8 -> (M,) int8``: COLLISION if any pair is, else UNDECIDED if any is, else CLEAR."""
    if pair_codes.shape[1] == 0:
        return np.zeros(len(pair_codes) if m is None else m, dtype=np.int8)
    hit = np.any(pair_codes == COLLISION, axis=1)
    und = np.any(pair_codes == UNDECIDED, axis=1)
    return np.where(hit, COLLISION, np.where(und, UNDECIDED, CLEAR)).astype(np.int8)


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
        out.setdefault(backend.strip(), {})[opt.strip()] = option_value(value)
    return out


def build_checkers(model, backends, options=None) -> dict:
    """``{backend: Checker}``, each warmed up (kernels compiled, batch pools built) so that timings are steady."""
    from ..backends import checker

    options = options or {}
    out = {}
    warm = np.concatenate([model.neutral()[None], model.random_q(64, 0)])
    for b in backends:
        c = checker(model, b, dict(options.get(b, {})))
        if answers_distances(c):
            c.pair_distances(warm[0])
        else:
            verdict_detail(c, warm, backend=b, where=f"the {len(warm)} warm-up configurations (the neutral q, then "
                                                       "model.random_q(64, seed=0))")
        c.collides(warm)
        out[b] = c
    return out


def rows_of(start: int, m: int) -> str:
    """Configurations ``#start`` .. ``#start + m - 1`` of the comparison, in words."""
    return f"configuration #{start}" if m == 1 else f"configurations #{start}..#{start + m - 1}"


def where_of(config, q) -> str:
    """The configuration a backend answered for: ``#k`` of the comparison's, or (None) the one given."""
    at = "the configuration given" if config is None else f"configuration #{config}"
    return f"{at} (q = {[float(v) for v in np.asarray(q).ravel()]})"


def _real_array(backend: str, what: str, a, shape: tuple, config, q) -> np.ndarray:
    """``a`` (an array of ``shape`` and a real number dtype) as float64, else the BackendError of
    ``backend``'s answer ``what`` at ``q`` (configuration ``#config``; None: the one given)."""
    if type(a) is np.ndarray and a.dtype == np.float64 and a.shape == shape:  # every backend's answer
        return a
    try:
        arr = np.asarray(a)
    except (TypeError, ValueError):
        arr = None
    if arr is None or arr.dtype == bool or not (np.issubdtype(arr.dtype, np.floating) or np.issubdtype(arr.dtype, np.integer)):
        kind = type(a).__name__ if arr is None else f"dtype {arr.dtype}"
        raise AnswerContractError(f"backend {backend!r} answered {what} of {kind} at {where_of(config, q)}, expected real "
                           "numbers (float64)")
    if arr.shape != shape:
        raise AnswerContractError(f"backend {backend!r} answered {what} of shape {arr.shape} at {where_of(config, q)}, "
                           f"expected {shape}")
    return arr.astype(np.float64, copy=False)


def checked_distances(backend: str, r, n: int, config, q) -> tuple:
    """``(distance (n,), p_WA (n, 3), p_WB (n, 3))`` of backend ``backend``'s ``pair_distances`` answer ``r``
    at ``q`` (configuration ``#config``; None: the one given), else a BackendError naming the backend,
    the configuration and what is wrong: no PairDistances, an array of another shape or not of real
    numbers.  Finiteness: :func:`check_finite` (one pass over a whole chunk)."""
    try:
        d, pa, pb = r.distance, r.p_WA, r.p_WB
    except AttributeError:
        raise AnswerContractError(f"backend {backend!r} answered pair_distances with {type(r).__name__} at "
                           f"{where_of(config, q)}, expected a PairDistances (distance, p_WA, p_WB)") from None
    return (_real_array(backend, "distance", d, (n,), config, q), _real_array(backend, "p_WA", pa, (n, 3), config, q),
            _real_array(backend, "p_WB", pb, (n, 3), config, q))


def check_finite(backend: str, model, d, pa, pb, Q, start) -> None:
    """A BackendError naming ``backend``, the configuration, ``q`` and the pair at the first NaN or
    infinite distance or witness point of ``d`` ``(m, n)``, ``pa``, ``pb`` ``(m, n, 3)`` at rows ``Q``
    (configurations ``start + i``; ``start`` None: the one given)."""
    for what, a in (("distance", d), ("witness point p_WA", pa), ("witness point p_WB", pb)):
        bad = ~np.isfinite(a)
        if not bad.any():
            continue
        i, k = (int(x) for x in np.argwhere(bad)[0][:2])
        names = model.pairs.names
        value = a[i, k]
        shown = str(float(value)).replace("nan", "NaN") if a.ndim == 2 else str([float(v) for v in value])
        raise BackendError(f"backend {backend!r} answered {what} {shown} at "
                           f"{where_of(None if start is None else start + i, Q[i])} for pair "
                           f"({str(names[k, 0])!r}, {str(names[k, 1])!r}), expected finite values (m)")


def checked_verdicts(backend: str, v, Q, start) -> np.ndarray:
    """``(m,) bool``: backend ``backend``'s ``collides(Q)`` answer ``v`` for rows ``Q`` (configurations
    ``start``..; None: the one given), else a BackendError naming the backend and the configurations."""
    m = len(Q)
    where = where_of(None, Q[0]) if start is None else rows_of(start, m)
    try:
        arr = np.asarray(v)
    except (TypeError, ValueError):
        arr = None
    if arr is None or arr.dtype != bool:
        kind = type(v).__name__ if arr is None else f"dtype {arr.dtype}"
        raise AnswerContractError(f"backend {backend!r} answered collides of {kind} at {where}, expected bool")
    if arr.shape != (m,):
        raise AnswerContractError(f"backend {backend!r} answered collides of shape {arr.shape} at {where}, expected ({m},)")
    return arr


def _cached(spec: str, backends: tuple, options_json: str, token: str = ""):
    """The worker's model and checkers for one :func:`evaluate` call (``token``: a cluster that stays
    up loads the model again for the next call, so a file edited between calls is read as edited)."""
    key = (spec, backends, options_json, token)
    got = _CACHE.get(key)
    if got is None:
        from ._models import resolve_model

        model = resolve_model(spec)
        got = (model, build_checkers(model, backends, json.loads(options_json)))
        _CACHE.clear()  # one model per worker process at a time
        _CACHE[key] = got
    return got


def _answer_chunk(model, checkers: dict, Q: np.ndarray, start: int = 0) -> dict:
    """``{backend: {field: value}}`` for rows ``Q`` (configurations ``start``..): the :class:`BackendAnswers`
    fields of this chunk.  Each answer is checked at the boundary, after the timed calls: an answer of
    another shape or type, or a NaN or infinite distance or witness point, is a BackendError naming
    the backend, the configuration and ``q`` (and the pair), never a comparison of it."""
    n = len(model.pairs)
    m = len(Q)
    out = {}
    for b, c in checkers.items():
        rec = {}
        if answers_distances(c):
            d = np.empty((m, n))
            pa = np.empty((m, n, 3))
            pb = np.empty((m, n, 3))
            pd = c.pair_distances
            rs = []  # the answers, for their shapes (a backend may answer views of its scratch: values copied here)
            t0 = time.perf_counter()
            try:
                for i in range(m):
                    r = pd(Q[i])
                    rs.append(r)
                    d[i], pa[i], pb[i] = r.distance, r.p_WA, r.p_WB
            except (AttributeError, TypeError, ValueError):  # not a PairDistances, or arrays that do not fit
                if len(rs) == i + 1:
                    checked_distances(b, rs[i], n, start + i, Q[i])
                raise
            rec["t_distances"] = time.perf_counter() - t0
            for i, r in enumerate(rs):  # a (1,) distance or (3,) point broadcast into the rows unnoticed
                checked_distances(b, r, n, start + i, Q[i])
            check_finite(b, model, d, pa, pb, Q, start)
            rec.update(distance=d, p_WA=pa, p_WB=pb)
        else:
            t0 = time.perf_counter()
            rec.update(verdict_detail(c, Q, backend=b, where=rows_of(start, m)),
                       verdicts_only=True, t_distances=0.0)
            rec["t_detail"] = time.perf_counter() - t0
        t1 = time.perf_counter()
        v = c.collides(Q)
        rec["t_verdicts"] = time.perf_counter() - t1
        rec["verdict"] = checked_verdicts(b, v, Q, start)
        out[b] = rec
    return out


def _chunk_task(spec, backends, options_json, Q, start=0, token="", keep_going=False):
    model, checkers = _cached(spec, tuple(backends), options_json, token)
    if keep_going:
        return _answer_rows(model, checkers, Q, start)
    return _answer_chunk(model, checkers, Q, start)


def _answer_rows(model, checkers: dict, Q: np.ndarray, start: int) -> tuple:
    """``(parts, refused)``: :func:`_answer_chunk`'s answers for the rows a backend answers, and for each row
    one refused (a BackendError: a NaN answer, a configuration the backend refuses), ``{"config", "q",
    "message"}``.  The chunk at once; after a refusal, row by row (the other rows' answers are kept).  An
    :class:`AnswerContractError` (a broken backend) raises."""
    try:
        return [_answer_chunk(model, checkers, Q, start)], []
    except AnswerContractError:
        raise
    except BackendError:
        pass
    parts, refused = [], []
    for i in range(len(Q)):
        try:
            parts.append(_answer_chunk(model, checkers, Q[i:i + 1], start + i))
        except AnswerContractError:
            raise
        except BackendError as exc:
            refused.append({"config": start + i, "q": Q[i].tolist(), "message": str(exc)})
    return parts, refused


_ARRAYS = ("distance", "p_WA", "p_WB", "verdict", "codes", "codes_first", "pair_codes", "pair_codes_first",
           "map_forbidden")
_TIMES = ("t_distances", "t_verdicts", "t_detail")


def _merge(parts: list, backends) -> dict:
    out = {}
    for b in backends:
        rows = [p[b] for p in parts]
        kw = {k: (np.concatenate([r[k] for r in rows]) if k in rows[0] else None) for k in _ARRAYS}
        kw.update({k: float(sum(r.get(k, 0.0) for r in rows)) for k in _TIMES})
        out[b] = BackendAnswers(verdicts_only=bool(rows[0].get("verdicts_only", False)), **kw)
    return out


def evaluate(model, Q, backends, options=None, *, spec: str | None = None, workers: int | None = None,
             scheduler: str | None = None, chunk_size: int | None = None, progress=None, checkers=None,
             refused: list | None = None) -> dict:
    """``{backend: BackendAnswers}`` at every row of ``Q`` ``(M, nq)``.

    Serially by default (``checkers``: prebuilt ones to reuse); with ``workers`` (a fresh Dask
    LocalCluster of that many single-threaded processes) or ``scheduler`` (an address), on Dask;
    the workers load the model from ``spec`` (what :func:`resolve_model` takes).  ``progress``:
    ``callable(done, total)`` after each chunk.

    A backend's refusal (BackendError) at one row raises, unless ``refused`` is a list: then each
    refused row is appended to it (``{"config", "q", "message"}``) and left out of every backend's
    answers, whose rows are the others, in order (what was answered is kept).  A refusal at every
    row raises the first.
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
            if refused is None:
                parts.append(_answer_chunk(model, checkers, Q[s:s + size], s))
            else:
                got, no = _answer_rows(model, checkers, Q[s:s + size], s)
                parts += got
                refused += no
            if progress is not None:
                progress(min(M, s + size), M)
        if not M:
            return _merge([_answer_chunk(model, checkers, Q)], backends)
        return _merged(parts, backends, refused)
    if spec is None:
        raise ArmguardError("evaluating on Dask needs the model's spec (a name or a file path the workers can load)")
    return _on_dask(str(spec), Q, backends, options, workers, scheduler, chunk_size, progress, refused)


def _merged(parts: list, backends, refused) -> dict:
    if not parts:  # every row refused: nothing to compare
        raise BackendError(f"every configuration was refused; the first: {refused[0]['message']}")
    return _merge(parts, backends)


def _on_dask(spec, Q, backends, options, workers, scheduler, chunk_size, progress, refused=None) -> dict:
    from distributed import as_completed

    from .._dask import dask_client

    with dask_client(workers, scheduler) as (client, n_workers):
        M = len(Q)
        size = chunk_size or max(1, math.ceil(M / (4 * n_workers)))
        starts = list(range(0, M, size)) or [0]
        opts, token = json.dumps(options, sort_keys=True), uuid.uuid4().hex
        keep_going = refused is not None
        futures = {client.submit(_chunk_task, spec, backends, opts, Q[s:s + size], s, token, keep_going, pure=False): k
                   for k, s in enumerate(starts)}
        parts: list = [None] * len(starts)
        done = 0
        for fut in as_completed(list(futures)):
            k = futures[fut]
            parts[k] = fut.result()
            done += len(Q[starts[k]:starts[k] + size])
            if progress is not None:
                progress(done, M)
        if not keep_going:
            return _merge(parts, backends)
        for _, no in parts:  # in the configurations' order
            refused += no
        return _merged([p for got, _ in parts for p in got], backends, refused)
