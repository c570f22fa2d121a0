"""``armguard.avoid``: velocity dampers (Faverjon & Tournassoud) as a small QP, never infeasible.

The QP's answer is checked against its constraints and against a slow reference (scipy's SLSQP
on the same problem); stopping must be the answer where nothing else is allowed.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import minimize

import armguard
from armguard import AvoidanceError
from armguard.avoidance import Avoidance, AvoidanceStatus, Damper, avoid, avoid_step, velocity_bounds
from armguard.backends import PairDistances

DAMPER = Damper(stand_off=0.02, influence=0.2, approach_speed=0.5, period=0.01, velocity_limit=1.0)


def _distances(d, J, nv=None) -> PairDistances:
    n = len(d)
    J = np.asarray(J, float).reshape(n, nv if nv is not None else -1)
    pairs = np.array([[f"a{k}", f"b{k}"] for k in range(n)], dtype=object).reshape(n, 2)
    return PairDistances(pairs, np.asarray(d, float), np.zeros((n, 3)), np.zeros((n, 3)), ("robot",) * n,
                         J, np.ones(n, bool))


def _reference(v_cmd, d, J, damper):
    """The same QP by SLSQP (slow, general)."""
    near = d < damper.influence
    A, b = J[near], damper.bound(d[near])
    lim = np.broadcast_to(damper.velocity_limit, v_cmd.shape)
    res = minimize(lambda v: 0.5 * np.sum((v - v_cmd) ** 2), np.zeros_like(v_cmd), jac=lambda v: v - v_cmd,
                   constraints=[{"type": "ineq", "fun": lambda v: A @ v - b, "jac": lambda v: A}] if len(b) else [],
                   bounds=list(zip(-lim, lim)), method="SLSQP", options={"ftol": 1e-14, "maxiter": 500})
    return res.x


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 10_000), st.integers(1, 8), st.integers(0, 12))
def test_damper_holds_and_matches_reference(seed, nv, n):
    rng = np.random.default_rng(seed)
    d = rng.uniform(-0.01, 0.3, n)
    J = rng.normal(size=(n, nv))
    v_cmd = rng.normal(size=nv) * 2.0
    out = avoid(v_cmd, _distances(d, J, nv), DAMPER)
    assert isinstance(out, Avoidance)
    v = out.velocity
    assert np.all(np.abs(v) <= 1.0 + 1e-9)
    near = d < DAMPER.influence
    assert np.all(J[near] @ v >= DAMPER.bound(d[near]) - 1e-9)  # (1): every pair within its damper
    np.testing.assert_allclose(out.closing, J[out.rows] @ v)
    assert set(out.rows.tolist()) <= set(np.flatnonzero(near).tolist())
    if out.status is not AvoidanceStatus.STOPPED or out.solver == "daqp: optimal":
        ref = _reference(v_cmd, d, J, DAMPER)
        cost = lambda x: np.sum((x - v_cmd) ** 2)  # noqa: E731
        assert cost(v) <= cost(ref) + 1e-7


def test_pushing_into_an_obstacle_at_stand_off_stops():
    J = np.array([[1.0, 0.0]])
    out = avoid([-0.5, 0.0], _distances([DAMPER.stand_off], J), DAMPER)
    assert out.status is AvoidanceStatus.STOPPED
    np.testing.assert_allclose(out.velocity, 0.0, atol=1e-12)


def test_inside_stand_off_no_further_closing_and_stop_is_feasible():
    J = np.array([[1.0, 0.0], [0.0, 1.0]])
    d = [0.5 * DAMPER.stand_off, -0.01]  # inside the stand-off, one penetrating
    out = avoid([-1.0, -1.0], _distances(d, J), DAMPER)
    assert out.status is AvoidanceStatus.STOPPED
    out = avoid([-1.0, 0.3], _distances(d, J), DAMPER)  # moving away is allowed
    assert out.status is AvoidanceStatus.SLOWED
    np.testing.assert_allclose(out.velocity, [0.0, 0.3], atol=1e-9)


def test_slides_along_a_wall():
    """Closing at an angle on a wall is deflected: the tangential part passes, the normal part is damped."""
    J = np.array([[1.0, 0.0]])
    d = 0.1
    out = avoid([-1.0, 0.5], _distances([d], J), DAMPER)
    assert out.status is AvoidanceStatus.SLOWED
    np.testing.assert_allclose(out.velocity, [DAMPER.bound([d])[0], 0.5], atol=1e-9)


def test_free_far_away_and_clipped_to_limits():
    out = avoid([0.3, -0.2], _distances([0.5], [[1.0, 0.0]]), DAMPER)
    assert out.status is AvoidanceStatus.FREE and len(out.rows) == 0
    out = avoid([3.0, 0.0], _distances([0.5], [[1.0, 0.0]]), DAMPER)
    assert out.status is AvoidanceStatus.SLOWED
    np.testing.assert_allclose(out.velocity, [1.0, 0.0])


def test_period_caps_the_rate():
    """One period at the allowed rate cannot carry a pair past the stand-off (first order)."""
    fast = Damper(stand_off=0.02, influence=0.03, approach_speed=10.0, period=0.01)
    assert fast.rate() == pytest.approx(100.0)
    d = 0.025
    assert d + fast.period * fast.bound([d])[0] >= fast.stand_off - 1e-15


@pytest.mark.parametrize("bad", [dict(stand_off=-1.0), dict(influence=0.01), dict(approach_speed=0.0),
                                 dict(period=float("nan")), dict(velocity_limit=-1.0)], ids=str)
def test_bad_settings_are_refused(bad):
    kw = dict(stand_off=0.02, influence=0.2, approach_speed=0.5, period=0.01)
    kw.update(bad)
    with pytest.raises(AvoidanceError):
        Damper(**kw)


def test_nan_inputs_are_refused():
    with pytest.raises(AvoidanceError):
        avoid([np.nan, 0.0], _distances([0.1], [[1.0, 0.0]]), DAMPER)
    with pytest.raises(AvoidanceError):
        avoid([0.0, 0.0], _distances([np.nan], [[1.0, 0.0]]), DAMPER)
    r = _distances([0.1], [[1.0, 0.0]])
    with pytest.raises(AvoidanceError, match="jacobian=True"):
        avoid([0.0, 0.0], PairDistances(r.pairs, r.distance, r.p_WA, r.p_WB, r.category), DAMPER)


def test_ranger_arm_driven_into_the_scene_keeps_stand_off():
    """Closed loop on Ranger: a constant command that would collide is filtered; the least
    distance over the run stays above the stand-off less 1 mm and no step is infeasible."""
    import pinocchio as pin

    m = armguard.load_model("ranger")
    c = armguard.checker(m, "analytic")
    q = m.neutral()
    damper = Damper(stand_off=0.03, influence=0.15, approach_speed=0.3, period=0.01, velocity_limit=1.0)
    rng = np.random.default_rng(2)
    v_cmd = rng.normal(size=m.pin_model.nv)
    seen = []
    for _ in range(60):
        out = avoid_step(c, q, v_cmd, damper)
        seen.append(out.status)
        q = pin.integrate(m.pin_model, q, out.velocity * damper.period)
        dmin = float(c.pair_distances(q).distance.min())
        assert dmin >= min(damper.stand_off, out.min_distance) - 1e-3
    assert AvoidanceStatus.FREE in seen or AvoidanceStatus.SLOWED in seen


def test_canned_tests_with_avoidance_keep_stand_off_and_progress():
    """Three of Ranger's canned tests with a 0.2 m stand-off (it binds on tests 1 and 2, which stop
    short of the module at 87 % and 96 % of the way; test 3 never comes near): no contact, least
    distance >= stand-off - 1 mm, and the arm gets most of the way.  The end distance is recomputed
    with coal from the returned configuration (an independent backend)."""
    from armguard.avoidance import run_canned

    m = armguard.load_model("ranger")
    damper = Damper(stand_off=0.2, influence=0.35, approach_speed=0.3, period=0.01, velocity_limit=1.0)
    coal = armguard.checker(m, "coal")
    s = m.scene
    for name in ("test1_left_inward", "test2_left_up_and_back", "test3_left_forward_up"):
        r = run_canned(m, name, damper)
        t = s.canned_tests[name]
        assert r.holds(damper.stand_off) and not r.contact, r
        assert r.min_distance >= damper.stand_off - 1e-3
        assert r.progress > 0.8, r
        if name != "test3_left_forward_up":
            assert r.statuses["slowed"] > 0 and r.min_distance < damper.stand_off + 1e-3, r  # the damper bound
        full = s.flat_q({k: np.asarray(v) for k, v in t.setup.items()})
        full[[n.startswith(t.robot + "/") for n in s.joint_names]] = r.q_end
        d = coal.pair_distances(m.pin_q(full)).distance
        mine = np.array([a.startswith(t.robot + "/") or b.startswith(t.robot + "/")
                         for a, b in zip(m.pairs.owner_a, m.pairs.owner_b)])
        assert abs(float(d[mine].min()) - r.end_distance) < 1e-6
        traj = t.trajectory(s)
        goal = traj.at(traj.duration)
        way = np.linalg.norm(goal - t.setup[t.robot])
        assert r.progress == pytest.approx(1.0 - np.linalg.norm(goal - r.q_end) / way)
    assert r.statuses["free"] == r.steps  # test 3 never comes near: the command passes unchanged


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 10_000), st.integers(1, 8), st.integers(0, 12), st.booleans())
def test_compiled_filter_equals_avoid(seed, nv, n, tightened):
    """The compiled step (:func:`armguard.avoidance._fast.filter_velocity`) gives :func:`avoid`'s
    answer on the same rows: velocity, constrained rows, bounds, closing speeds, status, note; with
    the damper's symmetric limits, or bounds tightened one side or the other (a joint near a limit)."""
    from armguard.avoidance._fast import filter_velocity

    rng = np.random.default_rng(seed)
    d = rng.uniform(-0.01, 0.3, n)
    J = rng.normal(size=(n, nv))
    J[rng.random(n) < 0.2] = 0.0  # rows no joint moves are not constraints
    v_cmd = rng.normal(size=nv) * 2.0
    lo, hi = -DAMPER.limits(nv), DAMPER.limits(nv).copy()
    if tightened:
        lo = np.where(rng.random(nv) < 0.5, np.maximum(lo, -rng.uniform(0.0, 1.5, nv)), lo)
        hi = np.where(rng.random(nv) < 0.5, np.minimum(hi, rng.uniform(0.0, 1.5, nv)), hi)
    ref = avoid(v_cmd, _distances(d, J, nv), DAMPER, bounds=(lo, hi))
    v, rows, rate, closing, status, note = filter_velocity(v_cmd, d, np.ascontiguousarray(J), lo, hi,
                                                           DAMPER, armguard.DEFAULT_TOLERANCES)
    assert np.all(lo <= v) and np.all(v <= hi)
    np.testing.assert_array_equal(v, ref.velocity)
    np.testing.assert_array_equal(rows, ref.rows)
    np.testing.assert_array_equal(rate, ref.rate)
    np.testing.assert_allclose(closing, ref.closing, rtol=0, atol=1e-14)
    assert (status, note) == (ref.status, ref.solver)


