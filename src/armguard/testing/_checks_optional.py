"""The conformance suite's checks of the optional methods (``nearest``, ``min_distance_many``,
``pair_distances(q, pairs=...)``, ``pair_distances_many``, distance Jacobians), of results that stay
the caller's, and of thread safety.  Conventions as :mod:`._checks`."""

from __future__ import annotations

import functools
import inspect
import threading

import numpy as np

from .._tolerance import DEFAULT_TOLERANCES as TOL
from ._checks import BIG_BATCH, _distances, _has_pairs_argument, _raises_backend_error, _require_distances, answer, where
from ._suite import NotApplicable, expect
from ._threads import run_in_threads

__all__ = ["check_optional_fast_paths", "check_pair_subset", "check_pair_distances_many", "check_thread_safety",
           "check_results_kept", "check_distance_jacobian", "check_model_as_made"]


def check_optional_fast_paths(ctx, model):
    """``nearest(q)`` equals ``pair_distances(q).nearest()`` and ``min_distance_many(Q)`` the rows'
    least distances (where the Checker has them)."""
    c = ctx.checker(model)
    _require_distances(c)
    if not (hasattr(c, "nearest") or hasattr(c, "min_distance_many")):
        raise NotApplicable("no nearest / min_distance_many")
    Q = ctx.configs(model)
    full = [answer(ctx, model, c, q, i) for i, q in enumerate(Q)]
    if hasattr(c, "nearest"):
        for i, q in enumerate(Q):
            got, want = c.nearest(q), full[i].nearest()
            expect(set(got) == set(want), f"configuration {i}: nearest has categories {sorted(got)}, expected {sorted(want)}")
            for cat, w in want.items():
                g = got[cat]
                expect((g.a, g.b) == (w.a, w.b) or abs(g.distance - w.distance) <= TOL.differential_distance,
                       f"configuration {i}, {cat}: nearest names {(g.a, g.b)}, pair_distances {(w.a, w.b)}")
                expect(abs(g.distance - w.distance) <= TOL.differential_distance,
                       f"configuration {i}, {cat}: nearest distance {g.distance} vs {w.distance} m")
                if (g.a, g.b) == (w.a, w.b):  # the same pair: its row and witness points too
                    expect(g.index == w.index, f"configuration {i}, {cat}: nearest index {g.index}, pair_distances {w.index}")
                    for key in ("p_WA", "p_WB"):
                        x, y = np.asarray(getattr(g, key), dtype=np.float64), np.asarray(getattr(w, key))
                        expect(x.shape == y.shape and np.allclose(x, y, rtol=0, atol=TOL.differential_distance),
                               f"configuration {i}, {cat}: nearest {key} {x.tolist()}, pair_distances {y.tolist()}")
    if hasattr(c, "min_distance_many"):
        got = np.asarray(c.min_distance_many(Q), dtype=np.float64)
        want = np.array([r.distance.min(initial=np.inf) for r in full])
        expect(got.shape == want.shape, f"min_distance_many gave shape {got.shape}, expected {want.shape}")
        expect(np.allclose(got, want, rtol=0, atol=TOL.differential_distance),
               f"min_distance_many differs from the rows' least distance by up to {np.max(np.abs(got - want)):.3g} m")


# ================================================================ optional methods
def _same_rows(got, want, idx, where: str) -> None:
    expect(np.array_equal(np.asarray(got.pairs), np.asarray(want.pairs)[idx]), f"{where}: pairs are not the rows asked for")
    expect(tuple(got.category) == tuple(np.asarray(want.category, dtype=object)[idx]), f"{where}: category differs")
    for key in ("distance", "p_WA", "p_WB"):
        x, y = np.asarray(getattr(got, key)), getattr(want, key)[idx]
        expect(x.shape == y.shape, f"{where}: {key} has shape {x.shape}, expected {y.shape}")
        expect(np.allclose(x, y, rtol=0, atol=1e-12),
               lambda: f"{where}: {key} differs from the full result's rows by up to {np.max(np.abs(x - y)):.3g} m")


