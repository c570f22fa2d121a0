"""The one dispatch table: (core kind of A, core kind of B) -> kernel, and ``distance``/``intersects``.

As coal's ``collision_func_matrix.h``: adding a shape pair is one kernel file and one line in
``_TABLE``.  A pair stored as (B, A) is answered by the (A, B) kernel with the result swapped.
The per-type table ``_BY_TYPE`` is derived from ``_TABLE`` once, so a call costs one dict
lookup and one compiled call on the shapes' packed buffers (see ``_pack``).
"""

from __future__ import annotations

import numpy as np
from numba import njit, types

from .._errors import GeometryError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from ._cylinder import Cylinder
from ._pair_box_box import box_box_overlap_packed
from ._pair_cylinder import SUPPORT_WORK_SIZE, support_pair
from ._pair_point_cylinder import point_cylinder_flat
from ._pair_epa import EPA_WORK_SIZE, convex_convex_fast
from ._pair_gjk import CLIMB_MIN_VERTICES, GJK_NOT_CONVERGED, GJK_WORK_SIZE
from ._pair_sat import convex_convex
from ._pack import polytope_adjacency, polytope_buffers, polytope_data
from ._pair_segment_box import capsule_box_packed
from ._pair_segment_polytope import capsule_polytope_packed
from ._pair_segment_segment import capsule_capsule_packed
from ._proximity import Proximity, proximity_from_buffer as _proximity
from ._shapes import Box, Capsule, ConvexPolyhedron, CoreKind, Polygon, Prism, Shape, Sphere

__all__ = ["distance", "intersects", "kernel_name"]


@njit(cache=True)
def _swap_out(out):  # pragma: no cover - compiled
    for k in range(3):
        t = out[k]
        out[k] = out[3 + k]
        out[3 + k] = t
        out[6 + k] = -out[6 + k]


@njit(cache=True)
def _box_capsule_packed(box, cap, out, eps_len, eps_par, offset):  # pragma: no cover - compiled
    d = capsule_box_packed(cap, box, out, eps_len, eps_par, offset)
    _swap_out(out)
    return d


# The closed-form kernels are called through their compiled entry points for one explicit
# signature (C-contiguous float64 buffers, float64 tolerances): numba's dispatcher would type
# every argument on every call, which costs more than the query itself.  Bound at first use
# (``Dispatcher.compile`` loads the on-disk cache or compiles), so importing stays cheap.
_BUF = types.float64[::1]
_CC_SIG = (_BUF, _BUF, _BUF, types.float64, types.float64)
_CB_SIG = (_BUF, _BUF, _BUF, types.float64, types.float64, types.float64)
_CP_SIG = (_BUF, _BUF, types.int64[::1], _BUF, types.float64, types.float64, types.float64, types.int64, types.float64)
_cc_entry = None
_cb_entry = None
_bc_entry = None
_cp_entry = None


def _bind_entries():
    global _cc_entry, _cb_entry, _bc_entry, _cp_entry
    _cc_entry = capsule_capsule_packed.compile(_CC_SIG)
    _cb_entry = capsule_box_packed.compile(_CB_SIG)
    _bc_entry = _box_capsule_packed.compile(_CB_SIG)
    _cp_entry = capsule_polytope_packed.compile(_CP_SIG)


def _rounded_segments(a, b, tol: Tolerances) -> Proximity:
    if _cc_entry is None:
        _bind_entries()
    out = np.empty(9)
    return _proximity(_cc_entry(a._pk, b._pk, out, tol.length, tol.parallel), out)


def _segment_box(a, b, tol: Tolerances) -> Proximity:
    if _cb_entry is None:
        _bind_entries()
    out = np.empty(9)
    return _proximity(_cb_entry(a._pk, b._pk, out, tol.length, tol.parallel, tol.penetration_witness_offset), out)


def _box_segment(a, b, tol: Tolerances) -> Proximity:
    if _bc_entry is None:
        _bind_entries()
    out = np.empty(9)
    return _proximity(_bc_entry(a._pk, b._pk, out, tol.length, tol.parallel, tol.penetration_witness_offset), out)


def _not_converged(a, b, tol: Tolerances) -> GeometryError:
    return GeometryError(
        f"distance({type(a).__name__}, {type(b).__name__}): GJK did not converge in "
        f"{tol.gjk_max_iterations} iterations (Tolerances.gjk_max_iterations)"
    )


def _segment_polytope(a, b, tol: Tolerances) -> Proximity:
    if _cp_entry is None:
        _bind_entries()
    fb, ib = polytope_buffers(b)
    out = np.empty(9)
    d, status = _cp_entry(
        a._pk, fb, ib, out, tol.length, tol.parallel, tol.gjk_epsilon, tol.gjk_max_iterations,
        tol.penetration_witness_offset,
    )
    if status == GJK_NOT_CONVERGED:
        raise _not_converged(a, b, tol)
    return _proximity(d, out)