def _ranger_left_arm():
    m = armguard.load_model("ranger")
    p = m.pairs
    rows = np.array([k for k, (a, b) in enumerate(zip(p.owner_a, p.owner_b))
                     if a.startswith("left_arm/") or b.startswith("left_arm/")])
    cols = [m.pin_model.joints[j].idx_v for j in range(1, m.pin_model.njoints)
            if m.pin_model.names[j].startswith("left_arm_")]
    return m, rows, cols


def test_avoid_step_equals_the_reference_path():
    """``avoid_step`` on the analytic checker (every row's Jacobian from the kernel, the compiled
    filter) against the slow path: the distances, Pinocchio's Jacobians of the rows within
    influence only (``witness_jacobian``), :func:`avoid`; and the checker's other path (Jacobians
    of the near rows only), which must give the identical answer."""
    m, rows, cols = _ranger_left_arm()
    c = armguard.checker(m, "analytic")
    slow = armguard.checker(m, "analytic")
    slow.jacobian_with_distances = False
    damper = Damper(stand_off=0.05, influence=0.3, approach_speed=0.5, period=0.01, velocity_limit=1.0)
    rng = np.random.default_rng(4)
    seen = set()
    ended = 0
    for q in m.random_q(60, rng=rng):
        v = np.zeros(m.pin_model.nv)
        v[cols] = rng.normal(size=len(cols))
        out = avoid_step(c, q, v, damper, pairs=rows)
        if "end-of-period check" in out.solver:  # the reference is the first-order filter alone
            ended += 1
            continue
        r = c.pair_distances(q, pairs=rows)
        k = np.flatnonzero(r.distance < damper.influence)
        sub = r.take(k)
        bounds = velocity_bounds(m.pin_model, q, damper)  # the damper's limits and the joint limits at q
        pin_ref = avoid(v, sub.with_jacobian(*c.witness_jacobian(q, sub, rows[k])), damper, bounds=bounds)
        np.testing.assert_allclose(out.velocity, pin_ref.velocity, rtol=0, atol=1e-9)
        assert out.status == pin_ref.status
        # on the kernel's rows (the same numbers) the answer is the reference's to the bit; with
        # Pinocchio's (1e-16 apart) a command exactly on a damper's bound may be called binding or not
        ref = avoid(v, sub.with_jacobian(*c.distance_jacobian(q, sub, rows[k])), damper, bounds=bounds)
        np.testing.assert_array_equal(out.velocity, ref.velocity)
        np.testing.assert_array_equal(out.rows, rows[k][ref.rows])
        assert (out.status, out.solver) == (ref.status, ref.solver)
        assert out.min_distance == float(r.distance.min())
        other = avoid_step(slow, q, v, damper, pairs=list(rows))
        np.testing.assert_array_equal(other.velocity, out.velocity)
        np.testing.assert_array_equal(other.rows, out.rows)
        seen.add(out.status)
    assert AvoidanceStatus.SLOWED in seen and AvoidanceStatus.FREE in seen and ended < 10


