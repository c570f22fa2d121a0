"""The exact signed distance of a cylinder against a flat core (box, polygon, polyhedron).

Two roundings on the cylinder's curved support made the kernel (``_pair_cylinder``, used by
``armguard.geometry.distance`` and the detector's narrow phase) report "touching" -- 0 m with
p_WA == p_WB -- for about 1 in 300 random cylinder-box pairs:

* penetrating: EPA's polytope broke near the curved optimum after the depth was bracketed (the
  depth was up to 0.36 m);
* separated: GJK, after a support plane had already proved the cores apart, took a tetrahedron
  that rounding had flattened for one holding the origin (the pairs were up to 28 mm apart).

The cases below are the ones a seeded search found (seed 0, 3,000 pairs per kind: 8 boxes, 4
polygons, 4 polyhedra).  The reference is the support-function minimum of
tests/test_geometry_cylinder.py, its support values over all directions at once (the two agree:
test_reference_is_the_slow_one); coal agrees on the separated ones (to 1e-6 m: 8.4e-7 m off on
box case 2228, where armguard and the reference agree to 1e-15 m) but is no oracle for the penetrating ones: its EPA on cylinders gives
-0.90 m for box case 45, whose depth is 0.2267 m.
"""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from _geometry_strategies import random_rotation, random_shape
from armguard.geometry import Box, Cylinder, distance
from armguard.geometry._dispatch import _support_core
from armguard.geometry._pair_cylinder import SUPPORT_WORK_SIZE, support_pair
from armguard._tolerance import DEFAULT_TOLERANCES as TOL
from armguard.geometry._support_reference import reference_signed_distance
from test_geometry_cylinder import check_contract


FOUND = {"box": (45, 843, 1552, 1779, 1890, 2150, 2228, 2280), "polygon": (892, 1274, 2687, 2752),
         "polyhedron": (700, 1440, 1910, 2763)}
"""Indices (in the seeded stream of :func:`_pairs`) of the pairs that were reported touching."""


def _pairs(kind: str, indices):
    """The seeded stream of the search: a cylinder near the origin and a random ``kind`` shape."""
    rng = np.random.default_rng(0)
    want = set(indices)
    for i in range(max(indices) + 1):
        a = Cylinder(rng.uniform(-0.3, 0.3, 3), random_rotation(rng), rng.uniform(0.05, 0.5), rng.uniform(0.05, 0.6))
        b = random_shape(kind, rng, 0.3)
        if i in want:
            yield i, a, b


def _detector_form(a, b):
    """The call the detector's narrow phase makes (``_narrow.pair_distance``): the flat side as its
    core points, the cylinder as its 15-float buffer, no early exit (``level = -inf``)."""
    pa, ca, ra = _support_core(a)
    pb, cb, rb = _support_core(b)
    out = np.empty(9)
    d, _ = support_pair(pa, ca, ra, pb, cb, rb, out, np.empty(SUPPORT_WORK_SIZE), TOL.length, TOL.gjk_epsilon,
                        TOL.gjk_max_iterations, -np.inf)
    return d, out


@pytest.mark.parametrize("kind", sorted(FOUND))
def test_found_cases_have_their_distance(kind):
    from test_geometry_cylinder import _coal_pair

    for i, a, b in _pairs(kind, FOUND[kind]):
        ref = reference_signed_distance(a, b)
        assert abs(ref) > 1e-4, (i, ref)  # none of them touches
        for r in (distance(a, b), distance(b, a)):
            assert abs(r.distance - ref) <= 1e-9, (kind, i, r.distance, ref)
            assert np.linalg.norm(r.p_WB - r.p_WA) >= 1e-4  # not p_WA == p_WB
        # witnesses are convex combinations of support points: on the curved surface they lie
        # inside it by a chord's sagitta (as in test_geometry_cylinder.test_touching)
        check_contract(a, b, distance(a, b), surface_tol=1e-6)
        d, out = _detector_form(a, b)
        assert abs(d - ref) <= 1e-9, (kind, i, d, ref)
        assert abs(np.linalg.norm(out[3:6] - out[0:3]) - abs(d)) <= 1e-9
        if ref > 0.0:  # coal's GJK on a cylinder: 8.4e-7 m short on box case 2228, else within 1e-9 m
            d_coal = _coal_pair(a, b)[0]
            # -DBL_MAX is coal's failure value, not a distance: after tests/test_reference_integrity.py in
            # the same process coal returned it for box case 2228 (not reproduced in a script)
            assert abs(d - d_coal) <= 1e-6 or d_coal == -sys.float_info.max, (kind, i, d, d_coal)


