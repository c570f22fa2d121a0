"""The console in headless chromium: what an operator waits for, on each built-in scene.

The console is served in-process (:func:`armguard.console._serve.serve`, port 0) and opened in
Debian's chromium, headless, without a GPU (software WebGL), at 1600×1000 -- the machine class
and window of issue 25.  A script added to the page before it loads records, on the page's own
clock (``performance.now()``):

* each Enter key press;
* each change of the status panel (a MutationObserver: the panel's HTML differs from the last);
* each WebGL frame: a ``requestAnimationFrame`` callback that issued draw calls, and when the
  next animation frame came after it (the frame handed on and the page ready for the next one --
  software WebGL rasterises in another process, so the JavaScript time alone is not the frame).

Per scene:

* **Enter → panel**: a value typed into the active arm's first joint field (its home value
  ±10 deg in turn, within the limits; on the rover its elevation, 30 deg -- into the ground with
  the terrain -- and 0 deg in turn: :data:`TYPED`), from the Enter key to the status panel
  showing the new check;
* **joint change drawn**: from the same Enter until the frame that drew the viewer's last render
  request for it (none for :data:`IDLE_MS` after it) was handed on: the frame during which the
  request was made (the viewer applies the server's scene messages at the start of a frame and
  asks for frames from there), else the next one; the viewer's 1 s heartbeat frames and its
  250 ms "settle" frames after a change redraw the same scene and do not count;
* **canned run**: a canned test's Setup, then Run: status-panel updates per second and WebGL
  frames per second while it runs (scenes with canned tests only).

Medians over the repetitions; the machine's load (``os.getloadavg``) beside each row.  These are
figures of this machine class, not limits checked by a test.
"""

from __future__ import annotations

import math
import os
import statistics
import time
from pathlib import Path

TITLE = "Console responsiveness in headless chromium (software WebGL, 1600×1000)"

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync"]
VIEWPORT = {"width": 1600, "height": 1000}
ROOT = Path(__file__).resolve().parent.parent
SCENES = (("ranger", None), ("hermes", None), ("puma560", None), ("rover", None),
          ("rover", "reference/terrain/rocky.npz"))
"""Built-in scenes (name, terrain file or None)."""
IDLE_MS = 1500
"""A change is drawn once the viewer has asked for no frame for this long after its last request."""
STEP_DEG = 10.0
"""The typed joint values: the first joint's home value ± this ..."""
TYPED = {"rover": (1, (30.0, 0.0))}
"""... except on the rover: its elevation (joint 1) at 30 deg (the arm in the ground: 213 pyramid
boxes tested, a collision) and back at 0 deg, in turn."""
TIMEOUT_MS = 120000

PROBE_JS = r"""
(() => {
  const ag = window.__ag = {enter: [], panel: [], frames: [], req: [], last: null};
  // the viewer's render requests (scene changes; its 1 s heartbeat frames are not requested)
  setInterval(() => {
    const m = window.__viserMutable;
    if (m && m.requestRender && !m.requestRender.__ag) {
      const f = m.requestRender;
      m.requestRender = function () { ag.req.push(performance.now()); return f.apply(this, arguments); };
      m.requestRender.__ag = true;
    }
  }, 20);
  let drew = false;
  for (const C of [window.WebGLRenderingContext, window.WebGL2RenderingContext]) {
    if (!C) continue;
    for (const m of ['drawElements', 'drawArrays', 'drawElementsInstanced', 'drawArraysInstanced', 'drawRangeElements']) {
      const f = C.prototype[m];
      if (!f) continue;
      C.prototype[m] = function () { drew = true; return f.apply(this, arguments); };
    }
  }
  const raf = window.requestAnimationFrame.bind(window);
  window.requestAnimationFrame = (cb) => raf((t) => {
    const t0 = performance.now();
    drew = false;
    try { cb(t); } finally {
      if (drew) {
        const rec = [t0, performance.now(), null];
        ag.frames.push(rec);
        raf(() => { rec[2] = performance.now(); });
      }
    }
  });
  document.addEventListener('keydown', (e) => { if (e.key === 'Enter') ag.enter.push(performance.now()); }, true);
  const watch = () => {
    const s = document.getElementById('armguard-status');
    if (!s || !s.parentElement) return;
    const h = s.parentElement.innerHTML;
    if (h !== ag.last) { ag.last = h; ag.panel.push(performance.now()); }
  };
  new MutationObserver(watch).observe(document, {subtree: true, childList: true, characterData: true, attributes: true});
})();
"""

