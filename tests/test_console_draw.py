"""The view draws what changed and keeps the nearest line in sight.

Without a browser: the shapes' frames from forward kinematics agree with the scene's own posed
shapes; what hides a line from a camera (:func:`hidden_from`, :func:`sight_buried`) against a
brute-force reference; the floor grid's spacing.

In chromium (software WebGL), the console in-process: a typed joint value moves the existing
meshes (pose messages only, no scene node created or removed); the terrain's pyramid boxes are
hidden until the Views tab's checkbox asks for them; a shape standing between the tab's camera
and the nearest line is drawn translucent while it does, and opaque again when the camera moves.
"""

from __future__ import annotations

import math
import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st_

from test_console_browser import CHROMIUM, CHROMIUM_ARGS, POLL_MS, UI_TIMEOUT_MS, _input_for, _need_chromium

TERRAIN = "reference/terrain/rocky.npz"


# ---------------------------------------------------------------------- no browser
@pytest.mark.parametrize("name", ["ranger", "rover"])
def test_item_frames_move_the_built_shapes_onto_the_posed_ones(name):
    from armguard.console._meshes import item_frames
    from armguard.console._serve import make_state

    st = make_state(name)
    sc = st.scene
    q0 = sc.default_q()
    rng = np.random.default_rng(3)
    q1 = {k: v + rng.normal(0.0, 0.4, len(v)) for k, v in q0.items()}
    a, b = sc.shapes_at(q0), sc.shapes_at(q1)
    F0, F1 = item_frames(sc, q0), item_frames(sc, q1)
    assert len(F0) == len(a) and len(F1) == len(b)
    for x, y, X0, X1 in zip(a, b, F0, F1):
        T = X1 @ np.linalg.inv(X0)
        P, Q = np.asarray(x.shape.core_points), np.asarray(y.shape.core_points)
        np.testing.assert_allclose(P @ T[:3, :3].T + T[:3, 3], Q, atol=1e-12)


class _Posed:
    """PosedItems' interface over plain shapes (no culling: every shape is near)."""

    def __init__(self, shapes):
        self.shapes = list(shapes)

    def near(self, a, b, pad=0.0):
        return list(range(len(self.shapes)))

    def shape(self, k):
        return self.shapes[k]


def _hidden_reference(eye, line, shapes) -> set[int]:
    """Brute force: a shape hides the line when one of the sight lines to SIGHT_FRACTIONS of it has
    a sample (1000 along it, short of the end) strictly inside the shape."""
    from armguard.console._sight import SIGHT_FRACTIONS
    from armguard.geometry import Sphere, distance

    out = set()
    L = np.asarray(line, dtype=float)
    for f in SIGHT_FRACTIONS:
        p = L[0] + f * (L[1] - L[0])
        for t in np.linspace(0.0, 0.99, 1000):
            x = eye + t * (p - eye)
            for k, sh in enumerate(shapes):
                if distance(Sphere(x, 1e-9), sh).distance < -1e-6:
                    out.add(k)
    return out


@settings(max_examples=25, deadline=None)
@given(st_.floats(-0.6, 0.6), st_.floats(-0.6, 0.6), st_.floats(0.05, 0.4))
def test_hidden_from_matches_brute_force(y, z, r):
    from armguard.console._sight import hidden_from
    from armguard.geometry import Box, Sphere

    eye = np.array([-3.0, 0.0, 0.0])
    line = np.array([[2.0, -0.5, 0.0], [2.0, 0.5, 0.0]])
    shapes = [Sphere(np.array([0.0, y, z]), r), Box(np.array([0.0, -y, -z]), np.array([r, r, r]), np.eye(3))]
    got = hidden_from(eye, line, _Posed(shapes))
    ref = _hidden_reference(eye, line, shapes)
    # the brute force only sees what a sample lands in: it may miss a graze, never invent one
    assert ref <= got
    for k in got - ref:  # a graze: the sight line passes within a few mm of the surface
        from armguard.console._sight import _targets
        from armguard.geometry import Capsule, distance

        d = min(distance(Capsule(eye, p, 1e-9), shapes[k]).distance for p in _targets(line))
        assert d > -5e-3, (k, d)


