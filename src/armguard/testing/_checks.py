"""The checks of the conformance suite: the interface contract (:mod:`armguard.backends`) and the
differential comparison against coal.

Each ``check_<name>(ctx, model)`` fails through :func:`~._suite.expect` / :func:`~._suite.fail`
(never a bare ``assert``) and raises :class:`~._suite.NotApplicable` where the backend does not
claim what the check is about.  Tolerances are :data:`armguard.DEFAULT_TOLERANCES`'
``differential_*`` fields, shared with ``armguard compare`` and the repository's differential tests.
"""

from __future__ import annotations

import inspect
import math

import numpy as np

from .._errors import BackendError
from .._tolerance import DEFAULT_TOLERANCES as TOL
from ..backends import Backend, Capability, Checker
from ._suite import REFERENCE, NotApplicable, expect, fail
from ._surface import round_cores_meet, surface_residuals

__all__ = ["BACKEND_CHECKS", "MODEL_CHECKS"]

BAND = TOL.differential_contact_band  # m: verdicts may differ only where the reference's distance is this close to 0
WITNESS = TOL.differential_witness  # m: | |p_WA - p_WB| - |d| |
UNKNOWN_OPTION = "conformance_no_such_option"
MARGIN = 0.05  # m: a margin every distances backend answers
EDGE = 5e-4  # m: margins this far either side of a least distance
BIG_BATCH = 160  # rows: a batch past the sizes at which backends switch to a parallel path (coal: 64)


def _distances(checker) -> bool:
    return Capability.DISTANCES in checker.capabilities


def _require_distances(checker) -> None:
    if not _distances(checker):
        raise NotApplicable(f"backend {checker.name!r} declares no distances (capabilities "
                            f"{sorted(c.value for c in checker.capabilities)})")


def _raises_backend_error(call, what: str) -> BackendError:
    """``call()`` must raise BackendError (never answer, never another exception)."""
    try:
        out = call()
    except BackendError as exc:
        return exc
    except NotApplicable:  # the backend cannot be built here at all (its dependency is not installed)
        raise
    except Exception as exc:  # noqa: BLE001 - the wrong kind of refusal
        fail(f"{what}: raised {type(exc).__name__}: {exc} (expected armguard.BackendError)")
    fail(f"{what}: answered {type(out).__name__} instead of raising armguard.BackendError")


def _has_pairs_argument(checker) -> bool:
    """Whether ``pair_distances`` takes ``pairs=``: its own signature, not the one ``functools.wraps`` copied
    onto the framework's wrapper (a CheckerBase whose ``pair_distances(q)`` takes no ``pairs`` is given them)."""
    try:
        return "pairs" in inspect.signature(checker.pair_distances, follow_wrapped=False).parameters
    except (TypeError, ValueError):
        return False


def where(i: int, q) -> str:
    """``configuration i (q = [...])``: how a failure names the configuration (its ``q`` to reproduce it)."""
    return f"configuration {i} (q = {np.asarray(q, dtype=np.float64).tolist()})"


def answer(ctx, model, c, q, i: int):
    """``c.pair_distances(q)`` with its arrays checked first: a wrong shape or dtype, or a value that is
    not finite, fails here, naming the configuration, the row and its pair, so that no later check
    trips over it with a message of its own (``pair_distances_shapes`` says more)."""
    r = c.pair_distances(q)
    names = ctx.model(model).pairs.names
    rows = np.arange(len(names))
    n = len(rows)
    for key, shape in (("distance", (n,)), ("p_WA", (n, 3)), ("p_WB", (n, 3))):
        a = getattr(r, key, None)
        expect(isinstance(a, np.ndarray) and a.shape == shape and a.dtype == np.float64,
               lambda: f"{where(i, q)}: {key} must be a float64 array of shape {shape}, got "
                       f"{getattr(a, 'dtype', type(a).__name__)} {getattr(a, 'shape', '')}")
        bad = ~np.isfinite(a) if a.ndim == 1 else ~np.isfinite(a).all(axis=1)
        k = np.flatnonzero(bad)
        expect(not k.size, lambda: f"{where(i, q)}: {key} is {a[k[0]].tolist()} (not finite) at row {rows[k[0]]}, "
                                   f"pair {tuple(names[rows[k[0]]])}")
    return r