DRAWN_JS = """([since, idle]) => {
  // when the last render request since ``since`` was drawn and handed on (null: not yet)
  const ag = window.__ag, now = performance.now();
  const rq = ag.req.filter(t => t >= since);
  if (!ag.panel.some(t => t >= since)) return null;
  const last = rq.length ? rq[rq.length - 1] : since;
  if (now - last < idle) return null;
  // the frame that drained the messages asked for it (the request made inside it), else the next one
  const f = ag.frames.find(f => f[0] <= last && last <= f[1]) || ag.frames.find(f => f[0] >= last);
  return (f && f[2] !== null) ? f[2] : null;
}"""


def _input_for(page, label: str):
    """The visible typed-value box of the widget labelled ``label``."""
    lab = page.locator("label:visible", has_text=label).first
    uuid = lab.get_attribute("for")
    return page.locator(
        f"xpath=//label[@for='{uuid}']/ancestor::div[.//input[not(@type='hidden')]][1]//input[not(@type='hidden')]"
    ).last


def _now(page) -> float:
    return float(page.evaluate("performance.now()"))


def _wait_drawn(page, since: float) -> float:
    """Page time at which the last change requested since ``since`` was drawn (no request for
    :data:`IDLE_MS` after it)."""
    return float(page.wait_for_function(DRAWN_JS, arg=[since, IDLE_MS], timeout=TIMEOUT_MS, polling=200).json_value())


def _joint_changes(page, app, n: int) -> tuple[list[float], list[float]]:
    """``n`` typed joint values: (Enter → panel, Enter → last frame) in ms each."""
    st = app.state
    snap = st.snapshot()
    name = snap.active
    robot = st.scene.robots[name]
    units = st.joint_units(name)
    lo, hi = st.joint_limits(name)
    j, values = TYPED.get(st.scene.name, (0, None))
    k = 180.0 / math.pi if units[j] == "deg" else 1.0
    step = STEP_DEG if units[j] == "deg" else 0.05
    home = float(snap.q[name][j]) * k
    if values is None:
        values = (home + step, home - step)
    box = _input_for(page, f"{robot.joint_names[j]} ({units[j]})")
    panel, drawn = [], []
    for i in range(n):
        v = min(max(values[i % 2], lo[j] * k), hi[j] * k)
        box.click()
        box.press("Control+a")
        box.type(f"{v:.2f}", delay=0)
        t0 = _now(page)
        box.press("Enter")
        done = _wait_drawn(page, t0)
        ag = page.evaluate("window.__ag")
        enter = [t for t in ag["enter"] if t >= t0][0]
        p = [t for t in ag["panel"] if t >= enter]
        panel.append(p[0] - enter)
        drawn.append(max(done, p[0]) - enter)
    return panel, drawn


def _canned_run(page, app) -> tuple[float, float, float] | None:
    """A canned test's Setup then Run: (panel updates/s, frames/s, run seconds); None without tests."""
    st = app.state
    tests = list(st.canned_tests())
    if not tests:
        return None
    name = tests[0]
    page.get_by_role("tab", name="Tests").click()
    t_setup = _now(page)
    page.get_by_role("button", name=f"Setup {name}").click()
    _wait_drawn(page, t_setup)
    t0 = _now(page)
    page.get_by_role("button", name=f"Run {name}").click()
    deadline = time.monotonic() + TIMEOUT_MS / 1000.0
    while st.snapshot().run_state != "running" and time.monotonic() < deadline:
        time.sleep(0.02)
    while st.snapshot().run_state == "running" and time.monotonic() < deadline:
        time.sleep(0.1)
    t1 = _now(page)
    ag = page.evaluate("window.__ag")
    p = [t for t in ag["panel"] if t0 <= t <= t1]
    f = [r for r in ag["frames"] if t0 <= r[0] <= t1]
    if len(p) < 2:
        return 0.0, 0.0, (t1 - t0) / 1000.0
    span = (p[-1] - p[0]) / 1000.0
    return (len(p) - 1) / span, len(f) / span, span


