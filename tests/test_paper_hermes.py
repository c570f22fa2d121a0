"""Hermes's link–link, payload–link and payload–obstacle modules (seed 001 §3) at ``fidelity = "paper"``.

The compiled kernels are held to slow numpy references of the same rules
(``armguard_analytic._paper_hermes_ref``) and to the exact geometry in the documented directions;
the operation counter is pinned on hand-counted cases.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

import armguard
from armguard.geometry import Box, Capsule, ConvexPolyhedron, distance

paper = pytest.importorskip("armguard_analytic._paper")
from armguard_analytic import _paper_hermes as H  # noqa: E402
from armguard_analytic._paper_count import count_call, count_rows, flop  # noqa: E402
from armguard_analytic._paper_hermes_ref import (  # noqa: E402
    ref_link_link, ref_link_obstacle, ref_payload_link, ref_payload_obstacle, ref_segments,
)

TIGHT = 1e-12
BOX = Box(center=[0.0, 0.0, 0.0], half_extents=[1.0, 1.0, 1.0])
LL = H.BRANCHES["link-link"]
PO = H.BRANCHES["payload-obstacle"]


def _cap(p0, p1, r=0.1):
    return Capsule(np.asarray(p0, float), np.asarray(p1, float), r)


# ------------------------------------------------------------------ link-link (Fig. 7)
LINK_CASES = {  # name: (segments, expected branch, expected axis distance)
    "skew, both feet inside": (([0, 0, 0], [2, 0, 0], [1, -1, 0.5], [1, 1, 0.5]), "interior", 0.5),
    "skew, a foot outside": (([0, 0, 0], [1, 0, 0], [2, -1, 0.3], [2, 1, 0.3]), "eight cases", np.hypot(1, 0.3)),
    "end to end": (([0, 0, 0], [1, 0, 0], [3, 1, 0], [2, 2, 0]), "eight cases", np.hypot(1.5, 1.5)),
    "parallel, overlapping": (([0, 0, 0], [2, 0, 0], [1, 0.3, 0], [3, 0.3, 0]), "parallel", 0.3),
    "parallel, disjoint (the lines' distance)": (([0, 0, 0], [1, 0, 0], [2, 0.3, 0], [3, 0.3, 0]), "parallel", 0.3),
    "coincident, overlapping": (([0, 0, 0], [2, 0, 0], [3, 0, 0], [1, 0, 0]), "coincident", 0.0),
    "coincident, apart": (([0, 0, 0], [1, 0, 0], [3, 0, 0], [2.5, 0, 0]), "coincident", 1.5),
    "coincident, behind": (([0, 0, 0], [1, 0, 0], [-2, 0, 0], [-3, 0, 0]), "coincident", 2.0),
    "a point": (([0.5, 0.5, 0], [0.5, 0.5, 0], [0, 0, 0], [1, 0, 0]), "point", 0.5),
}


@pytest.mark.parametrize("case", list(LINK_CASES))
def test_link_link_branches(case):
    seg, branch, d = LINK_CASES[case]
    hit, dk, Ma, Mb, br = paper.hermes_link_link(_cap(seg[0], seg[1]), _cap(seg[2], seg[3]))
    assert LL[br] == branch and abs(dk - d) < TIGHT and abs(np.linalg.norm(Mb - Ma) - dk) < TIGHT
    assert abs(dk - ref_link_link(*seg)) < TIGHT
    assert hit == (d <= 0.2)


def test_link_link_parallel_disjoint_is_below_exact():
    _, d, _, _, br = paper.hermes_link_link(_cap([0, 0, 0], [1, 0, 0]), _cap([2, 0.3, 0], [3, 0.3, 0]))
    assert LL[br] == "parallel" and d < ref_segments([0, 0, 0], [1, 0, 0], [2, 0.3, 0], [3, 0.3, 0]) - 0.5


_coord = st.floats(-3, 3, allow_nan=False)
_pt = st.tuples(_coord, _coord, _coord)


@settings(max_examples=300, deadline=None)
@given(_pt, _pt, _pt, _pt)
# exactly parallel axes whose a c - b^2 rounds to 1e-16 a c: once taken for skew (4.24 m for 3.0 m)
@example((0.0, 0.0, 0.0), (0.0, 0.4271966036234085, 0.0), (3.0, 3.0, 0.0), (3.0, 0.5, 0.0))
# crossing axes 1.3e-7 rad apart: once 12.2 mm (s, t solved from cancelling a c - b^2 and b e - c d)
@example((0.0, 0.875, 0.0), (0.0, 0.0, 5.960464477539063e-08), (0.0, 0.0, 0.0), (0.0, 1.0, 5.960464477539063e-08))
def test_link_link_equals_reference_and_exact(p0, p1, q0, q1):
    _, d, Ma, Mb, br = paper.hermes_link_link(_cap(p0, p1), _cap(q0, q1))
    # near-parallel axes fix the nearest points along them only to ~1e-16 L / sin(angle) (both
    # here and in the references); the distance is held to that, and to 1e-9 m elsewhere
    u, v = np.subtract(p1, p0), np.subtract(q1, q0)
    nu, nv = np.linalg.norm(u), np.linalg.norm(v)
    sin = np.linalg.norm(np.cross(u, v)) / (nu * nv) if nu > 0 and nv > 0 else 1.0
    tol = 1e-9 + 1e-15 * max(nu, nv) / max(sin, 1e-300)
    assert abs(d - ref_link_link(p0, p1, q0, q1)) < tol
    assert abs(np.linalg.norm(Mb - Ma) - d) < 1e-9
    if LL[br] != "parallel":  # exact everywhere but the parallel branch
        assert abs(d - distance(_cap(p0, p1, 0.0), _cap(q0, q1, 0.0)).distance) < tol


# ------------------------------------------------------------------ payload-link (Fig. 11)
PAYLOAD = _cap([0, 0, -1], [0, 0, 1], 0.5)  # cylinder's sphere sqrt(1 + 0.25) = 1.118 m; capsule reaches 1.5 m


def test_payload_link_documented_answers():
    assert paper.hermes_payload_link(PAYLOAD, _cap([0.55, -1, 0], [0.55, 1, 0], 0.1)) == (True, 0.55, 2)
    hit, d, br = paper.hermes_payload_link(PAYLOAD, _cap([0.7, -1, 0], [0.7, 1, 0], 0.1))
    assert not hit and abs(d - 0.7) < TIGHT and H.BRANCHES["payload-link"][br] == "distance"
    assert paper.hermes_payload_link(PAYLOAD, _cap([5, -1, 0], [5, 1, 0], 0.1))[2] == H.B_NO_ROOT
    assert paper.hermes_payload_link(PAYLOAD, _cap([0, 3, 0], [0, 5, 0], 0.1))[2] == H.B_ROOTS_OUTSIDE
    # touching the payload's hemispherical end beyond the cylinder's sphere: the pre-test misses it
    end = _cap([-1, 0, 1.55], [1, 0, 1.55], 0.1)
    assert distance(end, PAYLOAD).distance < 0 and paper.hermes_payload_link(PAYLOAD, end)[0] is False
    assert paper.hermes_payload_link(PAYLOAD, end, margin=0.4)[0]  # the margin grows the sphere too (1.618 m)


def test_payload_link_random_against_reference_and_exact():
    rng = np.random.default_rng(3)
    misses = 0
    for _ in range(800):
        pl = _cap(rng.normal(size=3), rng.normal(size=3), rng.uniform(0.1, 0.6))
        lk = _cap(rng.normal(size=3) * 1.5, rng.normal(size=3) * 1.5, rng.uniform(0.02, 0.3))
        margin = float(rng.choice([0.0, 0.1]))
        hit, d, br = paper.hermes_payload_link(pl, lk, margin)
        assert hit == ref_payload_link(pl, lk, margin)
        exact = distance(lk, pl).distance
        if hit:  # no false alarms
            assert exact <= margin + 1e-9
        elif exact <= margin:  # a miss: only the pre-test, at the payload's ends
            misses += 1
            assert br != H.B_DISTANCE
            c = 0.5 * (pl.p0 + pl.p1)
            M = distance(lk, _cap(c, c, 0.0))
            assert M.distance + lk.radius > 0.5 * np.linalg.norm(pl.p1 - pl.p0)
    assert misses > 0  # the sphere is the cylinder's, not the capsule's: some ends are missed


# ------------------------------------------------------------------ payload-obstacle (Figs. 8-9)
def test_payload_obstacle_documented_answers():
    cases = {  # payload axis end-points, radius -> (hit, exit)
        "spheres apart": (([9, 9, 9], [9, 9, 11], 0.5), (False, "spheres apart")),
        "end-point over the top face": (([0.2, 0, 1.3], [0.2, 0, 3], 0.5), (True, "end-point over a face")),
        "clear of the top face": (([0.2, 0, 1.6], [0.2, 0, 3], 0.5), (False, "no face")),
        "crossing, both projections in": (([0.2, 0.1, 0.2], [-0.3, 0.2, 2.5], 0.05),
                                          (True, "crossing, projections in")),
        "beside an edge": (([1.2, 1.2, -0.5], [1.2, 1.2 + 1e-3, 0.5], 0.3), (True, "edge")),
    }
    for name, ((p0, p1, r), (hit, exit_)) in cases.items():
        pl = _cap(p0, p1, r)
        got = paper.hermes_payload_obstacle(pl, BOX)
        assert (got[0], PO[got[1]]) == (hit, exit_), name
        assert got[0] == ref_payload_obstacle(pl, BOX), name
        if hit:
            assert distance(pl, BOX).distance <= 0.0, name


def test_payload_obstacle_misses_the_paper_admits():
    # crossing the top face steeply, one projection outside it, far from the edges: missed
    steep = _cap([0.5, 0.5, -0.1], [3, 0.5, 2.0], 0.05)
    assert distance(steep, BOX).distance < 0 and not paper.hermes_payload_obstacle(steep, BOX)[0]
    # wholly inside: both end-points farther than R from every face, same side
    inside = _cap([-0.3, 0, 0], [0.3, 0, 0], 0.1)
    assert distance(inside, BOX).distance < 0 and not paper.hermes_payload_obstacle(inside, BOX)[0]


def test_payload_obstacle_random_against_reference_and_exact():
    rng = np.random.default_rng(4)
    tet = ConvexPolyhedron([[0, 0, 0], [1.5, 0, 0], [0, 1.5, 0], [0, 0, 1.5]])
    n_hit = 0
    for k in range(500):
        ob = BOX if k % 2 else tet
        pl = _cap(rng.normal(size=3) * 1.5, rng.normal(size=3) * 1.5, rng.uniform(0.05, 0.5))
        margin = float(rng.choice([0.0, 0.1]))
        hit, _ = paper.hermes_payload_obstacle(pl, ob, margin)
        assert hit == ref_payload_obstacle(pl, ob, margin)
        if hit:  # every hit is a true contact of the capsule
            n_hit += 1
            assert distance(pl, ob).distance <= margin + 1e-9
    assert n_hit > 50


def test_link_obstacle_random_against_reference_and_exact():
    """The link–obstacle module (the compiled ``_hermes_hit``) against the clipped-axis reference, on random
    links about a box and a tetrahedron; its misses are the paper's (a link wholly inside the grown obstacle,
    or rejected by the pre-test beside a vertex), its false alarms beside edges: both measured, both rare."""
    from armguard_analytic._paper_pair import hermes_link_obstacle

    rng = np.random.default_rng(6)
    tet = ConvexPolyhedron([[0, 0, 0], [1.5, 0, 0], [0, 1.5, 0], [0, 0, 1.5]])
    hits = misses = alarms = 0
    for k in range(600):
        ob = BOX if k % 2 else tet
        link = _cap(rng.normal(size=3) * 1.5, rng.normal(size=3) * 1.5, rng.uniform(0.0, 0.3))
        margin = float(rng.choice([0.0, 0.1]))
        hit = hermes_link_obstacle(link, ob, margin)
        assert hit == ref_link_obstacle(link, ob, margin), (k, link.p0, link.p1, link.radius, margin)
        d = distance(link, ob).distance
        hits += hit
        misses += (not hit) and d <= margin - 1e-9
        alarms += hit and d > margin + 1e-9
    assert hits > 100 and misses <= 0.05 * 600 and alarms <= 0.05 * 600, (hits, misses, alarms)


# ------------------------------------------------------------------ the Checker on the Hermes model
@pytest.fixture(scope="module")
def hermes():
    m = armguard.load_model("hermes")
    return m, armguard.checker(m, "analytic", {"fidelity": "paper"}), armguard.checker(m, "analytic")


def test_checker_runs_the_four_modules(hermes):
    m, p, e = hermes
    mods = np.array(p.hermes_modules)
    cat = np.array(m.pairs.category)
    assert set(mods[cat == "arm-arm"]) == {"link-link"} and set(mods[cat == "arm-payload"]) == {"payload-link"}
    assert set(mods[cat == "arm-vehicle"]) == {"link-obstacle"}
    assert set(mods[cat == "payload-vehicle"]) == {"payload-obstacle"}
    Q = m.random_q(300, 11)
    for margin in (0.0, 0.1):
        hit, d, br = p.pair_verdicts_many(Q, margin=margin)
        assert np.array_equal(p.collides(Q, margin=margin), hit.any(axis=1))
        E = np.array([e.pair_distances(q).distance for q in Q])
        ll = mods == "link-link"  # random configurations: no parallel axes, so exact
        assert np.array_equal(hit[:, ll], E[:, ll] <= margin) and (br[:, ll] != H.B_PARALLEL).all()
        for mod in ("payload-link", "payload-obstacle"):  # no false alarms
            k = mods == mod
            assert not (hit[:, k] & (E[:, k] > margin + 1e-9)).any()
        assert np.isfinite(d[:, ll]).all() and np.isinf(d[:, mods == "payload-obstacle"]).all()


def test_ranger_model_has_no_hermes_modules():
    m = armguard.load_model("ranger")
    p = armguard.checker(m, "analytic", {"fidelity": "paper"})
    assert set(p.hermes_modules) == {""}


# ------------------------------------------------------------------ operation counts (seed 001 §4)
def test_count_link_link_interior_by_hand():
    # u, v, w: 9 sums; a, c, b, d, e: 5 dots = 15 mul + 10 sums; the length guard squares eps (1 mul);
    # det = a c - b b (2 mul, 1 sum); its cancellation test 1e-15 a c (1 mul, a c reused); its test
    # eps^2 a c (2 mul); s, t: 4 mul, 2 sums, 2 div; M1, M2: 6 mul, 6 sums; |M2 - M1|: 3 sums,
    # 3 mul, 2 sums, 1 sqrt.  Comparisons: 2 + 2 + 4.
    res, n = count_call(H._hermes_segments, (0., 0., 0.), (2., 0., 0.), (1., -1., 0.5), (1., 1., 0.5), 1e-12, 1e-12)
    assert res[3] == H.B_INTERIOR and abs(float(res[0]) - 0.5) < TIGHT
    assert n == {"mul": 34, "div": 2, "add": 33, "sqrt": 1, "trig": 0, "cmp": 8}
    assert flop(n) == 34 + 2 + 33 / 3 + 3


def test_count_payload_link_no_root_by_hand():
    # midpoint 3 mul 3 sums; v, w 6 sums; rho + grow 1 sum; A, B 6 mul 4 sums; C 4 mul 3 sums;
    # disc 2 mul 1 sum; the point-link guard squares eps (1 mul).  Comparisons: disc < 0, A <= eps^2.
    res, n = count_call(H._hermes_payload_link, (5., 0., 0.), (5., 1., 0.), 0.1, (0., 0., -1.), (0., 0., 1.), 1.118,
                        0.6, 1e-12, 1e-12)
    assert res[0] is False and res[2] == H.B_NO_ROOT
    assert n == {"mul": 16, "div": 0, "add": 18, "sqrt": 0, "trig": 0, "cmp": 2}


def test_counted_run_reaches_the_compiled_verdicts(hermes):
    m, p, _ = hermes
    Q = m.random_q(6, 5)
    counts, hit = count_rows(p, Q, 0.1)
    assert np.array_equal(hit, p.pair_verdicts_many(Q, margin=0.1)[0])
    for c in counts:
        assert set(c) == {"kinematics", "link-obstacle", "link-link", "payload-link", "payload-obstacle"}
        assert c["kinematics"]["trig"] == 12  # six revolute joints: one cos and one sin each
        assert c["link-link"]["sqrt"] >= 6  # six pairs, at least one distance each