# ================================================================ backend-wide
def check_backend_protocol(ctx, model):
    """The Backend has ``name`` and ``build``; given by name, the entry point gives it and its name
    is the entry point's."""
    b = ctx.backend_impl()
    what = f"get_backend({ctx.backend!r})" if ctx.backend_object is None else "the Backend given"
    expect(isinstance(b, Backend), f"{what} is a {type(b).__name__}, which lacks name / build")
    expect(isinstance(b.name, str) and b.name.strip() != "", f"Backend.name is {b.name!r}: a name is what config selects")
    if ctx.backend_object is None:  # given as an object, the suite takes its name from it: nothing to compare
        expect(b.name == ctx.backend, f"Backend.name is {b.name!r}, the entry point is {ctx.backend!r}")


def check_unknown_option_refused(ctx, model):
    """``build(model, options + {unknown: 1})`` raises BackendError naming the unknown option and
    listing the accepted ones (``options are [...]``, or that it takes none)."""
    exc = _raises_backend_error(lambda: ctx.build(model, {**ctx.options, UNKNOWN_OPTION: 1}),
                                f"build with option {UNKNOWN_OPTION!r}")
    msg = str(exc)
    expect(UNKNOWN_OPTION in msg, f"the refusal does not name the unknown option: {msg!r}")
    expect("options are" in msg or "takes none" in msg or "no options" in msg,
           f"the refusal does not list the accepted options ('options are [...]' or 'takes none'): {msg!r}")


# ================================================================ per model: the interface
def check_checker_protocol(ctx, model):
    """The Checker has ``name`` (the backend's), ``model`` (the one given), ``capabilities`` (a
    non-empty frozenset of :class:`~armguard.backends.Capability`), ``pair_distances`` and ``collides``."""
    c = ctx.checker(model)
    expect(isinstance(c, Checker), f"{type(c).__name__} lacks part of the Checker protocol "
                                   "(name, model, capabilities, pair_distances, collides)")
    expect(c.name == ctx.backend, f"Checker.name is {c.name!r}, the backend is {ctx.backend!r}")
    expect(c.model is ctx.model(model), "Checker.model is not the Model it was built for")
    caps = c.capabilities
    expect(isinstance(caps, frozenset) and caps and all(isinstance(x, Capability) for x in caps),
           f"capabilities must be a non-empty frozenset of Capability, got {caps!r}")


def check_pair_distances_shapes(ctx, model):
    """``pair_distances(q)``: pairs equal to ``model.pairs.names`` (that order), ``distance (n,)``,
    ``p_WA``/``p_WB (n, 3)`` float64, finite, ``category`` the Model's, at every configuration."""
    c = ctx.checker(model)
    _require_distances(c)
    m = ctx.model(model)
    names, cats = m.pairs.names, tuple(m.pairs.category)
    n = len(names)
    for i, q in enumerate(ctx.configs(model)):
        r = c.pair_distances(q)
        expect(np.shape(r.pairs) == (n, 2) and np.array_equal(np.asarray(r.pairs), names),
               f"{where(i, q)}: pairs differ from model.pairs.names (order too)")
        expect(tuple(r.category) == cats, f"{where(i, q)}: category differs from model.pairs.category")
        answer(ctx, model, c, q, i)  # shapes, dtypes, finite values, named by row


def check_witness_relation(ctx, model):
    """``| |p_WA - p_WB| - |distance| | <= Tolerances.differential_witness`` (1e-9 m) on every pair
    and configuration."""
    c = ctx.checker(model)
    _require_distances(c)
    for i, q in enumerate(ctx.configs(model)):
        r = answer(ctx, model, c, q, i)
        gap = np.linalg.norm(r.p_WA - r.p_WB, axis=1)
        err = np.abs(gap - np.abs(r.distance))
        k = int(np.argmax(err)) if err.size else 0
        expect(not err.size or err[k] <= WITNESS,
               lambda: f"{where(i, q)}, pair {tuple(r.pairs[k])}: |p_WA - p_WB| = {gap[k]:.12g} m but "
                       f"distance = {r.distance[k]:.12g} m (|difference| {err[k]:.3g} > {WITNESS:g} m)")


