"""armguard.clip prediction: the swept guard contains the guard at every intermediate pose of
the motion model, and the Predictor never calls an interval CLEAR when a densely sampled pose
in it collides (exact signed distance as the oracle)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from armguard.clip import ClipStatus, Guard, Obstacle, Predictor, interpolate_pose, rotation_growth, swept_guard
from armguard.geometry import Box, Capsule, distance


def _pose(rng, spread):
    X = np.eye(4)
    X[:3, :3] = Rotation.random(random_state=int(rng.integers(2**31))).as_matrix()
    X[:3, 3] = rng.uniform(-spread, spread, 3)
    return X


@pytest.fixture(scope="module")
def capsule_guard():
    return Guard.from_shape(Capsule([-0.2, 0.0, 0.0], [0.2, 0.0, 0.0], 0.05), max_depth=1)


def test_swept_hull_contains_every_intermediate_guard(capsule_guard):
    g = capsule_guard
    rng = np.random.default_rng(5)
    for _ in range(20):
        X0 = _pose(rng, 0.3)
        X1 = X0 @ _pose(rng, 0.1)  # up to a full turn between set points: the bound's worst case
        sw = swept_guard(g, X0, X1)
        for t in np.linspace(0.0, 1.0, 17):
            X = interpolate_pose(X0, X1, t, g.cs)
            V = g.outer.vertices @ X[:3, :3].T + X[:3, 3]
            assert np.all(V @ sw.outer_planes[:, :3].T - sw.outer_planes[:, 3] <= 0.0)
            assert np.all(np.linalg.norm(V - sw.cs, axis=1) <= sw.ro)


def test_rotation_growth_is_the_stated_bound(capsule_guard):
    g = capsule_guard
    X1 = np.eye(4)
    X1[:3, :3] = Rotation.from_rotvec([0, 0, 0.5]).as_matrix()
    rho = np.max(np.linalg.norm(g.outer.vertices - g.cs, axis=1))
    assert rotation_growth(g, np.eye(4), X1) == pytest.approx(0.25 * rho / 8)
    assert rotation_growth(g, np.eye(4), np.eye(4)) == 0.0


def test_predictor_never_clears_a_colliding_interval(capsule_guard):
    g = capsule_guard
    rng = np.random.default_rng(9)
    obstacles = [Box(rng.uniform(-0.5, 0.5, 3), rng.uniform(0.02, 0.1, 3)) for _ in range(3)]
    pred = Predictor([g], [Obstacle.from_shape(b) for b in obstacles])
    counts = {s: 0 for s in ClipStatus}
    for _ in range(40):
        X0 = _pose(rng, 0.4)
        X1 = X0.copy()
        X1[:3, :3] = X0[:3, :3] @ Rotation.from_rotvec(rng.normal(size=3) * 0.3).as_matrix()
        X1[:3, 3] += rng.normal(size=3) * 0.1
        r = pred.predict(X0[None], X1[None])
        counts[r.status] += 1
        dmin = min(
            distance(g.shape.transformed(interpolate_pose(X0, X1, t, g.cs)), b).distance
            for t in np.linspace(0, 1, 33) for b in obstacles
        )
        if r.status is ClipStatus.CLEAR:
            assert dmin > 0.0
        if r.status is ClipStatus.INTERSECTED:
            Xt = interpolate_pose(X0, X1, r.t, g.cs)
            assert distance(g.shape.transformed(Xt), obstacles[r.obstacle]).distance <= 1e-6
    assert counts[ClipStatus.CLEAR] and counts[ClipStatus.INTERSECTED]


def test_predictor_sees_a_collision_between_set_points(capsule_guard):
    g = capsule_guard
    post = Obstacle.from_shape(Box([0.0, 0.0, 0.0], [0.01, 0.01, 0.5]))
    X0, X1 = np.eye(4), np.eye(4)
    X0[1, 3], X1[1, 3] = -0.2, 0.2  # both set points clear; the arm passes through the post
    pred = Predictor([g], [post])
    answers = pred.run(np.stack([X0, X1])[:, None])
    assert len(answers) == 1 and answers[0].status is ClipStatus.INTERSECTED and 0.0 < answers[0].t < 1.0


def _sweep(x, ys):
    """One guard's poses along y at height x: (T, 1, 4, 4)."""
    P = np.tile(np.eye(4), (len(ys), 1, 1, 1))
    P[:, 0, 0, 3], P[:, 0, 1, 3] = x, ys
    return P


