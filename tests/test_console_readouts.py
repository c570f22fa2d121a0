"""Backend readouts and compare mode, the --watch reload diff, the camera framing, feature outlines."""

from __future__ import annotations

import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from armguard.console import ConsoleInputError, ConsoleState
from armguard.console._backends import compare_readouts
from armguard.console._readout import readout_off
from armguard.console._reload import describe_changes
from armguard.console._serve import ModelWatcher, load_for_console
from armguard.console._view import FOLLOW_ELEVATION_DEG, feature_segments, follow_view, pair_view
from armguard.geometry import Box, ConvexPolyhedron, Feature, FeatureKind, distance
from armguard.scene import load_scene

SCENE = Path(__file__).parent / "data" / "console_scene.yaml"


@pytest.fixture(scope="module")
def ranger():
    return load_for_console("ranger")


def test_backend_readout_and_compare_delta(ranger):
    scene, model = ranger
    st = ConsoleState(scene, model=model)
    assert "coal" in st.backends
    q0 = {k: v.copy() for k, v in st.snapshot().q.items()}
    d_analytic = st.snapshot().readout.distance
    rows_analytic = {r.category: r.distance for r in st.snapshot().readout.rows}
    st.set_backend("coal")
    snap = st.snapshot()
    assert snap.readout.backend == "coal" and snap.backend == "coal"
    rows_coal = {r.category: r.distance for r in snap.readout.rows}  # one vocabulary of categories
    assert set(rows_coal) <= set(rows_analytic) and "arm" in rows_coal
    assert all(abs(rows_coal[c] - rows_analytic[c]) < 1e-6 for c in rows_coal)
    with pytest.raises(ConsoleInputError, match="with itself"):
        st.set_compare("coal")
    assert all(np.array_equal(q0[k], v) for k, v in snap.q.items())
    assert abs(snap.readout.distance - d_analytic) < 1e-6
    assert snap.readout.link.startswith(snap.active)
    st.set_compare("analytic")
    cmp = st.snapshot().compare
    assert (cmp.primary, cmp.other) == ("coal", "analytic")
    assert cmp.delta == cmp.readout.distance - st.snapshot().readout.distance and abs(cmp.delta) < 1e-6
    with pytest.raises(ConsoleInputError, match="not installed"):
        st.set_compare("no-such-backend")
    assert st.snapshot().compare.other == "analytic"  # refused: compare mode unchanged
    st.set_compare(None)
    assert st.snapshot().compare is None


def test_backends_listed_are_those_that_answer_distances(ranger, monkeypatch):
    from armguard.backends import Capability, available, get_backend
    from armguard.console import _sources

    scene, model = ranger
    st = ConsoleState(scene, model=model)
    assert {"clip", "forbidden"} <= set(available())  # installed, but verdicts only
    assert declared_capabilities_of("clip") == frozenset({Capability.VERDICTS})
    assert "clip" not in st.backends and "forbidden" not in st.backends
    assert st.backends[0] == "analytic" and {"coal", "fcl"} <= set(st.backends)
    for name in st.backends[1:]:
        assert Capability.DISTANCES in _sources.declared_capabilities(get_backend(name))
    with pytest.raises(ConsoleInputError, match="does not answer distances"):
        st.set_backend("clip")
    # a backend listed because it declares nothing, whose checker then cannot be built (forbidden
    # needs a map file): refused at once, the panel, backend and message as they were, and no
    # longer offered; the next pick works
    monkeypatch.setattr(_sources, "distance_backends", lambda: ("coal", "forbidden"))
    st = ConsoleState(scene, model=model)
    assert st.backends == ("analytic", "coal", "forbidden")
    st.set_threshold(0.3)
    before = st.snapshot()
    with pytest.raises(ConsoleInputError, match="forbidden.*cannot compute the panel.*map"):
        st.set_backend("forbidden")
    after = st.snapshot()
    assert after.backend == "analytic" and after.readout.backend == "analytic"
    assert after.readout.distance == before.readout.distance and after.message == before.message
    assert st.backends == ("analytic", "coal")
    with pytest.raises(ConsoleInputError, match="cannot compute the panel"):
        st.set_compare("forbidden")
    assert st.snapshot().compare is None
    st.set_backend("coal")
    assert st.snapshot().readout.backend == "coal" and st.snapshot().message == "backend: coal"