def _residuals(ctx, model, c):
    """Per configuration: ``q``, the answer and each witness point's residual against both shapes of its
    pair (:func:`surface_residuals`), with the shapes the backend does not hold exactly masked out."""
    m = ctx.model(model)
    skip = list(getattr(c, "representation", {}) or {})
    for i, q in enumerate(ctx.configs(model)):
        r = answer(ctx, model, c, q, i)
        keep = ~(np.isin(r.pairs[:, 0], skip) | np.isin(r.pairs[:, 1], skip))
        on_a = surface_residuals(m, q, r.pairs[:, 0], r.p_WA)  # p_WA against A, ...
        on_b = surface_residuals(m, q, r.pairs[:, 1], r.p_WB)
        a_in_b = surface_residuals(m, q, r.pairs[:, 1], r.p_WA)  # ... p_WA against B
        b_in_a = surface_residuals(m, q, r.pairs[:, 0], r.p_WB)
        yield i, q, r, keep, on_a, on_b, a_in_b, b_in_a


def _swapped(other, k: int, side: int, pair) -> str:
    """A hint where witness point ``p_WA`` (side 0) or ``p_WB`` (1) of row ``k`` lies on the other shape's surface."""
    res, tol, _ = other
    if np.isfinite(res[k]) and abs(res[k]) <= tol[k]:
        return f" (p_W{'AB'[side]} lies on {pair[1 - side]}'s surface: p_WA and p_WB swapped?)"
    return ""


def check_witness_on_surfaces(ctx, model):
    """``p_WA`` lies on A's surface and ``p_WB`` on B's within 1e-6 m (1e-5 m on a convex hull), the
    shapes posed by Pinocchio (sphere, capsule, box, cylinder, convex hull, a workspace wall), on
    separated and on penetrating pairs (there: each shape's deepest point in the other); on separated
    pairs each is the pair's distance from the other shape where that shape's distance is exact (not a
    hull): they are the nearest points.  Shapes the backend declares it does not hold exactly
    (``representation``) and shapes this check cannot evaluate are left out, and so are penetrating
    pairs of two spheres or capsules whose cores (centre, segment) meet: any direction is then a
    deepest one."""
    c = ctx.checker(model)
    _require_distances(c)
    checked = 0
    for i, q, r, keep, on_a, on_b, a_in_b, b_in_a in _residuals(ctx, model, c):
        d = r.distance
        for side, (name, (res, tol, exact)) in enumerate((("p_WA against B", a_in_b), ("p_WB against A", b_in_a))):
            bad = np.flatnonzero(keep & (d > BAND) & np.isfinite(res) & exact & (np.abs(res - d) > tol))
            expect(not bad.size, lambda: f"{where(i, q)}, pair {tuple(r.pairs[bad[0]])}: distance "
                                         f"{d[bad[0]]:.12g} m but {name} is {res[bad[0]]:.12g} m from it"
                                         + _swapped((res, tol, exact), bad[0], side, r.pairs[bad[0]]))
        pen = keep & (d < -BAND)
        if pen.any():
            pen[pen] = ~round_cores_meet(ctx.model(model), q, r.pairs[pen, 0], r.pairs[pen, 1])
        for side, (res, tol, _) in enumerate((on_a, on_b)):
            if side == 1:  # a workspace witness lies on one wall
                res = np.where(r.pairs[:, 1] == "workspace", np.abs(res), res)
            ok = (keep & (d > BAND) | pen) & np.isfinite(res)
            checked += int(ok.sum())
            bad = np.flatnonzero(ok & (np.abs(res) > tol))
            expect(not bad.size, lambda: f"{where(i, q)}, pair {tuple(r.pairs[bad[0]])}: p_W{'AB'[side]} = "
                                         f"{getattr(r, 'p_W' + 'AB'[side])[bad[0]].tolist()} is {res[bad[0]]:.3g} m off "
                                         f"{r.pairs[bad[0], side]}'s surface (tolerance {tol[bad[0]]:g} m), "
                                         f"distance {d[bad[0]]:.9g} m"
                                         + _swapped((a_in_b, b_in_a)[side], bad[0], side, r.pairs[bad[0]]))
    if not checked:
        raise NotApplicable("no pair with a shape whose surface this check can evaluate")