def _toward(checker, q, k):
    """Full speed (1 rad/s on the largest column) straight at pair ``k``."""
    J = checker.pair_distances(q, jacobian=True).jacobian[k]
    return -J / np.abs(J).max()


def test_no_pair_ends_a_period_below_the_stand_off_or_closer_once_inside():
    """At the rate cap the first-order step carried a Ranger pair from 132 mm to 22 mm against a 30 mm stand-off
    at 2 Hz (the distance curves along the motion); a pair outside the influence crossed it in one period, FREE."""
    import pinocchio as pin

    for name, n in (("ranger", 40), ("hermes", 40)):
        m = armguard.load_model(name)
        a = armguard.checker(m, "analytic")
        Q = m.random_q(200, 7)
        Q = Q[a.pair_distances_many(Q).distance.min(axis=1) > 0.03][:n]
        acted = 0
        for T in (0.5, 0.1):
            dmp = Damper(stand_off=0.03, influence=0.15, approach_speed=0.3, period=T, velocity_limit=1.0)
            for q in Q:
                d0 = a.pair_distances(q).distance
                out = avoid_step(a, q, _toward(a, q, int(np.argmin(d0))), dmp)
                d1 = a.pair_distances(pin.integrate(m.pin_model, q, out.velocity * T)).distance
                assert np.all(d1 >= np.where(d0 >= 0.03, 0.03, d0 - 1e-12)), (name, T, out.solver)
                acted += "end-of-period check" in out.solver
        assert acted > 0  # the check is not idle here


