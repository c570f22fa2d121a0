"""The certified verifier's fast bookkeeping: the njit step kernel against its NumPy statement, and the
preallocated, detector-direct evaluation record against the general ``ClearanceModel.distances`` path."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from _verify_fixtures import thin_scene
from armguard.kinematics import Trajectory
from armguard.verify import Verifier
from armguard.verify._advance import advance_step, advance_step_reference
from armguard.verify._timelaw import segments_of

_FLOATS = st.floats(min_value=-2.0, max_value=5.0, allow_nan=False, allow_infinity=False)


@settings(max_examples=200, derandomize=True, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    data=st.lists(st.tuples(_FLOATS, _FLOATS, st.one_of(st.just(0.0), st.floats(0.0, 10.0))), min_size=1, max_size=40),
    margin=st.floats(0.0, 0.5),
    length=st.floats(0.0, 1.0),
    has_prev=st.booleans(),
)
def test_advance_step_matches_numpy_reference_bit_for_bit(data, margin, length, has_prev):
    d = np.array([x[0] for x in data])
    d_prev = np.array([x[1] for x in data])
    rates = np.array([x[2] for x in data])
    fast = advance_step(d, d_prev, rates, margin, length, has_prev)
    ref = advance_step_reference(d, d_prev, rates, margin, length, has_prev)
    assert fast[1] == ref[1]
    for a, b in zip((fast[0], fast[2], fast[3]), (ref[0], ref[2], ref[3])):
        assert a == b or (math.isinf(a) and math.isinf(b) and a == b)


@pytest.mark.parametrize("has_prev", [False, True], ids=["first", "interval"])
def test_advance_step_nan_clearance_gives_no_gap(has_prev):
    d = np.array([0.3, np.nan, 0.2])
    g, pair, step, lb = advance_step(d, np.full(3, 0.3), np.full(3, 0.1), 0.0, 0.5, has_prev)
    assert math.isnan(g) and pair == -1


def test_advance_step_closed_form():
    # two pairs; gaps 0.2 and 0.5 at margin 0.1; rates 1.0 and 0.25 -> steps 0.2 and 2.0
    d = np.array([0.3, 0.6])
    d_prev = np.array([0.4, 0.6])
    rates = np.array([1.0, 0.25])
    g, pair, step, lb = advance_step(d, d_prev, rates, 0.1, 0.2, True)
    assert g == pytest.approx(0.2) and pair == 0 and step == pytest.approx(0.2)
    # interval bound: pair 0 min(0.4, 0.3, (0.7 - 0.2) / 2 = 0.25) = 0.25; pair 1 min(0.6, 0.6, 0.575) = 0.575
    assert lb == pytest.approx(0.25)
    _, _, step0, lb0 = advance_step(d, d_prev, np.zeros(2), 0.1, 0.2, False)
    assert math.isinf(step0) and math.isinf(lb0)


def _cases(n_scenes=3, seed=11):
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n_scenes):
        sc = thin_scene(rng, n_obstacles=4)
        v = Verifier(sc)
        for _ in range(4):
            q0 = rng.uniform(-2.5, 2.5, 3)
            W = np.clip(q0 + np.cumsum(rng.uniform(-0.8, 0.8, (4, 3)), axis=0), -2.9, 2.9)
            out.append((v, Trajectory.joint_interpolated(sc.robots["arm"], np.vstack([q0, W]), profile="linear")))
    return out


def _fingerprint(r):
    fc = r.first_collision
    return (r.status, r.min_clearance, r.min_clearance_lower_bound, r.details.samples_evaluated,
            r.details.intervals_certified, tuple(r.profile.overall), tuple(np.round(r.profile.time, 12)),
            None if fc is None else (fc.time, fc.a, fc.b, fc.distance, tuple(fc.p_WA), tuple(fc.p_WB)))


@pytest.mark.parametrize("method", ["certified", "sampled"])
def test_detector_direct_record_matches_general_path(method, monkeypatch):
    cases = _cases()
    assert cases[0][0].model.source == "detector"
    fast = [_fingerprint(v.verify(t, method=method)) for v, t in cases]
    for v, _ in cases:  # the detector's pair_distances(q, robot=) without its lean evaluator (_row_eval)
        monkeypatch.setattr(v.model._det, "row_evaluator", None, raising=False)
    assert [_fingerprint(v.verify(t, method=method)) for v, t in cases] == fast
    for v, _ in cases:  # the general path: ClearanceModel.distances for every evaluation
        monkeypatch.setattr(v.model, "moving_fast_path", lambda robot: False)
    slow = [_fingerprint(v.verify(t, method=method)) for v, t in cases]
    assert fast == slow
    # the record grew beyond its first capacity (2 per segment + 2) somewhere: the growth path ran
    assert max(f[3] for f in fast) > 2 * 4 + 2
    assert {f[0].name for f in fast} >= {"SAFE", "COLLISION"} or method == "sampled"


class _SampledVelocity(Trajectory):
    """A Trajectory whose ``velocity`` is overridden: the verifier then samples the time law (the reference)."""

    def velocity(self, t):
        return super().velocity(t)


@pytest.mark.parametrize("profile", ["linear", "trapezoidal"], ids=["linear", "trapezoid"])
def test_closed_form_segment_speeds_match_sampled_time_law(profile):
    import armguard

    sc = armguard.load_scene("puma560")
    rob = next(iter(sc.robots.values()))
    rng = np.random.default_rng(5)
    lo, hi = np.asarray(rob.lower), np.asarray(rob.upper)
    W = 0.5 * (lo + hi) + rng.uniform(-0.3, 0.3, (6, len(lo)))
    t = Trajectory.joint_interpolated(rob, W, profile=profile)
    sampled = _SampledVelocity(t.robot_name, t.joint_names, t.times, t.waypoints, t.blend_times)
    v = Verifier(sc, robot=rob.name)
    segs = segments_of(t)
    k0, k1 = v._flat(rob.name, v._st.base)[1:]
    fast, bound = v._segment_speeds(t, segs, k0, k1, v.model)
    ref, sampled_bound = v._segment_speeds(sampled, segs, k0, k1, v.model)
    assert bound and not sampled_bound  # a sampled time law's peak is no bound (a speed table refuses it)
    # the closed form is the true peak; the 17 samples include each segment's midpoint (on the plateau)
    np.testing.assert_allclose(fast, ref, rtol=1e-12)
    assert np.all(fast >= ref * (1.0 - 1e-12)) and np.all(fast > 0.0)


@pytest.mark.parametrize("name, robot", [("ranger", "left_arm"), ("panda", None), ("z1", None), ("so101", None)])
def test_lean_evaluator_rows_and_witnesses_match_the_general_paths(name, robot, monkeypatch):
    """The analytic detector's lean evaluator (``row_evaluator``) against ``pair_distances(q, robot=)``
    (ranger: one shape pair per pair of links) or ``ClearanceModel.distances`` (several shapes on a
    link: the nearest kept, :func:`owner_rows`): the same rows bit for bit, the other robots' pairs
    from the fixed evaluation, the last witnesses too; a scene edited since: StaleModelError."""
    import armguard
    from armguard import StaleModelError
    from armguard.geometry import Box
    from armguard.verify._record import _Run

    m = armguard.load_model(name)
    v = Verifier(m)
    cm = v._current().model
    robot = robot or next(iter(cm.scene.robots))
    base = cm.scene.flat_q(cm.scene.default_q())
    k0, k1 = cm._joint_span(robot)
    lean = _Run(cm, base, k0, k1, robot)
    assert lean._rows is not None and lean._fast == (name == "ranger")
    monkeypatch.setattr(cm._det, "row_evaluator", None, raising=False)
    plain = _Run(cm, base, k0, k1, robot)
    assert plain._rows is None
    rob = cm.scene.robots[robot]
    lo, hi = np.asarray(rob.lower), np.asarray(rob.upper)
    Q = np.random.default_rng(5).uniform(np.maximum(lo, -np.pi), np.minimum(hi, np.pi), (40, k1 - k0))
    for q in Q:
        i, j = lean.eval(0, 0.5, q), plain.eval(0, 0.5, q)
        assert np.array_equal(lean.D[i], plain.D[j])
        for a, b in zip(lean.last_witnesses(), plain.last_witnesses()):
            assert np.array_equal(a[lean.moving], b[plain.moving])
    assert np.isinf(lean.D[0][~lean.moving]).all() and np.isfinite(lean.D[: len(Q)][:, lean.moving]).all()
    assert (lean.D[: len(Q)][:, lean.moving] <= 0).any() or name == "ranger"  # contacts in the sample too
    cm.scene.add_body("crate", [Box(center=[0.0, 0.0, 5.0], half_extents=[0.1, 0.1, 0.1])])
    with pytest.raises(StaleModelError):
        lean.eval(0, 0.5, Q[0])  # never rows of another scene's pairs


@settings(max_examples=200, derandomize=True, deadline=None)
@given(rows=st.lists(st.tuples(st.integers(0, 4), st.sampled_from([0.5, -0.1, 0.0, 0.5, 2.0, math.nan]),
                               st.floats(-1.0, 1.0)), min_size=1, max_size=12))
def test_owner_rows_matches_numpy_reference(rows):
    from armguard.verify._advance import owner_rows, owner_rows_reference

    owner = np.array([r[0] for r in rows], dtype=np.int64)
    ev = np.array([[r[1]] + [r[2] + k for k in range(6)] for r in rows])
    d, wit = np.full(5, np.inf), np.zeros((5, 6))
    owner_rows(ev, owner, d, wit)
    d_ref, wit_ref = owner_rows_reference(ev, owner, 5)
    assert np.array_equal(d, d_ref, equal_nan=True) and np.array_equal(wit, wit_ref)


def test_owner_rows_refuses_mismatched_rows():
    from armguard.verify._advance import owner_rows

    d, wit = np.full(2, np.inf), np.zeros((2, 6))
    with pytest.raises(ValueError):
        owner_rows(np.zeros((3, 7)), np.array([0, 1], dtype=np.int64), d, wit)  # a detector's rows of another scene
    with pytest.raises(ValueError):
        owner_rows(np.zeros((2, 7)), np.array([0, 2], dtype=np.int64), d, wit)
    assert np.isinf(d).all()


def test_a_scene_edited_during_a_lean_evaluation_gives_no_rows():
    """The scene edited while the kernel ran (another thread adding a body): the rows are of the model's
    revision but the scene's pairs are others: StaleModelError, never a row recorded."""
    import armguard
    from armguard import StaleModelError
    from armguard.geometry import Box
    from armguard.verify._record import _Run

    m = armguard.load_model("ur5")
    cm = Verifier(m)._current().model
    robot = next(iter(cm.scene.robots))
    base = cm.scene.flat_q(cm.scene.default_q())
    k0, k1 = cm._joint_span(robot)
    run = _Run(cm, base, k0, k1, robot)
    real = run._rows

    def edited_meanwhile(q):
        out = real(q)
        cm.scene.add_body("crate", [Box(center=[0.0, 0.0, 5.0], half_extents=[0.1, 0.1, 0.1])])
        return out

    run._rows = edited_meanwhile
    with pytest.raises(StaleModelError):
        run.eval(0, 0.5, base[k0:k1])
    assert run.n == 0


