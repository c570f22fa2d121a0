"""The console's 3-D view in a real browser (Playwright + Debian's chromium, software WebGL).

Runs :class:`armguard.console.ConsoleApp` in-process on a free loopback port so the test can
read the state and each tab's camera: a typed joint value changes the pixels inside the active
arm's projected box; the nearest-obstacle line's pixels are there, yellow, and turn red when the
threshold is raised past the distance; a refused value leaves the state and the box as they were;
a backend switch changes the panel's backend and keeps the configuration; compare mode draws a
second (cyan) line and shows Δd; at Ranger's and Hermes's home the line, inside a link of
neither side of its pair, shows through that (translucent) link; "frame the active arm" in a
collision shows the red link.  Saves ``docs/img/console-ranger.png`` and
``docs/img/console-hermes.png`` (each at a pose where the line is in view).
"""

from __future__ import annotations

import io
import math
from pathlib import Path

import numpy as np
import pytest

from test_console_browser import CHROMIUM, CHROMIUM_ARGS, UI_TIMEOUT_MS, POLL_MS, _input_for, _need_chromium, screenshot

KEY_DELAY_MS = 0
"""Between keystrokes: none (typed text stays in the box until Enter or blur)."""


def _type(box, text: str) -> None:
    box.click()
    box.press("Control+a")
    box.type(text, delay=KEY_DELAY_MS)
    box.press("Enter")

pytestmark = pytest.mark.browser

SCENE = Path(__file__).parent / "data" / "console_scene.yaml"
IMG = Path(__file__).resolve().parent.parent / "docs" / "img"
VIEWPORT = {"width": 1100, "height": 700}
PANEL_X = 690
"""Pixels right of this are under the control panel."""
YELLOW, RED, CYAN = "yellow", "red", "cyan"
HIDE_NOTICES = ".mantine-Notification-root, .mantine-Notifications-root {display: none !important}"


def _app(name_or_path):
    from armguard.console._serve import serve

    return serve(str(name_or_path), port=0, block=False)


def _shot(page) -> np.ndarray:
    from PIL import Image

    page.wait_for_timeout(1500)  # let software WebGL draw the latest frame
    return np.asarray(Image.open(io.BytesIO(screenshot(page))).convert("RGB")).astype(np.int32)


def _count(img: np.ndarray, colour: str, x_max: int = PANEL_X) -> int:
    """Pixels of ``colour`` ("yellow", "red", "cyan") left of the panel (shaded colours included)."""
    r, g, b = (img[:, :x_max, k] for k in range(3))
    mask = {"yellow": (r > 190) & (g > 0.85 * r) & (b < 0.55 * g),
            "red": (r > 150) & (g < 90) & (b < 90),
            "cyan": (r < 100) & (g > 140) & (b > 140)}[colour]
    return int(np.count_nonzero(mask))


def _open(browser, url):
    page = browser.new_page(viewport=VIEWPORT)
    page.goto(url)
    page.wait_for_selector("#armguard-status", timeout=UI_TIMEOUT_MS)
    page.add_style_tag(content=HIDE_NOTICES)
    page.wait_for_timeout(2500)  # the tab reports the camera the console placed
    return page


def _client(app):
    clients = list(app.server.get_clients().values())
    assert clients, "no browser tab connected"
    return clients[-1]


def _project(app, points: np.ndarray, size=(VIEWPORT["width"], VIEWPORT["height"])) -> np.ndarray:
    """Pixel coordinates (n, 2) of W points seen by the tab's camera (pinhole, vertical fov)."""
    cam = _client(app).camera
    eye, look = np.asarray(cam.position, dtype=float), np.asarray(cam.look_at, dtype=float)
    f = look - eye
    f /= np.linalg.norm(f)
    r = np.cross(f, [0.0, 0.0, 1.0])
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    rel = np.asarray(points, dtype=float) - eye
    z = rel @ f
    t = math.tan(0.5 * float(cam.fov))
    w, h = size
    x = (rel @ r) / (z * t) * (h / 2.0) + w / 2.0
    y = h / 2.0 - (rel @ u) / (z * t) * (h / 2.0)
    return np.stack([x, y], axis=1)


