"""Avoidance in the console: on/off and the stand-off (refused values leave the state as it was), a
canned run with avoidance that keeps the stand-off where the same run without it stops by detection,
and the time line's plot of the commanded against the filtered motion.

The console's recorded run (:func:`armguard.avoidance.run_canned` with ``record=True``) is checked
against the same run unrecorded and against the canned profile; the browser test drives the widgets
in chromium.
"""

from __future__ import annotations

import time

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as hst

from armguard.console import ConsoleInputError

TEST = "test1_left_inward"
"""Ranger's canned test 1: the left forearm comes to 80.6 mm of the manipulator module without avoidance."""
STAND_OFF = 0.1
SLACK = 1e-3
BAD_STAND_OFFS = ["-0.1", "abc", "nan", "inf", "", "11", "1e9", "0.1 m"]


@pytest.fixture(scope="module")
def ranger_state():
    from armguard.console._serve import make_state

    return make_state("ranger")


def _play(st, dt: float = 0.05, limit_s: float = 60.0):
    """Tick the state to the end of its run; returns the panel statuses seen on the way."""
    seen = []
    for _ in range(int(limit_s / dt)):
        st.tick(dt)
        snap = st.snapshot()
        seen.append(snap.readout.status.value)
        if snap.run_state not in ("running", "filtering"):
            return seen, snap
    raise AssertionError(f"the run did not end within {limit_s} s of play")


@pytest.mark.parametrize("bad", BAD_STAND_OFFS)
def test_bad_stand_off_is_refused_and_kept(ranger_state, bad):
    st = ranger_state
    st.set_stand_off("0.07")
    v0 = st.version
    with pytest.raises(ConsoleInputError, match="stand-off distance"):
        st.set_stand_off(bad)
    assert st.avoidance_settings()[1] == 0.07 and st.version == v0


def test_avoidance_needs_a_model():
    from pathlib import Path

    from armguard.console import ConsoleState
    from armguard.scene import load_scene

    st = ConsoleState(load_scene(Path(__file__).parent / "data" / "console_scene.yaml"))
    assert st.model is None
    with pytest.raises(ConsoleInputError, match="no Model"):
        st.set_avoidance(True)
    assert st.avoidance_settings()[0] is False


def test_recorded_run_is_run_canned_with_every_step(ranger_state):
    """The console's loop ends where run_canned's does (same damper), and its record is consistent."""
    from armguard.avoidance import robot_rows_and_columns, run_canned
    from armguard.backends import checker
    from armguard.console._avoid import AVOID_PERIOD, avoid_canned, console_damper

    model = ranger_state.model
    c = checker(model, "analytic")
    run = avoid_canned(model, TEST, STAND_OFF, c)
    ref = run_canned(model, TEST, console_damper(STAND_OFF), checker=c)
    assert np.array_equal(run.q[-1], ref.q_end)
    assert run.steps == ref.steps and run.statuses == ref.statuses
    assert run.min_distance == pytest.approx(ref.min_distance, abs=1e-12)
    assert run.progress == pytest.approx(ref.progress, abs=1e-12)
    # the commanded motion goes inside the stand-off, the filtered one does not
    assert run.distance_cmd.min() < STAND_OFF - 0.01
    assert run.min_distance >= STAND_OFF - SLACK and not run.contact
    assert run.outcome == "stopped short" and "stopped short at" in run.summary()
    # the record: commanded = the profile at each step's time, held at the end; filtered starts at setup
    test = model.scene.canned_tests[TEST]
    traj = test.trajectory(model.scene)
    k = len(run.times) // 3
    assert np.allclose(run.q_cmd[k], traj.at(min(run.times[k], traj.duration)))
    assert np.allclose(run.q_cmd[-1], traj.at(traj.duration))
    assert np.allclose(run.q[0], test.setup[test.robot])
    # the recorded distances are the robot's least pair distance at each filtered step
    rows, ks, _ = robot_rows_and_columns(model, test.robot)
    full = model.scene.flat_q({r: np.asarray(v) for r, v in test.setup.items()})
    full[ks] = run.q[k]
    assert run.distance[k] == pytest.approx(c.pair_distances(model.pin_q(full)).distance[rows].min(), abs=1e-12)
    assert np.allclose(np.diff(run.times), AVOID_PERIOD)
    # the time line's interpolation hits the steps and lies between them
    assert np.allclose(run.at(run.times[k]), run.q[k])
    mid = run.at(0.5 * (run.times[k] + run.times[k + 1]))
    assert np.allclose(mid, 0.5 * (run.q[k] + run.q[k + 1]))


@pytest.fixture(scope="module")
def ranger_checker(ranger_state):
    from armguard.backends import checker

    return checker(ranger_state.model, "analytic")