def check_sign_convention(ctx, model):
    """``distance > 0`` means apart: each witness point of a separated pair lies outside the other
    shape; ``distance < 0`` means penetrating: a witness point lies inside (or on) the other shape."""
    c = ctx.checker(model)
    _require_distances(c)
    checked = 0
    for i, q, r, keep, _, _, a_in_b, b_in_a in _residuals(ctx, model, c):
        d = r.distance
        for name, (res, tol, _) in (("p_WA against B", a_in_b), ("p_WB against A", b_in_a)):
            sep = keep & (d > BAND) & np.isfinite(res)
            checked += int(sep.sum())
            bad = np.flatnonzero(sep & (res < -tol))
            expect(not bad.size, lambda: f"{where(i, q)}, pair {tuple(r.pairs[bad[0]])}: distance "
                                         f"{d[bad[0]]:.9g} m > 0 but {name} is {-res[bad[0]]:.3g} m inside it")
        pen = keep & (d < -BAND) & np.isfinite(a_in_b[0]) & np.isfinite(b_in_a[0])
        checked += int(pen.sum())
        inside = np.minimum(a_in_b[0] - a_in_b[1], b_in_a[0] - b_in_a[1]) <= 0.0
        bad = np.flatnonzero(pen & ~inside)
        expect(not bad.size, lambda: f"{where(i, q)}, pair {tuple(r.pairs[bad[0]])}: distance "
                                     f"{d[bad[0]]:.9g} m < 0 but neither witness point is inside the other shape")
    if not checked:
        raise NotApplicable("no pair with a shape this check can evaluate")


def check_bad_q_refused(ctx, model):
    """NaN, infinite, wrongly shaped and non-numeric ``q`` / ``Q``, and a continuous joint's ``(cos, sin)``
    off the unit circle (a model with one: a sheared link otherwise), raise BackendError from
    ``pair_distances`` and ``collides`` (and the optional batch paths), a joint outside its limits
    JointLimitError: never a verdict."""
    c = ctx.checker(model)
    m = ctx.model(model)
    q = ctx.configs(model)[0]
    nan, inf = q.copy(), q.copy()
    nan[-1], inf[0] = np.nan, np.inf
    bad_q = {"NaN": nan, "inf": inf, "one value short": q[:-1], "one value extra": np.append(q, 0.0),
             "2-D": q[None], "text": ["a"] * m.nq}
    circle = np.asarray(m.continuous_q, dtype=np.int64)  # a continuous joint's (cos, sin) at q[j], q[j + 1]
    if circle.size:
        off = q.copy()
        off[circle[0]:circle[0] + 2] *= 1.5
        bad_q["with a continuous joint's (cos, sin) off the unit circle"] = off
    if _distances(c):
        for what, bq in bad_q.items():
            _raises_backend_error(lambda: c.pair_distances(bq), f"pair_distances(q {what})")
    Q = np.resize(ctx.configs(model), (3, m.nq))  # three rows, repeated when n_configs < 2
    Qn = Q.copy()
    Qn[1, 0] = np.nan
    Qi = Q.copy()
    Qi[2, -1] = -np.inf
    bad_Q = {"a NaN row": Qn, "an infinite row": Qi, "one column short": Q[:, :-1], "1-D": Q[0], "3-D": Q[None]}
    if circle.size:
        Qc = Q.copy()
        Qc[1, circle[0]:circle[0] + 2] *= 1.5
        bad_Q["a continuous joint's (cos, sin) off the unit circle in a row"] = Qc
    for what, bQ in bad_Q.items():
        _raises_backend_error(lambda: c.collides(bQ), f"collides(Q with {what})")
        if _distances(c) and hasattr(c, "pair_distances_many"):
            _raises_backend_error(lambda: c.pair_distances_many(bQ), f"pair_distances_many(Q with {what})")
    for margin in (math.nan, -0.01, math.inf):
        _raises_backend_error(lambda: c.collides(Q, margin=margin), f"collides(Q, margin={margin})")
    _out_of_limits_refused(c, m, q, Q)


PAST_LIMIT = 1e3 * TOL.joint_limit  # m or rad: a value this far past a limit is refused too (not only 0.1 past)


def _joint_of_q(pin_model, j: int) -> str:
    """The name of the joint whose value is ``q[j]``."""
    for k in range(1, pin_model.njoints):
        if pin_model.idx_qs[k] <= j < pin_model.idx_qs[k] + pin_model.nqs[k]:
            return pin_model.names[k]
    return "?"


