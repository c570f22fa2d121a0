"""The control panel's layout in a real browser (Playwright + Debian's chromium): where layout is the point.

Kinova's long link names (``kinova/j2s6s200_link_finger_tip_2``) made the panel wider than
its frame: it scrolled sideways, cutting text fields and slider ends on the right and, scrolled,
the status text on the left.  Here the panel never scrolls sideways and every line of the status
block is inside it.  On Ranger, the Tests tab's Stop is in view without scrolling (it sat below
ten tests, 800 px down) and red.  Saves ``out/console-kinova-panel.png`` and
``out/console-ranger-tests.png``.
"""

from __future__ import annotations

import warnings

import pytest
from test_console_browser import CHROMIUM, CHROMIUM_ARGS, OUT, UI_TIMEOUT_MS, _need_chromium, screenshot

pytestmark = pytest.mark.browser

VIEWPORT = {"width": 1600, "height": 1000}
"""The review's window."""

OVERFLOW_JS = """() => {
  const status = document.querySelector('#armguard-status');
  const view = status.closest('.mantine-ScrollArea-viewport');
  const box = view.getBoundingClientRect();
  const lines = Array.from(status.querySelectorAll('div')).concat(
      Array.from(document.querySelectorAll('#armguard-categories td, #armguard-categories th')));
  const outside = lines.filter(el => { const r = el.getBoundingClientRect();
      return r.width > 0 && (r.left < box.left - 0.5 || r.right > box.right + 0.5); })
    .map(el => el.innerText);
  return {scrollWidth: view.scrollWidth, clientWidth: view.clientWidth, scrollLeft: view.scrollLeft,
          statusScroll: status.scrollWidth, statusClient: status.clientWidth, outside: outside};
}"""


def _serve(name: str):
    from armguard.console._serve import serve

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return serve(name, port=0, block=False)


def _open(browser, app):
    page = browser.new_page(viewport=VIEWPORT)
    page.goto(app.url)
    page.wait_for_selector("#armguard-status", timeout=UI_TIMEOUT_MS)
    page.wait_for_timeout(1500)
    return page


def _fits(page) -> dict:
    m = page.evaluate(OVERFLOW_JS)
    assert m["scrollWidth"] <= m["clientWidth"], m  # nothing to scroll sideways
    assert m["scrollLeft"] == 0, m
    assert m["statusScroll"] <= m["statusClient"] and not m["outside"], m  # every status line inside the panel
    return m


def test_long_link_names_never_make_the_panel_scroll_sideways():
    from armguard.model import known_models

    if "kinova" not in {m.name for m in known_models() if m.available}:
        pytest.skip("kinova's package (example-robot-data) is not installed")
    _need_chromium()
    from playwright.sync_api import sync_playwright

    app = _serve("kinova")
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            try:
                page = _open(browser, app)
                status = page.inner_text("#armguard-status")
                assert "kinova/j2s6s200_link_6" in status and "j2s6s200_link_finger_tip_2" in status
                assert "obstacle" in page.inner_text("#armguard-categories")  # the header whole, not "obs"
                _fits(page)
                page.get_by_text("sliders kinova").click()  # the sliders too stay within the panel
                page.wait_for_timeout(800)
                m = _fits(page)
                ends = page.evaluate("""() => Array.from(document.querySelectorAll('.mantine-Slider-root, form input'))
                    .filter(e => e.getBoundingClientRect().width > 0)
                    .map(e => e.getBoundingClientRect().right)""")
                right = page.evaluate("""() => document.querySelector('#armguard-status')
                    .closest('.mantine-ScrollArea-viewport').getBoundingClientRect().right""")
                assert ends and max(ends) <= right + 0.5, (max(ends), right, m)  # no box or slider end clipped
                OUT.mkdir(exist_ok=True)
                screenshot(page, path=str(OUT / "console-kinova-panel.png"))
            finally:
                browser.close()
    finally:
        app.stop()


def test_stop_is_in_view_at_the_top_of_the_tests_tab_and_red():
    _need_chromium()
    from playwright.sync_api import sync_playwright

    app = _serve("ranger")
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            try:
                page = _open(browser, app)
                page.get_by_role("tab", name="Tests").click()
                stop = page.get_by_role("button", name="Stop")
                stop.wait_for(timeout=UI_TIMEOUT_MS)
                box = stop.bounding_box()
                first = page.get_by_role("button", name="Setup").first.bounding_box()
                assert box["y"] + box["height"] <= VIEWPORT["height"] and box["y"] < first["y"], (box, first)
                bg = stop.evaluate("b => getComputedStyle(b).backgroundColor")
                r, g, b = (int(x) for x in bg[bg.index("(") + 1:bg.index(")")].split(",")[:3])
                assert r > 150 and g < 100 and b < 100, bg  # red, not the other buttons' blue
                page.get_by_role("button", name="Run").first.click()
                page.wait_for_function("() => document.body.innerText.includes('test: running')",
                                       timeout=UI_TIMEOUT_MS)
                stop.click()  # no scrolling needed
                page.wait_for_function("() => /test: (stopped|done)/.test(document.body.innerText)",
                                       timeout=UI_TIMEOUT_MS)
                assert app.state.snapshot().run_state in ("stopped", "done")
                _fits(page)
                OUT.mkdir(exist_ok=True)
                screenshot(page, path=str(OUT / "console-ranger-tests.png"))
            finally:
                browser.close()
    finally:
        app.stop()


def test_the_status_panel_says_no_connection_when_the_server_is_gone():
    """The page kept the last CLEAR on screen, dimmed, after the server stopped: it is now covered by a red notice
    that there is no verdict."""
    _need_chromium()
    from playwright.sync_api import sync_playwright

    app = _serve("ranger")
    stopped = False
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            try:
                page = _open(browser, app)
                assert "CLEAR" in page.inner_text("#armguard-status")
                assert page.query_selector("#armguard-stale") is None
                app.stop()
                stopped = True
                notice = page.wait_for_selector("#armguard-stale", state="visible", timeout=UI_TIMEOUT_MS)
                assert notice.inner_text().startswith("NO CONNECTION: no verdict")
                box, panel = notice.bounding_box(), page.query_selector("#armguard-status").bounding_box()
                assert box["width"] >= panel["width"] - 1 and box["height"] >= panel["height"] - 1  # all of it covered
            finally:
                browser.close()
    finally:
        if not stopped:
            app.stop()
