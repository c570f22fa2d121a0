"""The closed-form sphere-cylinder distance (``armguard.geometry._pair_point_cylinder``) against the
general kernel it stands in for: GJK and EPA on the two cores' support functions
(``_pair_cylinder.support_pair``), on seeded random cylinders and spheres apart, touching and deep
inside (through the wall or a cap), and on panda_collision's pairs in the analytic backend against coal
(``tests/test_public_differential.py``).  Distances equal the definition's (nearest point or nearest
face), and the general kernel's to its tolerance where it settles one (a point deep on the axis it
reports touching, ``-(rp + rb)``: an upper bound, which the closed form's depth is below); the
witnesses are ``distance`` apart along the normal, and each lies on its own shape's surface."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from armguard import DEFAULT_TOLERANCES as TOL
from armguard.geometry._pair_cylinder import SUPPORT_WORK_SIZE, support_pair
from armguard.geometry._pair_point_cylinder import point_cylinder_flat

SETTINGS = settings(max_examples=300, deadline=None, derandomize=True)


def _cylinder(c, R, r, h) -> np.ndarray:
    return np.concatenate([c, [r, r, h], R.ravel()])


def _surface_distance(p, cyl, rb) -> float:
    """Signed distance of ``p`` to the cylinder swept by ``rb``, from its definition (the farthest
    face plane inside, the clamped nearest point outside), in the cylinder's frame."""
    c, r, h, R = cyl[0:3], cyl[3], cyl[5], cyl[6:15].reshape(3, 3)
    x, y, s = R.T @ (p - c)
    rho = math.hypot(x, y)
    if rho <= r and abs(s) <= h:
        return max(rho - r, abs(s) - h) - rb
    return math.hypot(max(rho - r, 0.0), max(abs(s) - h, 0.0)) - rb


@SETTINGS
@given(seed=st.integers(0, 2**31 - 1), where=st.sampled_from(["apart", "near", "inside", "axis"]),
       rp=st.sampled_from([0.0, 0.01, 0.05]), rb=st.sampled_from([0.0, 0.02]))
def test_the_closed_form_equals_gjk_and_epa_on_the_support_functions(seed, where, rp, rb):
    rng = np.random.default_rng(seed)
    R = Rotation.random(random_state=seed).as_matrix()
    c, r, h = rng.normal(size=3), rng.uniform(0.02, 0.2), rng.uniform(0.02, 0.3)
    cyl = _cylinder(c, R, r, h)
    scale = {"apart": 1.0, "near": 0.3, "inside": 0.0, "axis": 0.0}[where]
    local = rng.uniform(-1.0, 1.0, 3) * np.array([r, r, h]) * (0.95 if where == "inside" else 1.0)
    if where == "axis":
        local[:2] = 0.0
    p = c + R @ local + scale * rng.normal(size=3)
    out, ref = np.zeros(9), np.zeros(9)
    d = point_cylinder_flat(p[0], p[1], p[2], rp, cyl, 0, rb, out, 0)
    d_ref, status = support_pair(p[None, :].copy(), np.zeros(0), rp, np.zeros((0, 3)), cyl, rb, ref,
                                 np.zeros(SUPPORT_WORK_SIZE), TOL.length, TOL.gjk_epsilon, TOL.gjk_max_iterations,
                                 -math.inf)
    assert math.isfinite(d)
    assert d == pytest.approx(_surface_distance(p, cyl, rb) - rp, abs=1e-12)
    if d_ref > 0.0 or d_ref < -(rp + rb) - 1e-9:  # apart, or a depth EPA settled: the same
        assert d == pytest.approx(d_ref, abs=1e-9), (where, d, d_ref, status)
    else:  # EPA reported the cores touching (its fallback, -(rp + rb)): an upper bound
        assert d <= d_ref + 1e-9, (where, d, d_ref, status)
    n = out[6:9]
    assert np.linalg.norm(n) == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(out[3:6] - out[0:3], d * n, atol=1e-12)
    # each witness on its own surface: A's on the sphere, B's on the swept cylinder
    assert np.linalg.norm(out[0:3] - p) == pytest.approx(rp, abs=1e-12)
    assert _surface_distance(out[3:6], cyl, rb) == pytest.approx(0.0, abs=1e-12)


def test_a_point_on_the_axis_and_one_on_the_rim():
    cyl = _cylinder(np.zeros(3), np.eye(3), 0.1, 0.2)
    out = np.zeros(9)
    # on the axis, past the cap: the nearest point is the cap's centre
    assert point_cylinder_flat(0.0, 0.0, 0.5, 0.0, cyl, 0, 0.0, out, 0) == pytest.approx(0.3, abs=1e-15)
    np.testing.assert_allclose(out[3:6], [0.0, 0.0, 0.2], atol=1e-15)
    # at the centre: out through the wall (0.1 m) rather than a cap (0.2 m); any radial direction
    assert point_cylinder_flat(0.0, 0.0, 0.0, 0.0, cyl, 0, 0.0, out, 0) == pytest.approx(-0.1, abs=1e-15)
    assert np.linalg.norm(out[3:6]) == pytest.approx(0.1, abs=1e-15) and out[5] == 0.0
    # on the rim exactly: touching, a unit normal, no NaN
    assert point_cylinder_flat(0.1, 0.0, 0.2, 0.0, cyl, 0, 0.0, out, 0) == 0.0
    assert np.all(np.isfinite(out)) and np.linalg.norm(out[6:9]) == pytest.approx(1.0)