def _out_of_limits_refused(c, m, q, Q) -> None:
    """Each joint with finite limits 0.1 and :data:`PAST_LIMIT` beyond its upper limit and below its lower
    one: JointLimitError from every entry point, as every backend's ``check_q`` / ``check_Q``
    (``Model.check_pin_limits``) raise it (a backend that tested one joint, one side, or allowed 0.05 rad
    of slack, passed)."""
    from .._errors import JointLimitError

    lo = np.asarray(m.pin_model.lowerPositionLimit, dtype=np.float64)
    hi = np.asarray(m.pin_model.upperPositionLimit, dtype=np.float64)
    free = set(m.continuous_q.tolist()) | set((m.continuous_q + 1).tolist())
    for j in range(m.nq):
        if j in free:
            continue
        probes = [(f"{step:g} {way} its {which} limit", bound + sign * step) for step in (0.1, PAST_LIMIT)
                  for way, which, bound, sign in (("above", "upper", hi[j], 1.0), ("below", "lower", lo[j], -1.0))]
        for side, value in probes:
            if not (np.isfinite(value) and abs(value) < 1e6):
                continue
            out = q.copy()
            out[j] = value
            Qo = Q.copy()
            Qo[-1, j] = value
            what = f"q[{j}] (joint {_joint_of_q(m.pin_model, j)!r}) {side}"
            calls = {f"collides(Q with a row's {what})": lambda: c.collides(Qo)}
            if _distances(c):
                calls[f"pair_distances(q with {what})"] = lambda: c.pair_distances(out)
                if hasattr(c, "pair_distances_many"):
                    calls[f"pair_distances_many(Q with a row's {what})"] = lambda: c.pair_distances_many(Qo)
            for name, call in calls.items():
                try:
                    got = call()
                except JointLimitError:
                    continue
                except Exception as exc:  # noqa: BLE001 - the wrong kind of refusal
                    fail(f"{name}: raised {type(exc).__name__}: {exc} (expected armguard.JointLimitError)")
                fail(f"{name}: answered {type(got).__name__} instead of raising armguard.JointLimitError")


def check_capabilities_honoured(ctx, model):
    """What ``capabilities`` lacks is refused with BackendError (``pair_distances``, ``nearest``,
    ``min_distance_many``, ``pair_distances_many``), never faked or left as NotImplementedError;
    ``collides`` answers ``(M,) bool`` whatever the capabilities, for any ``M`` (0 too)."""
    c = ctx.checker(model)
    Q = ctx.configs(model)
    for rows in (Q, Q[:1], Q[:0]):
        v = c.collides(rows)
        expect(isinstance(v, np.ndarray) and v.dtype == bool and v.shape == (len(rows),),
               lambda: f"collides(Q of {len(rows)} rows) gave {getattr(v, 'dtype', type(v))} "
                       f"{getattr(v, 'shape', '')}, expected ({len(rows)},) bool")
    if _distances(c):
        return
    for meth, arg in (("pair_distances", Q[0]), ("nearest", Q[0]), ("min_distance_many", Q),
                      ("pair_distances_many", Q)):
        if hasattr(c, meth):
            _raises_backend_error(lambda: getattr(c, meth)(arg), f"{meth} of a backend without distances")


