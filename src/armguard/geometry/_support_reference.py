"""The slow, obviously-correct signed distance of two convex shapes, for differential checks.

The signed distance of two convex sets is ``-min_{|n| = 1} (h_A(n) + h_B(-n))``, ``h`` their
support functions (the distance when they are apart, minus the penetration depth when they
overlap).  Every armguard shape's support is exact (a cylinder's in closed form, the others' the
best core point plus the core radius); the minimum over the sphere of directions is taken over 6,000
Fibonacci directions, then polished by Nelder-Mead from the six best.  No GJK, no EPA: it shares no
code with any backend's kernels (the shapes themselves, a mesh hull's vertices included, are the
Model's, which every backend reads), so a backend's distance or depth is checked against geometry alone.  About
20-150 ms a pair on primitives and small hulls, up to ~1.5 s on hulls of thousands of vertices (the
first call also imports SciPy's optimiser).  ``armguard compare`` calls it on the worst
entries where two backends differ beyond tolerance, to say which is right
(:mod:`armguard.harness._compare`); ``bench sweep`` on the depths that differ.  ``tests/test_geometry_cylinder_depth.py`` holds it to 1e-12 m against the same
minimum taken one direction at a time (``tests/test_geometry_cylinder.py``).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["reference_signed_distance", "reference_wall_distance"]


def _fibonacci(k: int) -> np.ndarray:
    i = np.arange(k) + 0.5
    phi = np.arccos(1 - 2 * i / k)
    th = math.pi * (1 + 5**0.5) * i
    return np.stack([np.cos(th) * np.sin(phi), np.sin(th) * np.sin(phi), np.cos(phi)], 1)


_DIRS = _fibonacci(6000)


def _h_closed(shape, N) -> np.ndarray:
    """Support values ``h(n) = max_x n . x`` of ``shape`` along the unit rows of ``N (k, 3)``: the
    cylinder's closed form (``c . n + h |a . n| + r sqrt(1 - (a . n)^2)``, ``a`` its axis), else the
    core points' maximum plus the core radius (``Shape.support``, all directions at once)."""
    from ._cylinder import Cylinder

    N = np.atleast_2d(N)
    if isinstance(shape, Cylinder):
        an = N @ shape.rotation[:, 2]
        return N @ shape.center + shape.half_length * np.abs(an) + shape.radius * np.sqrt(np.maximum(0.0, 1 - an * an))
    return (N @ shape.core_points.T).max(axis=1) + shape.core_radius


def reference_signed_distance(a, b, support=None) -> float:
    """Signed distance (m) of armguard shapes ``a`` and ``b``: ``-min_n (h_A(n) + h_B(-n))``
    over unit ``n`` (see the module docstring).  ``support(shape, N (k, 3)) -> (k,)``: the support
    values ``h`` (default the closed forms of :func:`_h_closed`; ``tests/test_geometry_cylinder.py`` passes
    the shapes' own ``support`` one direction at a time, a second reference for this one)."""
    from scipy.optimize import minimize

    _h = support or _h_closed
    f = _h(a, _DIRS) + _h(b, -_DIRS)
    best = math.inf
    for k in np.argsort(f)[:6]:
        n0 = _DIRS[k]
        e1 = np.cross(n0, [1.0, 0, 0] if abs(n0[0]) < 0.9 else [0, 1.0, 0])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(n0, e1)

        def g(uv, n0=n0, e1=e1, e2=e2):
            n = n0 + uv[0] * e1 + uv[1] * e2
            n /= np.linalg.norm(n)
            return float(_h(a, n)[0] + _h(b, -n)[0])

        res = minimize(g, np.zeros(2), method="Nelder-Mead",
                       options={"xatol": 1e-11, "fatol": 1e-13, "maxiter": 4000, "initial_simplex":
                                np.array([[0, 0], [0.05, 0], [0, 0.05]])})
        best = min(best, float(res.fun), float(f[k]))
    return -best


def reference_wall_distance(shape, lo, hi) -> float:
    """Signed distance (m) of ``shape`` to the walls of the axis-aligned box ``[lo, hi]`` it should stay
    in (Ranger's workspace): the least over the six walls of the room left between the shape's extreme
    point along the wall's normal and the wall, ``hi_k - h(e_k)`` and ``h(-e_k) + lo_k`` sign-flipped
    (``-h(-e_k) - lo_k``), negative where the shape crosses a wall.  Six support values: exact."""
    E = np.eye(3)
    up = np.asarray(hi, dtype=np.float64) - _h_closed(shape, E)
    down = -_h_closed(shape, -E) - np.asarray(lo, dtype=np.float64)
    return float(min(up.min(), down.min()))
