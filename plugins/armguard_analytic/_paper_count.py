"""Operation counts of the ``fidelity = "paper"`` Hermes check, for seed ``001`` §4's table.

Hermes §4 reports, over 1,000 random configurations, 1651 multiplications per check on average
(SD 195, at most 6064) and "about 11,000" FLOP in the worst case, weighting "a multiplication 1
time unit, a sum 1/3, a square root 3 and a transcendental call 7"; with ``C = 11 f`` kFLOPS and
"about 18 kFLOPS" the checks run at 1.7 Hz.

The counts here are not estimates: :func:`count_rows` runs the *source* of the compiled kernels
(``_paper_rows`` with every Hermes module, and ``_fk_kernel``) as plain Python, with their
globals rebound so that every helper is its own Python source too, on :class:`Flop` numbers that
count each arithmetic operation they take part in.  Every branch the kernels take is therefore
counted as it is taken.  Conventions: a division counts as a multiplication (and is also
reported on its own), a subtraction as a sum, ``abs`` and negation are free (sign bits),
comparisons are counted apart and weigh nothing; ``math.sqrt`` 3, ``cos``/``sin`` 7 (the paper's
weights).  Index arithmetic (Python ints) is not floating point and is not counted.  Operations
are booked to the module running them (``MODULES``) or to ``"kinematics"`` (forward kinematics
and moving the link and payload end-points into W).
"""

from __future__ import annotations

import math
import types

import numpy as np

__all__ = ["Flop", "Counter", "count_call", "count_rows", "flop", "WEIGHTS", "FIELDS"]

FIELDS = ("mul", "div", "add", "sqrt", "trig", "cmp")
WEIGHTS = {"mul": 1.0, "div": 1.0, "add": 1.0 / 3.0, "sqrt": 3.0, "trig": 7.0, "cmp": 0.0}


class Counter:
    """Operation tallies per bucket: ``counts[bucket][field]``; ``bucket`` the one being charged."""

    def __init__(self) -> None:
        self.counts: dict[str, dict[str, int]] = {}
        self.bucket = "kinematics"

    def tick(self, field: str) -> None:
        b = self.counts.get(self.bucket)
        if b is None:
            b = self.counts[self.bucket] = dict.fromkeys(FIELDS, 0)
        b[field] += 1


_ACTIVE: list[Counter] = []


def _tick(field: str) -> None:
    _ACTIVE[-1].tick(field)


def _val(x):
    return x.v if isinstance(x, Flop) else x


class Flop:
    """A float that books every arithmetic operation on it to the active :class:`Counter`."""

    __slots__ = ("v",)

    def __init__(self, v) -> None:
        self.v = float(v)

    def __repr__(self) -> str:
        return f"Flop({self.v!r})"

    def __float__(self) -> float:
        return self.v

    def _op(self, other, field, fn):
        if not isinstance(other, (Flop, float, int)):
            return NotImplemented
        _tick(field)
        return Flop(fn(self.v, _val(other)))

    __add__ = lambda s, o: s._op(o, "add", lambda a, b: a + b)  # noqa: E731
    __radd__ = lambda s, o: s._op(o, "add", lambda a, b: b + a)  # noqa: E731
    __sub__ = lambda s, o: s._op(o, "add", lambda a, b: a - b)  # noqa: E731
    __rsub__ = lambda s, o: s._op(o, "add", lambda a, b: b - a)  # noqa: E731
    __mul__ = lambda s, o: s._op(o, "mul", lambda a, b: a * b)  # noqa: E731
    __rmul__ = lambda s, o: s._op(o, "mul", lambda a, b: b * a)  # noqa: E731
    __truediv__ = lambda s, o: s._op(o, "div", lambda a, b: a / b)  # noqa: E731
    __rtruediv__ = lambda s, o: s._op(o, "div", lambda a, b: b / a)  # noqa: E731

    def __neg__(self):
        return Flop(-self.v)

    def __abs__(self):
        return Flop(abs(self.v))

    def _cmp(self, other, fn):
        if not isinstance(other, (Flop, float, int)):
            return NotImplemented
        _tick("cmp")
        return fn(self.v, _val(other))

    __lt__ = lambda s, o: s._cmp(o, lambda a, b: a < b)  # noqa: E731
    __le__ = lambda s, o: s._cmp(o, lambda a, b: a <= b)  # noqa: E731
    __gt__ = lambda s, o: s._cmp(o, lambda a, b: a > b)  # noqa: E731
    __ge__ = lambda s, o: s._cmp(o, lambda a, b: a >= b)  # noqa: E731
    __eq__ = lambda s, o: s._cmp(o, lambda a, b: a == b)  # noqa: E731
    __ne__ = lambda s, o: s._cmp(o, lambda a, b: a != b)  # noqa: E731
    __hash__ = None

    def cos(self):  # numpy's ufuncs on object arrays call these
        _tick("trig")
        return Flop(math.cos(self.v))

    def sin(self):
        _tick("trig")
        return Flop(math.sin(self.v))