def _arm_box(app, robot: str, pad: int = 12):
    st = app.state
    snap = st.snapshot()
    pts = np.concatenate([np.asarray(it.shape.core_points) for it in st.scene.shapes_at(snap.q) if it.robot == robot])
    px = _project(app, pts)
    lo, hi = np.floor(px.min(axis=0)) - pad, np.ceil(px.max(axis=0)) + pad
    return int(max(lo[0], 0)), int(max(lo[1], 0)), int(min(hi[0], VIEWPORT["width"])), int(min(hi[1], VIEWPORT["height"]))


def _wait(page, js: str, arg=None) -> None:
    page.wait_for_function(js, arg=arg, timeout=UI_TIMEOUT_MS, polling=POLL_MS)


def test_view_follows_typed_values_line_backends(tmp_path):
    _need_chromium()
    from playwright.sync_api import sync_playwright

    app = _app(SCENE)
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            try:
                page = _open(browser, app.url)
                st = app.state
                assert st.snapshot().active == "left"
                # the default camera frames the active arm: its projected box is in the free canvas
                x0, y0, x1, y1 = _arm_box(app, "left", pad=0)
                assert 0 <= x0 < x1 <= PANEL_X + 60 and 0 <= y0 <= y1 <= VIEWPORT["height"], (x0, y0, x1, y1, _client(app).camera.position)

                # the nearest line is drawn (yellow: beyond the threshold)
                # a pose whose nearest obstacle is the post (at home it is the arm's own link 3,
                # with the line inside the arm), framed by the follow camera
                st.set_joints("left", [60, 0, 0], scale=math.pi / 180.0)
                assert st.snapshot().readout.obstacle == "post"
                app._frame(_client(app))
                page.wait_for_timeout(1500)
                before = _shot(page)
                assert st.snapshot().readout.distance > st.snapshot().threshold
                n_yellow = _count(before, YELLOW)
                assert n_yellow > 40, n_yellow

                # type a joint value: the pixels inside the arm's projected box change
                box = _arm_box(app, "left")
                j1 = _input_for(page, "joint1 (deg)")
                _type(j1, "70")
                _wait(page, "() => document.querySelector('#armguard-categories') !== null")
                deadline_q = math.radians(70.0)
                for _ in range(100):
                    if abs(st.snapshot().q["left"][0] - deadline_q) < 1e-9:
                        break
                    page.wait_for_timeout(100)
                assert abs(st.snapshot().q["left"][0] - deadline_q) < 1e-9
                after = _shot(page)
                bx0, by0, bx1, by1 = box
                changed = np.abs(after[by0:by1, bx0:bx1] - before[by0:by1, bx0:bx1]).max(axis=2) > 30
                assert changed.sum() > 200, changed.sum()

                # a refused value: state and box unchanged, the reason in the field's units
                q_before = st.snapshot().q["left"].copy()
                v_before = st.snapshot().version
                _type(j1, "-300")
                page.wait_for_selector("#armguard-message[data-error='true']", timeout=UI_TIMEOUT_MS)
                msg = page.inner_text("#armguard-message")
                assert "-300 deg" in msg and "[-170, 170] deg" in msg, msg
                for _ in range(50):
                    if j1.input_value() == "70":
                        break
                    page.wait_for_timeout(100)
                assert j1.input_value() == "70"
                assert np.array_equal(st.snapshot().q["left"], q_before)
                thr = _input_for(page, "threshold (m)")
                _type(thr, "1e309")
                _wait(page, "() => document.querySelector('#armguard-message').innerText.includes('finite')")
                assert st.snapshot().threshold == 0.05 and thr.input_value() == "0.05"
                _type(thr, "abc")
                _wait(page, "() => document.querySelector('#armguard-message').innerText.includes('abc')")
                assert st.snapshot().threshold == 0.05 and thr.input_value() == "0.05"
                assert st.snapshot().version > v_before

                # the line changes colour at the threshold: raise it past the distance
                d = st.snapshot().readout.distance
                yellow_now = _count(_shot(page), YELLOW)
                assert yellow_now > 40
                _type(thr, f"{d + 0.01:.4f}")
                _wait(page, "() => document.querySelector('#armguard-status').dataset.status == 'warning'")
                img = _shot(page)
                assert _count(img, YELLOW) < 0.2 * yellow_now
                assert _count(img, RED) > 40

                # backend switch: the panel's backend changes, the configuration stays
                q_all = {k: v.copy() for k, v in st.snapshot().q.items()}
                if "coal" in st.backends:
                    page.locator("label", has_text="backend").first.click()
                    st_before = page.get_attribute("#armguard-status", "data-distance")
                    page.get_by_role("option", name="coal").click()  # the dropdown's option list
                    _wait(page, "() => document.querySelector('#armguard-status').dataset.backend == 'coal'")
                    assert all(np.array_equal(q_all[k], v) for k, v in st.snapshot().q.items())
                    d_coal = float(page.get_attribute("#armguard-status", "data-distance"))
                    assert abs(d_coal - float(st_before)) < 1e-6
                # compare mode: a second (cyan) line and Δd in the panel
                other = "analytic" if st.snapshot().backend != "analytic" else next(b for b in st.backends if b != "analytic")
                st.set_compare(other)
                _wait(page, "() => document.querySelector('#armguard-compare') !== null")
                delta = float(page.get_attribute("#armguard-compare", "data-delta"))
                assert abs(delta) < 1e-6
                assert "Δd" in page.inner_text("#armguard-compare")
                assert _count(_shot(page), CYAN) > 30
            finally:
                browser.close()
    finally:
        app.stop()



