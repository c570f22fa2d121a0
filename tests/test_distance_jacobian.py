"""Jacobians of signed distance (``pair_distances(q, jacobian=True)``) against central differences.

The reference is the checker's own distances differenced along each velocity direction
(``armguard.backends._jacobian.finite_difference_rows``, step ``Tolerances.jacobian_step``): at
points where the witness Jacobian says ``smooth`` and the forward and backward differences agree,
the rows agree to a relative error below 1e-6 (row norms, the difference's norm floored at
1 cm/rad); where the differences disagree (a kink), ``smooth`` is False.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import armguard
from armguard import DEFAULT_TOLERANCES as TOL
from armguard.backends import CheckerBase
from armguard.backends._face_graph import face_scratch, vertex_graph
from armguard.backends._jacobian import _face_spans, finite_difference_rows

MODELS = ["ranger", "hermes", "puma560", "rover", "gmf_s480", "panda", "ur5", "iiwa"]
REL = 1e-6
FLOOR = 1e-2  # m/rad: rows smaller than this are compared absolutely at REL * FLOOR


@pytest.fixture(scope="module")
def models():
    cache = {}

    def get(name):
        if name not in cache:
            cache[name] = armguard.load_model(name)
        return cache[name]

    return get


def _relative_errors(checker, q, idx=None):
    """``(result, relative error, kink)``: the Jacobian against central differences at
    ``jacobian_step``.  Rows where central differences at that step and ten times it disagree by
    more than REL are marked ``kink`` too: the reference has not converged there (a switch of
    features at a stationary point makes the central difference first-order: seen on Hermes at
    the middle of every joint's range, exact Jacobian 0, differences 2.25 h)."""
    r = checker.pair_distances(q, pairs=idx, jacobian=True)
    fd, kink = finite_difference_rows(checker, q, idx, step=TOL.jacobian_step)
    fd10, kink10 = finite_difference_rows(checker, q, idx, step=10 * TOL.jacobian_step)
    scale = np.maximum(np.linalg.norm(fd, axis=1), FLOOR)
    unconverged = np.linalg.norm(fd - fd10, axis=1) / scale > REL
    err = np.linalg.norm(r.jacobian - fd, axis=1) / scale
    return r, err, kink | kink10 | unconverged


@pytest.mark.parametrize("name", MODELS)
def test_analytic_jacobian_matches_central_differences(models, name):
    m = models(name)
    c = armguard.checker(m, "analytic")
    n_smooth = 0
    for q in m.random_q(3, rng=7):
        r, err, kink = _relative_errors(c, q)
        assert r.jacobian.shape == (len(m.pairs), m.pin_model.nv) and r.smooth.shape == (len(m.pairs),)
        np.testing.assert_array_equal(r.distance, c.pair_distances(q).distance)  # same rows, same order
        ok = r.smooth & ~kink
        n_smooth += int(ok.sum())
        assert np.all(err[ok] < REL), (name, r.pairs[ok][err[ok] >= REL], err[ok][err[ok] >= REL])
        _, fd_kink = finite_difference_rows(c, q, None, step=TOL.jacobian_step)
        assert not np.any(r.smooth & fd_kink), ("a kink called smooth", r.pairs[r.smooth & fd_kink])
    assert n_smooth > len(m.pairs)  # most rows of 3 configurations are checked


@pytest.mark.parametrize("name", ["ranger", "hermes", "puma560", "gmf_s480", "panda"])
def test_coal_jacobian_matches_central_differences(models, name):
    """coal's witness points with Pinocchio's Jacobians; coal's GJK stops within its tolerance
    (1e-9 m) on hulls, so its central differences are only that good divided by the step: the
    rows of hull pairs are compared with the analytic backend's instead (same witness formula,
    exact witnesses)."""
    m = models(name)
    c = armguard.checker(m, "coal")
    a = armguard.checker(m, "analytic")
    kinds = [{type(m.collision_model.geometryObjects[m.geometry_index(x)].geometry).__name__
              for x in pair if x != "workspace"} for pair in zip(m.pairs.a, m.pairs.b)]
    exact = np.array([not (k & {"Convex", "BVHModel"}) for k in kinds])
    for q in m.random_q(2, rng=11):
        r, err, kink = _relative_errors(c, q)
        ok = r.smooth & ~kink & exact
        assert np.all(err[ok] < REL), (name, r.pairs[ok][err[ok] >= REL], err[ok][err[ok] >= REL])
        ra = a.pair_distances(q, jacobian=True)
        both = r.smooth & ra.smooth & (np.abs(ra.distance - r.distance) < TOL.differential_hull)
        scale = np.maximum(np.linalg.norm(ra.jacobian, axis=1), FLOOR)
        agree = np.linalg.norm(r.jacobian - ra.jacobian, axis=1) / scale
        assert np.all(agree[both & exact] < REL)
        assert np.median(agree[both]) < 1e-3  # hull witnesses: GJK-tolerance close, not exact


class _DistancesOnly(CheckerBase):
    """A backend answering distances only (no ``jacobian`` argument): gets the framework default."""

    name = "distances-only"

    def __init__(self, inner) -> None:
        super().__init__(inner.model)
        self.inner = inner

    def pair_distances(self, q, *, pairs=None):
        return self.inner.pair_distances(q, pairs=pairs)


def test_framework_default_is_central_differences(models):
    m = models("hermes")
    inner = armguard.checker(m, "analytic")
    c = _DistancesOnly(inner)
    q = m.random_q(1, rng=3)[0]
    r = c.pair_distances(q, jacobian=True)
    ra = inner.pair_distances(q, jacobian=True)
    ok = r.smooth & ra.smooth
    assert ok.sum() > len(ok) // 2
    err = np.linalg.norm(r.jacobian - ra.jacobian, axis=1) / np.maximum(np.linalg.norm(ra.jacobian, axis=1), FLOOR)
    assert np.all(err[ok] < REL)
    sub = np.array([5, 1, 5])
    rs = c.pair_distances(q, pairs=sub, jacobian=True)
    np.testing.assert_allclose(rs.jacobian, r.jacobian[sub], atol=1e-9)
    assert c.pair_distances(q).jacobian is None


def test_subset_rows_and_take_keep_jacobian(models):
    m = models("puma560")
    c = armguard.checker(m, "analytic")
    q = m.random_q(1, rng=5)[0]
    full = c.pair_distances(q, jacobian=True)
    rows = np.array([7, 0, 3])
    sub = c.pair_distances(q, pairs=rows, jacobian=True)
    np.testing.assert_allclose(sub.jacobian, full.jacobian[rows], atol=1e-12)
    np.testing.assert_array_equal(sub.smooth, full.smooth[rows])
    t = full.take(rows)
    np.testing.assert_array_equal(t.jacobian, full.jacobian[rows])


def test_parallel_capsules_are_not_smooth(models):
    """Ranger's arm at its home pose holds parallel links: where central differences find a kink
    the witness Jacobian must not claim smoothness, and some such pair exists there."""
    m = models("ranger")
    c = armguard.checker(m, "analytic")
    q = m.neutral()
    r = c.pair_distances(q, jacobian=True)
    _, kink = finite_difference_rows(c, q, None, step=TOL.jacobian_step)
    assert not np.any(r.smooth & kink)
    assert np.any(~r.smooth)


def test_support_faces_of_a_box():
    """The face-dimension kernel on a unit cube: a face normal gives a face, an edge bisector an
    edge (along the edge), a generic direction a vertex; a plane (-1) is always a face."""
    V = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=np.float64)
    R = np.repeat(np.eye(3)[None], 4, axis=0)
    u = np.array([[0, 0, 1.0], [0, 1 / np.sqrt(2), 1 / np.sqrt(2)], [0.3, 0.5, 0.81], [1.0, 0, 0]])
    u /= np.linalg.norm(u, axis=1)[:, None]
    g = np.array([0, 0, 0, -1])
    dims, dirs = np.zeros(4, np.int64), np.zeros((4, 3))
    adj, adj_start = vertex_graph(V, np.array([0, 8]))  # a cube: no graph (the scan)
    _face_spans(R, u, g, np.array([0, 8]), V, adj, adj_start, np.zeros((1, 3)), np.zeros(1), 1e-9, 1e-9, dims, dirs,
                *face_scratch(len(V)))
    assert dims.tolist() == [2, 1, 0, 2]
    assert abs(abs(dirs[1, 0]) - 1.0) < 1e-12


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.lists(st.floats(0.001, 0.999), min_size=6, max_size=6))  # central differences: inside the limits
def test_hermes_jacobian_property(models, u):
    """Hypothesis: at any in-limit Hermes configuration, smooth rows match central differences."""
    m = models("hermes")
    c = armguard.checker(m, "analytic")
    robot = next(iter(m.scene.robots.values()))
    lo, hi = np.where(np.isfinite(robot.lower), robot.lower, -np.pi), np.where(np.isfinite(robot.upper), robot.upper, np.pi)
    q = m.pin_q(lo + (hi - lo) * np.asarray(u))
    r, err, kink = _relative_errors(c, q)
    ok = r.smooth & ~kink
    assert ok.sum() >= len(ok) // 2
    assert np.all(err[ok] < REL)
    _, fd_kink = finite_difference_rows(c, q, None, step=TOL.jacobian_step)
    assert not np.any(r.smooth & fd_kink)