@pytest.mark.parametrize("stand_off, outcome, words", [
    (0.05, "free", "reached the goal, the filter never acting"),  # test 1 comes to 80.6 mm: never within reach
    (0.08, "slid", "reached the goal sliding along the obstacle"),
    (0.1, "stopped short", "stopped short at 97.8 % of the way"),
])
def test_outcome_says_what_the_filter_did(ranger_state, ranger_checker, stand_off, outcome, words):
    from armguard.console._avoid import GOAL_REACHED, avoid_canned

    run = avoid_canned(ranger_state.model, TEST, stand_off, ranger_checker)
    assert run.outcome == outcome and words in run.summary()
    assert (run.acted == 0) == (outcome == "free")
    assert (run.progress >= GOAL_REACHED) == (outcome != "stopped short")


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(stand_off=hst.floats(0.0, 0.22), test=hst.sampled_from(["test1_left_inward", "test2_left_up_and_back",
                                                               "test7_right_inward"]))
def test_every_step_keeps_the_stand_off(ranger_state, ranger_checker, stand_off, test):
    """Ranger's tests that approach the module: at every control step the filtered least distance
    is at least min(stand-off, start) - 1 mm, the arm stays within its limits, and the commanded
    configuration is the test's profile."""
    from armguard.console._avoid import avoid_canned

    model = ranger_state.model
    run = avoid_canned(model, test, stand_off, ranger_checker)
    assert np.all(run.distance >= min(stand_off, run.distance[0]) - SLACK), run.distance.min()
    robot = model.scene.robots[run.robot]
    assert np.all(run.q >= np.asarray(robot.lower) - 1e-12) and np.all(run.q <= np.asarray(robot.upper) + 1e-12)
    traj = model.scene.canned_tests[test].trajectory(model.scene)
    assert np.allclose(run.q_cmd[-1], traj.at(traj.duration)) and np.allclose(run.q_cmd[0], traj.at(0.0))
    assert sum(run.statuses.values()) == run.steps


def test_canned_run_with_avoidance_keeps_the_stand_off_and_without_stops_by_detection(ranger_state):
    st = ranger_state
    st.set_stopping_distance(STAND_OFF)
    st.set_stand_off(STAND_OFF)
    st.set_avoidance(True)
    p = st.run(TEST)
    assert p.kind == "avoid" and p.timeline.playing
    seen, snap = _play(st)
    assert "collision" not in seen
    assert snap.run_state == "stopped short by avoidance", (snap.run_state, snap.run_detail)
    assert "stopped short at" in snap.run_detail and "100.0 mm" in snap.run_detail
    assert p.report.min_distance >= STAND_OFF - SLACK
    assert snap.readout.distance >= STAND_OFF - SLACK  # the detector's own distance at the end agrees
    # the time line scrubs the filtered motion
    st.timeline_command("seek", 0.0)
    assert np.allclose(st.snapshot().q[p.robot], p.report.q[0])

    st.set_avoidance(False)
    p = st.run(TEST)
    assert p.kind == "run"
    seen, snap = _play(st)
    assert snap.run_state == "stopped by detection", (snap.run_state, snap.run_detail)
    assert snap.readout.distance <= STAND_OFF


def test_operator_stop_during_a_run_with_avoidance(ranger_state):
    st = ranger_state
    st.set_avoidance(True)
    st.run(TEST)
    st.tick(0.5)
    st.stop()
    snap = st.snapshot()
    assert snap.run_state == "stopped" and snap.player is None
    st.set_avoidance(False)


def test_a_run_with_avoidance_played_backwards_to_its_start_says_so_and_frees_the_arms(ranger_state):
    """It stayed "running" at t = 0 with nothing playing, and another arm could not be made active."""
    st = ranger_state
    st.set_stand_off(STAND_OFF)
    st.set_avoidance(True)
    try:
        p = st.run(TEST)
        for _ in range(10):
            st.tick(0.05)
        assert st.snapshot().run_state == "running" and p.timeline.t > 0.0
        st.timeline_command("reverse")
        while st.tick(0.05):
            pass
        snap = st.snapshot()
        assert p.timeline.t == 0.0 and snap.run_state == "back at the start", (snap.run_state, snap.message)
        other = next(r for r in snap.q if r != p.robot)
        st.set_active(other)  # refused while "running"
        st.set_active(p.robot)
        st.timeline_command("forward")
        st.timeline_command("play")
        st.tick(0.05)
        assert st.snapshot().run_state == "running" and st.snapshot().message.startswith(f"{TEST}: running from t = ")
    finally:
        st.stop()
        st.set_avoidance(False)