def test_typed_values_in_quick_succession_all_land():
    """A joint typed, then within 0-300 ms a refused threshold: every joint value is applied and
    every refusal shown.  The page's 50 ms message throttle once dropped one value in four of these
    (a value update replaced by the form's dirty notice), and the server applied commits in the
    order their threads ran rather than the order they were typed."""
    _need_chromium()
    from playwright.sync_api import sync_playwright

    app = _app(SCENE)
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            try:
                page = _open(browser, app.url)
                st = app.state
                j1 = _input_for(page, "joint1 (deg)")
                thr = _input_for(page, "threshold (m)")
                for k, gap_ms in enumerate((0, 40, 60, 80, 120, 160, 200, 300)):
                    deg = 10 + k
                    _type(j1, str(deg))
                    page.wait_for_timeout(gap_ms)
                    _type(thr, "-5")
                    page.wait_for_selector("#armguard-message[data-error='true']", timeout=UI_TIMEOUT_MS)
                    assert "-5" in page.inner_text("#armguard-message")
                    # the value lands (the server applies it on its own thread: on a loaded machine after the refusal shows)
                    _until(page, lambda: abs(st.snapshot().q["left"][0] - math.radians(deg)) < 1e-9,
                           f"joint1 = {deg} deg typed {gap_ms} ms before a refused threshold")
                    threshold = round(0.1 + 0.01 * k, 2)
                    _type(thr, str(threshold))  # a valid value clears the message
                    _wait(page, "() => document.querySelector('#armguard-message') === null "
                                "|| document.querySelector('#armguard-message').dataset.error !== 'true'")
                    _until(page, lambda: st.snapshot().threshold == threshold, f"threshold {threshold}")
            finally:
                browser.close()
    finally:
        app.stop()


def _pose_ranger(st) -> None:
    """Ranger's canned test 1 at its end: the left forearm 0.08 m from the manipulator module."""
    name = "test1_left_inward"
    test = st.scene.canned_tests[name]
    traj = test.trajectory(st.scene)
    st.setup(name)
    q = st.snapshot().q
    q[test.robot] = np.asarray(traj.at(traj.duration))
    st.set_q(q)
    assert st.snapshot().readout.obstacle == "manipulator_module"