def declared_capabilities_of(name):
    from armguard.backends import get_backend
    from armguard.console._sources import declared_capabilities

    return declared_capabilities(get_backend(name))


def test_compare_delta_is_nan_without_a_pair():
    off = readout_off(0.05)
    on = SimpleNamespace(distance=0.2, backend="coal")
    assert math.isnan(compare_readouts(off, on).delta)


def _moved_scene(tmp_path, dx: float):
    text = SCENE.read_text().replace("xyz: [-0.8, 0.8, 0.0]", f"xyz: [{-0.8 + dx}, 0.8, 0.0]")
    p = tmp_path / "scene.yaml"
    p.write_text(text)
    return p


def test_reload_diff_shapes_moved_and_pairs(tmp_path):
    old = load_scene(str(SCENE))
    new = load_scene(str(_moved_scene(tmp_path, 0.1)))
    q = old.default_q()
    assert describe_changes(old, old, q, q) == "no change"
    assert describe_changes(old, new, q, q) == "shapes moved: post"
    pairs = lambda *ab: SimpleNamespace(pairs=SimpleNamespace(owner_a=[a for a, _ in ab], owner_b=[b for _, b in ab]))  # noqa: E731
    m_old = pairs(("left/link1", "post"), ("left/link2", "post"))
    m_new = pairs(("left/link2", "post"), ("left/link3", "post"))
    text = describe_changes(old, old, q, q, m_old, m_new)
    assert "pairs added: 1 (left/link3 / post)" in text and "pairs removed: 1 (left/link1 / post)" in text


def _edited_scene(tmp_path, old: str, new: str, name: str = "edited.yaml"):
    """The test scene with the first ``old`` (the left arm's, where both arms have it) made ``new``."""
    text = SCENE.read_text()
    assert old in text, old
    p = tmp_path / name
    p.write_text(text.replace(old, new, 1))
    return p


def test_reload_diff_resized_is_not_moved(tmp_path):
    old = load_scene(str(SCENE))
    q = old.default_q()
    bigger = load_scene(str(_edited_scene(tmp_path, "size: [0.2, 0.2, 0.6]", "size: [0.24, 0.2, 0.6]")))
    assert describe_changes(old, bigger, q, q) == "shapes resized: post"
    both = load_scene(str(_edited_scene(tmp_path, "size: [0.2, 0.2, 0.6], xyz: [-0.8, 0.8, 0.0]",
                                        "size: [0.2, 0.2, 0.6], xyz: [-0.7, 0.8, 0.1]", "b.yaml")))
    assert describe_changes(old, both, q, q) == "shapes moved: post"
    fat = load_scene(str(_edited_scene(tmp_path, "link2: [{type: link_capsule, radius: 0.05}]",
                                       "link2: [{type: link_capsule, radius: 0.07}]", "c.yaml")))
    assert describe_changes(old, fat, q, q) == "shapes resized: left/link2"


def test_reload_diff_joint_limits_clipped_configuration_and_workspace(tmp_path):
    from armguard.console._reload import carry_q

    old = load_scene(str(SCENE))
    new = load_scene(str(_edited_scene(
        tmp_path, "{a: 0.4, alpha: 0, d: 0, limits: [-150, 150], max_velocity: 90, max_acceleration: 180}\n    link_shapes",
        "{a: 0.4, alpha: 0, d: 0, limits: [-20, 20], max_velocity: 90, max_acceleration: 180}\n    link_shapes")))
    q = old.default_q()
    q["left"] = np.radians([-90.0, 0.0, 30.0])
    q_new = carry_q(q, old, new)
    assert np.degrees(q_new["left"][2]) == pytest.approx(20.0)
    text = describe_changes(old, new, q, q_new)
    assert "joint limits changed: left/joint3 [-150, 150] → [-20, 20] deg" in text, text
    assert "configuration clipped into the new limits: left/joint3 30 → 20 deg" in text, text
    assert text != "no change" and "right/" not in text.split("shapes")[0]
    # the limits narrowed around a value inside them: limits only, nothing clipped
    q["left"] = np.radians([-90.0, 0.0, 10.0])
    text = describe_changes(old, new, q, carry_q(q, old, new))
    assert text == "joint limits changed: left/joint3 [-150, 150] → [-20, 20] deg", text
    ws = load_scene(str(_edited_scene(tmp_path, "workspace: {lo: [-2.5, -2.0, -1.0], hi: [2.5, 2.0, 1.0]}",
                                      "workspace: {lo: [-3, -2.0, -1.0], hi: [2.5, 2.0, 1.0]}", "w.yaml")))
    q = old.default_q()
    assert describe_changes(old, ws, q, q) == \
        "workspace changed: [-2.5, -2, -1] to [2.5, 2, 1] m → [-3, -2, -1] to [2.5, 2, 1] m"