def test_hidden_from_the_pair_and_nothing_between():
    from armguard.console._sight import hidden_from
    from armguard.geometry import Sphere

    eye = np.array([0.0, -3.0, 1.0])
    line = np.array([[0.0, 0.0, 1.0], [0.5, 0.0, 1.0]])
    blocker = Sphere(np.array([0.25, -1.5, 1.0]), 0.2)
    aside = Sphere(np.array([3.0, -1.5, 1.0]), 0.2)
    assert hidden_from(eye, line, _Posed([aside, blocker])) == {1}
    assert hidden_from(eye, line, _Posed([aside, blocker]), skip={1}) == set()
    assert hidden_from(np.array([0.0, 3.0, 1.0]), line, _Posed([aside, blocker])) == set()


def test_sight_buried_in_a_rock_between_camera_and_line():
    from armguard.console._sight import sight_buried
    from armguard.terrain import ElevationMap

    h = np.zeros((20, 20))
    h[10, 5] = 1.0  # one tall column (cell 0.1 m: x 0.5-0.6, y 1.0-1.1)
    m = ElevationMap(heights=h, origin=np.zeros(2), cell=0.1, known=np.ones(h.shape, bool),
                     counts=np.ones(h.shape, np.int64), floor=-0.1)
    line = np.array([[1.5, 1.05, 0.3], [1.6, 1.05, 0.3]])
    assert sight_buried(m, np.array([0.0, 1.05, 0.3]), line)  # straight through the column
    assert not sight_buried(m, np.array([0.0, 1.05, 1.8]), line)  # from above it
    assert not sight_buried(m, np.array([1.55, 0.0, 0.3]), line)  # from the side, past the rock


def test_grid_step_and_segments():
    from armguard.console._draw import grid_segments, grid_step

    for half in (0.37, 1.0, 3.0, 15.0, 120.0):
        s = grid_step(half)
        mant = s / 10.0 ** math.floor(math.log10(s) + 1e-9)
        assert round(mant, 6) in (1.0, 2.0, 5.0) and half / 10.0 <= s < half / 2.0 + 1e-9, (half, s)
    g = grid_segments(np.array([0.3, -0.2, 5.0]), 1.0, -0.5)
    assert g.dtype == np.float32 and g.shape[1:] == (2, 3) and np.all(g[..., 2] == -0.5)
    assert np.all(np.abs(g[..., :2]).max() < 1.6)


# ---------------------------------------------------------------------- in chromium
def _app(name, **kw):
    from armguard.console._serve import serve

    return serve(name, port=0, block=False, **kw)


def _open(browser, app, viewport=None):
    page = browser.new_page(viewport=viewport or {"width": 1000, "height": 700})
    page.goto(app.url)
    page.wait_for_selector("#armguard-status", timeout=UI_TIMEOUT_MS)
    return page


def _until(fn, what: str, timeout: float = UI_TIMEOUT_MS / 1000.0) -> None:
    t = time.monotonic() + timeout
    while time.monotonic() < t:
        if fn():
            return
        time.sleep(0.05)
    raise AssertionError(f"timed out waiting for {what}")


def _client(app):
    clients = list(app.server.get_clients().values())
    assert clients, "no browser tab connected"
    return clients[-1]