def _pose_hermes(st) -> None:
    """HERA along stow_misaligned 0.7 s before it strikes the tail: link 4 about 0.22 m from it."""
    traj = st.scene.trajectories["stow_misaligned"]
    q = st.snapshot().q
    q["hera"] = np.asarray(traj.at(50.8))
    st.set_q(q)
    st.set_threshold(0.3)
    assert st.snapshot().readout.obstacle == "tail"


def _segment_mask(shape, a, b, *, width: float, lo: float = 0.0, hi: float = 1.0) -> np.ndarray:
    """Pixels within ``width`` px of the part ``[lo, hi]`` of the segment ``a``-``b`` (pixel coordinates)."""
    h, w = shape[:2]
    yy, xx = np.mgrid[0:h, 0:w]
    P = np.stack([xx, yy], -1).astype(float)
    a, b = np.asarray(a, float), np.asarray(b, float)
    d = b - a
    t = np.clip(((P - a) @ d) / max(float(d @ d), 1e-9), lo, hi)
    return np.linalg.norm(P - (a + t[..., None] * d), axis=-1) <= width


def _colour_mask(img: np.ndarray, rgb, tol: int = 40) -> np.ndarray:
    return np.all(np.abs(img - np.asarray(rgb)[None, None, :]) <= tol, axis=-1)


@pytest.mark.parametrize("name, pose", [("ranger", _pose_ranger), ("hermes", _pose_hermes)])
def test_screenshots_show_the_line(name, pose):
    """The nearest line in the open, framed: its own pixels (the line's colour near the projected
    segment's middle, gone when the line is hidden), the obstacle end's marker and the distance label."""
    _need_chromium()
    from playwright.sync_api import sync_playwright

    from armguard.console._readout import LINE_COLORS

    app = _app(name)
    try:
        st = app.state
        pose(st)
        r = st.snapshot().readout
        assert r.within_threshold and r.distance > 0.05  # red, and long enough to see
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            try:
                page = _open(browser, app.url)
                app._frame(_client(app), focus="pair")
                img = _shot(page)
                a, b = _project(app, np.array([r.p_WA, r.p_WB]))
                assert np.all((a >= 0) & (a < [PANEL_X, VIEWPORT["height"]])), a
                assert np.all((b >= 0) & (b < [PANEL_X, VIEWPORT["height"]])), b
                length = float(np.linalg.norm(b - a))
                assert length > 90, f"{name}: the line is only {length:.0f} px long"
                red = _colour_mask(img, LINE_COLORS["within"])
                middle = _segment_mask(img.shape, a, b, width=6, lo=0.3, hi=0.7)
                on_line = int(np.count_nonzero(red & middle))
                assert on_line > 0.4 * 0.4 * length * 3, (name, on_line, length)
                # the obstacle end's marker, in the line's colour (the arm end's lies on the red link)
                near_b = _segment_mask(img.shape, b, b, width=12)
                assert np.count_nonzero(red & near_b) > 60, (name, b)
                label = f"{r.distance * 1000.0:.1f} mm"
                assert page.get_by_text(label, exact=True).count() >= 1, label  # the label at the line
                IMG.mkdir(parents=True, exist_ok=True)
                screenshot(page, path=str(IMG / f"console-{name}.png"))
                # the same pixels without the line: they were the line's own
                app.drawer.lines["primary"][0].visible = False
                hidden = _shot(page)
                assert np.count_nonzero(_colour_mask(hidden, LINE_COLORS["within"]) & middle) < 0.25 * on_line
            finally:
                browser.close()
    finally:
        app.stop()


def _line_own_pixels(app, page, readout) -> tuple[int, float]:
    """``(pixels, length)``: pixels near the middle of the projected nearest line (30 % to 70 %)
    that are the line's own -- they change towards the line's colour when it is drawn, against
    the same view with the line hidden -- and the projected line's length (px)."""
    a, b = _project(app, np.array([readout.p_WA, readout.p_WB]))
    for p in (a, b):
        assert 0 <= p[0] < PANEL_X and 0 <= p[1] < VIEWPORT["height"], (a, b)
    shown = _shot(page)
    line = app.drawer.lines["primary"][0]
    line.visible = False
    try:
        hidden = _shot(page)
    finally:
        line.visible = True
    col = np.asarray(readout.line_color)[None, None, :]
    middle = _segment_mask(shown.shape, a, b, width=4, lo=0.3, hi=0.7)
    changed = np.abs(shown - hidden).max(axis=-1) > 25
    towards = np.abs(shown - col).sum(axis=-1) + 30 < np.abs(hidden - col).sum(axis=-1)
    return int(np.count_nonzero(middle & changed & towards)), float(np.linalg.norm(b - a))


