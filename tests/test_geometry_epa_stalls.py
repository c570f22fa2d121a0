"""Configurations where a single distance or collision query stalled for seconds to minutes.

A review that drove the analytic backend as a planner would (random states, bisection of edges to
contact) found three: each left EPA unsettled and fell back to the exhaustive SAT, whose cost on mesh
hulls is ``E_A E_B (V_A + V_B)``:

* so101, an ordinary random configuration (15 mm deep): EPA, from 13 of 32 GJK start tetrahedra,
  saw faces nearly in a plane with a new vertex as a set that is no cap and gave up (110 s);
* kinova, two hulls 3.4e-13 m apart: GJK ends touching, with no tetrahedron for EPA (58 s, and
  ``collides`` as long);
* kuka_iiwa, 1e-13 m deep: EPA settled a depth below ``eps_len``, which was not taken (0.55 s).

Each is checked for its answer (coal's) and its path (EPA settles); the wall-clock bounds are guards
against a stall of that order, not benchmarks.
"""

from __future__ import annotations

import math
import time

import numpy as np
import pinocchio as pin
import pytest

import armguard
from armguard.geometry._pack import hull_graph
from armguard.geometry._pair_epa import EPA_WORK_SIZE, complete_simplex, convex_convex_fast, epa_depth
from armguard.geometry._pair_gjk import gjk_dir_adj2, inner_difference

STALL = 20.0  # s: far above a query's cost (µs to ms), far below the stalls (0.5 s to 110 s on a shared core)

SO101_Q = [0.8496853676960754, 0.5941887355449778, 1.3734836143493263, -0.11596793850029563, 1.2331306303769822,
           0.17006900175857903]
KINOVA_Q = [0.11228307819929059, 0.9936762603333603, 1.5209837147046552, 5.24683545701067, 0.9726316288951986,
            -0.23235256502279622, 2.2863434427728957, 0.4081711365967891, 0.9129054295211992]
IIWA_Q = [-0.7579498727945321, 0.41663862691959475, -0.5026721121503782, 0.8359443357444296, 2.344383975789882,
          -1.9623244286738664, 0.5728025855457503]


def _hulls_W(model, q, a: str, b: str):
    """The two collision hulls of pair ``(a, b)`` posed at ``q``, in W, with their vertex graphs."""
    gm = model.collision_model
    data, gdata = model.pin_model.createData(), pin.GeometryData(gm)
    pin.updateGeometryPlacements(model.pin_model, data, gm, gdata, np.asarray(q, dtype=np.float64))
    out = []
    for name in (a, b):
        i = model.geometry_index(name)
        M = gdata.oMg[i]
        P = np.asarray(gm.geometryObjects[i].geometry.points()).reshape(-1, 3)
        P = np.ascontiguousarray(P @ np.asarray(M.rotation).T + np.asarray(M.translation))
        out.append((P, *hull_graph(P)))
    return out


def _timed(call):
    t = time.perf_counter()
    out = call()
    return out, time.perf_counter() - t


@pytest.mark.parametrize("robot, q", [("so101", SO101_Q), ("kinova", KINOVA_Q), ("kuka_iiwa", IIWA_Q)])
def test_the_stalled_configurations_answer_as_coal_at_once(robot, q):
    m = armguard.load_model(robot)
    q = np.asarray(q)
    analytic, coal = armguard.checker(m, "analytic"), armguard.checker(m, "coal")
    analytic.pair_distances(m.neutral())  # the kernels loaded
    r, took = _timed(lambda: analytic.pair_distances(q))
    assert took < STALL, took
    ref = coal.pair_distances(q)
    hull = np.array([any("Convex" in type(m.collision_model.geometryObjects[m.geometry_index(n)].geometry).__name__
                         for n in pair) for pair in m.pairs.names])
    np.testing.assert_allclose(r.distance, ref.distance, rtol=0, atol=1e-5)
    assert np.all(np.abs(r.distance - ref.distance)[~hull] < 1e-9)
    k = int(np.argmin(ref.distance))
    assert abs(r.distance[k] - ref.distance[k]) < 1e-9  # the stalled pair itself, to GJK's and EPA's tolerance
    v, took = _timed(lambda: analytic.collides(q[None]))
    assert took < STALL and bool(v[0]) == bool(ref.distance.min() <= m.tol.length)