def test_stand_off_zero_never_steers_into_contact():
    """Stand-off 0, 20 steps at 20 Hz straight at a pair: the first-order filter ended 0.1 mm inside it (coal), STOPPED
    while in collision."""
    import pinocchio as pin

    m = armguard.load_model("ranger")
    a, e = armguard.checker(m, "analytic"), armguard.checker(m, "coal")
    Q = m.random_q(400, 7)
    q = Q[a.pair_distances_many(Q).distance.min(axis=1) > 0.03][8]
    dmp = Damper(stand_off=0.0, influence=0.12, approach_speed=2.5, period=0.05, velocity_limit=1.0)
    k = 171
    for _ in range(20):
        s = avoid_step(a, q, _toward(a, q, k), dmp)
        q = pin.integrate(m.pin_model, q, s.velocity * dmp.period)
        assert a.pair_distances(q).distance.min() >= 0.0 and e.pair_distances(q).distance[k] > -1e-9


@pytest.mark.parametrize("bad", [np.nan, "lo"])
def test_nan_bounds_are_refused(bad):
    m, rows, cols = _ranger_left_arm()
    c = armguard.checker(m, "analytic")
    nv = m.pin_model.nv
    lo, hi = np.full(nv, -1.0), np.full(nv, 1.0)
    (lo if bad == "lo" else hi)[0] = np.nan
    damper = Damper(stand_off=0.05, influence=0.3, approach_speed=0.5, period=0.01, velocity_limit=1.0)
    with pytest.raises(armguard.AvoidanceError, match="bounds"):
        avoid(np.ones(nv), c.pair_distances(m.neutral(), jacobian=True), damper, bounds=(lo, hi))