def test_watch_reload_and_a_broken_file_keeps_the_last_good_model(tmp_path):
    path = _moved_scene(tmp_path, 0.0)
    st = ConsoleState(load_scene(str(path)))
    st.set_joint("left", 0, 60, deg=True)
    app = SimpleNamespace(state=st, reloaded=0)
    app.model_reloaded = lambda: setattr(app, "reloaded", app.reloaded + 1)
    w = ModelWatcher(app, str(path), [path])
    path.write_text(path.read_text().replace("xyz: [-0.8, 0.8, 0.0]", "xyz: [-0.7, 0.8, 0.0]"))
    assert w.reload_now() == "shapes moved: post"
    snap = st.snapshot()
    assert app.reloaded == 1 and snap.changes == "model reloaded: shapes moved: post"
    html = _panel(snap)
    assert html.count("shapes moved: post") == 1 and 'data-reload="true"' in html  # one message
    assert math.isclose(snap.q["left"][0], math.radians(60))  # the configuration kept
    post = [it.shape for it in st.scene.shapes_at(snap.q) if it.owner == "post"][0]
    path.write_text(path.read_text().replace("size: [0.2, 0.2, 0.6]", "sise: [0.2, 0.2, 0.6]"))
    assert w.reload_now() is None and app.reloaded == 1
    snap = st.snapshot()
    assert snap.message_is_error and "last good one keeps running" in snap.message and "sise" in snap.message
    html = _panel(snap)
    assert "sise" in html and "model reloaded" not in html  # the current message only
    again = [it.shape for it in st.scene.shapes_at(snap.q) if it.owner == "post"][0]
    assert np.array_equal(np.asarray(again.center), np.asarray(post.center))


def test_watch_reload_refreshes_the_widgets(tmp_path):
    """After a reload the joint fields and sliders show the new limits (and hints), the workspace
    fields the new box: "apply limits" keeps the new workspace."""
    import time

    from armguard.console import ConsoleApp

    path = _edited_scene(tmp_path, "armguard_scene: 1", "armguard_scene: 1")
    app = ConsoleApp(ConsoleState(load_scene(str(path))), port=0).start()
    try:
        st = app.state
        st.set_joint("left", 2, "30", deg=True)
        fields, sliders, _ = app._w_joints["left"]
        assert sliders[2].max == pytest.approx(150.0) and "-150 to 150 deg" in fields[2].handle.hint
        text = path.read_text().replace("limits: [-150, 150]", "limits: [-20, 20]", 2)  # left joints 2 and 3
        text = text.replace("workspace: {lo: [-2.5, -2.0, -1.0]", "workspace: {lo: [-3.0, -2.0, -1.0]")
        assert "Run hit_post" in [b.label for b in app._w_test_buttons]
        text = text.replace("name: hit_post", "name: swing_into_post")
        path.write_text(text)
        generation = app._built_generation
        app.watcher = ModelWatcher(app, str(path), [path])
        assert "joint limits changed" in app.watcher.reload_now()
        deadline = time.monotonic() + 120.0  # the display thread rebuilds the widgets (slow on a loaded machine)
        while time.monotonic() < deadline:
            if app._built_generation != generation and app._shown_version == st.version:
                break
            time.sleep(0.05)
        fields, sliders, _ = app._w_joints["left"]
        assert (sliders[2].min, sliders[2].max) == (pytest.approx(-20.0), pytest.approx(20.0))
        assert sliders[2].value == pytest.approx(20.0) and fields[2].shown == "20"  # clipped from 30
        assert "-20 to 20 deg" in fields[2].handle.hint and "-170 to 170 deg" in fields[0].handle.hint
        assert app._w_joints["right"][1][2].max == pytest.approx(150.0)  # the right arm's stay
        assert app._fields["ws_lo"].shown == "-3, -2, -1"
        labels = [b.label for b in app._w_test_buttons]  # the canned tests' buttons are the new model's
        assert "Run swing_into_post" in labels and "Setup swing_into_post" in labels and "Run hit_post" not in labels
        st.apply_workspace()  # what "apply limits" does
        assert np.allclose(st.snapshot().workspace[0], [-3.0, -2.0, -1.0])
    finally:
        app.stop()


