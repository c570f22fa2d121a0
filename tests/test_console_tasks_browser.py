"""WORKMATE's task menu, training views and jogging in a real browser (Playwright + Debian's chromium).

Runs :class:`armguard.console.ConsoleApp` in-process on the demonstration's cell
(``examples/workmate/cell.yaml``) so the test can read the state and the tab's camera:

* a PICKUP composed by the menu — the task chosen in its dropdown, the object answered by a click
  on the cylinder in the 3-D view — runs (each motion verified, then emulated), lands on the time
  line and plays to its end; the saved file reads back to the same listing.  Saves
  ``docs/img/console-tasks.png``;
* the top / front / side buttons put the tab's camera at :func:`armguard.console.view_pose`'s
  poses, *main view: eye in the hand* puts it on the tool looking along the tool's z, and the four
  insets are rendered, each a picture (not blank) and each different;
* jogging +x in tool coordinates moves the tool 20 mm along its own x axis (not W's), its
  orientation kept;
* a step typed at machine speed right after a dropdown choice lands, each of eight times (the
  page's GUI throttle keeps only the latest message of each 50 ms, and such a value was once lost:
  ``armguard.console._fields.COMMIT_GAP_MS``).
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

from test_console_browser import CHROMIUM, CHROMIUM_ARGS, POLL_MS, UI_TIMEOUT_MS, _input_for, _need_chromium, screenshot
from test_console_view import HIDE_NOTICES, VIEWPORT, _client, _project, _type

pytestmark = pytest.mark.browser

CELL = Path(__file__).resolve().parent.parent / "examples" / "workmate" / "cell.yaml"
IMG = Path(__file__).resolve().parent.parent / "docs" / "img"
RUN_TIMEOUT_S = 300.0
"""The run verifies three motions (certified) and checks them in the emulated real cell: seconds
here, minutes on a loaded 2-core machine compiling its kernels for the first time."""


@pytest.fixture(scope="module")
def app():
    _need_chromium()
    from armguard.console._serve import serve

    a = serve(str(CELL), port=0, block=False)
    yield a
    a.stop()


@pytest.fixture(scope="module")
def browser():
    _need_chromium()
    from playwright.sync_api import sync_playwright

    with sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        yield b
        b.close()


def _open(browser, app):
    page = browser.new_page(viewport=VIEWPORT)
    logs: list = []  # the tab's console (viser logs its connects and disconnects there): said on a timeout
    page.on("console", lambda m: logs.append(m.text))
    page.armguard_logs = logs
    page.goto(app.url)
    page.wait_for_selector("#armguard-status", timeout=UI_TIMEOUT_MS)
    page.add_style_tag(content=HIDE_NOTICES)
    page.wait_for_timeout(2500)
    return page


def _until(page, ok, what: str, timeout_s: float = UI_TIMEOUT_MS / 1000) -> None:
    for _ in range(int(timeout_s * 1000 / POLL_MS)):
        if ok():
            return
        page.wait_for_timeout(POLL_MS)
    shown = page.evaluate("() => { const m = document.querySelector('#armguard-message'); "
                          "return m === null ? '(no #armguard-message)' : m.innerText; }")
    logs = getattr(page, "armguard_logs", [])[-12:]
    raise AssertionError(f"timed out waiting for {what}; the tab's message: {shown!r}; its last console lines: {logs}")


def _choose(page, label: str, option: str) -> None:
    page.locator("label").filter(has_text=re.compile(f"^{re.escape(label)}$")).first.click()
    page.get_by_role("option", name=option, exact=True).click()


def _button(page, name: str):
    return page.get_by_role("button", name=name, exact=True)


def test_pickup_composed_by_the_menu_runs_on_the_time_line(app, browser, tmp_path):
    from armguard.program import load_program

    st, panel = app.state, app._tasks
    page = _open(browser, app)
    try:
        page.get_by_role("tab", name="Tasks").click()
        assert panel.w_kind.value == "FIND" and panel.w_object.value == "block_a"  # the menu's first answers
        _choose(page, "task", "PICKUP")
        _until(page, lambda: panel.w_kind.value == "PICKUP", "the task menu to say PICKUP")
        page.wait_for_selector("text=click the object in the 3-D view", timeout=UI_TIMEOUT_MS)

        # answer the prompt by clicking the cylinder in the 3-D view (looked at from above the table)
        c = st.cell.objects["cylinder_a"][:3, 3]
        app._place(_client(app), c + np.array([0.45, 0.25, 0.55]), c)
        page.wait_for_timeout(1500)
        x, y = _project(app, c[None])[0]
        page.mouse.click(float(x), float(y))
        _until(page, lambda: panel.w_object.value == "cylinder_a", "the click to answer the object prompt")
        assert "picked in the 3-D view" in st.snapshot().message

        _button(page, "add task").click()
        _until(page, lambda: panel.composer.lines() == ["1. PICKUP cylinder_a"], "the task in the program")
        page.wait_for_selector("text=PICKUP cylinder_a", timeout=UI_TIMEOUT_MS)  # a numbered list item

        _button(page, "run: verify, emulate, play on the time line").click()
        _until(page, lambda: panel.run_result is not None, "the program's run", RUN_TIMEOUT_S)
        run = panel.run_result
        assert run.ok, run.summary()
        assert [m.label.split(" ", 1)[1] for m in run.motions] == [f"PICKUP cylinder_a {p}" for p in ("approach", "grasp", "depart")]
        assert all(m.status == "ran" and m.report.safe for m in run.motions)
        page.wait_for_selector("#armguard-program-report", timeout=UI_TIMEOUT_MS)
        assert "every motion verified and ran" in page.inner_text("#armguard-program-report")
        p = st.snapshot().player
        assert p is not None and p.name == "console_program"
        assert p.timeline.duration == pytest.approx(sum(m.trajectory.duration for m in run.motions))

        # the picture: the cylinder lifted in the hand, the program and its report in the Tasks tab
        st.timeline_command("seek", p.timeline.duration)
        page.wait_for_function("() => document.querySelector('#armguard-message').innerText.includes('every motion verified')",
                               timeout=UI_TIMEOUT_MS, polling=POLL_MS)
        page.locator("#armguard-program-report").scroll_into_view_if_needed()
        page.wait_for_timeout(4000)  # software WebGL on a loaded machine: let it draw the arm there
        IMG.mkdir(parents=True, exist_ok=True)
        screenshot(page, path=str(IMG / "console-tasks.png"))

        # save: the file reads back to the program that ran
        out = tmp_path / "pickup.yaml"
        _type(_input_for(page, "save as"), str(out))
        _button(page, "save program").click()
        _until(page, lambda: out.exists(), "the saved file")
        assert [(s.op, s.args) for s in load_program(out).steps()] == [(s.op, s.args) for s in panel.composer.program().steps()]

        # play it on the time line to its end: the arm ends where the depart put it
        page.get_by_role("tab", name="Time line").click()
        st.timeline_command("seek", 0.0)
        _button(page, "play ▶").click()
        _until(page, lambda: p.timeline.t >= p.timeline.duration, "the time line's end", 120.0)
        q_end = run.motions[-1].trajectory.waypoints[-1]
        _until(page, lambda: np.allclose(st.snapshot().q["puma560"], q_end, atol=1e-12), "the arm at the depart")
        assert "1. PICKUP cylinder_a ▶" in panel.w_list.content  # the task the time line is in
        # the cylinder went with the hand: its mesh 0.1 m (the lift) above where it stood
        meshes = [(it[3], it[4]) for it in app.drawer.items if it[0] == "cylinder_a"]
        assert meshes
        for c0, h in meshes:
            _until(page, lambda: np.allclose(h.position, c0 + [0.0, 0.0, 0.10], atol=1e-6), "the carried cylinder")
    finally:
        page.close()


def _look(cam) -> np.ndarray:
    d = np.asarray(cam.look_at, dtype=float) - np.asarray(cam.position, dtype=float)
    return d / np.linalg.norm(d)


def test_view_buttons_set_the_camera_and_the_training_views_render(app, browser):
    from armguard.console import view_pose

    app.state.stop()  # no program on the time line, the arm at home (the hand looks at the table's corner)
    app.state.set_q(app.state.scene.default_q())
    page = _open(browser, app)
    try:
        page.get_by_role("tab", name="Views").click()
        d = app.drawer
        for label, ahead in (("top", (0, 0, -1)), ("front", (-1, 0, 0)), ("side", (0, 1, 0))):
            _button(page, label).click()
            pos, look = view_pose(label, d.center, d.radius)
            # the client reports its camera back a property at a time: wait for both, position and target
            _until(page, lambda: np.allclose(_client(app).camera.position, pos, atol=1e-4)
                   and np.allclose(_client(app).camera.look_at, look, atol=1e-4), f"the {label} view")
            cam = _client(app).camera
            assert np.allclose(cam.position, pos, atol=1e-4) and np.allclose(cam.look_at, look, atol=1e-4)
            assert np.allclose(_look(cam), ahead, atol=2e-3)

        # the main camera rides on the tool
        page.locator("label").filter(has_text=re.compile("^main view: eye in the hand$")).first.click()
        X = app.state.ee_pose()
        _until(page, lambda: np.allclose(_client(app).camera.position, X[:3, 3], atol=1e-4)
               and np.allclose(_look(_client(app).camera), X[:3, 2], atol=1e-4), "the eye in the hand")
        assert np.allclose(_look(_client(app).camera), X[:3, 2], atol=1e-4)
        page.locator("label").filter(has_text=re.compile("^main view: eye in the hand$")).first.click()
        _until(page, lambda: not app._training.w_eye.value, "the eye in the hand off")

        # top, front, side and the hand at once: four insets, each a picture, all different
        app._training.images = {}
        _button(page, "render the training views").click()
        _until(page, lambda: len(app._training.images) == 4, "the four insets", 180.0)
        imgs = app._training.images
        for label, img in imgs.items():
            assert img.shape[:2] == (180, 240) and float(img.astype(float).std()) > 8.0, label
        names = list(imgs)
        for i in range(len(names)):
            for j in range(i + 1, len(names)):
                diff = np.abs(imgs[names[i]].astype(float) - imgs[names[j]].astype(float)).mean()
                assert diff > 8.0, (names[i], names[j], diff)
    finally:
        page.close()


def test_jog_plus_x_in_tool_coordinates_moves_along_the_tool_x(app, browser):
    st = app.state
    home = st.snapshot().q["puma560"].copy()
    st.set_joints("puma560", home + np.array([0.3, 0.2, -0.2, 0.4, 0.5, 0.6]))
    X0 = st.ee_pose()
    assert np.max(np.abs(X0[:3, 0])) < 0.95  # the tool's x is no axis of W: a world jog would differ
    page = _open(browser, app)
    try:
        page.get_by_role("tab", name="Control").click()
        _choose(page, "mode", "cartesian")
        _until(page, lambda: st.snapshot().mode == "cartesian", "cartesian mode")
        _choose(page, "jog in", "tool")
        _until(page, lambda: app._jog.w_frame.value == "tool", "the tool frame")
        _type(_input_for(page, "jog step (mm)"), "20")
        _until(page, lambda: app._jog.step == pytest.approx(0.02), "the 20 mm step")
        box = _input_for(page, "jog step (mm)")
        _until(page, lambda: box.input_value() == "20", "the box showing the step in force")
        _type(box, "0")  # refused: the step and the box stay
        page.wait_for_selector("#armguard-message[data-error='true']", timeout=UI_TIMEOUT_MS)
        assert app._jog.step == pytest.approx(0.02) and np.array_equal(st.ee_pose(), X0)
        _until(page, lambda: box.input_value() == "20", "the box back at the step in force")
        page.locator("xpath=//label[normalize-space()='move along']/ancestor::div[.//button][1]//button",
                     has_text="+x").first.click()
        _until(page, lambda: not np.array_equal(st.ee_pose(), X0), "the jog")
        X1 = st.ee_pose()
        assert np.allclose(X1[:3, 3] - X0[:3, 3], 0.02 * X0[:3, 0], atol=1e-6)
        assert np.allclose(X1[:3, :3], X0[:3, :3], atol=1e-6)
        assert "jog: tool +20 mm along tool x" in st.snapshot().message
    finally:
        page.close()
        st.set_joints("puma560", home)


def test_a_value_typed_at_once_after_a_dropdown_choice_lands(app, browser):
    page = _open(browser, app)
    try:
        page.get_by_role("tab", name="Control").click()
        _choose(page, "mode", "cartesian")
        _until(page, lambda: app.state.snapshot().mode == "cartesian", "cartesian mode")
        for k in range(8):
            frame, mm = ("tool", "world")[k % 2], 11 + k
            _choose(page, "jog in", frame)  # no wait for the server: the value follows at machine speed
            _type(_input_for(page, "jog step (mm)"), str(mm))
            _until(page, lambda: app._jog.w_frame.value == frame and app._jog.step == pytest.approx(mm * 1e-3),
                   f"the frame {frame} and the {mm} mm step")
    finally:
        page.close()
