"""Batched pairwise queries over arrays of pairs, broadcasting over leading axes.

Each function takes the parameters of shape A and shape B as arrays whose leading axes
broadcast together (``(..., 3)`` points, ``(...)`` radii) and returns one result object with
arrays of the broadcast shape.  The loops run in numba over the scalar kernels that
``distance()`` uses, so batched and single answers agree bit for bit.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numba import njit

from .._errors import GeometryError
from .._tolerance import DEFAULT_TOLERANCES, Tolerances
from ._pair_box_box import box_box_overlap_scalar
from ._pair_gjk import GJK_NOT_CONVERGED
from ._pack import polytope_adjacency, polytope_data
from ._pair_segment_polytope import capsule_polytope_adj_at
from ._pair_segment_box import capsule_box_scalar
from ._pair_segment_segment import capsule_capsule_scalar
from ._shapes import Box, ConvexPolyhedron, Polygon, Prism

__all__ = [
    "BatchProximity",
    "sphere_sphere",
    "capsule_capsule",
    "capsule_box",
    "capsule_convex",
    "box_box_overlap",
]


@dataclass(frozen=True)
class BatchProximity:
    """Signed distances and witness points of a batch of pairs (invariants as :class:`Proximity`).

    ``distance : (...) float64, m``; ``p_WA, p_WB : (..., 3) float64, m``;
    ``nhat_AB_W : (..., 3) float64`` unit, with ``p_WB - p_WA == distance * nhat_AB_W``.
    """

    distance: np.ndarray
    p_WA: np.ndarray
    p_WB: np.ndarray
    nhat_AB_W: np.ndarray


_MAX_MAGNITUDE = DEFAULT_TOLERANCES.max_magnitude  # compiled in: the scalar API's bound on every length (m)


def _arr(x, name: str, trailing: tuple, check: bool = True) -> np.ndarray:
    try:
        a = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise GeometryError(f"{name}: expected numbers") from exc
    if a.shape[a.ndim - len(trailing):] != trailing or a.ndim < len(trailing):
        raise GeometryError(f"{name}: expected shape (..., {', '.join(map(str, trailing))}), got {a.shape}")
    if check and not np.all(np.isfinite(a)):
        raise GeometryError(f"{name}: contains NaN or infinite values")
    if check and a.size and max(float(a.max()), -float(a.min())) > _MAX_MAGNITUDE:  # as the scalar API (no temporary)
        raise GeometryError(f"{name}: a value beyond {_MAX_MAGNITUDE:g} (Tolerances.max_magnitude)")
    return a


def _radius(x, name: str) -> np.ndarray:
    a = _arr(x, name, ())
    if np.any(a < 0.0):
        raise GeometryError(f"{name}: radii must be >= 0")
    return a


def _flat(arrays: list[tuple[np.ndarray, tuple]], copy: bool = True):
    """Broadcast leading axes; return the shape and (N, *trailing) arrays: C-contiguous copies, or
    with ``copy=False`` views where the broadcast allows (a shared operand keeps stride 0, so a
    box shared by a million capsules is not written out a million times)."""
    lead = np.broadcast_shapes(*[a.shape[: a.ndim - len(t)] for a, t in arrays])
    n = int(np.prod(lead, dtype=np.int64))
    if not copy:
        out = []
        for a, t in arrays:
            b = np.broadcast_to(a, lead + t)
            v = b.reshape((n,) + t) if b.ndim == len(t) + 1 or b.ndim == len(t) else None
            out.append(v if v is not None else np.ascontiguousarray(b).reshape((n,) + t))
        return lead, n, out
    out = [np.ascontiguousarray(np.broadcast_to(a, lead + t).reshape((n,) + t)) for a, t in arrays]
    return lead, n, out


def _raise_bad(bad: int, what: str) -> None:
    if bad >= 0:
        raise GeometryError(f"pair {bad}: {what}")


def _result(lead, dist, out) -> BatchProximity:
    o = out.reshape(lead + (9,))
    return BatchProximity(dist.reshape(lead), o[..., 0:3], o[..., 3:6], o[..., 6:9])


@njit(cache=True, inline="always")
def _within(a, b, c, d, e, f):  # pragma: no cover - compiled
    """Every value at most ``_MAX_MAGNITUDE`` in magnitude (a NaN is not)."""
    m = _MAX_MAGNITUDE
    return abs(a) <= m and abs(b) <= m and abs(c) <= m and abs(d) <= m and abs(e) <= m and abs(f) <= m


@njit(cache=True, _nrt=False)
def _capsule_capsule_loop(a0, a1, ra, b0, b1, rb, dist, out, eps_len, eps_par):  # pragma: no cover
    """Returns the index of the first pair with a non-finite input or a negative radius, or -1."""
    bad = -1
    for i in range(dist.shape[0]):
        p0x = a0[i, 0]
        p0y = a0[i, 1]
        p0z = a0[i, 2]
        p1x = a1[i, 0]
        p1y = a1[i, 1]
        p1z = a1[i, 2]
        q0x = b0[i, 0]
        q0y = b0[i, 1]
        q0z = b0[i, 2]
        q1x = b1[i, 0]
        q1y = b1[i, 1]
        q1z = b1[i, 2]
        r1 = ra[i]
        r2 = rb[i]
        if not (_within(p0x, p0y, p0z, p1x, p1y, p1z) and _within(q0x, q0y, q0z, q1x, q1y, q1z)
                and 0.0 <= r1 <= _MAX_MAGNITUDE and 0.0 <= r2 <= _MAX_MAGNITUDE):  # a NaN fails every comparison
            if bad < 0:
                bad = i
            continue
        dist[i] = capsule_capsule_scalar(
            p0x, p0y, p0z, p1x, p1y, p1z, r1, q0x, q0y, q0z, q1x, q1y, q1z, r2, out, 9 * i, eps_len, eps_par
        )
    return bad


def capsule_capsule(p0_A, p1_A, r_A, p0_B, p1_B, r_B, tol: Tolerances = DEFAULT_TOLERANCES) -> BatchProximity:
    """Capsule-capsule signed distances: ``p*_A, p*_B : (..., 3) m``, ``r_A, r_B : (...) m``."""
    arrs = [
        (_arr(p0_A, "p0_A", (3,), False), (3,)), (_arr(p1_A, "p1_A", (3,), False), (3,)), (_arr(r_A, "r_A", (), False), ()),
        (_arr(p0_B, "p0_B", (3,), False), (3,)), (_arr(p1_B, "p1_B", (3,), False), (3,)), (_arr(r_B, "r_B", (), False), ()),
    ]
    lead, n, (a0, a1, ra, b0, b1, rb) = _flat(arrs)
    dist = np.empty(n)
    out = np.empty(9 * n)
    bad = _capsule_capsule_loop(a0, a1, ra, b0, b1, rb, dist, out, tol.length, tol.parallel)
    _raise_bad(bad, f"NaN, infinite or beyond {_MAX_MAGNITUDE:g} (Tolerances.max_magnitude) coordinate or radius, "
                    "or a negative radius")
    return _result(lead, dist, out)


def sphere_sphere(c_A, r_A, c_B, r_B, tol: Tolerances = DEFAULT_TOLERANCES) -> BatchProximity:
    """Sphere-sphere signed distances: ``c_A, c_B : (..., 3) m``, ``r_A, r_B : (...) m``."""
    cA = _arr(c_A, "c_A", (3,))
    cB = _arr(c_B, "c_B", (3,))
    arrs = [(cA, (3,)), (_radius(r_A, "r_A"), ()), (cB, (3,)), (_radius(r_B, "r_B"), ())]
    lead, n, (a, ra, b, rb) = _flat(arrs)
    dist = np.empty(n)
    out = np.empty(9 * n)
    bad = _capsule_capsule_loop(a, a, ra, b, b, rb, dist, out, tol.length, tol.parallel)
    _raise_bad(bad, f"NaN, infinite or beyond {_MAX_MAGNITUDE:g} (Tolerances.max_magnitude) coordinate or radius, "
                    "or a negative radius")
    return _result(lead, dist, out)


@njit(cache=True, _nrt=False)
def _capsule_box_loop(a0, a1, ra, c, h, R, dist, out, eps_len, eps_par, offset):  # pragma: no cover
    """Returns the index of the first pair with a non-finite input or a bad radius/extent, or -1."""
    bad = -1
    for i in range(dist.shape[0]):
        acc = ra[i]
        ok = ra[i] <= _MAX_MAGNITUDE
        for q in range(3):
            acc += a0[i, q] + a1[i, q] + c[i, q] + h[i, q] + R[i, q, 0] + R[i, q, 1] + R[i, q, 2]
            ok = ok and abs(a0[i, q]) <= _MAX_MAGNITUDE and abs(a1[i, q]) <= _MAX_MAGNITUDE \
                and abs(c[i, q]) <= _MAX_MAGNITUDE and h[i, q] <= _MAX_MAGNITUDE
        if not (acc - acc == 0.0) or not ok or ra[i] < 0.0 or h[i, 0] <= 0.0 or h[i, 1] <= 0.0 or h[i, 2] <= 0.0:
            if bad < 0:
                bad = i
            continue
        dist[i] = capsule_box_scalar(
            a0[i, 0], a0[i, 1], a0[i, 2], a1[i, 0], a1[i, 1], a1[i, 2], ra[i],
            c[i, 0], c[i, 1], c[i, 2], h[i, 0], h[i, 1], h[i, 2],
            R[i, 0, 0], R[i, 0, 1], R[i, 0, 2], R[i, 1, 0], R[i, 1, 1], R[i, 1, 2],
            R[i, 2, 0], R[i, 2, 1], R[i, 2, 2], out, 9 * i, eps_len, eps_par, offset,
        )
    return bad


def capsule_box(p0, p1, r, center, half_extents, rotation, tol: Tolerances = DEFAULT_TOLERANCES) -> BatchProximity:
    """Capsule (A) - box (B) signed distances.

    ``p0, p1 : (..., 3) m``; ``r : (...) m``; ``center, half_extents : (..., 3) m``;
    ``rotation : (..., 3, 3)`` R_WB (columns are the box axes; trusted to be rotations).
    """
    arrs = [
        (_arr(p0, "p0", (3,), False), (3,)), (_arr(p1, "p1", (3,), False), (3,)), (_arr(r, "r", (), False), ()),
        (_arr(center, "center", (3,), False), (3,)), (_arr(half_extents, "half_extents", (3,), False), (3,)),
        (_arr(rotation, "rotation", (3, 3), False), (3, 3)),
    ]
    lead, n, (a0, a1, ra, c, hh, R) = _flat(arrs, copy=False)  # one box for many capsules: no copies
    dist = np.empty(n)
    out = np.empty(9 * n)
    bad = _capsule_box_loop(a0, a1, ra, c, hh, R, dist, out, tol.length, tol.parallel, tol.penetration_witness_offset)
    _raise_bad(bad, f"NaN, infinite or beyond {_MAX_MAGNITUDE:g} (Tolerances.max_magnitude) input, a negative radius or "
                    "a half extent <= 0")
    return _result(lead, dist, out)


# compiled without reference counting (``_nrt=False``): nothing is allocated inside (``seg`` is
# passed in), and the atomic increments numba emits for each array view handed to a kernel cost
# ~40% of the loop's time with a 20-vertex hull
@njit(cache=True, _nrt=False)
def _capsule_convex_loop(
    a0, a1, ra, hull_of, pv, po, pl, fo, ed, eo, bis, cen, aj, ao, rb, dist, out, status, seg, eps_len, eps_par, gjk_eps,
    max_iter, offset,
):  # pragma: no cover
    k = 0  # views of the current hull, re-sliced only when the hull changes (slicing costs refcounts)
    v = pv[po[0]:po[1]]
    p = pl[fo[0]:fo[1]]
    e = ed[eo[0]:eo[1]]
    b = bis[eo[0]:eo[1]]
    c = cen[0]
    g = aj[ao[0]:ao[1]]
    for i in range(dist.shape[0]):
        if hull_of[i] != k:
            k = hull_of[i]
            v = pv[po[k]:po[k + 1]]
            p = pl[fo[k]:fo[k + 1]]
            e = ed[eo[k]:eo[k + 1]]
            b = bis[eo[k]:eo[k + 1]]
            c = cen[k]
            g = aj[ao[k]:ao[k + 1]]
        for q in range(3):
            seg[0, q] = a0[i, q]
            seg[1, q] = a1[i, q]
        d, s = capsule_polytope_adj_at(
            seg, ra[i], v, p, e, b, c, g, rb[k], out, 9 * i, eps_len, eps_par, gjk_eps, max_iter, offset,
        )
        dist[i] = d
        if s == GJK_NOT_CONVERGED:
            status[0] = s


def capsule_convex(p0, p1, r, hulls, tol: Tolerances = DEFAULT_TOLERANCES) -> BatchProximity:
    """Capsule (A) - convex polytope (B) signed distances (GJK; Minkowski-facet depth).

    ``p0, p1 : (..., 3) m``; ``r : (...) m``.  ``hulls`` is one ConvexPolyhedron / Prism / Box /
    Polygon (every capsule against it) or a sequence of ``H`` of them, in which case the
    capsules' leading axes broadcast against ``(H,)``: pair ``i`` is capsule ``i`` with hull ``i``.
    """
    kinds = (ConvexPolyhedron, Prism, Box, Polygon)
    many = not isinstance(hulls, kinds)
    hs: Sequence = list(hulls) if many else [hulls]
    for j, h in enumerate(hs):
        if not isinstance(h, kinds):
            raise GeometryError(f"hulls[{j}]: expected a ConvexPolyhedron, Prism, Box or Polygon, got {type(h).__name__}")
    arrs = [(_arr(p0, "p0", (3,)), (3,)), (_arr(p1, "p1", (3,)), (3,)), (_radius(r, "r"), ())]
    if many:
        arrs.append((np.arange(len(hs), dtype=np.float64), ()))
    lead, n, flat = _flat(arrs)
    a0, a1, ra = flat[:3]
    hull_of = flat[3].astype(np.int64) if many else np.zeros(n, dtype=np.int64)
    data = [polytope_data(h) for h in hs]  # per hull, built once (see _pack.polytope_data)

    def cat(j, dtype=np.float64):
        return np.ascontiguousarray(np.concatenate([dd[j] for dd in data]), dtype=dtype)

    def offsets(j):
        return np.concatenate([[0], np.cumsum([len(dd[j]) for dd in data])]).astype(np.int64)

    cen = np.ascontiguousarray(np.stack([dd[4] for dd in data]))
    adj = [polytope_adjacency(h) for h in hs]  # each hull's vertex graph (offsets local to its slice)
    adj_off = np.concatenate([[0], np.cumsum([len(a) for a in adj])]).astype(np.int64)
    rb = np.array([h._sat[3] for h in hs])
    dist = np.empty(n)
    out = np.empty(9 * n)
    status = np.zeros(1, dtype=np.int64)
    _capsule_convex_loop(
        a0, a1, ra, hull_of, cat(0), offsets(0), cat(1), offsets(1), cat(2, np.int64), offsets(2), cat(3), cen,
        np.concatenate(adj), adj_off, rb,
        dist, out, status, np.empty((2, 3)), tol.length, tol.parallel, tol.gjk_epsilon, tol.gjk_max_iterations, tol.penetration_witness_offset,
    )
    if status[0] == GJK_NOT_CONVERGED:
        raise GeometryError(f"capsule_convex: GJK did not converge in {tol.gjk_max_iterations} iterations")
    return _result(lead, dist, out)


@njit(cache=True, _nrt=False)
def _box_box_loop(ca, ha, Ra, cb, hb, Rb, res, eps_par):  # pragma: no cover
    for i in range(res.shape[0]):
        res[i] = box_box_overlap_scalar(
            ca[i, 0], ca[i, 1], ca[i, 2], ha[i, 0], ha[i, 1], ha[i, 2],
            Ra[i, 0, 0], Ra[i, 0, 1], Ra[i, 0, 2], Ra[i, 1, 0], Ra[i, 1, 1], Ra[i, 1, 2], Ra[i, 2, 0], Ra[i, 2, 1], Ra[i, 2, 2],
            cb[i, 0], cb[i, 1], cb[i, 2], hb[i, 0], hb[i, 1], hb[i, 2],
            Rb[i, 0, 0], Rb[i, 0, 1], Rb[i, 0, 2], Rb[i, 1, 0], Rb[i, 1, 1], Rb[i, 1, 2], Rb[i, 2, 0], Rb[i, 2, 1], Rb[i, 2, 2],
            eps_par,
        )


def box_box_overlap(
    center_A, half_extents_A, rotation_A, center_B, half_extents_B, rotation_B, tol: Tolerances = DEFAULT_TOLERANCES
) -> np.ndarray:
    """JPL division-free OBB overlap test: ``(...) bool``, True where the boxes overlap or touch.

    ``center_*, half_extents_* : (..., 3) m``; ``rotation_* : (..., 3, 3)`` R_W* (columns are axes).
    A half extent <= 0 or a matrix that is no rotation is refused (either passes every axis test:
    "no overlap"); the arrays are checked as given, before they are broadcast.
    """
    for side, h, R in (("A", half_extents_A, rotation_A), ("B", half_extents_B, rotation_B)):
        h = _arr(h, f"half_extents_{side}", (3,))
        R = _arr(R, f"rotation_{side}", (3, 3))
        bad = np.argwhere(~(h > 0.0))
        if bad.size:
            at = tuple(int(i) for i in bad[0][:-1])
            raise GeometryError(f"half_extents_{side}{list(at) if at else ''} must be > 0, got {h[at].tolist()}")
        err = np.abs(np.einsum("...ji,...jk->...ik", R, R) - np.eye(3)).max(axis=(-2, -1), initial=0.0)
        det = np.linalg.det(R) if R.size else np.zeros(R.shape[:-2])
        bad = np.argwhere(np.atleast_1d((err > 1e-6) | (det <= 0.0)))
        if bad.size:
            at = tuple(int(i) for i in bad[0]) if R.ndim > 2 else ()
            raise GeometryError(f"rotation_{side}{list(at) if at else ''} is no rotation (RᵀR differs from I by "
                                f"{float(np.atleast_1d(err)[tuple(bad[0])]):.3g}, det "
                                f"{float(np.atleast_1d(det)[tuple(bad[0])]):.3g})")
    return _box_box_overlap(center_A, half_extents_A, rotation_A, center_B, half_extents_B, rotation_B, tol)


def _box_box_overlap(center_A, half_extents_A, rotation_A, center_B, half_extents_B, rotation_B,
                     tol: Tolerances = DEFAULT_TOLERANCES) -> np.ndarray:
    """:func:`box_box_overlap` without the checks of the boxes (callers whose boxes are :class:`Box`
    objects, already checked: the terrain's body hierarchy)."""
    arrs = [
        (_arr(center_A, "center_A", (3,)), (3,)), (_arr(half_extents_A, "half_extents_A", (3,)), (3,)),
        (_arr(rotation_A, "rotation_A", (3, 3)), (3, 3)), (_arr(center_B, "center_B", (3,)), (3,)),
        (_arr(half_extents_B, "half_extents_B", (3,)), (3,)), (_arr(rotation_B, "rotation_B", (3, 3)), (3, 3)),
    ]
    lead, n, (ca, ha, Ra, cb, hb, Rb) = _flat(arrs)
    res = np.empty(n, dtype=np.bool_)
    _box_box_loop(ca, ha, Ra, cb, hb, Rb, res, tol.parallel)
    return res.reshape(lead)
