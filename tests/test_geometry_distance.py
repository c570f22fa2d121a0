"""Signed distance for every shape pair against the slow feature-enumeration reference, and
the Proximity contract (witness relation, witnesses on the surfaces, swap symmetry, rigid
motion invariance, agreement with ``intersects``).  Golden source: ``armguard.geometry._reference``
(exact enumeration of vertex/edge/face pairs, exhaustive SAT) and closed forms."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from _geometry_strategies import KINDS, random_rotation, random_shape
from armguard import DEFAULT_TOLERANCES, GeometryError
from armguard.geometry import Box, Capsule, ConvexPolyhedron, Polygon, Sphere, distance, intersects
from armguard.geometry._reference import reference_distance, sdf

PAIRS = [(a, b) for a in KINDS for b in KINDS]
CLOSED = {"sphere", "capsule", "box"}
SETTINGS = settings(max_examples=40, deadline=None, derandomize=True)


def _tol_sep(ka, kb):
    # issue #2: 1e-9 m for sphere/capsule/box pairs (closed forms), 1e-7 m for GJK pairs
    return 1e-9 if (ka in CLOSED and kb in CLOSED and not (ka == kb == "box")) else 1e-7


def _check_contract(a, b, r):
    d = r.distance
    assert np.isfinite(d)
    np.testing.assert_allclose(np.linalg.norm(r.nhat_AB_W), 1.0, atol=1e-9)
    np.testing.assert_allclose(r.p_WB - r.p_WA, d * r.nhat_AB_W, atol=1e-9)
    assert abs(np.linalg.norm(r.p_WB - r.p_WA) - abs(d)) <= 1e-9
    assert abs(sdf(r.p_WA, a)) <= 1e-9, sdf(r.p_WA, a)
    assert abs(sdf(r.p_WB, b)) <= 1e-9, sdf(r.p_WB, b)


@pytest.mark.parametrize("ka,kb", PAIRS, ids=[f"{a}-{b}" for a, b in PAIRS])
def test_matches_reference_and_contract(ka, kb):
    rng = np.random.default_rng(KINDS.index(ka) * 10 + KINDS.index(kb))
    # the reference enumerates every feature pair: fewer samples where both have many features
    for _ in range(25 if {ka, kb} & {"sphere", "capsule"} else 8):
        a = random_shape(ka, rng)
        b = random_shape(kb, rng)
        r = distance(a, b)
        ref, _, _ = reference_distance(a, b)
        if ref > 0.0:
            assert abs(r.distance - ref) <= _tol_sep(ka, kb), (r.distance, ref)
        else:
            assert abs(r.distance - ref) <= 1e-6, (r.distance, ref)
        _check_contract(a, b, r)
        assert intersects(a, b) == (r.distance <= DEFAULT_TOLERANCES.length)


@pytest.mark.parametrize("ka,kb", PAIRS, ids=[f"{a}-{b}" for a, b in PAIRS])
def test_swap_and_rigid_motion(ka, kb):
    rng = np.random.default_rng(100 + KINDS.index(ka) * 10 + KINDS.index(kb))
    for _ in range(10):
        a = random_shape(ka, rng, spread=0.6)
        b = random_shape(kb, rng, spread=0.6)
        r = distance(a, b)
        s = distance(b, a)
        assert abs(r.distance - s.distance) <= 1e-9
        if r.distance > 1e-6:  # witnesses are unique when apart (strictly convex or generic)
            np.testing.assert_allclose(r.nhat_AB_W, -s.nhat_AB_W, atol=1e-6)
        X = np.eye(4)
        X[:3, :3] = random_rotation(rng)
        X[:3, 3] = rng.uniform(-2, 2, 3)
        m = distance(a.transformed(X), b.transformed(X))
        assert abs(m.distance - r.distance) <= 1e-7


@SETTINGS
@given(
    ka=st.sampled_from(KINDS), kb=st.sampled_from(KINDS), seed=st.integers(0, 2**31 - 1),
    spread=st.floats(0.0, 1.5),
)
def test_property_contract(ka, kb, seed, spread):
    rng = np.random.default_rng(seed)
    a = random_shape(ka, rng, spread)
    b = random_shape(kb, rng, spread)
    r = distance(a, b)
    _check_contract(a, b, r)
    s = distance(b, a)
    assert abs(r.distance - s.distance) <= 1e-9
    assert intersects(a, b) == intersects(b, a) == (r.distance <= DEFAULT_TOLERANCES.length)
    # translating B by the signed distance along nhat makes the shapes just touch
    if r.distance < -1e-6:
        X = np.eye(4)
        X[:3, 3] = (-r.distance + 1e-6) * r.nhat_AB_W
        assert distance(a, b.transformed(X)).distance > 0.0
        X[:3, 3] = (-r.distance - 1e-6) * r.nhat_AB_W
        assert distance(a, b.transformed(X)).distance < 0.0


CLOSED_FORMS = [
    ("sphere-sphere apart", Sphere([0, 0, 0], 1.0), Sphere([3, 0, 0], 0.5), 1.5),
    ("sphere-sphere deep", Sphere([0, 0, 0], 1.0), Sphere([0.5, 0, 0], 0.5), -1.0),
    ("capsules crossing (Ranger §3)", Capsule([-1, 0, 0], [1, 0, 0], 0.1), Capsule([0, -1, 0.5], [0, 1, 0.5], 0.2), 0.2),
    ("capsules parallel (Hermes)", Capsule([0, 0, 0], [1, 0, 0], 0.1), Capsule([0.5, 1, 0], [2, 1, 0], 0.1), 0.8),
    ("capsules colinear apart", Capsule([0, 0, 0], [1, 0, 0], 0.1), Capsule([2, 0, 0], [3, 0, 0], 0.1), 0.8),
    ("capsules colinear overlap", Capsule([0, 0, 0], [1, 0, 0], 0.1), Capsule([0.5, 0, 0], [3, 0, 0], 0.1), -0.2),
    ("segments intersecting", Capsule([-1, 0, 0], [1, 0, 0], 0.0), Capsule([0, -1, 0], [0, 1, 0], 0.0), 0.0),
    ("zero-length capsule is a sphere", Capsule([0, 0, 0], [0, 0, 0], 0.5), Sphere([2, 0, 0], 0.5), 1.0),
    ("end-point vs interior", Capsule([0, 0, 0], [1, 0, 0], 0.0), Capsule([2, -1, 0], [2, 1, 0], 0.0), 1.0),
    ("sphere-box face", Sphere([3, 0, 0], 0.5), Box([0, 0, 0], [1, 1, 1]), 1.5),
    ("sphere-box corner", Sphere([2, 2, 2], 0.0), Box([0, 0, 0], [1, 1, 1]), np.sqrt(3)),
    ("sphere inside box", Sphere([0.5, 0, 0], 0.1), Box([0, 0, 0], [1, 1, 1]), -0.6),
    ("capsule through box", Capsule([-2, 0, 0], [2, 0, 0], 0.1), Box([0, 0.2, 0], [1, 1, 1]), -0.9),
    ("box-box face", Box([0, 0, 0], [1, 1, 1]), Box([2.5, 0, 0], [1, 1, 1]), 0.5),
    ("box-box overlap", Box([0, 0, 0], [1, 1, 1]), Box([1.5, 0.2, 0], [1, 1, 1]), -0.5),
    ("point above face (Ranger §4)", Sphere([0.2, 0.2, 1], 0.0), Polygon([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]), 1.0),
]


@pytest.mark.parametrize("a,b,expected", [c[1:] for c in CLOSED_FORMS], ids=[c[0] for c in CLOSED_FORMS])
def test_closed_forms(a, b, expected):
    r = distance(a, b)
    assert abs(r.distance - expected) <= 1e-12
    _check_contract(a, b, r)


def test_bad_input_raises():
    with pytest.raises(GeometryError, match="Sphere.center"):
        Sphere([np.nan, 0, 0], 1.0)
    with pytest.raises(GeometryError, match="Capsule.p1"):
        Capsule([0, 0, 0], [np.inf, 0, 0], 1.0)
    with pytest.raises(GeometryError, match="Capsule.radius"):
        Capsule([0, 0, 0], [1, 0, 0], -0.1)
    with pytest.raises(GeometryError, match="half_extents"):
        Box([0, 0, 0], [1, 0, 1])
    with pytest.raises(GeometryError, match="ConvexPolyhedron.vertices"):
        ConvexPolyhedron([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    with pytest.raises(GeometryError, match="coplanar|non-coplanar"):
        ConvexPolyhedron([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
    with pytest.raises(GeometryError, match="not planar"):
        Polygon([[0, 0, 0], [1, 0, 0], [1, 1, 0.1], [0, 1, 0]])
    with pytest.raises(GeometryError, match="convex"):
        Polygon([[0, 0, 0], [2, 0, 0], [1, 0.2, 0], [1, 2, 0]])
    with pytest.raises(GeometryError, match="a:"):
        distance("box", Sphere([0, 0, 0], 1.0))


@pytest.mark.parametrize("kind", KINDS, ids=KINDS)
def test_bounding_volumes(kind):
    rng = np.random.default_rng(3)
    for _ in range(5):
        s = random_shape(kind, rng)
        lo, hi = s.aabb()
        outer = s.circumscribed_sphere()
        inner = s.inscribed_sphere()
        # directions: the support point of the shape lies inside the AABB and the outer sphere
        for u in rng.normal(size=(12, 3)):
            p = s.support(u)
            assert np.all(p >= lo - 1e-12) and np.all(p <= hi + 1e-12)
            assert np.linalg.norm(p - outer.center) <= outer.radius + 1e-9
            # and the inner sphere's support point lies inside the shape
            q = inner.support(u)
            assert sdf(q, s) <= 1e-9


def test_inscribed_sphere_of_a_polyhedron_the_dual_simplex_gives_up_on():
    """A regular pentagonal prism (``tests/test_clip.py``'s seed 6665) whose Chebyshev-centre LP
    HiGHS's dual simplex once left unsolved (status "Unknown" on a feasible LP, so
    ``Guard.from_shape`` raised): its largest inscribed sphere is the prism's own, as a Prism
    says (its radius; the centre is free along the longer span), and inside the prism."""
    _same_inscribed_sphere(random_shape("prism", np.random.default_rng(6665), spread=0.0))


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_inscribed_sphere_of_a_prism_polyhedron(seed):
    _same_inscribed_sphere(random_shape("prism", np.random.default_rng(seed)))


def _same_inscribed_sphere(prism):
    want, got = prism.inscribed_sphere(), prism.as_polyhedron().inscribed_sphere()
    assert abs(got.radius - want.radius) <= 1e-9
    for u in np.random.default_rng(0).normal(size=(12, 3)):
        assert sdf(got.support(u), prism) <= 1e-9


def test_two_thin_overlapping_boxes_are_not_called_apart():
    """Boxes 0.34 and 8 um thick overlapping by 9 nm: GJK's simplex, flattened by rounding, stalled with
    |v| = 2.3e-7 m and no support plane separating, and the pair was reported apart by |v| (coal: -2.0e-8,
    an exact rational SAT: -9.2e-9).  A stall without that proof is settled by the exact SAT."""
    import numpy as np

    from armguard.geometry import Box, distance

    ha = np.array([1.6712350368125251e-07, 5.6948351127196276e-02, 7.2161457778022617e-02])
    hb = np.array([4.0433160065348468e-06, 1.0217414717276228e-01, 1.7260343604863720e-01])
    Xa = np.array([[5.7399163443870971e-01, -8.1876144581147725e-01, 1.2778828079215820e-02, -0.07229964190526061],
                   [-5.2247103764534597e-01, -3.7820472543830991e-01, -7.6418924389049614e-01, 0.11236052140441188],
                   [6.3052170336648539e-01, 4.3196166555474835e-01, -6.4486549068390531e-01, -0.0021780085535283433],
                   [0.0, 0.0, 0.0, 1.0]])
    Xb = np.array([[8.8787724918534511e-02, 5.7149336849064514e-01, 8.1578923115900859e-01, 0.0],
                   [7.4250600953143842e-01, -5.8390505083004240e-01, 3.2823728829135967e-01, 0.0],
                   [6.6392888603636624e-01, 5.7658496458577668e-01, -4.7618086154330946e-01, 0.0], [0.0, 0.0, 0.0, 1.0]])
    d = distance(Box(np.zeros(3), ha, np.eye(3)).transformed(Xa), Box(np.zeros(3), hb, np.eye(3)).transformed(Xb)).distance
    assert -1.0e-8 < d < -8.0e-9, d
