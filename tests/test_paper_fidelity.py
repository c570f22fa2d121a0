"""The analytic backend at ``fidelity = "paper"``: the seeds' minimalist checkers.

Where the papers' methods are exact (segment pairs; a distal end-point projecting into a face)
they equal the exact kernels to 1e-12; where they are known to err they err in the documented
direction; and the paper distance of a capsule–polytope pair is never below the exact one.
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest

import armguard
from armguard._errors import BackendError
from armguard.geometry import Box, Capsule, ConvexPolyhedron, Polygon, distance

from _geometry_strategies import random_shape

paper = pytest.importorskip("armguard_analytic._paper")
TIGHT = 1e-12


def _seg(p0, p1):
    return tuple(map(float, p0)), tuple(map(float, p1))


# ------------------------------------------------------------------ Ranger §3: exact for segment pairs
SEGMENT_CASES = {
    "crossing skew, both interior": ([0, 0, 0], [2, 0, 0], [1, -1, 0.5], [1, 1, 0.5]),
    "intersecting": ([0, 0, 0], [2, 0, 0], [1, -1, 0], [1, 1, 0]),
    "one clamped": ([0, 0, 0], [1, 0, 0], [2, -1, 0.3], [2, 1, 0.3]),
    "both clamped, end to end": ([0, 0, 0], [1, 0, 0], [2, 1, 0.5], [3, 2, 0.5]),
    "both clamped, two-stage": ([0, 0, 0], [1, 0.1, 0], [1.6, -0.9, 0.2], [3, -2.4, 0.2]),
    "parallel, overlapping": ([0, 0, 0], [2, 0, 0], [1, 0.3, 0], [3, 0.3, 0]),
    "parallel, disjoint": ([0, 0, 0], [1, 0, 0], [2, 0.3, 0.1], [3, 0.3, 0.1]),
    "anti-parallel collinear": ([0, 0, 0], [1, 0, 0], [3, 0, 0], [2, 0, 0]),
    "degenerate point": ([0.5, 0.5, 0.5], [0.5, 0.5, 0.5], [0, 0, 0], [1, 0, 0]),
}


@pytest.mark.parametrize("case", list(SEGMENT_CASES))
def test_ranger_segment_segment_equals_exact(case):
    p0, p1, q0, q1 = SEGMENT_CASES[case]
    M1, M2 = paper.ranger_segment_segment(*_seg(p0, p1), *_seg(q0, q1), 1e-12, 1e-12)
    exact = distance(Capsule(p0, p1, 0.0), Capsule(q0, q1, 0.0)).distance
    assert abs(np.linalg.norm(np.subtract(M2, M1)) - exact) < TIGHT
    a, b = np.asarray(p0, float), np.asarray(p1, float)  # M1 on segment 1, M2 on segment 2
    assert np.linalg.norm(np.cross(np.subtract(M1, a), b - a)) < 1e-9 or np.allclose(a, b)


def _rational_distance(p0, p1, q0, q1) -> float:
    """Segment-segment distance from exact rational arithmetic (every candidate of the clamped form)."""
    P0, P1, Q0, Q1 = ([Fraction(float(x)) for x in v] for v in (p0, p1, q0, q1))
    d1, d2, r = [b - a for a, b in zip(P0, P1)], [b - a for a, b in zip(Q0, Q1)], [a - b for a, b in zip(P0, Q0)]
    dot = lambda u, v: sum(x * y for x, y in zip(u, v))  # noqa: E731
    clamp = lambda x: min(max(x, Fraction(0)), Fraction(1))  # noqa: E731
    a, e, f, c, b = dot(d1, d1), dot(d2, d2), dot(d2, r), dot(d1, r), dot(d1, d2)
    cands = [(s, clamp((b * s + f) / e)) for s in (Fraction(0), Fraction(1))]
    cands += [(clamp((b * t - c) / a), t) for t in (Fraction(0), Fraction(1))]
    if a * e - b * b != 0:
        s, t = (b * f - c * e) / (a * e - b * b), (a * f - b * c) / (a * e - b * b)
        if 0 <= s <= 1 and 0 <= t <= 1:
            cands.append((s, t))
    return math.sqrt(min(dot(v, v) for v in ([P0[k] + d1[k] * s - Q0[k] - d2[k] * t for k in range(3)]
                                             for s, t in cands)))


def test_ranger_segment_segment_random_equals_exact():
    rng = np.random.default_rng(12)
    for _ in range(2000):
        p = rng.normal(size=(4, 3))
        M1, M2 = paper.ranger_segment_segment(*_seg(p[0], p[1]), *_seg(p[2], p[3]), 1e-12, 1e-12)
        exact = distance(Capsule(p[0], p[1], 0.0), Capsule(p[2], p[3], 0.0)).distance
        assert abs(np.linalg.norm(np.subtract(M2, M1)) - exact) < TIGHT


def test_ranger_segment_segment_near_parallel_against_rational_arithmetic():
    # within 1e-7 rad of parallel: Ranger's unit-direction form keeps full precision here
    rng = np.random.default_rng(13)
    for _ in range(300):
        p = rng.normal(size=(4, 3))
        p[3] = p[2] + (p[1] - p[0]) * rng.uniform(-2, 2) + rng.normal(size=3) * 1e-7
        M1, M2 = paper.ranger_segment_segment(*_seg(p[0], p[1]), *_seg(p[2], p[3]), 1e-12, 1e-12)
        assert abs(np.linalg.norm(np.subtract(M2, M1)) - _rational_distance(*p)) < TIGHT


# ------------------------------------------------------------------ Ranger §2/§4: link-face
BOX = Box(center=[0.0, 0.0, 0.0], half_extents=[1.0, 1.0, 1.0])


def test_distal_end_point_projecting_inside_a_face_is_exact():
    link = Capsule([0.2, -0.1, 3.0], [0.3, 0.1, 1.5], 0.1)  # p1 distal, above the top face's interior
    d, pa, pb = paper.paper_capsule_polytope(link, BOX)
    exact = distance(link, BOX)
    assert abs(d - exact.distance) < TIGHT and abs(d - 0.4) < TIGHT
    assert np.allclose(pb, [0.3, 0.1, 1.0], atol=TIGHT) and np.allclose(pa, exact.p_WA, atol=1e-9)


def test_polygon_face_two_sided_distal_inside_is_exact():
    face = Polygon([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    for z in (0.5, -0.5):  # either side of Ranger's planar solar array
        link = Capsule([0.5, 0.5, 2 * z], [0.4, 0.6, z], 0.05)
        assert abs(paper.paper_capsule_polytope(link, face)[0] - distance(link, face).distance) < TIGHT


def test_proximal_end_nearest_to_a_face_interior_paper_is_farther():
    # The link's nearest point to the top face is its proximal end-point, inside the face; the
    # distal end projects outside the face, so only the edges speak (the paper's blind spot).
    link = Capsule([0.0, 0.0, 1.3], [2.5, 0.0, 3.0], 0.1)
    d, _, _ = paper.paper_capsule_polytope(link, BOX)
    exact = distance(link, BOX).distance
    assert abs(exact - 0.2) < TIGHT
    assert d > exact + 0.1


def test_link_whose_middle_is_nearest_to_a_face_interior():
    # The middle of the link lies on the face interior (it dips to touch the plane of a thin
    # face): the nearest point is neither end-point nor on an edge; the paper sees only the
    # distal end-point's height and the edges.
    face = Polygon([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]])
    link = Capsule([-0.5, 0.0, 0.6], [0.5, 0.0, -0.6], 0.05)
    d, _, _ = paper.paper_capsule_polytope(link, face)
    exact = distance(link, face).distance
    assert exact < 0.0 < d and abs(d - (0.6 - 0.05)) < TIGHT


def test_segment_through_a_face_with_both_end_points_outside():
    link = Capsule([-1.5, 0.0, 0.5], [0.5, 0.0, 2.0], 0.02)  # enters at x = -1, leaves through the top
    d, _, _ = paper.paper_capsule_polytope(link, BOX)
    assert distance(link, BOX).distance < 0.0  # exact: penetrating
    assert d > 0.0  # paper: clear (the distal end projects outside; the edges are not touched)


def test_paper_never_below_exact_for_capsule_polytope_random():
    rng = np.random.default_rng(5)
    for _ in range(600):
        link = random_shape("capsule", rng, 1.0)
        ob = random_shape(["box", "polyhedron", "polygon", "prism"][int(rng.integers(4))], rng, 0.5)
        d, pa, pb = paper.paper_capsule_polytope(link, ob)
        assert d >= distance(link, ob).distance - TIGHT
        assert abs(np.linalg.norm(pb - pa) - abs(d)) < 1e-9  # the witness contract


# ------------------------------------------------------------------ Hermes link-obstacle module
def test_hermes_module_documented_answers():
    # pierces the top face: collision
    assert paper.hermes_link_obstacle(Capsule([0, 0, 3], [0, 0, 0.5], 0.1), BOX)
    # clear by 0.3 m at margin 0; within a 0.4 m stopping distance
    clear = Capsule([0, 0, 3], [0, 0, 1.4], 0.1)
    assert not paper.hermes_link_obstacle(clear, BOX) and paper.hermes_link_obstacle(clear, BOX, 0.4)
    # wholly inside the grown obstacle: it crosses no face, so no collision (exact: penetrating)
    inside = Capsule([-0.2, 0, 0], [0.2, 0, 0], 0.1)
    assert distance(inside, BOX).distance < 0 and not paper.hermes_link_obstacle(inside, BOX)
    # beside an edge: inside the plane-grown box, outside the capsule's true reach (false alarm)
    edge = Capsule([1.12, 1.12, 3], [1.12, 1.12, 0.0], 0.15)
    assert distance(edge, BOX).distance > 0 and paper.hermes_link_obstacle(edge, BOX)
    # above a vertex the grown box pokes out of the grown sphere: the pre-test rejects the pair
    vertex = Capsule([1.12, 1.12, 3], [1.12, 1.12, 1.12], 0.15)
    assert distance(vertex, BOX).distance > 0 and not paper.hermes_link_obstacle(vertex, BOX)


def test_hermes_sphere_pretest_and_parallel_faces():
    tet = ConvexPolyhedron([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    assert not paper.hermes_link_obstacle(Capsule([5, 5, 5], [6, 6, 6], 0.1), tet)
    # in the plane z = 0 of a face (parallel to it): the module does not consider that face,
    # but the segment crosses the two side faces and is found through them
    assert paper.hermes_link_obstacle(Capsule([-1, 0.2, 0.0], [2, 0.2, 0.0], 0.0), tet)


# ------------------------------------------------------------------ the Checker on the built-in models
@pytest.fixture(scope="module", params=["ranger", "hermes"])
def pair(request):
    m = armguard.load_model(request.param)
    return m, armguard.checker(m, "analytic", {"fidelity": "paper"}), armguard.checker(m, "analytic")


def test_option_plumbing_and_capabilities(pair, tmp_path, monkeypatch):
    m, p, _ = pair
    assert type(p).__name__ == "PaperChecker" and p.fidelity == "paper" and p.name == "analytic"
    assert {c.value for c in p.capabilities} == {"distances", "verdicts"}
    assert len(p.methods) == len(m.pairs)
    assert p.verdicts == ("ranger" if m.name == "ranger" else "hermes")
    fallback = {"ranger": "camera_arm_camera_0", "hermes": "payload_0"}[m.name]
    assert "exact" in p.representation[fallback]
    assert type(armguard.checker(m, "analytic", {"fidelity": "exact"})).__name__ == "AnalyticChecker"
    with pytest.raises(BackendError, match="verdicts"):
        armguard.checker(m, "analytic", {"fidelity": "paper", "verdicts": "nasa"})
    (tmp_path / "armguard.toml").write_text('[backend]\nname = "analytic"\nfidelity = "paper"\nverdicts = "ranger"\n')
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ARMGUARD_BACKEND", raising=False)
    c = armguard.checker(m)
    assert c.fidelity == "paper" and c.verdicts == "ranger"
    # the same file serves the Detector and the CLI (they refused "verdicts", which the Checker takes)
    det = armguard.Detector(m)
    q = m.neutral()
    np.testing.assert_allclose(det.pair_distances(m.scene_q(q[None])[0]).distance, c.pair_distances(q).distance,
                               atol=1e-12)  # the Detector takes q in the scene's joint order
    from click.testing import CliRunner

    from armguard.cli import main

    r = CliRunner().invoke(main, ["check", m.name])
    assert r.exit_code in (0, 1), r.output  # an answer (clear, warning or collision), not a refused option (3)
    (tmp_path / "armguard.toml").write_text('[backend]\nname = "analytic"\nverdicts = "ranger"\n')
    with pytest.raises(BackendError, match="verdicts"):  # the exact fidelity has no such option
        armguard.Detector(m)
    (tmp_path / "armguard.toml").write_text('[backend]\nname = "analytic"\nfidelity = "exat"\nrelease_gil = true\n')
    with pytest.raises(BackendError, match="fidelity 'exat' is not one of"):  # named first, not release_gil
        armguard.Detector(m)


def test_model_rows_exact_where_the_paper_is_and_never_below(pair):
    m, p, e = pair
    Q = m.random_q(150, 7)
    D, W = p.paper_distances_many(Q, points=True)
    E = np.array([e.pair_distances(q).distance for q in Q])
    meth = np.array(p.methods)
    seg = np.char.startswith(meth.astype(str), paper.METHODS[paper.M_SEGSEG])  # "(verdict: hermes ...)" follows
    assert np.abs(D[:, seg] - E[:, seg]).max() < TIGHT
    fallback = np.char.startswith(meth.astype(str), "exact")
    if fallback.any():
        assert np.abs(D[:, fallback] - E[:, fallback]).max() < 1e-9
    face = np.char.startswith(meth.astype(str), paper.METHODS[paper.M_FACE_EDGE])
    assert (D[:, face] >= E[:, face] - TIGHT).all() and (D[:, face] > E[:, face] + 1e-3).any()
    box = meth == paper.METHODS[paper.M_BOX]
    if box.any():  # the axis's end-points: exactly the link radius more than the exact wall distance
        k = np.flatnonzero(box)
        r = np.array([m.collision_model.geometryObjects[m.geometry_index(m.pairs.a[i])].geometry.radius for i in k])
        assert np.abs(D[:, k] - E[:, k] - r).max() < 1e-12
    assert np.abs(np.linalg.norm(W[..., :3] - W[..., 3:], axis=-1) - np.abs(D)).max() < 1e-9
    r0 = p.pair_distances(Q[0])
    assert np.array_equal(r0.distance, D[0]) and (r0.pairs == m.pairs.names).all()


def test_verdicts(pair):
    m, p, e = pair
    Q = m.random_q(300, 9)
    D = p.paper_distances_many(Q)
    if p.verdicts == "ranger":
        for margin in (0.0, 0.15):
            assert np.array_equal(p.collides(Q, margin=margin), D.min(axis=1) <= margin)
    else:  # Hermes: its four modules on the pairs they cover (tests/test_paper_hermes.py), distances elsewhere
        hit = p.collides(Q)
        ph, _, br = p.pair_verdicts_many(Q)
        assert np.array_equal(hit, ph.any(axis=1))
        herm = np.array([mod != "" for mod in p.hermes_modules])
        assert herm.any() and ("hermes" in p.methods[int(np.flatnonzero(herm)[0])])
        assert np.array_equal(ph[:, ~herm], D[:, ~herm] <= 0.0) and (br[:, ~herm] == -1).all()
        assert (br[:, herm] >= 0).all()
        exact = e.collides(Q)  # docs/paper-fidelity.md (10^4 configurations): 0.16 % false alarms, 0.06 % missed
        assert (hit & ~exact).mean() <= 0.02 and (~hit & exact).mean() <= 0.01, \
            ((hit & ~exact).sum(), (~hit & exact).sum())  # (a checker always "clear" agreed on 63 %)