def _polytope_segment(a, b, tol: Tolerances) -> Proximity:
    if _cp_entry is None:
        _bind_entries()
    fb, ib = polytope_buffers(a)
    out = np.empty(9)
    d, status = _cp_entry(
        b._pk, fb, ib, out, tol.length, tol.parallel, tol.gjk_epsilon, tol.gjk_max_iterations,
        tol.penetration_witness_offset,
    )
    if status == GJK_NOT_CONVERGED:
        raise _not_converged(a, b, tol)
    _swap_out(out)
    return _proximity(d, out)


_NO_GRAPH = np.zeros(0, dtype=np.int64)
_NO_TRI = np.zeros((0, 3), dtype=np.int64)


def _climb_graph(shape) -> np.ndarray:
    """The vertex graph GJK and EPA climb on ``shape``'s core points: a ConvexPolyhedron of
    ``CLIMB_MIN_VERTICES`` or more vertices (its ``polytope_adjacency``), else empty (the supports
    scan the points).  Cached on the shape (shapes are immutable)."""
    try:
        return shape._climb
    except AttributeError:
        g = _NO_GRAPH
        pts = shape._sat[0]
        if isinstance(shape, ConvexPolyhedron) and len(pts) >= CLIMB_MIN_VERTICES:
            v = polytope_data(shape)[0]
            if v.shape == pts.shape and np.array_equal(v, pts):  # the graph indexes these very points
                g = polytope_adjacency(shape)
        object.__setattr__(shape, "_climb", g)
        return g


def _convex(a, b, tol: Tolerances) -> Proximity:
    """Polytope pairs: GJK + exhaustive SAT for small cores (its few axes cost less than EPA's set-up),
    GJK climbing the vertex graphs + EPA when either core is a hull with a graph (the SAT's
    edge-edge axes grow as E_A * E_B: seconds for two 500-vertex hulls, against tens of µs)."""
    pa, fa, ea, ra = a._sat
    pb, fb, eb, rb = b._sat
    ga, gb = _climb_graph(a), _climb_graph(b)
    out = np.empty(9)
    if len(ga) == 0 and len(gb) == 0:
        d, status = convex_convex(
            pa, fa, ea, ra, pb, fb, eb, rb, out, np.empty(GJK_WORK_SIZE), tol.length, tol.parallel, tol.gjk_epsilon,
            tol.gjk_max_iterations, tol.penetration_witness_offset,
        )
    else:
        d, status = convex_convex_fast(
            pa, fa, ea, ga, _NO_TRI, ra, pb, fb, eb, gb, _NO_TRI, rb, out, np.empty(EPA_WORK_SIZE),
            tol.length, tol.parallel, tol.gjk_epsilon, tol.gjk_max_iterations, tol.penetration_witness_offset, -np.inf,
        )
    if status == GJK_NOT_CONVERGED:
        raise _not_converged(a, b, tol)
    return _proximity(d, out)


_NO_CYL = np.zeros(0)


def _support_core(s):
    """``(points, cylinder buffer, radius)`` of a shape for ``_pair_cylinder`` (a Cylinder: its
    15-float buffer; any other shape: its core points, an empty buffer and its core radius)."""
    if isinstance(s, Cylinder):
        return s._sat[0], s._pk, 0.0
    return s._sat[0], _NO_CYL, s._sat[3]


def _cylinder_pair(a, b, tol: Tolerances) -> Proximity:
    """A Cylinder against any shape: GJK + EPA on support functions (``_pair_cylinder``)."""
    pa, ca, ra = _support_core(a)
    pb, cb, rb = _support_core(b)
    out = np.empty(9)
    d, status = support_pair(pa, ca, ra, pb, cb, rb, out, np.empty(SUPPORT_WORK_SIZE), tol.length, tol.gjk_epsilon,
                             tol.gjk_max_iterations, -np.inf)
    if status == GJK_NOT_CONVERGED:
        raise _not_converged(a, b, tol)
    return _proximity(d, out)


def _point_cylinder(a, b, tol: Tolerances) -> Proximity:
    """A Sphere against a Cylinder: the closed form (``_pair_point_cylinder``; exact, no iterations)."""
    p, out = a._sat[0][0], np.empty(9)
    return _proximity(point_cylinder_flat(p[0], p[1], p[2], a._sat[3], b._pk, 0, 0.0, out, 0), out)


def _cylinder_point(a, b, tol: Tolerances) -> Proximity:
    """:func:`_point_cylinder` with the sides swapped back (witnesses exchanged, the normal negated)."""
    p, out = b._sat[0][0], np.empty(9)
    d = point_cylinder_flat(p[0], p[1], p[2], b._sat[3], a._pk, 0, 0.0, out, 0)
    return _proximity(d, np.concatenate([out[3:6], out[0:3], -out[6:9]]))