def _sqrt(x):
    _tick("sqrt")
    return Flop(math.sqrt(_val(x)))


_math = types.SimpleNamespace(sqrt=_sqrt, inf=math.inf, nan=math.nan, isfinite=lambda x: math.isfinite(_val(x)))
_np = types.SimpleNamespace(empty=lambda shape, dtype=None: np.full(shape, Flop(0.0), dtype=object),
                            cos=lambda x: x.cos() if isinstance(x, Flop) else math.cos(x),
                            sin=lambda x: x.sin() if isinstance(x, Flop) else math.sin(x))


def _python(fn, cache: dict, wrap: dict):
    """``fn``'s Python source (a numba dispatcher's ``py_func``) with its globals rebound: every
    compiled helper it calls to its own rebound source, ``math``/``np`` to the counting shims, and
    the names in ``wrap`` to ``wrap[name](rebound)``."""
    py = getattr(fn, "py_func", fn)
    if py in cache:
        return cache[py]
    g = dict(py.__globals__)
    out = types.FunctionType(py.__code__, g, py.__name__, py.__defaults__, py.__closure__)
    cache[py] = out
    for name, val in list(g.items()):
        if hasattr(val, "py_func"):
            g[name] = _python(val, cache, wrap)
            if name in wrap:
                g[name] = wrap[name](g[name])
    g["math"], g["np"] = _math, _np
    return out


def _charged(fn):
    """``_hermes_pair`` booking its operations to the module its ``code`` names."""
    from ._paper_hermes import MODULES

    def run(code, *args):
        c = _ACTIVE[-1]
        prev, c.bucket = c.bucket, MODULES[int(code)]
        try:
            return fn(code, *args)
        finally:
            c.bucket = prev
    return run


def _flops(a):
    a = np.asarray(a, dtype=np.float64)
    return np.vectorize(Flop, otypes=[object])(a) if a.size else a.astype(object)


def count_call(kernel, *args):
    """Run compiled ``kernel``'s source on ``args`` (floats and 3-tuples of floats become :class:`Flop`;
    arrays of float64 become arrays of them): ``(result, tallies)`` with every operation booked."""
    def conv(x):
        if isinstance(x, float):
            return Flop(x)
        if isinstance(x, tuple):
            return tuple(conv(y) for y in x)
        if isinstance(x, np.ndarray) and x.dtype == np.float64:
            return _flops(x)
        return x

    c = Counter()
    _ACTIVE.append(c)
    try:
        res = _python(kernel, {}, {})(*(conv(a) for a in args))
    finally:
        _ACTIVE.pop()
    return res, c.counts.get("kinematics", dict.fromkeys(FIELDS, 0))


def count_rows(checker, Q, margin: float = 0.0) -> tuple[list[dict], np.ndarray]:
    """Count the operations of ``checker``'s (a Hermes :class:`PaperChecker`) per-pair check at each row
    of ``Q`` (M, nq), every pair evaluated (``pair_verdicts_many``'s rule): returns ``(counts, hit)``,
    ``counts[m][bucket][field]`` and ``hit`` (M, n) the verdicts the counted run reached."""
    from ._paper_kernels import _paper_rows

    run = _python(_paper_rows, {}, {"_hermes_pair": _charged})
    Qs = checker.model.scene_q(np.atleast_2d(Q))
    T = tuple(_flops(x) if np.asarray(x).dtype == np.float64 else x for x in checker._T)
    E = tuple(_flops(x) if np.asarray(x).dtype == np.float64 else x for x in checker._E)
    H = checker._H[:3] + (_flops(checker._H[3]),)
    P = checker._n
    eps = tuple(Flop(x) if isinstance(x, float) else x for x in checker._eps)  # the kernels square them per call
    out = []
    hits = np.zeros((len(Qs), P), dtype=bool)
    for m in range(len(Qs)):
        c = Counter()
        _ACTIVE.append(c)
        try:
            out_d = np.full((1, P), Flop(0.0), dtype=object)
            out_mod = np.zeros((1, P, 2), dtype=np.int64)
            bad = run(_flops(Qs[m:m + 1]), T, E, checker._R, 2, Flop(margin), H, False, out_d, np.empty((0, P, 6)),
                      np.zeros(0, dtype=bool), out_mod, eps, np.zeros(1))
        finally:
            _ACTIVE.pop()
        if bad >= 0:
            raise RuntimeError("count_rows: a pair fell back to the exact kernels; counts cover Hermes's modules only")
        hits[m] = out_mod[0, :, 0] == 1
        out.append(c.counts)
    return out, hits


def flop(counts: dict) -> float:
    """The paper's weighted FLOP of one bucket's tallies (seed 001 §4's time units)."""
    return sum(WEIGHTS[k] * counts.get(k, 0) for k in FIELDS)