def test_predictor_run_from_several_threads_matches_one_at_a_time():
    """``run`` keeps no state between its intervals on the Predictor: four threads sharing one give
    each run the answers it gets alone (it used to step through the shared stream, and a run that
    crosses the post between set points 19 and 20 was called CLEAR when another run interleaved)."""
    from armguard.testing import run_in_threads

    guard = Guard.from_shape(Capsule([0.0, 0.0, 0.0], [0.4, 0.0, 0.0], 0.05))
    pred = Predictor([guard], [Obstacle.segment([0.3, 0.0, -1.0], [0.3, 0.0, 1.0])])
    crossing, far = _sweep(0.0, np.repeat([-0.3, 0.3], 20)), _sweep(5.0, np.linspace(-0.3, 0.3, 40))
    alone = {k: [p.status for p in pred.run(P)] for k, P in (("crossing", crossing), ("far", far))}
    assert [i for i, s in enumerate(alone["crossing"]) if s is not ClipStatus.CLEAR] == [19]
    assert set(alone["far"]) == {ClipStatus.CLEAR}
    got, errors = [], []

    def job(name, P):
        def go():
            try:
                for _ in range(4):
                    got.append((name, [p.status for p in pred.run(P)]))
            except Exception as exc:  # noqa: BLE001 - recorded, asserted below
                errors.append(exc)
        return go

    for _ in range(5):
        run_in_threads([job("crossing", crossing), job("far", far), job("crossing", crossing), job("far", far)])
    assert not errors and len(got) == 80
    assert all(statuses == alone[name] for name, statuses in got)


def test_predictor_step_keeps_its_own_copy_of_the_set_point():
    """A control loop that writes each set point into one buffer: the stream kept a view of it, so the next
    step compared the buffer with itself (a zero-length interval) and missed the crossing."""
    guard = Guard.from_shape(Capsule([0.0, 0.0, 0.0], [0.4, 0.0, 0.0], 0.05))
    pred = Predictor([guard], [Obstacle.segment([0.3, 0.0, -1.0], [0.3, 0.0, 1.0])])
    left, right = _sweep(0.0, [-0.3, 0.3])
    buf = left.copy()
    pred.step(buf)
    buf[...] = right
    assert pred.step(buf).status is ClipStatus.INTERSECTED


def test_predictor_run_leaves_the_step_stream_as_it_was():
    guard = Guard.from_shape(Capsule([0.0, 0.0, 0.0], [0.4, 0.0, 0.0], 0.05))
    pred = Predictor([guard], [Obstacle.segment([0.3, 0.0, -1.0], [0.3, 0.0, 1.0])])
    left, right = _sweep(0.0, [-0.3, 0.3])
    assert pred.step(left).status is ClipStatus.CLEAR  # the stream's first set point
    pred.run(_sweep(5.0, np.linspace(-0.3, 0.3, 5)))  # far away: must not become the stream's last set point
    assert pred.step(right).status is ClipStatus.INTERSECTED  # left -> right crosses the post


def test_halving_keeps_the_whole_growth_so_no_clear_within_it():
    """A post 70 mm beside the model path of a 5 cm box, growth 8 cm: the whole interval is MAYBE, and halving
    answered CLEAR (each half's growth scaled by its length) though the real motion may come within 10 mm."""
    from armguard.clip import check
    from armguard.geometry import Box

    g = Guard.from_shape(Box([0, 0, 0], [0.05, 0.05, 0.05]))
    X0, X1 = np.eye(4), np.eye(4)
    X1[1, 3] = 0.4
    for gap, growth, want in ((0.02, 0.08, ClipStatus.MAYBE), (0.07, 0.08, ClipStatus.MAYBE),
                              (0.07, 0.0, ClipStatus.CLEAR), (0.12, 0.08, ClipStatus.CLEAR)):
        post = Obstacle.segment([0.05 + gap, 0.2, -1], [0.05 + gap, 0.2, 1])
        whole = check(swept_guard(g, X0, X1, growth=growth), post, subdivide=False).status
        got = Predictor([g], [post], growth=growth).predict(X0[None], X1[None]).status
        assert got is want, (gap, growth, whole, got)
        if gap < growth:  # within the growth: never CLEAR, whatever the halving
            assert whole is ClipStatus.MAYBE and got is not ClipStatus.CLEAR