@pytest.mark.browser
def test_typed_joint_moves_the_existing_meshes_and_boxes_come_on_request():
    _need_chromium()
    from playwright.sync_api import sync_playwright
    from viser import _messages

    ranger = _app("ranger")
    rover = _app("rover", terrain=TERRAIN)
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            try:
                # -- a typed joint value: pose messages for the existing meshes, nothing created
                page = _open(browser, ranger)
                page.wait_for_timeout(1500)
                sent = []
                ws = ranger.server._websock_server
                orig = ws.queue_message
                ws.queue_message = lambda msg, *a, **k: (sent.append(msg), orig(msg, *a, **k))[1]
                try:
                    st = ranger.state
                    names = {n.handle.name for n in ranger.drawer.items}
                    before = st.snapshot().q["left_arm"].copy()
                    box = _input_for(page, "j1 (deg)")
                    box.click()
                    box.press("Control+a")
                    box.type(f"{math.degrees(before[0]) + 20.0:.2f}", delay=0)
                    box.press("Enter")
                    _until(lambda: abs(st.snapshot().q["left_arm"][0] - before[0] - math.radians(20.0)) < 1e-6,
                           "the typed joint value")
                    _until(lambda: any(isinstance(m, _messages.SetOrientationMessage) and m.name in names
                                       for m in list(sent)), "the link meshes moved")
                    time.sleep(0.5)
                finally:
                    ws.queue_message = orig
                created = [type(m).__name__ for m in sent if isinstance(m, _messages._CreateSceneNodeMessage)]
                removed = [m.name for m in sent if isinstance(m, _messages.RemoveSceneNodeMessage)]
                assert not created and not removed, (created, removed)
                moved = {m.name for m in sent if isinstance(m, (_messages.SetOrientationMessage,
                                                               _messages.SetPositionMessage)) and m.name in names}
                # the left arm's links moved; the vehicle body and the other arms did not
                assert moved and all("left_arm" in n for n in moved), moved
                page.close()

                # -- the rover in the ground: the pyramid boxes only when asked for
                st = rover.state
                q = st.snapshot().q["arm"].copy()
                q[1] = math.radians(30.0)
                st.set_joints("arm", q)
                page = _open(browser, rover)
                levels = rover.drawer.overlays._levels
                _until(lambda: rover.state.snapshot().terrain is not None and rover.drawer.overlays._last_tv is not None,
                       "the terrain check drawn")
                assert len(rover.state.snapshot().terrain.boxes) > 50
                assert not any(h.visible for pair in levels.values() for h in pair)
                page.get_by_role("tab", name="Views").click()
                page.get_by_text("terrain: tested pyramid boxes").click()
                _until(lambda: any(h.visible for pair in rover.drawer.overlays._levels.values() for h in pair),
                       "the boxes shown")
                page.get_by_text("terrain: tested pyramid boxes").click()
                _until(lambda: not any(h.visible for pair in rover.drawer.overlays._levels.values() for h in pair),
                       "the boxes hidden again")
            finally:
                browser.close()
    finally:
        ranger.stop()
        rover.stop()


@pytest.mark.browser
@pytest.mark.parametrize("name", ["ranger", "hermes", "puma560", "rover"])
def test_a_shape_between_the_camera_and_the_line_turns_translucent(name):
    """In every built-in scene: a camera placed beyond a shape, looking at the nearest line through
    it, makes that shape translucent (the line itself drawn); after "frame the nearest pair" the
    translucent shapes are exactly those the line runs through or that still hide it.  On the rover
    with its terrain, a camera under the ground makes the terrain translucent."""
    _need_chromium()
    from playwright.sync_api import sync_playwright

    from armguard.console._draw import SEE_THROUGH_OPACITY
    from armguard.console._draw_overlays import TERRAIN_SEE_THROUGH_OPACITY
    from armguard.console._nodes import PosedItems

    app = _app(name, **({"terrain": TERRAIN} if name == "rover" else {}))
    try:
        st = app.state
        snap = st.snapshot()
        r = snap.readout
        line = np.array([r.p_WA, r.p_WB])
        mid = line.mean(axis=0)
        posed = PosedItems(app.drawer.items, st.scene, snap.q)
        # a shape away from the line (a body if one is), and a camera beyond it looking at the line through it
        far = [i for i, n in enumerate(app.drawer.items) if np.linalg.norm(posed.centers[i] - mid) > posed.bounds[i] + 0.05]
        k = min(far, key=lambda i: (app.drawer.items[i].kind != "body", -posed.bounds[i]))
        c = posed.centers[k]
        eye = c + 2.0 * (c - mid)
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            try:
                _open(browser, app)
                client = _client(app)
                app._place(client, eye, mid)
                _until(lambda: app.drawer.items[k].handle.opacity == SEE_THROUGH_OPACITY,
                       f"{app.drawer.items[k].owner} translucent in front of the line")
                assert app.drawer.lines["primary"][0].visible  # the line itself is drawn
                app._frame(client, focus="pair")
                time.sleep(1.0)
                _until(lambda: {i for i, n in enumerate(app.drawer.items) if n.handle.opacity is not None}
                       == app.drawer.see_through(st.snapshot()) | app.drawer.line_hidden(st.snapshot()),
                       "only the shapes hiding the line translucent")
                if st.terrain is not None:
                    handles = list(app.drawer.overlays.terrain_handles.values())
                    _until(lambda: all(h.opacity is None for h in handles), "the terrain opaque from the pair framing")
                    under = np.array([mid[0] + 0.5, mid[1] + 0.5, st.terrain.floor + 0.01])
                    app._place(client, under, mid)
                    _until(lambda: all(h.opacity == TERRAIN_SEE_THROUGH_OPACITY for h in handles),
                           "the terrain translucent seen from under the ground")
            finally:
                browser.close()
    finally:
        app.stop()
