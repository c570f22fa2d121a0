"""Public robots, analytic against coal: the differential spine on robots no one here wrote.

Four robots of different kinds, loaded by name with the SRDF armguard finds for them: the KUKA
iiwa of pybullet_data (mesh hulls, no SRDF), xarm7 (dense meshes and its SRDF) and z1 (dense
meshes, cylinders; its SRDF's chain names a link the URDF lacks), and panda_collision (spheres and
cylinders only: 112 of its 252 pairs a sphere and a cylinder, ``_pair_point_cylinder``'s closed form).  On seeded random in-limit
configurations both backends must give the same verdict everywhere, and the same distance on
every separated pair.  Penetration depths of cylinder pairs are left out of the distance check:
coal's EPA overestimates deep cylinder–cylinder penetrations (z1 ``link02_1``/``link04_0``: coal
−81.7 mm where the exact depth, bounded by 2 M sampled separating directions, is −49.2 mm).
The full table over all fifteen robots is ``python -m bench robots`` (docs/performance.md).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import armguard
from armguard.model import known_models

_AVAILABLE = {m.name for m in known_models() if m.available}


@pytest.mark.parametrize("name", ["kuka_iiwa", "xarm7", "z1", "panda_collision"])
def test_public_robot_analytic_equals_coal(name):
    if name not in _AVAILABLE:
        pytest.skip(f"{name}'s package is not installed")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = armguard.load_model(name)
    assert len(model.pairs) > 0
    ana, ref = armguard.checker(model, "analytic"), armguard.checker(model, "coal")
    Q = model.random_q(40, 11)
    for q in Q:
        a, c = ana.pair_distances(q), ref.pair_distances(q)
        assert [tuple(p) for p in a.pairs] == [tuple(p) for p in c.pairs]
        assert np.all(np.isfinite(a.distance))
        assert (a.distance <= 0).any() == (c.distance <= 0).any(), (name, q.tolist())
        np.testing.assert_array_equal(a.distance <= 0, c.distance <= 0)
        apart = (a.distance > 1e-9) & (c.distance > 1e-9)
        np.testing.assert_allclose(a.distance[apart], c.distance[apart], rtol=0, atol=1e-6)
        # witness relation on the analytic side, on every pair
        gap = np.linalg.norm(a.p_WA - a.p_WB, axis=1)
        np.testing.assert_allclose(gap, np.abs(a.distance), rtol=0, atol=1e-9)
    assert ana.collides(Q).tolist() == ref.collides(Q).tolist()