def _panel(snap) -> str:
    from armguard.console._readout import panel_html

    return panel_html(snap.readout, snap.message, error=snap.message_is_error, changes=snap.changes)


def _project(eye, look, P, fov):
    f = (look - eye) / np.linalg.norm(look - eye)
    r = np.cross(f, [0, 0, 1.0])
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    rel = P - eye
    z = rel @ f
    return (rel @ r) / (z * math.tan(fov / 2)), (rel @ u) / (z * math.tan(fov / 2)), z


def test_follow_view_frames_the_points_across_the_line():
    fov = math.radians(75.0)
    P = np.array([[1.0, 0.0, 0.0], [1.5, 0.3, 0.2], [1.2, -0.2, 0.5]])
    eye, look = follow_view(P, np.zeros(3), fov_rad=fov)
    x, y, z = _project(eye, look, P, fov)
    assert np.all(z > 0) and np.all(np.abs(y) < 1.0) and np.all(np.abs(x) < 1.0 * 1100 / 700)
    d = eye - look
    assert math.degrees(math.atan2(d[2], np.linalg.norm(d[:2]))) == pytest.approx(FOLLOW_ELEVATION_DEG)
    assert d[0] > 0  # from the points' side of the scene (+x of its centre)
    line = np.array([[1.0, 0.0, 0.0], [1.0, 0.5, 0.0]])  # along y: seen from +-x
    eye, look = follow_view(P, np.zeros(3), line=line, fov_rad=fov)
    h = (eye - look)[:2] / np.linalg.norm((eye - look)[:2])
    assert abs(h @ [0.0, 1.0]) < 1e-9 and h[0] > 0


def test_pair_view_sees_the_line_past_a_blocking_wall():
    fov = math.radians(75.0)
    line = np.array([[0.0, 0.0, 0.0], [0.0, 0.2, 0.0]])
    eye0, look0 = pair_view(line, fov_rad=fov)
    mid = line.mean(axis=0)
    x, y, z = _project(eye0, look0, line, fov)
    assert np.all(z > 0) and np.all(np.abs(y) < 1.0)
    view = (mid - eye0) / np.linalg.norm(mid - eye0)
    assert abs(view @ [0, 1.0, 0]) <= 0.8  # across the line, not along it
    # a wall between the first camera and the line: another direction, with a clear sight line
    c = 0.5 * (eye0 + mid)
    wall = Box(center=c, half_extents=[0.05, 0.3, 0.3], rotation=np.eye(3))
    eye, _ = pair_view(line, [wall], fov_rad=fov)
    assert not np.allclose(eye, eye0)
    from armguard.geometry import Capsule

    assert distance(Capsule(eye, mid, 1e-3), wall).distance > 0


def test_feature_outlines():
    box = Box(center=[0, 0, 0], half_extents=[1.0, 2.0, 3.0], rotation=np.eye(3))
    for k in range(6):
        seg = feature_segments(box, Feature(FeatureKind.FACE, k))
        axis = k // 2
        assert seg.shape == (4, 2, 3)
        assert np.allclose(np.abs(seg[..., axis]), [1.0, 2.0, 3.0][axis])  # every edge on that face
        assert len({float(v) for v in np.sign(seg[..., axis]).ravel()}) == 1
    edge = feature_segments(box, Feature(FeatureKind.EDGE, 0))
    assert edge.shape == (1, 2, 3)
    assert np.linalg.norm(edge[0, 1] - edge[0, 0]) in (2.0, 4.0, 6.0)
    tet = ConvexPolyhedron(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]]))
    f0 = feature_segments(tet, Feature(FeatureKind.FACE, 0))
    assert f0.shape == (len(tet.faces[0]), 2, 3)
    assert np.allclose(f0[1:, 0], f0[:-1, 1]) and np.allclose(f0[0, 0], f0[-1, 1])  # a closed loop
    assert feature_segments(box, Feature(FeatureKind.VERTEX, 0)).shape == (0, 2, 3)
    assert feature_segments(box, None).shape == (0, 2, 3)


