"""Public robots, analytic against coal: the differential spine on robots no one here wrote.

Twelve robots of the public table (the other three, panda, ur5 and kinova, are in the conformance
suite's models); first four of different kinds, loaded by name with the SRDF armguard finds for them: the KUKA
iiwa of pybullet_data (mesh hulls, no SRDF), xarm7 (dense meshes and its SRDF) and z1 (dense
meshes, cylinders; its SRDF's chain names a link the URDF lacks), and panda_collision (spheres and
cylinders only: 112 of its 252 pairs a sphere and a cylinder, ``_pair_point_cylinder``'s closed form).  On seeded random in-limit
configurations both backends must give the same verdict everywhere, and the same distance on
every separated pair.  Penetration depths of cylinder pairs are left out of the distance check:
coal's EPA overestimates deep cylinder–cylinder penetrations (z1 ``link02_1``/``link04_0``: coal
−81.7 mm where the exact depth, bounded by 2 M sampled separating directions, is −49.2 mm); on z1
those depths are held to python-fcl's instead, and where coal's EPA gives up (``-DBL_MAX``) its
backend computes the pair again with a looser EPA tolerance.
The full table over all fifteen robots is ``python -m bench robots`` (docs/performance.md).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import armguard
from armguard.model import known_models

_AVAILABLE = {m.name for m in known_models() if m.available}


@pytest.mark.parametrize("name, n", [("kuka_iiwa", 40), ("xarm7", 40), ("z1", 40), ("panda_collision", 40),
                                     # the rest of the public table (bench robots: 300 configurations each)
                                     ("ur3", 40), ("ur10", 40), ("ur5_gripper", 40), ("franka_panda", 40), ("xarm6", 40),
                                     ("talos_left_arm", 40), ("so100", 40), ("so101", 20)])
def test_public_robot_analytic_equals_coal(name, n):
    if name not in _AVAILABLE:
        pytest.skip(f"{name}'s package is not installed")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = armguard.load_model(name)
    assert len(model.pairs) > 0
    ana, ref = armguard.checker(model, "analytic"), armguard.checker(model, "coal")
    Q = model.random_q(n, 11)
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


# z1 at a configuration where coal's EPA, at the reference's 1e-9 tolerance, gives up on a
# penetrating cylinder pair and returns -DBL_MAX as the distance (found by `armguard compare z1`)
_Z1_EPA_GAVE_UP = [-0.8453603385916364, 1.9922585316821473, -0.24661979153421276, 1.4037013798562386,
                   -0.5459526902129788, 0.5770467243061099, -1.2367346345542591]


def _z1_pair(model, a, b):
    return next(k for k, (x, y) in enumerate(zip(model.pairs.a, model.pairs.b)) if {x, y} == {a, b})


def test_coal_settles_a_depth_its_epa_gave_up_on():
    if "z1" not in _AVAILABLE:
        pytest.skip("z1's package is not installed")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = armguard.load_model("z1")
    q = np.array(_Z1_EPA_GAVE_UP)
    k = _z1_pair(model, "link02_1", "link06_0")
    ref = armguard.checker(model, "coal")
    import pinocchio as pin

    # the premise: at the reference's own EPA tolerance coal returns its sentinel for this pair
    data, gdata = ref._thread_data()
    pin.updateGeometryPlacements(model.pin_model, data, ref.geometry_model, gdata, q)
    i = ref._row_pairs[k][0]
    assert pin.computeDistance(ref.geometry_model, gdata, i).min_distance < -1e300
    c = ref.pair_distances(q)
    a = armguard.checker(model, "analytic").pair_distances(q)
    assert np.all(c.distance > -1.0)  # no sentinel left in any row
    # the retried depth (EPA tolerance 1e-8 or looser) against the exact one: -20.7356 mm
    assert c.distance[k] < 0 and abs(c.distance[k] - a.distance[k]) < 1e-6
    np.testing.assert_allclose(np.linalg.norm(c.p_WA[k] - c.p_WB[k]), -c.distance[k], rtol=0, atol=1e-6)
    # the request keeps the reference's tolerance for the next call
    assert gdata.distanceRequests[i].epa_tolerance == ref.gjk_tolerance


def test_coal_refuses_a_depth_no_tolerance_settles(monkeypatch):
    if "z1" not in _AVAILABLE:
        pytest.skip("z1's package is not installed")
    import armguard_coal

    from armguard._errors import BackendError

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = armguard.load_model("z1")
    monkeypatch.setattr(armguard_coal, "EPA_RETRY_TOLERANCES", (1e-9,))  # the tolerance that gave up
    with pytest.raises(BackendError, match=r"no penetration depth for link0\d_\d / link0\d_\d at q = \[-0\.845"):
        armguard.checker(model, "coal").pair_distances(np.array(_Z1_EPA_GAVE_UP))


def test_z1_cylinder_depths_equal_python_fcl():
    """z1's pairs all have a cylinder side, where coal's depths are off (the module docstring); python-fcl's
    EPA is the second opinion: on every penetrating pair the two depths agree to 1e-6 m (``bench agreement``:
    9.7e-7 m at most over 270,000 pair entries)."""
    from armguard.backends import available

    if "z1" not in _AVAILABLE or "fcl" not in available():
        pytest.skip("z1's package or python-fcl is not installed")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = armguard.load_model("z1")
    ana, fcl = armguard.checker(model, "analytic"), armguard.checker(model, "fcl")
    n_pen = 0
    for q in model.random_q(60, 11):
        a, f = ana.pair_distances(q), fcl.pair_distances(q)
        pen = (a.distance < -1e-6) & (f.distance < -1e-6)
        n_pen += int(pen.sum())
        np.testing.assert_allclose(a.distance[pen], f.distance[pen], rtol=0, atol=1e-6)
        np.testing.assert_array_equal(a.distance <= 0, f.distance <= 0)
    assert n_pen >= 5  # the check saw penetrations: 10 pair entries in these 60 configurations, within 2.6e-7 m


def test_coal_on_z1_from_four_threads_within_its_tolerance():
    """z1's hull–cylinder pairs make coal's answers depend, within its GJK tolerance, on the calling
    thread's earlier calls (``armguard_coal``'s docstring): from 4 threads at once, each walking the
    configurations in its own order, every distance is within ``gjk_tolerance`` of the single-threaded
    one and every verdict the same."""
    import threading

    if "z1" not in _AVAILABLE:
        pytest.skip("z1's package is not installed")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = armguard.load_model("z1")
    ref = armguard.checker(model, "coal")
    Q = model.random_q(40, 3)
    want = np.array([ref.pair_distances(q).distance for q in Q])
    got = np.full((4,) + want.shape, np.nan)
    start = threading.Barrier(4)

    def work(t):
        start.wait()
        for i in np.random.default_rng(t).permutation(len(Q)):
            got[t, i] = ref.pair_distances(Q[i]).distance

    threads = [threading.Thread(target=work, args=(t,)) for t in range(4)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    assert np.isfinite(got).all()
    np.testing.assert_allclose(got, np.broadcast_to(want, got.shape), rtol=0, atol=ref.gjk_tolerance)
    np.testing.assert_array_equal(got <= 0, np.broadcast_to(want <= 0, got.shape))