def test_epa_settles_from_every_start_on_so101s_dense_hulls():
    """Base link (453 vertices) against the gripper (4,262), 15 mm deep: EPA from the tetrahedra GJK ends
    with from 32 initial directions.  Every face seen from a new vertex removed (no margin) gave up
    from 13 of them (a new face with the origin 15.7 mm outside)."""
    m = armguard.load_model("so101")
    (pa, ga, _), (pb, gb, _) = _hulls_W(m, SO101_Q, "base_link_1", "gripper_link_1")
    rng = np.random.default_rng(0)
    starts = [inner_difference(pa, ga, pb, gb), (0.0, 1.0, 0.0)] + [tuple(rng.normal(size=3)) for _ in range(30)]
    depths = []
    for d in starts:
        simp = np.zeros(16)
        status = gjk_dir_adj2(pa, ga, pb, gb, 0.0, 0.0, 0.0, *d, 1e-9, 1e-12, 1000, simp, math.inf)[0]
        assert status == 1 and simp[0] == 1.0  # overlapping, a tetrahedron
        work = np.zeros(EPA_WORK_SIZE)
        work[:9] = simp[:9]
        ok, depth = epa_depth(pa, ga, pb, gb, work, 1e-12)[:2]
        assert ok
        depths.append(depth)
    assert max(depths) - min(depths) < 1e-12 and abs(depths[0] - 0.015467764442605) < 1e-9


def test_a_touching_simplex_is_completed_for_epa():
    """kinova's base against link 6, 3.4e-13 m apart: GJK ends touching on a smaller simplex (``simp[0] = -n``);
    completed to a tetrahedron, EPA settles a depth of about 0, and the W path answers 0 without the SAT."""
    m = armguard.load_model("kinova")
    (pa, ga, ta), (pb, gb, tb) = _hulls_W(m, KINOVA_Q, "j2s6s200_link_base_0", "j2s6s200_link_6_0")
    simp = np.zeros(16)
    status, d = gjk_dir_adj2(pa, ga, pb, gb, 0.0, 0.0, 0.0, *inner_difference(pa, ga, pb, gb), 1e-9, 1e-12, 1000,
                             simp, math.inf)[:2]
    assert status == 1 and d < 1e-9 and -3.0 <= simp[0] <= -1.0
    work = np.zeros(EPA_WORK_SIZE)
    work[:9] = simp[:9]
    assert complete_simplex(pa, ga, pb, gb, work, 1e-9) and work[0] == 1.0
    ok, depth = epa_depth(pa, ga, pb, gb, work, 1e-12)[:2]
    assert ok and 0.0 <= depth < 1e-9
    E = np.zeros((0, 3))
    (dist, st), took = _timed(lambda: convex_convex_fast(pa, E, E, ga, ta, 0.0, pb, E, E, gb, tb, 0.0, np.zeros(9),
                                                          np.zeros(EPA_WORK_SIZE), 1e-9, 1e-9, 1e-12, 1000, 1e-6,
                                                          -math.inf))
    assert took < STALL and abs(dist) < 1e-9 and st == 1


def test_an_exact_vertex_contact_settles_without_the_sat():
    """A hull and its point reflection through one of its vertices touch at that vertex alone: EPA's new faces
    through the vertex the origin sits on had plane distances of -0.0 or -1e-17 by rounding, so EPA gave up and
    the exhaustive SAT ran (0.3-2.7 s on hulls of 150-300 vertices).  Within eps such a face is at distance 0."""
    E = np.zeros((0, 3))
    rng = np.random.default_rng(3)
    for trial in range(8):
        P = rng.normal(size=(200, 3)) * [0.1, 0.07, 0.05]
        u = rng.normal(size=3)
        v = P[np.argmax(P @ u)]
        pa, pb = np.ascontiguousarray(P), np.ascontiguousarray(2.0 * v - P)
        (ga, ta), (gb, tb) = hull_graph(pa), hull_graph(pb)
        simp = np.zeros(16)
        gjk_dir_adj2(pa, ga, pb, gb, 0.0, 0.0, 0.0, *inner_difference(pa, ga, pb, gb), 1e-9, 1e-12, 1000, simp, math.inf)
        work = np.zeros(EPA_WORK_SIZE)
        work[:9] = simp[:9]
        assert simp[0] == 1.0 or complete_simplex(pa, ga, pb, gb, work, 1e-9), (trial, simp[:9])
        ok, depth = epa_depth(pa, ga, pb, gb, work, 1e-12)[:2]
        assert ok and 0.0 <= depth <= 1e-9, (trial, ok, depth)  # EPA settles it: no SAT
        dist, _ = convex_convex_fast(pa, E, E, ga, ta, 0.0, pb, E, E, gb, tb, 0.0, np.zeros(9), np.zeros(EPA_WORK_SIZE),
                                     1e-9, 1e-9, 1e-12, 1000, 1e-6, -math.inf)
        assert abs(dist) <= 1e-9, (trial, dist)