def test_a_backend_that_fails_is_said_and_no_longer_offered(ranger, monkeypatch):
    from armguard.console import _backends

    scene, model = ranger
    st = ConsoleState(scene, model=model)
    st.set_backend("coal")
    st.set_compare("fcl")

    def boom(self, *args, **kwargs):
        raise RuntimeError("plugin bug")

    monkeypatch.setattr(_backends.BackendView, "readout", boom)
    st.set_joints(st.snapshot().active, st.snapshot().q[st.snapshot().active])  # the next update fails
    snap = st.snapshot()
    assert snap.backend == "analytic" and snap.readout.backend == "analytic" and snap.compare is None
    assert snap.message_is_error and "'coal' failed (RuntimeError: plugin bug)" in snap.message
    assert "'fcl' failed (RuntimeError: plugin bug)" in snap.message and "comparison off" in snap.message
    assert "coal" not in st.backends and "fcl" not in st.backends
    with pytest.raises(ConsoleInputError, match="plugin bug"):
        st.set_backend("coal")
    assert st.snapshot().backend == "analytic"


def test_delta_below_the_shown_digits_has_no_sign():
    from dataclasses import replace

    from armguard.console import panel_html

    r = replace(readout_off(0.05), backend="analytic", distance=0.2)
    for d in (0.2 - 1e-9, 0.2 + 1e-9):
        html = panel_html(r, compare=compare_readouts(r, replace(r, backend="coal", distance=d)))
        assert "<b>0.0000 mm</b>" in html and "-0.0000" not in html and "+0.0000" not in html
    html = panel_html(r, compare=compare_readouts(r, replace(r, backend="coal", distance=0.2 - 2e-7)))
    assert "<b>-0.0002 mm</b>" in html


def test_widgets_offer_only_what_the_scene_has():
    """3-joint arms: no arm-angle slider; canned tests: a Stop button; the corner and target
    fields show the state's box and the tool pose, and the corners empty once the box is removed."""
    import time

    from armguard.console._app import ConsoleApp

    app = ConsoleApp(ConsoleState(load_scene(str(SCENE))), port=0).start()
    try:
        st = app.state
        assert app._w_psi.visible is False and app._b_stop.visible is True
        assert app._fields["ws_lo"].shown == "-2.5, -2, -1" and app._fields["ws_hi"].shown == "2.5, 2, 1"
        p = st.ee_pose()[:3, 3]
        shown = [round(float(v), 4) for v in p]  # 0.1 mm, as the field rounds it
        assert app._fields["pos"].shown == ", ".join(f"{0.0 if v == 0 else v:.6g}" for v in shown)
        st.remove_workspace()
        for _ in range(200):
            if app._fields["ws_hi"].shown == "":
                break
            time.sleep(0.05)
        assert app._fields["ws_lo"].shown == "" and app._fields["ws_hi"].shown == ""
    finally:
        app.stop()


def test_a_static_arm_body_is_the_obstacle_not_the_link():
    """Puma's pedestal (its base link, moved by no joint) is a static body: at home its nearest pair
    with link2 names link2 the link (the one coloured red) and the pedestal the obstacle, points
    swapped with them, for every backend; a moving link's rows keep their sides."""
    from armguard.console._serve import make_state

    st = make_state("puma560")
    assert st._is_static("puma560/base") and not st._is_static("puma560/link1") and not st._is_static("table")
    for backend in ("analytic", "coal"):
        st.set_backend(backend)
        r = st.snapshot().readout
        assert {r.link, r.obstacle} == {"puma560/base", "puma560/link2"}  # the pair this test is about
        assert r.link == r.owner_a == "puma560/link2" and r.obstacle == "puma560/base"
        arm = {c.category: c for c in r.rows}["arm"]
        assert arm.link == "puma560/link2" and arm.obstacle == "puma560/base"
        # the arm point lies on link2's side: farther from the pedestal's axis (x = y = 0) than the pedestal's
        assert np.hypot(*r.p_WA[:2]) >= np.hypot(*r.p_WB[:2]) - 1e-9
        assert abs(np.linalg.norm(r.p_WB - r.p_WA) - r.distance) < 1e-6