@settings(max_examples=60, derandomize=True, deadline=None)
@given(seed=st.integers(0, 10_000), linear=st.booleans())
def test_closed_form_segment_times_match_the_bisection(seed, linear):
    """A plain Trajectory's collision time by the trapezoid's closed-form inverse (``path_tau``) against the
    bisection on ``trajectory.at`` (kept for time laws of their own): within 1e-12 of the segment time."""
    from armguard.verify._timelaw import segment_times

    rng = np.random.default_rng(seed)
    sc = thin_scene(rng, n_obstacles=1)
    W = rng.uniform(-2.5, 2.5, (4, 3))
    traj = Trajectory.joint_interpolated(sc.robots["arm"], W, profile="linear" if linear else "trapezoidal")
    segs = segments_of(traj)
    idx = rng.integers(0, len(segs), 20)
    s = np.r_[rng.uniform(0, 1, 17), 0.0, 1.0, 1e-12]
    closed = segment_times(traj, segs, idx, s)

    class OwnLaw(Trajectory):  # the same law through an overridden at: the bisection
        def at(self, t):
            return super().at(t)

    own = OwnLaw(traj.robot_name, traj.joint_names, traj.times, traj.waypoints, traj._blend)
    bisected = segment_times(own, segs, idx, s)
    spans = np.array([segs[i][1] - segs[i][0] for i in idx])
    # near a segment's ends (s = 1e-12 on the parabola) the bisection's own rounding of q(t) dominates
    assert np.all(np.abs(closed - bisected) <= 1e-10 * np.maximum(spans, 1.0)), np.max(np.abs(closed - bisected))
    from armguard.kinematics._profile import path_s

    t0 = np.array([segs[i][0] for i in idx])
    back = path_s(closed - t0, spans, traj._blend[idx])  # the closed form's times give back the fractions
    assert np.allclose(back, s, rtol=0, atol=1e-13)
    from armguard.verify._timelaw import profile_times  # the profile's time axis: exact, the tabulation near it

    exact, tabulated = profile_times(traj, segs, idx, s), profile_times(own, segs, idx, s)
    assert np.allclose(exact, closed, rtol=0, atol=1e-12) and np.all(np.abs(exact - tabulated) <= 0.02 * spans)