@pytest.mark.parametrize("cmd", ["complex", "bool"])
def test_complex_or_bool_commands_are_refused(cmd):
    m, rows, cols = _ranger_left_arm()
    c = armguard.checker(m, "analytic")
    nv = m.pin_model.nv
    v = np.ones(nv) * (1 + 1j) if cmd == "complex" else [True] * nv
    damper = Damper(stand_off=0.05, influence=0.3, approach_speed=0.5, period=0.01, velocity_limit=1.0)
    with pytest.raises(armguard.AvoidanceError, match="v_cmd"):
        avoid_step(c, m.neutral(), v, damper)


def test_a_result_keeps_its_command_when_the_caller_reuses_the_buffer():
    m, rows, cols = _ranger_left_arm()
    c = armguard.checker(m, "analytic")
    damper = Damper(stand_off=0.05, influence=0.3, approach_speed=0.5, period=0.01, velocity_limit=1.0)
    buf = np.zeros(m.pin_model.nv)
    buf[cols] = 0.5
    out = avoid(buf, c.pair_distances(m.neutral(), jacobian=True), damper)
    step = avoid_step(c, m.neutral(), buf, damper)
    buf[:] = 7.0
    assert np.all(out.commanded[cols] == 0.5) and np.all(step.commanded[cols] == 0.5)


def test_avoid_step_refuses_nan():
    m, rows, cols = _ranger_left_arm()
    c = armguard.checker(m, "analytic")
    damper = Damper(stand_off=0.05, influence=0.3, approach_speed=0.5, period=0.01, velocity_limit=1.0)
    q = m.neutral()
    v = np.zeros(m.pin_model.nv)
    v[cols[0]] = np.nan
    with pytest.raises(AvoidanceError, match="v_cmd"):
        avoid_step(c, q, v, damper, pairs=rows)
    with pytest.raises(AvoidanceError, match="v_cmd"):
        avoid_step(c, q, [0.0] * 3, damper, pairs=rows)
    bad = q.copy()
    bad[0] = np.nan
    with pytest.raises(armguard.BackendError):
        avoid_step(c, bad, np.zeros(m.pin_model.nv), damper, pairs=rows)