@pytest.mark.parametrize("name", ["ranger", "hermes"])
def test_line_at_home_is_seen_through_the_link_around_it(name):
    """At home the nearest line runs inside a link that is not part of its pair (Ranger: left_arm/link1
    around link3 -> the manipulator module; Hermes: hera/link4 around link3 -> link6): that link is drawn
    translucent, and the line's own pixels show at the default camera and after "frame the nearest pair"."""
    _need_chromium()
    from playwright.sync_api import sync_playwright

    from armguard.console._draw import SEE_THROUGH_OPACITY

    app = _app(name)
    try:
        st = app.state
        snap = st.snapshot()
        r = snap.readout
        wrapped = [st.scene.shapes_at(snap.q)[k].owner for k in app.drawer.see_through(snap)]
        assert wrapped == {"ranger": ["left_arm/link1"], "hermes": ["hera/link4"]}[name], wrapped
        k = next(i for i, node in enumerate(app.drawer.items) if node.owner == wrapped[0])
        assert app.drawer.items[k].handle.opacity == SEE_THROUGH_OPACITY
        # no tab yet, so no camera for anything else to hide the line from
        assert all(node.handle.opacity is None for node in app.drawer.items if node.owner not in wrapped)
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            try:
                page = _open(browser, app.url)  # the console framed the active arm on connect
                own, length = _line_own_pixels(app, page, r)
                # (Hermes frames the whole 15 m arm: its 0.33 m line is short at that camera)
                assert own >= max(5.0, 0.2 * length), (name, "default camera", own, length)
                app._frame(_client(app), focus="pair")
                own, length = _line_own_pixels(app, page, r)
                assert length > 90 and own > 0.2 * length, (name, "pair framing", own, length)
            finally:
                browser.close()
    finally:
        app.stop()


def test_frame_the_active_arm_in_a_collision_shows_the_red_link():
    """Ranger's left arm 20 mm into the electronics module (j2 = -90 deg, j4 = -10 deg): "frame the
    active arm" looks from a side where the module does not hide the red link."""
    _need_chromium()
    from playwright.sync_api import sync_playwright

    app = _app("ranger")
    try:
        st = app.state
        q = st.snapshot().q["left_arm"].copy()
        q[1], q[3] = math.radians(-90.0), math.radians(-10.0)
        st.set_joints("left_arm", q)
        r = st.snapshot().readout
        assert r.status.value == "collision" and r.obstacle == "electronics_module" and r.distance < -0.015
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            try:
                page = _open(browser, app.url)
                app._frame(_client(app), focus="arm")
                img = _shot(page)
                # the red link's projected area (its axis's length x its diameter, plus the caps)
                link = next(it.shape for it in st.scene.shapes_at(st.snapshot().q) if it.owner == r.owner_a)
                ends = np.asarray(link.core_points)
                a, b = _project(app, ends)
                cam = _client(app).camera
                depth = float(np.linalg.norm(ends.mean(axis=0) - np.asarray(cam.position)))
                diameter = 2.0 * link.radius * (VIEWPORT["height"] / 2.0) / (depth * math.tan(0.5 * float(cam.fov)))
                area = float(np.linalg.norm(b - a)) * diameter + math.pi * diameter ** 2 / 4.0
                assert np.linalg.norm(b - a) > 1.2 * diameter, "the red link (0.2 m long, 0.1 m thick) is seen end-on"
                red = (img[..., 0] > 150) & (img[..., 1] < 90) & (img[..., 2] < 90)  # shaded red too
                box = _segment_mask(img.shape, a, b, width=diameter)
                seen = int(np.count_nonzero(red & box))
                assert seen > 0.4 * area, (seen, area, cam.position)  # (hidden behind the module: < 100)
            finally:
                browser.close()
    finally:
        app.stop()