def test_moving_link_first_swaps_only_a_static_arm_side():
    from dataclasses import replace

    from armguard.console._readout import CategoryRow, moving_link_first

    static = {"r/base"}.__contains__
    pa, pb = np.array([0.0, 0.0, 0.1]), np.array([0.2, 0.0, 0.1])
    r = replace(readout_off(0.05), distance=0.2, link="r/base", obstacle="r/link2", owner_a="r/base",
                owner_b="r/link2", p_WA=pa, p_WB=pb,
                rows=(CategoryRow("arm", 0.2, "r/base", "r/link2"), CategoryRow("environment", 0.3, "r/link1", "table")))
    s = moving_link_first(r, static)
    assert (s.link, s.obstacle, s.owner_a, s.owner_b) == ("r/link2", "r/base", "r/link2", "r/base")
    assert np.array_equal(s.p_WA, pb) and np.array_equal(s.p_WB, pa) and s.distance == r.distance
    assert s.rows == (CategoryRow("arm", 0.2, "r/link2", "r/base"), r.rows[1])
    t = replace(r, link="r/link1", owner_a="r/link1", owner_b="table", obstacle="table", rows=r.rows[1:])
    u = moving_link_first(t, static)  # a moving link first already: unchanged
    assert (u.link, u.obstacle, u.owner_a, u.owner_b, u.rows) == (t.link, t.obstacle, t.owner_a, t.owner_b, t.rows)
    assert u.p_WA is t.p_WA and u.p_WB is t.p_WB


def test_compare_labels_stand_on_opposite_sides_of_the_line():
    from armguard.console._draw import label_place

    pa, pb = np.array([0.0, 0.0, 0.0]), np.array([0.1, 0.0, 0.0])
    (p1, a1), (p2, a2) = label_place("primary", pa, pb), label_place("compare", pa, pb)
    assert a1 == "bottom-center" and a2 == "top-center"  # one rests above its point, the other hangs below
    assert p1[2] > 0.0 > p2[2] and np.allclose(p1[:2], p2[:2])
    (q1, _), (q2, _) = label_place("primary", pa, pa), label_place("compare", pa, pa)
    assert q1 == q2  # a zero-length line: still apart, by the anchors


def test_no_negative_zero_anywhere_in_the_panel():
    from dataclasses import replace

    from armguard.console import panel_html

    r = replace(readout_off(0.05), backend="analytic", distance=-1e-6, p_WA=np.array([-1e-5, 0.1, -2e-4]),
                p_WB=np.array([0.0, -1e-6, 0.2]))
    html = panel_html(r, compare=compare_readouts(r, replace(r, backend="coal", distance=-1e-6 + 1e-11)))
    assert "-0.0" not in html and "−0.0" not in html
    assert "0.0 mm" in html and "(+0.000, +0.100, -0.000)" not in html and "(+0.000, +0.100, +0.000) m" in html


def _wait(cond, seconds: float = 20.0) -> bool:
    import time

    t_end = time.monotonic() + seconds
    while time.monotonic() < t_end:
        if cond():
            return True
        time.sleep(0.05)
    return cond()


def test_widgets_of_a_six_joint_scene_without_tests_and_a_seven_joint_arm(ranger):
    """Puma (6 joints, no canned tests): no arm-angle slider, no Stop, compare never offers the
    panel's backend.  Ranger's 7-joint left arm: the slider, its value in its label, following
    the state."""
    from armguard.console._app import ConsoleApp
    from armguard.console._serve import make_state

    app = ConsoleApp(make_state("puma560"), port=0).start()
    try:
        assert app._w_psi.visible is False and app._b_stop.visible is False
        assert "analytic" not in app._w_compare.options and "coal" in app._w_compare.options
        app.state.set_backend("coal")
        assert _wait(lambda: "coal" not in app._w_compare.options and "analytic" in app._w_compare.options)
    finally:
        app.stop()
    scene, model = ranger
    st = ConsoleState(scene, model=model)
    st.set_active("left_arm")
    st.set_mode("cartesian")
    app = ConsoleApp(st, port=0).start()
    try:
        assert _wait(lambda: app._w_psi.visible is True) and app._b_stop.visible is True
        st.set_arm_angle(0.2)
        assert _wait(lambda: app._w_psi.label == "arm angle +11.5 deg")
        assert abs(app._w_psi.value - math.degrees(0.2)) < 1e-9
        st.set_active("grapple_arm")  # 6 joints: no slider
        assert _wait(lambda: app._w_psi.visible is False)
    finally:
        app.stop()
