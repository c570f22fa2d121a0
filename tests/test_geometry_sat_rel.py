"""The link-frame SAT (``_pair_sat_rel``: B's points in B's frame, placed by ``X_AB``) against the
exhaustive SAT on both cores moved to one frame (``_pair_sat.sat_depth`` / ``convex_convex``).

Boxes, prisms (3 to 16 sides) and random hulls of few points, in random relative poses from deep
overlap to apart: the depth must agree with the reference to ``TOL`` (relative to the shapes' size:
the two differ only by the rounding of moving B's points), the axis must be a separating direction
with that overlap, and the witnesses must be those of the reference kernel (same signed distance,
``p_B - p_A = distance * n``).  The engine uses it for overlapping boxes and small hulls
(``_narrow.narrow_rel``); ``tests/test_engine_link_frame.py`` holds the engine to its W path.
"""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from armguard.geometry import Box, ConvexPolyhedron, Prism
from armguard.geometry._pair_gjk import GJK_INTERSECTING, GJK_NOT_CONVERGED, GJK_SEPARATED, GJK_WORK_SIZE
from armguard.geometry._pair_sat import convex_convex, sat_depth
from armguard.geometry._pair_sat_rel import sat_depth_rel, sat_witnesses_rel
from armguard._tolerance import DEFAULT_TOLERANCES as TOLS

TOL = 1e-12  # m per m of size: the rounding of moving B's points (EPA's tests allow 1e-9)
EPS = dict(eps_len=TOLS.length, eps_par=TOLS.parallel, gjk_eps=TOLS.gjk_epsilon, max_iter=TOLS.gjk_max_iterations,
           offset=TOLS.penetration_witness_offset)
SETTINGS = settings(max_examples=150, deadline=None, derandomize=True)


def _rotation(rng) -> np.ndarray:
    q = rng.normal(size=4)
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _shape(kind: int, rng):
    """A shape in its own frame (centre near the origin, random orientation in that frame)."""
    c = rng.uniform(-0.05, 0.05, 3)
    R = _rotation(rng)
    if kind == 0:
        return Box(c, rng.uniform(0.02, 0.5, 3), R)
    if kind == 1:
        return Prism(c, R, float(rng.uniform(0.02, 0.3)), float(rng.uniform(0.02, 0.5)), int(rng.integers(3, 17)))
    p = rng.normal(size=(int(rng.integers(4, 24)), 3)) * rng.uniform(0.05, 0.4, 3)
    return ConvexPolyhedron(p + c)


def _moved(B, R, t):
    """B's SAT data moved by ``(R, t)``: the reference's input."""
    pb, fb, eb, _ = B._sat
    return np.ascontiguousarray(pb @ R.T + t), np.ascontiguousarray(fb @ R.T), np.ascontiguousarray(eb @ R.T)


def _size(A, B) -> float:
    return float(max(np.ptp(A._sat[0], axis=0).max(), np.ptp(B._sat[0], axis=0).max()))


case = st.tuples(st.integers(0, 2**31), st.integers(0, 2), st.integers(0, 2), st.floats(0.0, 1.2))


@SETTINGS
@given(case)
def test_link_frame_sat_depth_is_the_exhaustive_sat(c):
    """Same depth as ``sat_depth`` on B moved into A's frame, and its axis overlaps by that depth."""
    seed, ka, kb, reach = c
    rng = np.random.default_rng(seed)
    A, B = _shape(ka, rng), _shape(kb, rng)
    R = _rotation(rng)
    t = rng.normal(size=3)
    t *= reach * _size(A, B) / np.linalg.norm(t)
    pa, fa, ea, _ = A._sat
    pb, fb, eb, _ = B._sat
    pbm, fbm, ebm = _moved(B, R, t)
    ref = sat_depth(pa, fa, ea, pbm, fbm, ebm, TOLS.parallel)
    got = sat_depth_rel(pa, fa, ea, pb, fb, eb, np.ascontiguousarray(R.reshape(-1)), t[0], t[1], t[2], TOLS.parallel)
    size = _size(A, B)
    assert abs(got[0] - ref[0]) <= TOL * size
    n = np.array(got[1:4])
    assert abs(np.linalg.norm(n) - 1.0) < 1e-12
    # the axis's own overlap (moved points, brute force) is the depth returned
    overlap = (pa @ n).max() - (pbm @ n).min()
    assert abs(overlap - got[0]) <= TOL * size


@SETTINGS
@given(case)
def test_link_frame_sat_witnesses_are_the_reference_kernels(c):
    """Depth and witnesses as ``convex_convex`` (GJK, exhaustive SAT, B pushed out, GJK) on the moved
    cores: same signed distance, witnesses within GJK's tolerance, ``p_B - p_A = distance * n``."""
    seed, ka, kb, reach = c
    rng = np.random.default_rng(seed)
    A, B = _shape(ka, rng), _shape(kb, rng)
    R = _rotation(rng)
    t = rng.normal(size=3)
    t *= 0.5 * reach * _size(A, B) / np.linalg.norm(t)  # mostly overlapping
    pa, fa, ea, _ = A._sat
    pb, fb, eb, _ = B._sat
    pbm, fbm, ebm = _moved(B, R, t)
    out = np.zeros(9)
    d_ref, st_ref = convex_convex(pa, fa, ea, 0.0, pbm, fbm, ebm, 0.0, out, np.zeros(GJK_WORK_SIZE), *EPS.values())
    if st_ref != GJK_INTERSECTING:
        return  # apart: GJK's answer, not the SAT's
    rot = np.ascontiguousarray(R.reshape(-1))
    depth, nx, ny, nz = sat_depth_rel(pa, fa, ea, pb, fb, eb, rot, t[0], t[1], t[2], TOLS.parallel)
    simp = np.zeros(9)
    st_, ax, ay, az, bx, by, bz = sat_witnesses_rel(pa, np.zeros(0, np.int64), np.zeros(0, np.int64), pb,
                                                    np.zeros(0, np.int64), np.zeros(0, np.int64), rot, t[0], t[1], t[2],
                                                    depth, nx, ny, nz, simp, EPS["eps_len"], EPS["gjk_eps"],
                                                    EPS["max_iter"], EPS["offset"])
    assert st_ != GJK_NOT_CONVERGED
    assert st_ == (GJK_INTERSECTING if depth >= 0.0 else GJK_SEPARATED)
    size = _size(A, B)
    assert abs(-depth - d_ref) <= TOL * size
    a, b, n = np.array([ax, ay, az]), np.array([bx, by, bz]), np.array([nx, ny, nz])
    assert np.allclose(a, out[0:3], atol=1e-9 * size) and np.allclose(b, out[3:6], atol=1e-9 * size)
    assert np.allclose(b - a, -depth * n, atol=1e-9 * max(size, 1.0))
    assert math.isfinite(depth)