def check_collides_matches_distances(ctx, model):
    """``collides(Q, margin)`` is ``min(pair_distances(q).distance) <= margin`` row by row (margins 0
    and 0.05 m, and 0.5 mm either side of the clearest configurations' least distance), except
    within the contact band of the margin; a batch answers as its rows alone, a batch of
    :data:`BIG_BATCH` rows too (where a backend may take another path: threads, a pool)."""
    c = ctx.checker(model)
    _require_distances(c)
    Q = ctx.configs(model)
    dmin = np.array([float(np.min(answer(ctx, model, c, q, i).distance, initial=np.inf)) for i, q in enumerate(Q)])
    big = np.resize(np.arange(len(Q)), BIG_BATCH)  # the configurations again and again
    default = np.asarray(c.collides(Q))
    zero = np.asarray(c.collides(Q, margin=0.0))
    bad = np.flatnonzero(default != zero) if default.shape == zero.shape else [0]
    expect(not len(bad), lambda: f"collides(Q) answers otherwise than collides(Q, margin=0.0) ({where(bad[0], Q[bad[0]])}): "
                                 "the default margin is 0 (touching or penetrating)")
    for margin in (0.0, MARGIN):
        v = c.collides(Q, margin=margin)
        clear = np.abs(dmin - margin) > BAND
        bad = np.flatnonzero(clear & (v != (dmin <= margin)))
        expect(not bad.size, lambda: f"margin {margin} m, {where(bad[0], Q[bad[0]])}: collides says {bool(v[bad[0]])} "
                                     f"but the least distance is {dmin[bad[0]]:.9g} m")
        one = np.array([bool(c.collides(q[None], margin=margin)[0]) for q in Q])
        bad = np.flatnonzero(clear & (one != v))
        expect(not bad.size, lambda: f"margin {margin} m, {where(bad[0], Q[bad[0]])}: the batch says "
                                     f"{bool(v[bad[0]])}, the row alone {bool(one[bad[0]])}")
        vb = np.asarray(c.collides(Q[big], margin=margin))
        bad = np.flatnonzero(clear[big] & (vb != one[big])) if vb.shape == big.shape else [0]
        expect(not len(bad), lambda: f"margin {margin} m: a batch of {BIG_BATCH} rows (the configurations repeated) "
                                     f"answers {vb[bad[0]] if vb.shape == big.shape else vb.shape} in row {bad[0]} "
                                     f"({where(big[bad[0]], Q[big[bad[0]]])}), the row alone {one[big[bad[0]]]}")
    # a margin just above / below a separated configuration's least distance turns its verdict
    for i in np.argsort(-dmin)[:2]:
        if dmin[i] > 2 * EDGE:
            for margin, want in ((dmin[i] + EDGE, True), (dmin[i] - EDGE, False)):
                got = bool(c.collides(Q[i][None], margin=float(margin))[0])
                expect(got == want, f"configuration {i}, least distance {dmin[i]:.9g} m: collides at margin "
                                    f"{margin:.9g} m says {got}")


STEP_FAR, STEP_NEAR = 1e-3, 1e-6  # rad (m): a joint step that moves a pair, and one a thousand times smaller


def _small_step_answered(ctx, model, c, Q, fwd) -> None:
    """At two configurations, a joint that moves some pair by more than 1e-5 m over :data:`STEP_FAR`
    moves it over :data:`STEP_NEAR` too: the distances there are not the very same as at ``q`` (a cache
    keyed by ``q`` rounded to 1e-3 answered every nearby configuration with the old answer, and passed)."""
    import pinocchio as pin

    pm = ctx.model(model).pin_model
    lo, hi = pm.lowerPositionLimit, pm.upperPositionLimit

    def step(q, j, h):  # joint velocity j by h, into the limits' interior where a limit is near
        v = np.zeros(pm.nv)
        v[j] = h
        q2 = pin.integrate(pm, q, v)
        if np.any((q2 < lo - 1e-12) | (q2 > hi + 1e-12)):
            v[j] = -h
            q2 = pin.integrate(pm, q, v)
        return q2

    for i, q in list(enumerate(Q))[:2]:
        base = fwd[i].distance
        for j in range(pm.nv):
            moved = float(np.max(np.abs(answer(ctx, model, c, step(q, j, STEP_FAR), i).distance - base), initial=0.0))
            if not moved > 1e-5:
                continue
            near = answer(ctx, model, c, step(q, j, STEP_NEAR), i).distance
            expect(not np.array_equal(near, base),
                   lambda: f"{where(i, q)}: a step of {STEP_NEAR:g} of velocity {j} gives the very same distances as q, "
                           f"though {STEP_FAR:g} moves a pair by {moved:.3g} m: an answer kept from an earlier q?")
            break