def test_run_canned_takes_per_column_limits_and_refuses_bad_arguments():
    """Damper's velocity_limit may be (nv,), one per velocity column of the model: run_canned broadcast it
    to the test robot's 7 columns and failed (numpy's broadcast error); an unknown test was a KeyError,
    None an AttributeError, a negative settle time ran -1e11 steps' worth of nothing."""
    from armguard import AvoidanceError
    from armguard.avoidance import run_canned

    m = armguard.load_model("ranger")
    kw = dict(stand_off=0.03, influence=0.15, approach_speed=0.3, period=0.01)
    name = "test1_left_inward"
    one = run_canned(m, name, Damper(**kw, velocity_limit=1.0))
    per_column = run_canned(m, name, Damper(**kw, velocity_limit=tuple([1.0] * m.pin_model.nv)))
    assert np.array_equal(one.q_end, per_column.q_end) and one.min_distance == per_column.min_distance
    damper = Damper(**kw, velocity_limit=1.0)
    with pytest.raises(AvoidanceError, match="'nope' is not a canned test of 'ranger'"):
        run_canned(m, "nope", damper)
    with pytest.raises(AvoidanceError, match="expected a canned test"):
        run_canned(m, None, damper)
    with pytest.raises(AvoidanceError, match="settle_s: expected a finite number >= 0"):
        run_canned(m, name, damper, settle_s=-1e9)


def test_damper_refuses_a_velocity_limit_that_is_no_numbers():
    """'abc' was a raw ValueError; [] was accepted and failed at the first step."""
    kw = dict(stand_off=0.03, influence=0.15, approach_speed=0.3, period=0.01)
    for bad in ("abc", [], [[1.0]], -1.0):
        with pytest.raises(AvoidanceError, match="Damper.velocity_limit: expected a number or one per velocity column"):
            Damper(**kw, velocity_limit=bad)


def test_a_pair_no_joint_moves_does_not_stop_the_arm():
    """ur5's wrist 2 and tool link are 19.80 mm apart at every configuration: their Jacobian row is rounding
    noise (about -3.8e-9 m/rad), and with a 20 mm stand-off its "may not close" constraint, met by DAQP only to
    its own tolerance, stopped the arm ("a constraint broken by 1.38e-09").  Rows no longer than
    ``Tolerances.avoid_row`` are no constraint; the pairs a joint does move still are."""
    from armguard.avoidance import AvoidanceStatus, Damper, avoid_step

    m = armguard.load_model("ur5")
    c = armguard.checker(m)
    Q = m.random_q(50, 5)
    q = Q[~c.collides(Q)][0]
    v = np.random.default_rng(0).normal(size=6)
    damper = Damper(stand_off=0.02, influence=0.1, approach_speed=0.3, period=0.01, velocity_limit=1.0)
    r = c.pair_distances(q, jacobian=True)
    still = np.linalg.norm(r.jacobian, axis=1) <= m.tol.avoid_row
    assert np.any(still & (r.distance < damper.stand_off))  # the pair no joint moves, inside the stand-off
    s = avoid_step(c, q, v, damper)
    assert s.status is not AvoidanceStatus.STOPPED, s.solver
    moved = (r.distance < damper.influence) & ~still
    closing = r.jacobian[moved] @ s.velocity
    bound = -damper.rate() * np.maximum(r.distance[moved] - damper.stand_off, 0.0)
    assert np.all(closing >= bound - m.tol.avoid_feasibility)  # the others still held to their dampers