def _scene_row(browser, name: str, terrain, reps: int) -> dict:
    from armguard.console._serve import serve

    app = serve(name, port=0, block=False, terrain=None if terrain is None else str(ROOT / terrain))
    try:
        page = browser.new_page(viewport=VIEWPORT)
        page.add_init_script(PROBE_JS)
        t0 = time.perf_counter()
        page.goto(app.url)
        page.wait_for_selector("#armguard-status", timeout=TIMEOUT_MS)
        _wait_drawn(page, 0.0)
        first = time.perf_counter() - t0
        load = os.getloadavg()[0]
        panel, drawn = _joint_changes(page, app, reps)
        run = _canned_run(page, app)
        load = max(load, os.getloadavg()[0])
        page.close()
    finally:
        app.stop()
    return {"scene": name + ("" if terrain is None else f" --terrain {Path(terrain).name}"), "first_s": first,
            "panel": panel, "drawn": drawn, "run": run, "load": load}


def measure(scenes=SCENES, reps: int = 7) -> list[dict]:
    from playwright.sync_api import sync_playwright

    rows = []
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            for name, terrain in scenes:
                rows.append(_scene_row(browser, name, terrain, reps))
                print(rows[-1], flush=True)
        finally:
            browser.close()
    return rows


def _ms(xs) -> str:
    return f"{statistics.median(xs):.0f} ms (max {max(xs):.0f})"


def table(rows) -> str:
    out = ["| scene | page ready | Enter → panel | joint change drawn | canned run: panel updates/s | frames/s | load |",
           "|---|---|---|---|---|---|---|"]
    for r in rows:
        run = r["run"]
        rate = "—" if run is None else f"{run[0]:.1f}"
        fps = "—" if run is None else f"{run[1]:.1f}"
        out.append(f"| {r['scene']} | {r['first_s']:.1f} s | {_ms(r['panel'])} | {_ms(r['drawn'])} | {rate} | {fps} "
                   f"| {r['load']:.1f} |")
    return "\n".join(out)


def run(quick: bool) -> str:
    if not os.path.exists(CHROMIUM):
        return f"Not measured: {CHROMIUM} not found (`make browser`)."
    rows = measure(reps=3 if quick else 7)
    return (
        "Headless Debian chromium (`--disable-gpu`: software WebGL), 1600×1000, the console served "
        "in-process.  *Enter → panel*: a value typed into the active arm's first joint field (home ±10 deg; "
        "the rover: elevation 30 deg, into the ground with the terrain, and 0 deg in turn), "
        "from the Enter key to the status panel changed; *joint change drawn*: from the same Enter until the WebGL "
        "frame that applied the change's scene messages was handed on (the next animation frame; the "
        "viewer's heartbeat and settle frames, redrawing the same scene, not counted); medians (max) over "
        "the typed values.  *Canned run*: the scene's first canned test, status-panel updates and WebGL frames per "
        "second while it runs.  Targets (issue 25): Enter → panel ≤ 250 ms, ≥ 5 panel updates/s in a "
        "canned run, ≤ 1 s per joint change on the rover with terrain.  *load*: the 1-minute load average "
        "(2 cores shared).\n\n" + table(rows) + "\n"
    )


if __name__ == "__main__":
    import sys

    names = sys.argv[1:]
    sel = [s for s in SCENES if not names or s[0] in names or (s[1] and "terrain" in names)]
    print(table(measure(sel, reps=3)))
