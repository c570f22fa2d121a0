"""Support tables: where a hull's support climbs start, by direction.

A hull's support table (:func:`armguard.geometry._pack.support_table`) holds, for each cell of a
cube map of directions, the vertex farthest along that cell's centre.  GJK's and EPA's climbs over
the hull's vertex graph (``_pair_gjk._climb``) start there or at the previous support, whichever is
farther along the new direction (Cameron, "Enhancing GJK", ICRA 1997: warm-started climbs); any
start is correct, a climb over the graph ends at a true support vertex, the table only shortens
the walk.  Split from ``_pair_gjk`` (which re-exports these names).
"""

from __future__ import annotations

import math

from numba import njit

__all__ = ["TABLE_N", "table_cell", "table_size", "table_start", "warm_start"]

TABLE_N = 16
"""Cells per cube face edge of the support tables :func:`armguard.geometry._pack.support_table` makes
(``6 n n`` entries): :func:`table_size` knows this size without a square root."""


@njit(cache=True, inline="always")
def table_cell(dx, dy, dz, n):  # pragma: no cover - compiled
    """The cube-map cell of direction ``d`` (see :func:`armguard.geometry._pack.support_table`), or -1
    for the zero vector.  Inlined, with one division (a compiled call of its own showed in
    ``perf`` samples of ur5's ``pair_distances``).  The face chosen by selects instead of these
    branches (which mispredict when the direction changes) left ur3's and ur5's kernels as they were
    (20.8 / 13.1 against 20.1 / 13.0 us, 2026-12-05)."""
    x = abs(dx)
    y = abs(dy)
    z = abs(dz)
    if x >= y and x >= z:
        f = 0 if dx >= 0.0 else 1
        m, u, v = x, dy, dz
    elif y >= z:
        f = 2 if dy >= 0.0 else 3
        m, u, v = y, dx, dz
    else:
        f = 4 if dz >= 0.0 else 5
        m, u, v = z, dx, dy
    if not m > 0.0:
        return -1
    h = 0.5 * n / m
    iu = min(max(int(u * h + 0.5 * n), 0), n - 1)
    iv = min(max(int(v * h + 0.5 * n), 0), n - 1)
    return (f * n + iu) * n + iv


@njit(cache=True, inline="always")
def table_size(tab):  # pragma: no cover - compiled
    """``n`` of a support table of ``6 n n`` entries (0: ``None`` or empty)."""
    if tab is None:
        return 0
    m = tab.shape[0]
    if m == 6 * TABLE_N * TABLE_N:  # the tables the engine makes, without the division and square root that
        return TABLE_N  # showed in ``perf`` samples (z1's pair_distances ~2 % faster, hull robots within noise)
    if m == 0:
        return 0
    return int(math.sqrt(m / 6.0) + 0.5)


@njit(cache=True, inline="always")
def warm_start(p, tab, n, i, dx, dy, dz):  # pragma: no cover - compiled
    """Where a warm climb along ``d`` starts: vertex ``i`` (the previous support), or ``tab``'s entry
    for ``d`` (``n`` its :func:`table_size`; 0: no table) when that is farther along ``d``.  Any start
    is correct (a climb ends at a true support); after GJK's first step the search direction turns by
    tens of degrees, and a climb from the previous support took 4-6 steps where one from the table's
    entry takes 1-2."""
    if n == 0:
        return i
    k = table_cell(dx, dy, dz, n)
    if k < 0:
        return i
    c = tab[k]
    if p[c, 0] * dx + p[c, 1] * dy + p[c, 2] * dz > p[i, 0] * dx + p[i, 1] * dy + p[i, 2] * dz:
        return c
    return i


@njit(cache=True, inline="always")
def table_start(tab, dx, dy, dz):  # pragma: no cover - compiled
    """Where a cold climb along ``d`` starts: ``tab``'s entry for ``d`` (-1, the stored extremes,
    when ``tab`` is empty or ``d`` zero).  ``tab`` has ``6 n n`` entries."""
    n = table_size(tab)
    if n == 0:
        return -1
    k = table_cell(dx, dy, dz, n)
    return tab[k] if k >= 0 else -1
