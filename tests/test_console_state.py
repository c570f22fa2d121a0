"""The console's state machine without a browser, on ``tests/data/console_scene.yaml``.

Geometry of that scene (closed forms): planar 3R arms, links 0.4 m, capsules r = 0.05 m; the
left arm's base at (-0.8, 0, 0); the post a 0.2 m box centred at (-0.8, 0.8, 0).  With the left
arm straight along +y (joint1 = +90 deg) link2 (y from 0.4 to 0.8) reaches into the post:
penetration 0.15 m (capsule tip at y = 0.85, post face at y = 0.7).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from armguard.console import ConsoleInputError, ConsoleState, PanelStatus
from armguard.scene import load_scene

SCENE = Path(__file__).parent / "data" / "console_scene.yaml"
DEG = math.pi / 180.0


@pytest.fixture(scope="module")
def scene():
    return load_scene(str(SCENE))


@pytest.fixture()
def state(scene):
    return ConsoleState(scene, threshold=0.05)


def test_home_is_clear_and_panel_names_the_nearest(state):
    snap = state.snapshot()
    assert snap.active == "left" and snap.mode == "joint" and snap.detection
    r = snap.readout
    assert r.status is PanelStatus.CLEAR and r.distance > 0.05
    assert np.linalg.norm(r.p_WA - r.p_WB) == pytest.approx(abs(r.distance), abs=1e-9)
    assert {row.category for row in r.rows} >= {"arm", "environment", "workspace"}
    env = next(row for row in r.rows if row.category == "environment")
    assert env.obstacle == "post" and env.distance == pytest.approx(0.65, abs=1e-9)  # base cap to post face


def test_joint_into_post_is_red_and_link_named(state):
    state.set_joint("left", 0, 90 * DEG)
    r = state.snapshot().readout
    assert r.status is PanelStatus.COLLISION and r.within_threshold
    assert r.distance == pytest.approx(-0.15, abs=1e-6)
    assert r.obstacle == "post" and r.owner_a == "left/link2"
    assert r.color == "#d62828" and r.line_color == (220, 30, 30)


def test_within_threshold_is_yellow(state):
    # at home the nearest pair is 0.3 m apart (link1 to link3 of the straight arm): a 0.5 m
    # threshold puts it within the threshold without contact
    state.set_threshold(0.5)
    r = state.snapshot().readout
    assert r.status is PanelStatus.WARNING and r.color == "#f2c200" and r.within_threshold


@pytest.mark.parametrize(
    "call",
    [
        lambda s: s.set_joint("left", 0, "abc"),
        lambda s: s.set_joint("left", 0, float("nan")),
        lambda s: s.set_joint("left", 0, 3.5),  # beyond the 170 deg limit
        lambda s: s.set_joint("left", 7, 0.0),
        lambda s: s.set_joint("nobody", 0, 0.0),
        lambda s: s.set_joints("left", "1, 2"),
        lambda s: s.set_threshold(-1),
        lambda s: s.set_threshold("inf"),
        lambda s: s.set_stopping_distance("x"),
        lambda s: s.set_workspace("0 0 0", "1 1 -1"),
        lambda s: s.set_workspace("0 0", "1 1 1"),
        lambda s: s.set_mode("telepathy"),
        lambda s: s.set_active("nobody"),
        lambda s: s.setup("no_such_test"),
        lambda s: s.timeline_command("play"),  # nothing loaded
        lambda s: s.move_ee([50.0, 0.0, 0.0]),  # far out of reach
    ],
    ids=["word", "nan", "over-limit", "bad-index", "bad-arm", "short-list", "neg-threshold", "inf-threshold",
         "word-stop", "inverted-box", "short-corner", "bad-mode", "bad-active", "bad-test", "no-timeline",
         "unreachable"],
)
def test_bad_input_raises_and_keeps_state(state, call):
    before = state.snapshot()
    with pytest.raises(ConsoleInputError):
        call(state)
    after = state.snapshot()
    for k in before.q:
        np.testing.assert_array_equal(after.q[k], before.q[k])
    assert (after.threshold, after.stopping_distance, after.active, after.mode) == (
        before.threshold, before.stopping_distance, before.active, before.mode)
    assert after.workspace[0].tolist() == before.workspace[0].tolist()
    assert after.readout.status is before.readout.status


def test_detection_off_is_grey_and_back_on(state):
    state.set_joint("left", 0, 90 * DEG)
    state.set_detection(False)
    assert state.snapshot().readout.status is PanelStatus.OFF
    state.set_detection(True)
    assert state.snapshot().readout.status is PanelStatus.COLLISION


def test_setup_poses_arms_selects_active_and_threshold(state):
    state.set_active("right")
    state.set_detection(False)
    state.setup("in_post")
    snap = state.snapshot()
    assert snap.active == "left" and snap.detection and snap.threshold == pytest.approx(0.1)
    np.testing.assert_allclose(snap.q["left"], [90 * DEG, 0, 0], atol=1e-12)
    assert snap.readout.status is PanelStatus.COLLISION
    state.setup("fold_right")
    assert state.snapshot().active == "right" and state.snapshot().readout.status is PanelStatus.CLEAR


def test_active_arm_changes_the_checked_arm(state):
    state.set_joint("left", 0, 90 * DEG)  # left in the post
    state.set_active("right")
    r = state.snapshot().readout
    assert r.owner_a.startswith("right/")
    assert r.status is PanelStatus.CLEAR  # only the active arm is checked: the left arm's collision is not its own


def test_run_plays_the_trapezoid_and_halts_at_the_stopping_distance(state):
    player = state.run("hit_post")
    assert player.kind == "run" and player.timeline.playing
    np.testing.assert_allclose(state.snapshot().q["left"], [0, 0, 0], atol=1e-12)  # setup pose at t = 0
    while state.tick(0.05):
        pass
    snap = state.snapshot()
    assert snap.player.timeline.t == pytest.approx(player.timeline.duration)
    np.testing.assert_allclose(snap.q["left"], [90 * DEG, 0, 0], atol=1e-9)  # the goal
    assert snap.readout.status is PanelStatus.COLLISION  # no stand-off set: it drives into the post
    state.set_stopping_distance(0.05)
    state.run("hit_post")
    while state.tick(0.05):
        pass
    snap = state.snapshot()
    assert snap.player.timeline.t < player.timeline.duration and snap.message_is_error
    assert 0.0 < snap.readout.distance <= 0.05 + 1e-9  # halted within the stand-off, before contact
    assert "stopped by detection" in snap.message and snap.run_state == "stopped by detection"
    assert snap.run_detail.startswith(f"at t = {snap.player.timeline.t:.2f} s, left/")
    assert "within the stopping distance 50 mm" in snap.run_detail and snap.run_detail in snap.message


def test_a_run_played_backwards_to_its_start_says_so_and_plays_on_when_started_again(state):
    """It said "done at t = 0.00 s" (the end of the run's motion is at its duration)."""
    player = state.run("hit_post")
    for _ in range(10):
        state.tick(0.05)
    assert state.snapshot().run_state == "running" and player.timeline.t > 0.0
    state.timeline_command("reverse")
    while state.tick(0.05):
        pass
    snap = state.snapshot()
    assert player.timeline.t == 0.0 and snap.run_state == "back at the start", (snap.run_state, snap.message)
    assert snap.message == "hit_post: back at the start at t = 0.00 s" and not snap.message_is_error
    state.timeline_command("forward")
    state.timeline_command("play")
    state.tick(0.05)
    assert state.snapshot().run_state == "running" and state.snapshot().run_detail == ""
    while state.tick(0.05):
        pass
    snap = state.snapshot()
    assert snap.run_state == "done" and snap.run_detail == f"at t = {player.timeline.duration:.2f} s"


def test_a_joint_typed_for_the_arm_a_run_moves_pauses_the_run_and_stays(state):
    """The next tick overwrote the typed joint, without a word."""
    player = state.run("hit_post")
    for _ in range(5):
        state.tick(0.05)
    t = player.timeline.t
    state.set_joint("left", 1, "10", deg=True)
    snap = state.snapshot()
    assert not player.timeline.playing and snap.run_state == "stopped"
    assert snap.run_detail == f"at t = {t:.2f} s (left moved by hand)"
    assert snap.message == f"hit_post: paused at t = {t:.2f} s: left moved by hand" and not snap.message_is_error
    assert not state.tick(0.05)  # nothing plays: the typed joint stays
    assert state.snapshot().q["left"][1] == pytest.approx(10 * DEG)


def test_setting_every_arm_while_a_run_plays_pauses_it_with_a_note(state):
    """``set_q`` paused the run but dropped the note (the active arm's pause was not kept)."""
    player = state.run("hit_post")
    for _ in range(5):
        state.tick(0.05)
    snap = state.snapshot()
    state.set_q({k: np.asarray(v) for k, v in snap.q.items()})
    snap = state.snapshot()
    assert not player.timeline.playing and snap.run_state == "stopped"
    assert snap.message.startswith("hit_post: paused at t = ") and "moved by hand" in snap.message


def test_test_line_says_when_a_run_ended(state):
    from armguard.console._app import run_line

    assert run_line(state.snapshot()) == "test: none running"
    player = state.run("hit_post")
    assert run_line(state.snapshot()) == "**test: running**"
    while state.tick(0.05):
        pass
    snap = state.snapshot()
    end = f"at t = {player.timeline.duration:.2f} s"
    assert snap.run_state == "done" and snap.run_detail == end and snap.message == f"hit_post: done {end}"
    assert run_line(snap) == f"**test: done {end}**"
    state.run("hit_post")
    state.tick(0.1)
    state.stop()
    assert run_line(state.snapshot()) == "**test: stopped at t = 0.10 s**"


def test_verified_trajectory_time_line(state):
    player = state.load_trajectory("sweep_through_post", samples=60)
    assert player.kind == "verified" and not player.report.safe
    assert player.clearance.shape == (60,) and player.clearance.min() == pytest.approx(-0.15, abs=1e-6)
    fc = player.report.first_collision.time
    # the sampled profile turns negative no earlier than the verifier's first collision
    first_neg = player.times[np.argmax(player.clearance <= 0.0)]
    assert first_neg >= fc - 1e-9
    T = player.timeline.duration
    state.timeline_command("seek", T / 2)
    np.testing.assert_allclose(state.snapshot().q["left"], player.trajectory.at(T / 2))
    state.timeline_command("faster")
    state.timeline_command("play")
    state.tick(0.1)
    assert state.snapshot().player.timeline.t == pytest.approx(T / 2 + 0.2)
    state.timeline_command("backward")
    state.tick(0.1)
    assert state.snapshot().player.timeline.t == pytest.approx(T / 2)
    state.timeline_command("pause")
    assert not state.tick(1.0)
    with pytest.raises(ConsoleInputError):
        state.timeline_command("seek", "soon")
    assert state.snapshot().player.timeline.t == pytest.approx(T / 2)


def test_cartesian_move_reaches_the_target(state):
    state.set_joints("left", "-90, 30, 30", scale=DEG)
    X = state.ee_pose()
    state.set_joints("left", "-90, 0, 0", scale=DEG)
    q = state.move_ee(X[:3, 3])
    np.testing.assert_allclose(state.ee_pose()[:3, 3], X[:3, 3], atol=1e-6)
    assert q.shape == (3,)


def test_arm_angle_needs_seven_joints(state):
    with pytest.raises(ConsoleInputError, match="7-DOF"):
        state.set_arm_angle(0.2)


def test_workspace_limits_change_the_workspace_distance(state):
    d0 = next(r.distance for r in state.snapshot().readout.rows if r.category == "workspace")
    state.set_workspace("-2.5 -1.5 -1", "2.5 2 1")  # the wall behind the arm tip moves 0.5 m closer
    d1 = next(r.distance for r in state.snapshot().readout.rows if r.category == "workspace")
    assert d1 == pytest.approx(d0 - 0.5, abs=1e-9)


def test_arm_angle_moves_the_elbow_and_keeps_the_tool_pose():
    """A 7-DOF S-R-S arm (shoulder, elbow, wrist spherical; made up for the test): the arm-angle
    null-space motion keeps the tool pose (to the IK tolerance) while the elbow moves."""
    from armguard.geometry import Box, Sphere
    from armguard.kinematics import Robot
    from armguard.scene import Scene

    h = math.pi / 2
    rows = [(0, -h, 0.3, 0), (0, h, 0, 0), (0, -h, 0.4, 0), (0, h, 0, 0), (0, -h, 0.4, 0), (0, h, 0, 0), (0, 0, 0.1, 0)]
    # a tool ball, so that the console's detector has a pair to check (a scene with none is refused)
    robot = Robot.from_dh("arm7", rows, lower=[-3.0] * 7, upper=[3.0] * 7,
                          link_shapes={"link7": [Sphere([0.0, 0.0, 0.0], 0.02)]})
    sc = Scene("seven")
    sc.add_robot(robot, home=[0.1, 0.5, 0.1, 1.0, 0.1, 0.5, 0.1])
    sc.add_body("block", Box([1.0, 1.0, 0.0], [0.1, 0.1, 0.1]))
    st = ConsoleState(sc)
    X0 = st.ee_pose()
    elbow0 = robot.link_pose(st.snapshot().q["arm7"], "link4")[:3, 3]
    assert st.set_arm_angle(0.3) == pytest.approx(0.3)
    q1 = st.snapshot().q["arm7"]
    np.testing.assert_allclose(st.ee_pose()[:3, 3], X0[:3, 3], atol=1e-5)
    np.testing.assert_allclose(st.ee_pose()[:3, :3], X0[:3, :3], atol=1e-4)
    elbow1 = robot.link_pose(q1, "link4")[:3, 3]
    assert np.linalg.norm(elbow1 - elbow0) > 0.01
    assert st.snapshot().arm_angle == pytest.approx(0.3)


# ---------------------------------------------------------------------- typed targets and corners
@pytest.mark.parametrize(
    "text, words",
    [
        ("", "expected 3 numbers (m) (x, y, z), got an empty entry"),
        ("0.1, 0.2", "expected 3 numbers (m) (x, y, z), got 2"),
        ("0.1, 0.2, -0.5.2", "target position z: expected a number (m), got '-0.5.2'"),
        ("-1e309, 0, 0", "target position x: expected a finite number (m), got '-1e309'"),
        ("0, nan, 0", "target position y: expected a finite number (m)"),
        ("0, 0, -1000", "target position z: -1000 m is outside [-100, 100] m"),
        ("0, 0, abc", "target position z: expected a number (m), got 'abc'"),
    ],
)
def test_typed_target_refused_with_the_axis_and_kept(state, text, words):
    before = state.target()
    with pytest.raises(ConsoleInputError) as exc:
        state.set_target_position(text)
    assert words in str(exc.value)
    after = state.target()
    np.testing.assert_array_equal(after[0], before[0])
    assert after[2] is False  # still the tool pose now: nothing typed was kept


def test_typed_target_keeps_its_sign_and_exponent_and_move_tool_goes_there(state):
    state.set_joints("left", "-90, 30, 30", scale=DEG)
    X = state.ee_pose()
    state.set_joints("left", "-90, 0, 0", scale=DEG)
    p0, rpy0, typed = state.target()
    np.testing.assert_allclose(p0, state.ee_pose()[:3, 3], atol=1e-12)
    assert not typed
    x, y, z = (float(v) for v in X[:3, 3])
    text = f"{x!r}, {y!r}, {z + 1e-3:.6e}"  # an exponent, and a negative y
    assert y < 0
    p = state.set_target_position(text)
    assert p[1] == y and p[2] == pytest.approx(z + 1e-3, abs=1e-9)
    np.testing.assert_array_equal(state.snapshot().q["left"], np.radians([-90, 0, 0]))  # nothing moved yet
    snap = state.snapshot()
    np.testing.assert_array_equal(snap.target[0], p)
    assert snap.target[2] and "move tool" in snap.message
    state.set_target_position(f"{x!r}, {y!r}, {z!r}")
    state.move_to_target()
    np.testing.assert_allclose(state.ee_pose()[:3, 3], X[:3, 3], atol=1e-6)
    assert not state.target()[2]  # the arm moved: the target follows the tool again


def test_typed_orientation_in_degrees_checked(state):
    rpy = state.set_target_rpy("-10, 1e-3, 170")
    np.testing.assert_allclose(rpy, np.radians([-10, 1e-3, 170]))
    with pytest.raises(ConsoleInputError, match="target roll pitch yaw yaw: 190 deg is outside"):
        state.set_target_rpy("0, 0, 190")
    np.testing.assert_allclose(state.target()[1], np.radians([-10, 1e-3, 170]))


def test_workspace_corners_typed_then_applied_refusal_restores(state):
    lo0, hi0 = (c.copy() for c in state.snapshot().workspace)
    with pytest.raises(ConsoleInputError, match="workspace lower corner x: expected a finite number"):
        state.set_workspace_corner("lower", "-1e309, 0, 0")
    with pytest.raises(ConsoleInputError, match=r"outside \[-100, 100\] m"):
        state.set_workspace_corner("lower", "-1309, 0, 0")
    np.testing.assert_array_equal(state.workspace_corners()[0], lo0)
    state.set_workspace_corner("lower", "-2.5, -1.5, -1")
    np.testing.assert_array_equal(state.snapshot().workspace[0], lo0)  # typed, not applied
    np.testing.assert_array_equal(state.snapshot().workspace_corners[0], [-2.5, -1.5, -1])
    state.apply_workspace()
    np.testing.assert_array_equal(state.snapshot().workspace[0], [-2.5, -1.5, -1])
    state.set_workspace_corner("upper", "-3, 0, 0")  # below the lower corner in x
    with pytest.raises(ConsoleInputError, match="upper corner must exceed the lower one"):
        state.apply_workspace()
    snap = state.snapshot()
    np.testing.assert_array_equal(snap.workspace[1], hi0)  # the box in force
    np.testing.assert_array_equal(snap.workspace_corners[1], hi0)  # the refused corner is gone from the field


def test_workspace_removed_and_none_shown_until_both_corners_typed(state):
    state.remove_workspace()
    snap = state.snapshot()
    assert snap.workspace is None and snap.workspace_corners == (None, None)
    assert "workspace" not in {r.category for r in snap.readout.rows} and snap.message == "workspace box removed"
    with pytest.raises(ConsoleInputError, match="no box to remove"):
        state.remove_workspace()
    state.set_workspace_corner("upper", "2, 2, 2")
    with pytest.raises(ConsoleInputError, match="type the lower corner first"):
        state.apply_workspace()
    assert state.snapshot().workspace is None and state.snapshot().workspace_corners == (None, None)
    state.set_workspace_corner("lower", "-2, -2, -2")
    state.set_workspace_corner("upper", "2, 2, 2")
    state.apply_workspace()
    assert "workspace" in {r.category for r in state.snapshot().readout.rows}


def test_collision_inside_the_stopping_distance_says_why_and_is_red_in_the_view(state):
    from armguard.console import panel_html

    # at home the nearest pair is 0.3 m apart: threshold 0.2, stopping distance 0.35
    state.set_threshold(0.2)
    state.set_stopping_distance(0.35)
    r = state.snapshot().readout
    assert r.status is PanelStatus.COLLISION and r.distance > r.threshold and not r.within_threshold
    assert r.reason == "within the stopping distance 350.0 mm"
    assert r.alarm and r.line_color == (220, 30, 30)  # the line and the link red, as the headline
    html = panel_html(r)
    assert 'data-reason="within the stopping distance 350.0 mm"' in html and "stopping distance: 350.0 mm" in html
    state.set_stopping_distance(0.0)
    r = state.snapshot().readout
    assert r.status is PanelStatus.CLEAR and not r.alarm and r.reason == "nothing within the threshold 200.0 mm"
    state.set_joint("left", 0, 90 * DEG)
    assert state.snapshot().readout.reason == "contact"
