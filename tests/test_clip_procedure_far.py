"""Smith's clipping procedure far from the origin: ``REL = IVOLLOC * OBLOC`` rounds at about 1e-16 of the poses'
translations, and a fixed plane tolerance of 1 nm let pairs posed 1e7-1e8 m out, touching or penetrating by
10 nm, come out CLEAR (19 of 89 at 1e8 m).  The tolerance grows with the translations (erring to INTERSECTED)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from armguard.clip import ClipStatus, Guard, Obstacle, check, check_many
from armguard.geometry import Box, ConvexPolyhedron, distance


def _pairs(n=40, seed=5):
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        a = Box(np.zeros(3), rng.uniform(0.05, 0.3, 3), np.eye(3)) if i % 2 else ConvexPolyhedron(rng.normal(size=(12, 3)) * 0.1)
        b = ConvexPolyhedron(rng.normal(size=(12, 3)) * 0.1) if i % 3 else Box(np.zeros(3), rng.uniform(0.05, 0.3, 3), np.eye(3))
        Xa, Xb = np.eye(4), np.eye(4)
        Xa[:3, :3] = Rotation.random(random_state=int(rng.integers(2**31))).as_matrix()
        Xa[:3, 3] = rng.uniform(-0.5, 0.5, 3)
        Xb[:3, :3] = Rotation.random(random_state=int(rng.integers(2**31))).as_matrix()
        p = distance(a.transformed(Xa), b.transformed(Xb))
        if p.distance > 0.0:
            out.append((a, b, Xa, Xb, p))
    return out


@pytest.mark.parametrize("offset", [0.0, 1e6, 1e7, 1e8])
@pytest.mark.parametrize("depth", [0.0, 1e-8, 1e-7])
def test_touching_or_penetrating_pairs_far_out_are_never_clear(offset, depth):
    wrong, wrong_many = [], []
    for a, b, Xa, Xb, p in _pairs():
        Xa2, Xb2 = Xa.copy(), Xb.copy()
        Xa2[:3, 3] += (p.distance + depth) * p.nhat_AB_W + offset
        Xb2[:3, 3] += offset
        Xa0, Xb0 = Xa2.copy(), Xb2.copy()  # the same float placement at the origin (Sterbenz: exact)
        Xa0[:3, 3] -= offset
        Xb0[:3, 3] -= offset
        d = distance(a.transformed(Xa0), b.transformed(Xb0)).distance
        g, ob = Guard.from_shape(a), Obstacle.from_shape(b)
        r = check(g, ob, Xa2, Xb2)
        status, _ = check_many(g, ob, Xa2[None], Xb2)  # code 0: CLEAR
        if d <= 0.0 and r.status is ClipStatus.CLEAR:
            wrong.append(d)
        if d <= 0.0 and status[0] == 0:
            wrong_many.append(d)
    assert not wrong and not wrong_many, (wrong, wrong_many)