def check_deterministic(ctx, model):
    """The same ``q`` gives the same answer whatever was asked before: the configurations forwards,
    backwards and again give identical distances, witness points and verdicts (a batch of
    :data:`BIG_BATCH` rows too, verdicts-only backends included), and a fresh Checker's very first
    ``pair_distances`` the same as a used one's (no state from earlier calls: caches, warm starts);
    a configuration a small step from another is answered anew (:func:`_small_step_answered`)."""
    c = ctx.checker(model)
    Q = ctx.configs(model)
    if _distances(c):
        fwd = [answer(ctx, model, c, q, i) for i, q in enumerate(Q)]
        back = [answer(ctx, model, c, q, i) for i, q in reversed(list(enumerate(Q)))][::-1]
        for i, (a, b) in enumerate(zip(fwd, back)):
            for key in ("distance", "p_WA", "p_WB"):
                x, y = getattr(a, key), getattr(b, key)
                expect(np.array_equal(x, y), lambda: f"{where(i, Q[i])}: {key} differs between two calls "
                                                     f"(by up to {np.max(np.abs(x - y)):.3g} m) after other configurations")
        _small_step_answered(ctx, model, c, Q, fwd)
        k = len(Q) - 1
        first = ctx.build(model).pair_distances(Q[k])  # a fresh Checker's first call
        for key in ("distance", "p_WA", "p_WB"):
            x, y = np.asarray(getattr(first, key)), getattr(fwd[k], key)
            expect(x.shape == y.shape and np.array_equal(x, y),
                   lambda: f"{where(k, Q[k])}: a fresh Checker's first call answers {key} otherwise than a used one "
                           + (f"(by up to {np.max(np.abs(x - y)):.3g} m)" if x.shape == y.shape else f"(shape {x.shape})"))
    v1, v2 = c.collides(Q), c.collides(Q[::-1])[::-1]
    expect(np.array_equal(v1, v2), f"collides differs for configurations {np.flatnonzero(v1 != v2).tolist()} "
                                   "when the batch is reversed")
    big = np.resize(np.arange(len(Q)), BIG_BATCH)
    vb = np.asarray(c.collides(Q[big]))
    bad = np.flatnonzero(vb != v1[big]) if vb.shape == big.shape else [0]
    expect(not len(bad), lambda: f"a batch of {BIG_BATCH} rows (the configurations repeated) answers otherwise than "
                                 f"the batch of {len(Q)}: row {bad[0]} ({where(big[bad[0]], Q[big[bad[0]]])})")


# ================================================================ per model: against coal
def _vs_reference(ctx, model):
    if ctx.backend == REFERENCE:
        raise NotApplicable(f"the backend is the reference ({REFERENCE}) itself")
    return ctx.reference(model)


def check_coal_distances(ctx, model):
    """Signed distances equal coal's within 1e-6 m (1e-5 m where a side is a convex hull: coal's GJK
    stops within that) on separated and on penetrating pairs, and no sign differs outside the
    contact band; a pair with a shape the backend holds only conservatively (``representation``)
    may be nearer, never farther."""
    c = ctx.checker(model)
    _require_distances(c)
    _, ref, _ = _vs_reference(ctx, model)
    m = ctx.model(model)
    cm = m.collision_model
    names = m.pairs.names
    hull = np.array([any(n != "workspace" and "Convex" in type(cm.geometryObjects[m.geometry_index(n)].geometry).__name__
                         for n in pair) for pair in names])
    tol = np.where(hull, TOL.differential_hull, TOL.differential_distance)
    rep = set(getattr(c, "representation", {}) or {})
    approx = np.array([a in rep or b in rep for a, b in names])
    for i, q in enumerate(ctx.configs(model)):
        r, rr = answer(ctx, model, c, q, i), ref[i]
        d, dr = r.distance, rr.distance
        far = np.abs(dr) > BAND
        bad = np.flatnonzero(far & (np.sign(d) != np.sign(dr)) & ~approx)
        expect(not bad.size, lambda: f"configuration {i}, pair {tuple(names[bad[0]])}: distance {d[bad[0]]:.9g} m, "
                                     f"coal {dr[bad[0]]:.9g} m (opposite signs); q = {q.tolist()}")
        # wherever coal is outside the contact band, whatever the backend's own value: a backend that
        # answered every penetration as touching (-5e-7 m) escaped a test on |d| > BAND as well
        err = np.where(approx, np.maximum(d - dr, 0.0), np.abs(d - dr))
        bad = np.flatnonzero(far & (err > tol))
        expect(not bad.size, lambda: f"configuration {i}, pair {tuple(names[bad[0]])}: distance {d[bad[0]]:.12g} m, "
                                     f"coal {dr[bad[0]]:.12g} m (|difference| {err[bad[0]]:.3g} > {tol[bad[0]]:g} m); "
                                     f"q = {q.tolist()}")


