"""Exact signed distances between posed link hulls and terrain cell columns, compiled.

The pyramid's exact mode (:meth:`TerrainPyramid.check` with ``exact=True``) confirms each
candidate (link, cell) with :func:`armguard.geometry.distance` on shape objects; a
:class:`~armguard.terrain.TerrainGuard` that poses the same links at many configurations keeps
their hulls as arrays instead (vertices, face normals, edge directions in W) and runs the same
narrow phase, :func:`armguard.geometry.kernels.convex_convex` (GJK, SAT depth when they
overlap), over every candidate in one call.  A cell's column is the axis-aligned box from the
map's floor to the cell's height (thickness at least ``Tolerances.length``, as
:meth:`TerrainPyramid.cell_box`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..geometry._pair_gjk import GJK_NOT_CONVERGED, GJK_WORK_SIZE
from ..geometry.kernels import convex_convex

__all__ = ["column_distances"]


@njit(cache=True)
def column_distances(pa, ps, fa, fs, ea, es, ra, link, lo, hi, thick, out_d, out_w, eps_len, eps_par, gjk_eps,
                     max_iter, offset):  # pragma: no cover - compiled
    """Signed distance of each candidate pair ``i``: link ``link[i]`` against the column ``[lo[i], hi[i]]``.

    Parameters
    ----------
    pa : (V, 3) float64, m
        Every link's hull vertices in W, link ``k``'s rows ``ps[k]:ps[k + 1]``.
    fa, ea : (F, 3), (E, 3) float64
        Unit face normals / edge directions in W, rows ``fs[k]:fs[k + 1]``, ``es[k]:es[k + 1]``.
    ra : (K,) float64, m
        Each link's core radius.
    link : (n,) int64
    lo, hi : (n, 3) float64, m
        The columns' corners.
    thick : float, m
        Least half extent of a column (a zero-height column is that thick).
    out_d : (n,) float64, m
    out_w : (n, 6) float64, m
        Witness points ``[p_WA (link), p_WB (column)]``.

    Returns the index of the first pair GJK did not converge on, or -1.
    """
    work = np.empty(GJK_WORK_SIZE)
    out = np.empty(9)
    pb = np.empty((8, 3))
    eye = np.eye(3)
    for i in range(link.shape[0]):
        k = link[i]
        for j in range(3):
            c = 0.5 * (lo[i, j] + hi[i, j])
            h = 0.5 * (hi[i, j] - lo[i, j])
            if h < thick:
                h = thick
            for v in range(8):
                pb[v, j] = c + h if (v >> j) & 1 else c - h
        d, st = convex_convex(pa[ps[k]:ps[k + 1]], fa[fs[k]:fs[k + 1]], ea[es[k]:es[k + 1]], ra[k], pb, eye, eye,
                              0.0, out, work, eps_len, eps_par, gjk_eps, max_iter, offset)
        if st == GJK_NOT_CONVERGED:
            return i
        out_d[i] = d
        for j in range(6):
            out_w[i, j] = out[j]
    return -1