def check_pair_subset(ctx, model):
    """``pair_distances(q, pairs=rows)`` (where the Checker takes ``pairs``) equals rows ``rows`` of
    ``pair_distances(q)``, in that order (within 1e-12 m), for sorted, unsorted, single and empty
    row arrays; a row outside ``[0, n)``, a 2-D array, a boolean mask or floats raise BackendError."""
    c = ctx.checker(model)
    _require_distances(c)
    if not _has_pairs_argument(c):
        raise NotApplicable("pair_distances takes no pairs= argument")
    n = len(ctx.model(model).pairs)
    rng = np.random.default_rng(ctx.seed)
    subsets = {"all": np.arange(n), "single": np.array([n - 1]), "empty": np.zeros(0, np.int64),
               "sorted": np.sort(rng.choice(n, size=max(1, n // 3), replace=False)),
               "unsorted": rng.permutation(n)[: max(1, n // 2)]}
    for i, q in enumerate(ctx.configs(model)[:3]):
        full = answer(ctx, model, c, q, i)
        for what, idx in subsets.items():
            _same_rows(c.pair_distances(q, pairs=idx), full, idx, f"configuration {i}, pairs={what}")
    q = ctx.configs(model)[0]
    for what, idx in (("out of range", np.array([n])), ("negative", np.array([-1])), ("2-D", np.zeros((1, 1), np.int64)),
                      ("a boolean mask", np.ones(n, dtype=bool)), ("floats", np.array([0.5]))):
        _raises_backend_error(lambda: c.pair_distances(q, pairs=idx), f"pair_distances(q, pairs {what})")


def check_pair_distances_many(ctx, model):
    """``pair_distances_many(Q)`` (where the Checker has it) equals ``pair_distances`` row by row
    (within 1e-12 m): ``pairs``/``category`` the Model's, ``distance (M, n)``, ``p_WA``/``p_WB
    (M, n, 3)`` float64, for ``M = 1`` (not ``(n,)``), ``M = 0`` and :data:`BIG_BATCH` rows too; with ``pairs=rows`` (where it
    takes them) those rows, ``pairs=[]`` none (not all), and rows outside ``[0, n)`` or not integers
    refused with BackendError."""
    c = ctx.checker(model)
    _require_distances(c)
    if not hasattr(c, "pair_distances_many"):
        raise NotApplicable("no pair_distances_many")
    Q = ctx.configs(model)
    m = ctx.model(model)
    n = len(m.pairs)
    full = [answer(ctx, model, c, q, i) for i, q in enumerate(Q)]
    rows = np.random.default_rng(ctx.seed).permutation(n)[: max(1, n // 3)]
    takes_pairs = _has_pairs_argument(c) and "pairs" in inspect.signature(c.pair_distances_many).parameters
    big = np.resize(np.arange(len(Q)), BIG_BATCH)  # the configurations again and again: where a backend may switch path
    cases = [(None, Q, full, "pair_distances_many(Q)"), (None, Q[:1], full[:1], "pair_distances_many(Q[:1]) (one row)"),
             (None, Q[big], [full[k] for k in big], f"pair_distances_many of {BIG_BATCH} rows (the configurations repeated)")]
    if takes_pairs:
        cases += [(rows, Q, full, "pair_distances_many(Q, pairs=rows)"),
                  (np.zeros(0, np.int64), Q, full, "pair_distances_many(Q, pairs=[]) (no row)")]
    for subset, rows_q, rows_full, what in cases:
        many = c.pair_distances_many(rows_q) if subset is None else c.pair_distances_many(rows_q, pairs=subset)
        idx = np.arange(n) if subset is None else subset
        for key in ("pairs", "category"):
            expect(hasattr(many, key), f"{what}: the result has no {key!r} (a PairDistancesMany names its rows)")
        expect(np.array_equal(np.asarray(many.pairs), m.pairs.names[idx]), f"{what}: pairs are not the rows asked for")
        expect(tuple(many.category) == tuple(np.asarray(m.pairs.category, dtype=object)[idx]), f"{what}: category differs")
        for key, shape in (("distance", (len(rows_q), len(idx))), ("p_WA", (len(rows_q), len(idx), 3)),
                           ("p_WB", (len(rows_q), len(idx), 3))):
            a = np.asarray(getattr(many, key))
            expect(a.shape == shape and a.dtype == np.float64, f"{what}: {key} is {a.dtype} {a.shape}, expected float64 {shape}")
            for i, r in enumerate(rows_full):
                x, y = a[i], getattr(r, key)[idx]
                expect(np.allclose(x, y, rtol=0, atol=1e-12),
                       lambda: f"{what}, row {i}: {key} differs from pair_distances(Q[{i}]) by up to "
                               f"{np.max(np.abs(x - y)):.3g} m")
    empty = c.pair_distances_many(Q[:0])
    for key, shape in (("distance", (0, n)), ("p_WA", (0, n, 3)), ("p_WB", (0, n, 3))):
        a = np.asarray(getattr(empty, key))
        expect(a.shape == shape, f"M = 0: {key} has shape {a.shape}, expected {shape}")
    if takes_pairs:  # rows outside [0, n) or not integers: refused, as by pair_distances
        for bad, idx in (("out of range", np.array([n])), ("negative", np.array([-1])), ("floats", np.array([0.5])),
                         ("a boolean mask", np.ones(n, dtype=bool))):
            _raises_backend_error(lambda: c.pair_distances_many(Q, pairs=idx), f"pair_distances_many(Q, pairs {bad})")


# ================================================================ threads
THREADS = 4


def _answer(r) -> tuple:
    """Copies: an answer in a scratch buffer another thread rewrites compared equal to itself."""
    return tuple(np.array(getattr(r, k), copy=True) for k in ("distance", "p_WA", "p_WB"))


def check_thread_safety(ctx, model):
    """One Checker called from 4 threads at once (``pair_distances`` on different configurations, with
    and without ``pairs=`` where it takes them, ``pair_distances_many`` where it has it, ``collides``
    on different batches; thread switches forced often) gives exactly the answers of single-threaded
    calls: distances and witness points."""
    c = ctx.checker(model)
    Q = ctx.configs(model)
    dist = _distances(c)
    rows = np.random.default_rng(ctx.seed).permutation(len(ctx.model(model).pairs))[:3]
    calls = {}  # what -> the call (its single-threaded answer: want[what])
    if dist:
        for i, q in enumerate(Q):
            calls[f"pair_distances(configuration {i})"] = functools.partial(c.pair_distances, q)
            if _has_pairs_argument(c):
                calls[f"pair_distances(configuration {i}, pairs={rows.tolist()})"] = functools.partial(c.pair_distances, q,
                                                                                                       pairs=rows)
        if hasattr(c, "pair_distances_many"):
            calls["pair_distances_many(Q)"] = functools.partial(c.pair_distances_many, Q)
    want = {k: _answer(f()) for k, f in calls.items()}
    order = list(calls)
    batches = [np.roll(Q, k, axis=0)[:3] for k in range(THREADS)]
    want_v = [c.collides(b) for b in batches]
    rounds = 2
    barrier = threading.Barrier(THREADS)
    problems: list[str] = []

    def work(t: int) -> None:
        try:
            barrier.wait()
            for _ in range(rounds):
                for k in range(len(order)):
                    what = order[(k + t) % len(order)]
                    got = _answer(calls[what]())
                    for key, x, y in zip(("distance", "p_WA", "p_WB"), got, want[what]):
                        if not np.array_equal(x, y):
                            problems.append(f"thread {t}: {what}.{key} differs from the single-threaded answer"
                                            + (f" by up to {np.max(np.abs(x - y)):.3g} m" if x.shape == y.shape else ""))
                            return
                got = c.collides(batches[t])
                if not np.array_equal(got, want_v[t]):
                    problems.append(f"thread {t}: collides differs from the single-threaded answer in rows "
                                    f"{np.flatnonzero(got != want_v[t]).tolist()}")
                    return
        except Exception as exc:  # noqa: BLE001 - a crash under threads is the finding
            problems.append(f"thread {t} raised {type(exc).__name__}: {exc}")

    run_in_threads([functools.partial(work, t) for t in range(THREADS)])
    expect(not problems, lambda: f"{len(problems)} of {THREADS} threads saw wrong answers; first: {problems[0]}")


# ================================================================ results stay the caller's
def check_results_kept(ctx, model):
    """An answer stays as it was returned whatever is asked after it: ``pair_distances(q)``'s arrays (with
    ``pairs=`` too), ``collides(Q)``'s, ``pair_distances_many(Q)``'s, ``min_distance_many(Q)``'s and
    ``nearest(q)``'s witness points are the caller's, not the backend's scratch (a later call that wrote
    into them changed a result already handed out); and a caller editing an answer it holds changes no
    later answer (a cache that hands out its own arrays)."""
    c = ctx.checker(model)
    Q = ctx.configs(model)
    other = np.vstack([Q[1:], ctx.model(model).random_q(1, ctx.seed + 1)])  # configurations other than Q[0]
    later = [functools.partial(c.collides, other)]
    kept = {"collides(Q[:1])": (c.collides(Q[:1]),)}
    if _distances(c):
        rows = np.arange(min(3, len(ctx.model(model).pairs)))
        kept["pair_distances(configuration 0)"] = _arrays(c.pair_distances(Q[0]))
        later += [functools.partial(c.pair_distances, q) for q in other]
        if _has_pairs_argument(c):
            kept[f"pair_distances(configuration 0, pairs={rows.tolist()})"] = _arrays(c.pair_distances(Q[0], pairs=rows))
            later += [functools.partial(c.pair_distances, q, pairs=rows) for q in other]
        if hasattr(c, "pair_distances_many"):
            kept["pair_distances_many(Q[:1])"] = _arrays(c.pair_distances_many(Q[:1]))
            later += [functools.partial(c.pair_distances_many, rows_q) for rows_q in (other[-1:], other)]  # as many rows first
        if hasattr(c, "min_distance_many"):
            kept["min_distance_many(Q[:1])"] = (c.min_distance_many(Q[:1]),)
            later += [functools.partial(c.min_distance_many, rows_q) for rows_q in (other[-1:], other)]
        if hasattr(c, "nearest"):
            kept["nearest(configuration 0)"] = tuple(x for n in c.nearest(Q[0]).values() for x in (n.p_WA, n.p_WB))
            later += [functools.partial(c.nearest, q) for q in other]
    copies = {what: tuple(np.array(a, copy=True) for a in arrays) for what, arrays in kept.items()}
    for call in later:
        call()
    for what, arrays in kept.items():
        for a, was in zip(arrays, copies[what]):
            expect(np.array_equal(a, was, equal_nan=True),
                   f"{what}: an answer changed after later calls (it shares memory the backend writes again): "
                   "return arrays of their own (copies), not the backend's scratch")
    if _distances(c):  # a caller that edits an answer it holds changes no later answer (a cache handing it out)
        r = c.pair_distances(Q[0])
        for key in ("distance", "p_WA", "p_WB"):
            a = getattr(r, key)
            if isinstance(a, np.ndarray) and a.flags.writeable:
                a += 0.05
        again = c.pair_distances(Q[0])
        for key, was in zip(("distance", "p_WA", "p_WB"), copies["pair_distances(configuration 0)"]):
            expect(np.allclose(getattr(again, key), was, rtol=0.0, atol=1e-6, equal_nan=True),
                   f"pair_distances(configuration 0).{key}: after the caller added 0.05 to the answer it held, the "
                   "same configuration was answered with the edited values: a cache handing out its own arrays")


def _arrays(r) -> tuple:
    return tuple(getattr(r, k) for k in ("distance", "p_WA", "p_WB"))


# ================================================================ distance Jacobians
JACOBIAN_STEPS = (1e-4, 1e-3)  # rad or m: central differences at both; rows where they disagree are left out
JACOBIAN_REL = 1e-2  # row norms: |J - differences| / max(|differences|, JACOBIAN_FLOOR)
JACOBIAN_FLOOR = 1e-2  # m/rad
JACOBIAN_APART = 1e-2  # m: rows this far apart, without a kink, are expected smooth ...
JACOBIAN_SMOOTH_SHARE = 0.5  # ... at least this share of them


def check_distance_jacobian(ctx, model):
    """``pair_distances(q, jacobian=True)`` (where the Checker takes ``jacobian``): ``jacobian (n, nv)``
    float64 and ``smooth (n,)`` bool, the same distances as without; on rows it calls smooth, each
    row equals the central differences of the backend's own distances (at 1e-4 and 1e-3, where the two
    agree and show no kink) within 1 % of the row's norm (floored at 1 cm/rad), and at least half the
    rows more than 1 cm apart without a kink are called smooth (and at least half of those rows show no kink:
    distances that do not follow ``q`` escaped the comparison).  A wrong sign or column steers
    collision avoidance (``armguard.avoidance``) into the obstacle."""
    from ..backends._jacobian import finite_difference_rows

    c = ctx.checker(model)
    _require_distances(c)
    try:
        takes = "jacobian" in inspect.signature(c.pair_distances, follow_wrapped=False).parameters
    except (TypeError, ValueError):
        takes = False
    if not takes:
        raise NotApplicable("pair_distances takes no jacobian= argument")
    m = ctx.model(model)
    n, nv = len(m.pairs), m.pin_model.nv
    compared = candidates = said_smooth = apart = 0
    pick = list(enumerate(ctx.configs(model)))
    for i, q in pick[1:3] or pick:  # two random configurations (the neutral pose alone when there are none)
        r = c.pair_distances(q, jacobian=True)
        J, smooth = getattr(r, "jacobian", None), getattr(r, "smooth", None)
        expect(isinstance(J, np.ndarray) and J.shape == (n, nv) and J.dtype == np.float64,
               lambda: f"{where(i, q)}: jacobian must be a float64 array of shape {(n, nv)}, got "
                       f"{getattr(J, 'dtype', type(J).__name__)} {getattr(J, 'shape', '')}")
        expect(isinstance(smooth, np.ndarray) and smooth.shape == (n,) and smooth.dtype == bool,
               lambda: f"{where(i, q)}: smooth must be a bool array of shape {(n,)}, got "
                       f"{getattr(smooth, 'dtype', type(smooth).__name__)} {getattr(smooth, 'shape', '')}")
        plain = answer(ctx, model, c, q, i).distance
        expect(np.allclose(r.distance, plain, rtol=0.0, atol=TOL.differential_witness),
               lambda: f"{where(i, q)}: the distances with jacobian=True differ from those without by up to "
                       f"{np.max(np.abs(r.distance - plain)):.3g} m")
        fd, kink = finite_difference_rows(c, q, None, step=JACOBIAN_STEPS[0])
        fd10, kink10 = finite_difference_rows(c, q, None, step=JACOBIAN_STEPS[1])
        scale = np.maximum(np.linalg.norm(fd, axis=1), JACOBIAN_FLOOR)
        plain_rows = ~kink & ~kink10 & (np.linalg.norm(fd - fd10, axis=1) / scale <= JACOBIAN_REL)
        ok = smooth & plain_rows
        clear = plain_rows & (r.distance > JACOBIAN_APART)
        apart += int((r.distance > JACOBIAN_APART).sum())
        candidates += int(clear.sum())
        said_smooth += int((clear & smooth).sum())
        err = np.linalg.norm(J - fd, axis=1) / scale
        bad = np.flatnonzero(ok & (err > JACOBIAN_REL))
        compared += int(ok.sum())
        expect(not bad.size, lambda: f"{where(i, q)}, pair {tuple(r.pairs[bad[0]])}: jacobian row "
                                     f"{np.round(J[bad[0]], 6).tolist()}, central differences "
                                     f"{np.round(fd[bad[0]], 6).tolist()} (relative error {err[bad[0]]:.3g})")
    # rows whose differences at the two steps disagree are not compared: distances that do not follow q smoothly
    # (a cache keyed by a rounded q: a zero Jacobian passed, 0 to 2 of the rows compared) would escape the check
    expect(apart < 10 or candidates >= JACOBIAN_SMOOTH_SHARE * apart,
           f"the central differences of the distances at steps {JACOBIAN_STEPS[0]:g} and {JACOBIAN_STEPS[1]:g} agree on "
           f"{candidates} of the {apart} rows more than {JACOBIAN_APART * 100:g} cm apart (at least "
           f"{JACOBIAN_SMOOTH_SHARE:.0%} expected: the bundled backends' agree on 85-100 %): distances that do not follow q")
    # a row called non-smooth is not compared: calling every row so would escape the check
    expect(candidates < 10 or said_smooth >= JACOBIAN_SMOOTH_SHARE * candidates,
           f"smooth is True on {said_smooth} of the {candidates} rows more than {JACOBIAN_APART * 100:g} cm apart whose "
           f"central differences show no kink (at least {JACOBIAN_SMOOTH_SHARE:.0%} expected: the bundled backends "
           "call 85-100 % of them smooth)")
    if not compared:
        raise NotApplicable("no row smooth at the configurations checked")


# ================================================================ the Model as made
def check_model_as_made(ctx, model):
    """A Checker answers for the Model it was built on, whatever ``model.scene`` does afterwards: built on a
    Model whose scene's workspace box was then shrunk by a quarter each side, it answers as on the Model
    unedited (distances, witness points, verdicts).  A backend reads ``model.workspace``, not
    ``model.scene.workspace`` (coal, fcl and the example backend read the edited box once)."""
    from ..model import model_of

    m = ctx.model(model)
    if m.workspace is None:
        raise NotApplicable("the model has no workspace box")
    c = ctx.checker(model)
    fresh = model_of(m.scene_for().copy())  # a Model of its own, whose scene can be edited
    lo, hi = np.asarray(fresh.scene.workspace.lo, float), np.asarray(fresh.scene.workspace.hi, float)
    fresh.scene.set_workspace(lo + 0.25 * (hi - lo), hi - 0.25 * (hi - lo))
    edited = ctx.build_on(fresh)
    Q = ctx.configs(model)
    v, w = np.asarray(c.collides(Q)), np.asarray(edited.collides(Q))
    expect(np.array_equal(v, w), lambda: f"configuration {np.flatnonzero(v != w)[0]}: collides says "
                                         f"{bool(w[np.flatnonzero(v != w)[0]])} after the scene's workspace box was "
                                         "shrunk, the Model as made says otherwise: read model.workspace, not "
                                         "model.scene.workspace")
    if not _distances(c):
        return
    for i, q in enumerate(Q):
        a, b = c.pair_distances(q), edited.pair_distances(q)
        for key in ("distance", "p_WA", "p_WB"):
            x, y = np.asarray(getattr(a, key)), np.asarray(getattr(b, key))
            expect(x.shape == y.shape and np.allclose(x, y, rtol=0.0, atol=1e-9),
                   lambda: f"{where(i, q)}: {key} differs by up to {np.max(np.abs(x - y)):.3g} m after the scene's "
                           "workspace box was shrunk (the Model's is unchanged): read model.workspace, not "
                           "model.scene.workspace")