def test_reference_is_the_slow_one():
    from test_geometry_cylinder import reference_signed_distance as slow

    for _, a, b in _pairs("box", (45, 2228)):
        assert abs(reference_signed_distance(a, b) - slow(a, b)) <= 1e-12


_unit = st.floats(-1.0, 1.0)


@settings(max_examples=12, deadline=None, derandomize=True)
@given(st.integers(0, 2**31 - 1), st.tuples(_unit, _unit, _unit), st.floats(0.0, 0.9))
def test_penetrating_cylinder_box_depth(seed, offset, reach):
    """Any penetrating cylinder-box pair: a depth (never 'touching' at 0 m), equal to the
    support-function reference, the same in both orders and in the detector's form."""
    rng = np.random.default_rng(seed)
    a = Cylinder(rng.uniform(-0.2, 0.2, 3), random_rotation(rng), rng.uniform(0.05, 0.4), rng.uniform(0.05, 0.5))
    half = rng.uniform(0.05, 0.4, 3)
    c = a.center + reach * min(a.radius, a.half_length) * np.asarray(offset)  # the box's centre inside the cylinder
    b = Box(c, half, random_rotation(rng))
    ref = reference_signed_distance(a, b)
    assert ref < 0.0
    r = distance(a, b)
    assert r.distance < 0.0 and abs(r.distance - ref) <= 1e-6, (r.distance, ref)
    assert abs(distance(b, a).distance - r.distance) <= 1e-9
    d, _ = _detector_form(a, b)
    assert abs(d - r.distance) <= 1e-9
    check_contract(a, b, r, surface_tol=1e-7)


def _flat_contact(rng, plate: bool):
    """A cylinder and a box sharing a flat contact: the box turned only about the cylinder's axis
    (its faces parallel to the caps) and centred anywhere within 1.5 half-lengths along the axis, or a
    thin plate (1-10 mm) through the cylinder.  Coplanar caps and faces are where the supports are
    most degenerate: every point of a cap is a support along the axis."""
    a = Cylinder(rng.uniform(-0.2, 0.2, 3), random_rotation(rng), rng.uniform(0.02, 0.4), rng.uniform(0.02, 0.5))
    if plate:
        half = np.r_[rng.uniform(0.05, 0.5, 2), rng.uniform(0.001, 0.01)]
        return a, Box(a.center + rng.uniform(-1, 1, 3) * (a.radius + a.half_length), half, random_rotation(rng))
    t = rng.uniform(0.0, 2 * math.pi)
    Rz = np.array([[math.cos(t), -math.sin(t), 0.0], [math.sin(t), math.cos(t), 0.0], [0.0, 0.0, 1.0]])
    c = a.center + a.rotation @ np.r_[rng.uniform(-1, 1, 2) * a.radius, rng.uniform(-1.5, 1.5) * a.half_length]
    return a, Box(c, rng.uniform(0.02, 0.4, 3), a.rotation @ Rz)


@pytest.mark.parametrize("plate", [False, True], ids=["faces parallel to the caps", "thin plate"])
def test_penetrating_flat_contacts_against_coal_and_the_reference(plate):
    """Seeded penetrating cylinder-box pairs with a flat contact: a depth, never 'touching' at 0 m
    with p_WA == p_WB; geometry.distance equals the detector's call and coal's answer (to 1e-6 m)
    -- or, where coal's EPA is off (about 1 pair in 25 in a search of 4,000), the slow reference.
    (A search of 4,000 such pairs, 2,868 penetrating: none touching, 120 coal disagreements, all
    sided with armguard by the reference.)"""
    from test_geometry_cylinder import _coal_pair

    rng = np.random.default_rng(2027 + plate)
    seen = coal_off = 0
    while seen < 25:
        a, b = _flat_contact(rng, plate)
        r = distance(a, b)
        if r.distance > 1e-6:
            continue
        seen += 1
        assert np.linalg.norm(r.p_WB - r.p_WA) >= abs(r.distance) - 1e-9
        assert r.distance < -1e-9 or abs(reference_signed_distance(a, b)) <= 1e-6, (r.distance, reference_signed_distance(a, b))
        d, out = _detector_form(a, b)
        assert abs(d - r.distance) <= 1e-9 and abs(distance(b, a).distance - r.distance) <= 1e-9
        if abs(_coal_pair(a, b)[0] - r.distance) > 1e-6:
            coal_off += 1
            assert abs(reference_signed_distance(a, b) - r.distance) <= 1e-6, (r.distance, _coal_pair(a, b)[0])
        check_contract(a, b, r, surface_tol=1e-7)
    assert coal_off <= 5  # coal is the comparison, not decoration: most pairs are held to it