def test_a_joint_commanded_past_its_limit_stops_at_it():
    """Panda's first joint 2 mrad below its upper limit, commanded +1 rad/s: the filter answered FREE with
    1 rad/s, and the next step's configuration was refused (JointLimitError, no velocity).  Now one period
    at the answer reaches the limit and no further; the joint may move back in at full speed; and a joint
    at its limit (or past it within the allowance) may stay."""
    import pinocchio as pin

    m = armguard.load_model("panda")
    c = armguard.checker(m, "analytic")
    damper = Damper(stand_off=0.02, influence=0.1, approach_speed=0.3, period=0.01, velocity_limit=2.0)
    j = m.pin_model.joints[1]
    upper = m.pin_model.upperPositionLimit[j.idx_q]
    q = m.neutral()
    q[j.idx_q] = upper - 0.002
    v = np.zeros(m.pin_model.nv)
    v[j.idx_v] = 1.0
    out = avoid_step(c, q, v, damper)
    assert out.status is AvoidanceStatus.SLOWED and out.velocity[j.idx_v] == pytest.approx(0.2, abs=1e-9)
    q1 = pin.integrate(m.pin_model, q, out.velocity * damper.period)
    assert q1[j.idx_q] <= upper + 1e-12
    avoid_step(c, q1, v, damper)  # the next step answers (it raised JointLimitError)
    v[j.idx_v] = -1.0
    assert avoid_step(c, q, v, damper).velocity[j.idx_v] == -1.0  # back in: unchanged
    q[j.idx_q] = upper
    v[j.idx_v] = 1.0
    at = avoid_step(c, q, v, damper)
    assert at.velocity[j.idx_v] == 0.0 and at.status is AvoidanceStatus.STOPPED
    lo, hi = velocity_bounds(m.pin_model, q, damper)
    assert lo[j.idx_v] == -2.0 and hi[j.idx_v] == 0.0 and np.all(lo <= 0.0) and np.all(hi >= 0.0)


def test_a_nan_jacobian_row_beyond_influence_is_refused_by_both_paths_and_still_pairs_are_named():
    """avoid() refused a NaN Jacobian entry anywhere, the compiled step only within influence (it answered
    where the reference refused); and with the only pair within influence moved by no joint, the note said
    "no pair within influence"."""
    from armguard.avoidance._fast import filter_velocity

    d = np.array([0.05, 0.5])
    J = np.array([[1.0, 0.0], [np.nan, 0.0]])
    lo, hi = -DAMPER.limits(2), DAMPER.limits(2)
    with pytest.raises(AvoidanceError, match="Jacobian entry is NaN"):
        avoid([0.1, 0.0], _distances(d, J), DAMPER)
    with pytest.raises(AvoidanceError, match="Jacobian entry is NaN"):
        filter_velocity(np.array([0.1, 0.0]), d, J, lo, hi, DAMPER, armguard.DEFAULT_TOLERANCES)
    J = np.array([[0.0, 0.0], [1.0, 0.0]])  # the near pair moved by no joint, the far one by joint 0
    ref = avoid([0.1, 0.0], _distances(d, J), DAMPER)
    got = filter_velocity(np.array([0.1, 0.0]), d, J, lo, hi, DAMPER, armguard.DEFAULT_TOLERANCES)
    assert ref.solver == got[5] == "none: 1 pair within influence, moved by no joint"
    assert avoid([0.1, 0.0], _distances([0.5], [[1.0, 0.0]]), DAMPER).solver == "none: no pair within influence"


@pytest.mark.parametrize("kw", [dict(stand_off=True), dict(period=True), dict(velocity_limit="1.0"),
                                dict(velocity_limit=(1.0, "2")), dict(velocity_limit=True), dict(velocity_limit=1j)])
def test_a_damper_refuses_bools_and_text_for_numbers(kw):
    base = dict(stand_off=0.05, influence=0.3, approach_speed=0.5, period=0.01, velocity_limit=1.0)
    with pytest.raises(AvoidanceError, match="Damper."):
        Damper(**{**base, **kw})


def test_a_closing_speed_that_overflows_is_never_free():
    """J v of 1e308-sized commands overflowed to NaN in the compiled rows, which called the row not binding: FREE with a
    NaN closing, where the reference solved the QP."""
    from armguard.avoidance._fast import filter_velocity

    damper = Damper(stand_off=0.0, influence=0.1, approach_speed=0.5, period=0.01)
    J = np.array([[2.0, 2.0, 1.0]])
    d = np.array([0.05])
    v = np.array([1e308, -1e308, -1e300])
    lo, hi = np.full(3, -np.inf), np.full(3, np.inf)
    out = filter_velocity(v, d, J, lo, hi, damper, armguard.DEFAULT_TOLERANCES)
    assert out[4] is not AvoidanceStatus.FREE and np.all(np.isfinite(out[0]))