def check_coal_verdicts(ctx, model):
    """``collides(Q)`` agrees with coal's least distance outside the contact band; a verdicts-only
    backend may be conservative (say collision where coal is clear) but never says clear where
    coal's least distance is within the band or below; with distances, margin 0.05 m too."""
    c = ctx.checker(model)
    _, _, dmin = _vs_reference(ctx, model)
    Q = ctx.configs(model)
    v = c.collides(Q)
    unsafe = np.flatnonzero(~v & (dmin <= BAND))
    expect(not unsafe.size, lambda: f"configuration {unsafe[0]}: said clear, coal's least distance is "
                                    f"{dmin[unsafe[0]]:.9g} m; q = {Q[unsafe[0]].tolist()}")
    if not _distances(c):  # conservative only, at a margin too (where it takes one: clip answers contact alone)
        try:
            v = c.collides(Q, margin=MARGIN)
        except BackendError:
            return
        unsafe = np.flatnonzero(~v & (dmin <= MARGIN - BAND))
        expect(not unsafe.size, lambda: f"margin {MARGIN} m, configuration {unsafe[0]}: said clear, coal's least "
                                        f"distance is {dmin[unsafe[0]]:.9g} m; q = {Q[unsafe[0]].tolist()}")
        return
    for margin in (0.0, MARGIN):
        v = c.collides(Q, margin=margin)
        bad = np.flatnonzero((np.abs(dmin - margin) > BAND) & (v != (dmin <= margin)))
        expect(not bad.size, lambda: f"margin {margin} m, configuration {bad[0]}: collides {bool(v[bad[0]])}, coal's "
                                     f"least distance {dmin[bad[0]]:.9g} m; q = {Q[bad[0]].tolist()}")


def _category_model(m, category: str):
    """``m`` with only its pairs of ``category``: every other owner pair disabled, the workspace box dropped
    unless it is that category (a Model made from an edited copy of the system it holds)."""
    from ..model import model_of

    scene = m.scene_for().copy()
    for a, b, cat in zip(m.pairs.owner_a, m.pairs.owner_b, m.pairs.category):
        if cat != category and "workspace" not in (a, b):
            scene.disable_pair(a, b)
    if category != "workspace":
        scene.clear_workspace()
    return model_of(scene)


def check_coal_verdicts_by_category(ctx, model):
    """:func:`check_coal_verdicts` on the Model's pairs of one category at a time (the others disabled): a
    ``collides`` that skipped a whole category (the workspace walls, which are no GeometryObject; an arm's
    payload) passed on the whole Model, where nearer pairs of other categories decided every row."""
    from ..backends import get_backend

    if ctx.backend == REFERENCE:
        raise NotApplicable(f"the backend is the reference ({REFERENCE}) itself")
    m = ctx.model(model)
    cats = sorted(set(m.pairs.category))
    if len(cats) < 2:
        raise NotApplicable(f"one category ({cats[0] if cats else 'none'}): check_coal_verdicts covers it")
    Q = ctx.configs(model)
    for cat in cats:
        sub = _category_model(m, cat)
        expect(sub.nq == m.nq and len(sub.pairs) and set(sub.pairs.category) == {cat},
               f"the suite's sub-Model of category {cat!r} has categories {sorted(set(sub.pairs.category))}")
        try:
            c = ctx.build_on(sub)
        except BackendError as exc:  # a backend bound to its model's files (forbidden's map): tests/test_cspace_backend.py checks its categories
            raise NotApplicable(f"the backend builds no Checker on a Model made in process: {exc}") from None
        ref = get_backend(REFERENCE).build(sub, {})
        dmin = np.array([float(np.min(ref.pair_distances(q).distance, initial=np.inf)) for q in Q])
        v = np.asarray(c.collides(Q))
        unsafe = np.flatnonzero(~v & (dmin <= BAND))
        expect(not unsafe.size, lambda: f"{cat} pairs alone, configuration {unsafe[0]}: said clear, coal's least "
                                        f"distance is {dmin[unsafe[0]]:.9g} m; q = {Q[unsafe[0]].tolist()}")
        if not _distances(c):
            continue
        clearest = int(np.argmax(dmin))  # margins either side of the clearest row's least distance
        margins = [0.0, MARGIN] + ([float(dmin[clearest] + EDGE), float(dmin[clearest] - EDGE)]
                                   if np.isfinite(dmin[clearest]) and dmin[clearest] > 2 * EDGE else [])
        for margin in margins:
            v = np.asarray(c.collides(Q, margin=margin))
            bad = np.flatnonzero((np.abs(dmin - margin) > BAND) & (v != (dmin <= margin)))
            expect(not bad.size, lambda: f"{cat} pairs alone, margin {margin:.9g} m, configuration {bad[0]}: collides "
                                         f"{bool(v[bad[0]])}, coal's least distance {dmin[bad[0]]:.9g} m; "
                                         f"q = {Q[bad[0]].tolist()}")