def _until(page, fn, what: str) -> None:
    for _ in range(UI_TIMEOUT_MS // POLL_MS):
        if fn():
            return
        page.wait_for_timeout(POLL_MS)
    raise AssertionError(f"timed out waiting for {what}")


def test_typed_target_and_workspace_corners_keep_sign_and_refuse_garbage():
    """Negative numbers, exponents and garbage typed over the selected Cartesian target and
    workspace corner: kept exactly or refused with the field's message, the box back to the state
    (viser's vector boxes dropped the minus and mangled exponents: "-0.342" became 0.342).  And
    the status panel stays in sight with the controls scrolled to their end."""
    _need_chromium()
    from playwright.sync_api import sync_playwright

    app = _app(SCENE)
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            try:
                st = app.state
                st.set_mode("cartesian")
                page = _open(browser, app.url)
                # the whole control panel is built (slow on a loaded machine: software WebGL)
                page.wait_for_selector("label:has-text('upper corner (m)')", state="attached", timeout=4 * UI_TIMEOUT_MS)
                pos = _input_for(page, "target position (m)")
                pos.wait_for(state="visible", timeout=UI_TIMEOUT_MS)
                for text, want in (("0.3, -0.25, -0.342", (0.3, -0.25, -0.342)), ("1e-3, -0.05, 0", (1e-3, -0.05, 0.0))):
                    _type(pos, text)
                    _until(page, lambda: st.target()[2] and st.target()[0].tolist() == list(want), f"target {want}")
                for text, words in (("-0.5.2, 0, 0", "x: expected a number (m), got '-0.5.2'"),
                                    ("", "got an empty entry"), ("-1e309, 0, 0", "x: expected a finite number")):
                    if text:
                        _type(pos, text)
                    else:  # the selected text deleted, then Enter
                        pos.click()
                        pos.press("Control+a")
                        pos.press("Backspace")
                        pos.press("Enter")
                    _wait(page, "w => { const m = document.querySelector('#armguard-message');"
                                " return m && m.dataset.error === 'true' && m.textContent.includes(w); }", words)
                    assert st.target()[0].tolist() == [1e-3, -0.05, 0.0]
                    _until(page, lambda: pos.input_value() == "0.001, -0.05, 0", "the box back to the target")
                page.get_by_text("workspace box").first.click()
                lo = _input_for(page, "lower corner (m)")
                lo.wait_for(state="visible", timeout=UI_TIMEOUT_MS)
                assert lo.input_value() == "-2.5, -2, -1"  # the scene's box
                _type(lo, "-1e309,0,0")
                _wait(page, "() => { const m = document.querySelector('#armguard-message');"
                            " return m && m.textContent.includes('workspace lower corner x: expected a finite'); }")
                _until(page, lambda: lo.input_value() == "-2.5, -2, -1", "the corner back to the box")
                _type(lo, "-3, -2, -1e-1")
                _until(page, lambda: st.snapshot().workspace_corners[0].tolist() == [-3.0, -2.0, -0.1], "the corner")
                page.get_by_role("button", name="apply limits").click()
                _until(page, lambda: st.snapshot().workspace[0].tolist() == [-3.0, -2.0, -0.1], "the box applied")
                # the status stays in sight with the controls scrolled to their end
                page.evaluate("() => document.querySelectorAll('.mantine-ScrollArea-viewport')"
                              ".forEach(v => { v.scrollTop = v.scrollHeight; })")
                page.wait_for_timeout(300)
                top, scrolled = page.evaluate(
                    "() => { const s = document.querySelector('#armguard-status').getBoundingClientRect();"
                    " const v = document.querySelector('#armguard-status').closest('.mantine-ScrollArea-viewport');"
                    " return [s.top - v.getBoundingClientRect().top, v.scrollTop]; }")
                assert scrolled > 0 and 0 <= top < 20, (top, scrolled)
            finally:
                browser.close()
    finally:
        app.stop()