_P, _S, _B, _T = CoreKind.POINT, CoreKind.SEGMENT, CoreKind.BOX, CoreKind.POLYTOPE
_C = CoreKind.CYLINDER

# (core kind A, core kind B) -> (kernel, kernel name)
_TABLE = {
    (_P, _P): (_rounded_segments, "capsule_capsule"),
    (_P, _S): (_rounded_segments, "capsule_capsule"),
    (_S, _P): (_rounded_segments, "capsule_capsule"),
    (_S, _S): (_rounded_segments, "capsule_capsule"),
    (_P, _B): (_segment_box, "capsule_box"),
    (_S, _B): (_segment_box, "capsule_box"),
    (_B, _P): (_box_segment, "capsule_box (swapped)"),
    (_B, _S): (_box_segment, "capsule_box (swapped)"),
    (_B, _B): (_convex, "convex_convex (GJK + SAT; hulls of 48+ vertices: GJK on vertex graphs + EPA)"),
    (_P, _T): (_segment_polytope, "capsule_polytope (GJK + Minkowski facets)"),
    (_T, _P): (_polytope_segment, "capsule_polytope (swapped)"),
    (_S, _T): (_segment_polytope, "capsule_polytope (GJK + Minkowski facets)"),
    (_T, _S): (_polytope_segment, "capsule_polytope (swapped)"),
    (_B, _T): (_convex, "convex_convex (GJK + SAT; hulls of 48+ vertices: GJK on vertex graphs + EPA)"),
    (_T, _B): (_convex, "convex_convex (GJK + SAT; hulls of 48+ vertices: GJK on vertex graphs + EPA)"),
    (_T, _T): (_convex, "convex_convex (GJK + SAT; hulls of 48+ vertices: GJK on vertex graphs + EPA)"),
}
for _k in (_P, _S, _B, _T, _C):
    _TABLE[(_C, _k)] = _TABLE[(_k, _C)] = (_cylinder_pair, "support_pair (GJK + EPA on support functions)")
_TABLE[(_P, _C)] = (_point_cylinder, "point_cylinder (closed form)")
_TABLE[(_C, _P)] = (_cylinder_point, "point_cylinder (closed form, swapped)")

_SHAPES = (Sphere, Capsule, Box, Prism, ConvexPolyhedron, Polygon, Cylinder)
_BY_TYPE = {(ta, tb): _TABLE[(ta.core_kind, tb.core_kind)][0] for ta in _SHAPES for tb in _SHAPES}


def _lookup(a, b):
    fn = _BY_TYPE.get((type(a), type(b)))
    if fn is None:
        for name, s in (("a", a), ("b", b)):
            if not isinstance(s, Shape):
                raise GeometryError(f"{name}: expected an armguard shape, got {type(s).__name__}")
        fn = _TABLE[(a.core_kind, b.core_kind)][0]  # a subclass of a known shape
    return fn


def kernel_name(a: Shape, b: Shape) -> str:
    """Which kernel answers ``distance(a, b)`` (for reports and the demo table)."""
    for name, s in (("a", a), ("b", b)):
        if not isinstance(s, Shape):
            raise GeometryError(f"{name}: expected an armguard shape, got {type(s).__name__}")
    return _TABLE[(a.core_kind, b.core_kind)][1]


def distance(a: Shape, b: Shape, tol: Tolerances = DEFAULT_TOLERANCES) -> Proximity:
    """Exact signed distance between two shapes, with witness points.

    Returns a :class:`Proximity`: ``distance`` (m; > 0 apart, < 0 penetrating with magnitude the
    penetration depth), ``p_WA``, ``p_WB`` ``(3,) float64, m`` on the surfaces of ``a`` and
    ``b`` and ``nhat_AB_W`` with ``p_WB - p_WA == distance * nhat_AB_W``.  Any pair of Sphere,
    Capsule, Box, Prism, ConvexPolyhedron, Polygon and Cylinder.  Raises GeometryError on a non-shape
    argument or if GJK fails to converge within ``tol.gjk_max_iterations``.
    """
    fn = _BY_TYPE.get((type(a), type(b))) or _lookup(a, b)
    return fn(a, b, tol)


def intersects(a: Shape, b: Shape, tol: Tolerances = DEFAULT_TOLERANCES) -> bool:
    """True when the shapes overlap or touch: ``distance(a, b, tol).distance <= tol.length``.

    ``Tolerances.length`` is the one contact tolerance: the Detector's collision status uses the
    same rule.  Two boxes first go through the division-free JPL separating-axis test, whose
    ``tol.parallel`` slack only errs towards overlap: a separation it finds is final, an overlap
    it reports is confirmed by the distance (so the answer is the same rule for every pair).
    """
    if type(a) is Box and type(b) is Box and not box_box_overlap_packed(a._pk, b._pk, tol.parallel):
        return False
    return distance(a, b, tol).distance <= tol.length