@pytest.mark.parametrize("name", ["ranger", "puma560", "ur5", "kinova", "panda"])
def test_joint_jacobians_equal_pinocchio_per_joint(models, name):
    """The one masked copy of ``data.J`` (no mimic joints; kinova's continuous joints included), or
    the per-joint path (the Panda's mimic finger), equals ``getJointJacobian`` joint by joint."""
    import pinocchio as pin

    from armguard.backends._jacobian import WitnessJacobian

    m = models(name)
    pm = m.pin_model
    wj = WitnessJacobian(m)
    assert wj._mimic == (name == "panda")
    data = pm.createData()
    joints = list(range(1, pm.njoints))
    for _ in range(5):
        q = pin.randomConfiguration(pm, np.maximum(pm.lowerPositionLimit, -3.0), np.minimum(pm.upperPositionLimit, 3.0))
        Jj, R_WJ = wj.joint_jacobians(q, joints)
        pin.computeJointJacobians(pm, data, q)
        for j in joints:
            np.testing.assert_allclose(Jj[j], pin.getJointJacobian(pm, data, j, pin.ReferenceFrame.WORLD), atol=1e-12)
            np.testing.assert_allclose(R_WJ[j], data.oMi[j].rotation, atol=1e-15)
        assert not Jj[0].any() and np.array_equal(R_WJ[0], np.eye(3))


def test_finite_differences_on_a_joint_narrower_than_the_step_is_an_error_naming_the_column():
    """A joint range narrower than the step either way raised TypeError (JointLimitError built with one argument)."""
    import armguard
    from armguard._errors import BackendError
    from armguard.backends._jacobian import finite_difference_rows

    m = armguard.load_model("panda")
    c = armguard.checker(m, "coal")
    q = m.neutral()
    with pytest.raises(BackendError, match=r"finite differences: joint column 0 cannot move 10.0 either way"):
        finite_difference_rows(c, q, None, step=10.0)