def test_plot_marks_time_across_both_axes(ranger_state):
    from armguard.backends import checker
    from armguard.console._avoid import avoid_canned
    from armguard.console._avoid_panel import AvoidPlot
    from armguard.console._plot import MARKER_RGB

    model = ranger_state.model
    run = avoid_canned(model, TEST, STAND_OFF, checker(model, "analytic"))
    plot = AvoidPlot(run, ranger_state.joint_units(run.robot))
    T = run.duration
    cols = [plot.column_of(x) for x in (0.0, T / 4, T / 2, T)]
    assert cols == sorted(cols) and cols[0] < cols[-1]
    assert cols[2] - cols[0] == pytest.approx(2 * (cols[1] - cols[0]), abs=1)
    img = plot.image_at(T / 2)
    assert img.dtype == np.uint8 and img.shape == plot.shape
    marked = np.all(img[:, cols[2]] == MARKER_RGB, axis=-1)
    assert marked[: img.shape[0] // 3].any() and marked[2 * img.shape[0] // 3:].any()  # both axes
    assert not np.array_equal(img, plot.image_at(T / 3))


@pytest.mark.browser
def test_avoidance_in_a_browser():
    """Toggle avoidance and type stand-offs in chromium (bad ones refused, the box put back); Run
    canned test 1 with avoidance: no COLLISION headline, ends stopped short with the least distance
    at the stand-off and the plot shown (saved as ``docs/img/console-avoidance.png``); without
    avoidance the same Run stops by detection."""
    from test_console_browser import CHROMIUM, CHROMIUM_ARGS, POLL_MS, UI_TIMEOUT_MS, _input_for, _need_chromium
    from test_console_browser import screenshot
    from test_console_view import IMG, _app, _open, _type, _wait

    _need_chromium()
    from playwright.sync_api import sync_playwright

    app = _app("ranger")
    st = app.state
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            try:
                page = _open(browser, app.url)
                box = page.get_by_role("checkbox", name="avoidance")
                assert not box.is_checked() and st.avoidance_settings()[0] is False  # off, as the seed's GUI
                box.click()
                _until(lambda: st.avoidance_settings()[0] is True, "avoidance on")

                field = _input_for(page, "stand-off (m)")
                for bad in ("-0.1", "abc", "nan", "11"):
                    before = st.avoidance_settings()[1]
                    _type(field, bad)
                    _wait(page, "() => document.querySelector('#armguard-message[data-error=\"true\"]') && "
                                "document.querySelector('#armguard-message').innerText.includes('stand-off')")
                    _until(lambda: _num(field.input_value()) == before, "the box put back")
                    assert st.avoidance_settings()[1] == before
                    _type(field, "0.05")  # a good value clears the message before the next bad one
                    _until(lambda: st.avoidance_settings()[1] == 0.05, "stand-off 0.05")
                _type(field, str(STAND_OFF))
                _until(lambda: st.avoidance_settings()[1] == STAND_OFF, "stand-off typed")
                _type(_input_for(page, "stopping distance (m)"), str(STAND_OFF))
                _until(lambda: st.snapshot().stopping_distance == STAND_OFF, "stopping distance typed")

                # record every headline the page shows during the run
                page.evaluate("() => { window.__seen = new Set(); setInterval(() => { const s = "
                              "document.querySelector('#armguard-status'); if (s) window.__seen.add(s.dataset.status); "
                              "}, 50); }")
                page.get_by_role("tab", name="Tests").click()
                page.get_by_role("button", name=f"Run {TEST}").click()
                _wait_run(page, st, "stopped short by avoidance")
                seen = set(page.evaluate("() => Array.from(window.__seen)"))
                assert seen and "collision" not in seen, seen
                run = st.snapshot().player.report
                assert run.min_distance >= STAND_OFF - SLACK and not run.contact
                assert "100.0 mm" in page.inner_text("body")
                page.get_by_role("tab", name="Time line").click()
                _wait(page, "() => Array.from(document.querySelectorAll('img')).some(i => i.naturalWidth >= 400)")
                page.set_viewport_size({"width": 1100, "height": 1150})  # the panel and the plot below it
                page.evaluate("() => Array.from(document.querySelectorAll('img')).find(i => i.naturalWidth >= 400)"
                              ".scrollIntoView({block: 'end'})")
                page.wait_for_timeout(1500)  # let software WebGL draw the latest frame
                screenshot(page, path=str(IMG / "console-avoidance.png"))

                page.get_by_role("tab", name="Control").click()
                box.click()
                _until(lambda: st.avoidance_settings()[0] is False, "avoidance off")
                page.get_by_role("tab", name="Tests").click()
                page.get_by_role("button", name=f"Run {TEST}").click()
                _wait_run(page, st, "stopped by detection")
                assert st.snapshot().readout.distance <= STAND_OFF
            finally:
                browser.close()
    finally:
        app.stop()


RUN_TIMEOUT_S = 240.0
"""A run's filtering and its 13 s of play, on a loaded machine with software WebGL."""


def _wait_run(page, st, state: str) -> None:
    """Until the page says the run ended in ``state``; a failure says where the server's run was
    (its state, time and whether it still plays), so a page left behind tells from a run that stalled."""
    deadline = time.monotonic() + RUN_TIMEOUT_S
    while time.monotonic() < deadline:
        if f"test: {state}" in page.inner_text("body"):
            return
        page.wait_for_timeout(200)
    snap = st.snapshot()
    tl = None if snap.player is None else snap.player.timeline.state
    server = (f"server: run state {snap.run_state!r}, message {snap.message!r}, "
              + ("no player" if tl is None else f"t = {tl.t:.2f} / {tl.duration:.2f} s, playing {tl.playing}"))
    raise AssertionError(f"the page did not show the run ended {state!r} in {RUN_TIMEOUT_S:g} s; {server}; "
                         f"page: {page.inner_text('body')[:1500]}")


def _num(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        return float("nan")


def _until(fn, what: str, timeout_s: float = 30.0) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if fn():
            return
        time.sleep(0.1)
    raise AssertionError(f"timed out waiting for {what}")
