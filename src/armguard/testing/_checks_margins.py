"""The conformance checks of ``collides``' margins per pair or category and its ``pairs=``
(:mod:`armguard.backends._margins`): the interface contract, as :mod:`._checks`."""

from __future__ import annotations

import numpy as np

from ._checks import BAND, MARGIN, _raises_backend_error, _require_distances, answer, where
from ._suite import NotApplicable, expect

__all__ = ["check_margins_per_pair", "check_collides_pairs"]

SEAM = ("; a CheckerBase subclass's collides (defined in its class body) gets margins per pair and pairs= from the "
        "framework, any other answers them itself: armguard.backends.check_margins, collides_per_pair, subset_verdicts")


def check_margins_per_pair(ctx, model):
    """``collides(Q, margin=m)`` with a margin per pair (an ``(n,)`` array: each pair's own between 0 and
    its median distance, so that the least and the largest margin decide rows otherwise, and the clearest
    configuration's nearest pair's just above its distance) and by category
    (``{first category: 0, "*": 0.05}``) is ``any(distance <= m)`` row by row, except within the contact
    band of a pair's margin (:mod:`armguard.backends._margins`)."""
    c = ctx.checker(model)
    _require_distances(c)
    Q = ctx.configs(model)
    D = np.array([answer(ctx, model, c, q, i).distance for i, q in enumerate(Q)]).reshape(len(Q), -1)
    if D.shape[1] < 2:
        raise NotApplicable("one pair: a margin per pair is one margin")
    m = np.clip(np.median(D, axis=0) * np.random.default_rng(0).random(D.shape[1]), 0.0, 0.2)
    r = int(np.argmax(D.min(axis=1)))  # the clearest configuration: within its nearest pair's margin only
    k = int(np.argmin(D[r]))
    m[k] = max(m[k], D[r, k] + 10 * BAND)
    cats = tuple(c.model.pairs.category)
    by_cat = {cats[0]: 0.0, "*": MARGIN}
    m_cat = np.where(np.asarray(cats) == cats[0], 0.0, MARGIN)
    for what, given, mk in (("an array per pair", m, m), (f"{{{cats[0]!r}: 0, '*': {MARGIN}}}", by_cat, m_cat)):
        v = np.asarray(c.collides(Q, margin=given))
        want = np.any(D <= mk, axis=1)
        clear = ~np.any(np.abs(D - mk) <= BAND, axis=1)
        expect(v.shape == want.shape, lambda: f"margin {what}: collides gave shape {v.shape}, expected {want.shape}")
        bad = np.flatnonzero(clear & (v != want))
        expect(not bad.size, lambda: f"margin {what}, {where(bad[0], Q[bad[0]])}: collides says {bool(v[bad[0]])} but "
                                     f"{'pair ' + str(int(np.argmax(D[bad[0]] <= mk))) + ' is within its margin' if want[bad[0]] else 'every pair is outside its margin'} "
                                     f"(least distance less margin {float(np.min(D[bad[0]] - mk)):.6g} m){SEAM}")


def check_collides_pairs(ctx, model):
    """``collides(Q, pairs=rows)`` (with one margin and with margins per pair) is ``any(distance[rows] <=
    margin[rows])`` row by row, outside the contact band: the pairs of every other row left out, ``pairs=[]``
    all False, a row out of range refused (:func:`armguard.backends.check_pairs`)."""
    c = ctx.checker(model)
    _require_distances(c)
    Q = ctx.configs(model)
    D = np.array([answer(ctx, model, c, q, i).distance for i, q in enumerate(Q)]).reshape(len(Q), -1)
    n = D.shape[1]
    if n < 2:
        raise NotApplicable("one pair: a subset of the pairs is all or none")
    order = np.argsort(D.min(axis=0))
    near_half = order[: max(1, n // 2)]  # the pairs nearest anywhere left out: the rest decide alone
    far_half = np.sort(order[max(1, n // 2):])
    m = np.clip(np.median(D, axis=0) * np.random.default_rng(1).random(n), 0.0, 0.2)
    cats = tuple(c.model.pairs.category)
    by_cat = {cats[0]: 0.0, "*": MARGIN}
    for rows, margin in ((far_half, 0.0), (far_half, MARGIN), (near_half[::-1].copy(), m), (far_half, m), (far_half, by_cat)):
        mk = (np.full(n, margin) if np.ndim(margin) == 0 else margin) if not isinstance(margin, dict) else \
            np.where(np.asarray(cats) == cats[0], 0.0, MARGIN)
        v = np.asarray(c.collides(Q, margin=margin, pairs=rows))
        want = np.any(D[:, rows] <= mk[rows], axis=1)
        clear = ~np.any(np.abs(D[:, rows] - mk[rows]) <= BAND, axis=1)
        expect(v.shape == want.shape, lambda: f"collides(pairs=...) gave shape {v.shape}, expected {want.shape}")
        bad = np.flatnonzero(clear & (v != want))
        what = "one margin" if np.ndim(margin) == 0 else "margins by category" if isinstance(margin, dict) else "margins per pair"
        expect(not bad.size, lambda: f"pairs={rows.tolist()[:6]}{'...' if len(rows) > 6 else ''} ({what}), "
                                     f"{where(bad[0], Q[bad[0]])}: collides says {bool(v[bad[0]])}, those pairs' least "
                                     f"distance less margin is {float(np.min(D[bad[0], rows] - mk[rows])):.6g} m{SEAM}")
    none = np.asarray(c.collides(Q, pairs=np.zeros(0, dtype=np.int64)))
    expect(none.shape == (len(Q),) and not none.any(), lambda: f"collides(pairs=[]) gave {none}, expected all False")
    _raises_backend_error(lambda: c.collides(Q, pairs=[n]), f"collides(pairs=[{n}]) (a row past the Model's {n} pairs)")
