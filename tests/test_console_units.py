"""Unit tests of the console's pure parts: typed-value checks, the time line, the distance panel,
display meshes and the clearance plot.  No browser, no scene."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from armguard import ArmguardError
from armguard.console import (
    PANEL_COLORS,
    ClearancePlot,
    ConsoleInputError,
    PanelStatus,
    Timeline,
    panel_html,
    parse_number,
    parse_numbers,
    readout_from_report,
    readout_off,
    view_pose,
    VIEWS,
    VISTA_POINTS,
)
from armguard.console._meshes import mesh_of, quat_wxyz_from_matrix, rigid_motion
from armguard.console._timeline import MAX_RATE, MIN_RATE
from armguard.geometry import Box, Capsule, ConvexPolyhedron, Polygon, Prism, Sphere


# ---------------------------------------------------------------------------- parsing
@pytest.mark.parametrize(
    "value",
    ["abc", "", "  ", "nan", "inf", "-inf", float("nan"), float("inf"), None, True, [1.0], "4_5", "\uff19\uff10",
     "\u0661\u0662"],
    ids=["word", "empty", "blank", "nan-text", "inf-text", "minus-inf-text", "nan", "inf", "none", "bool", "list",
         "underscore", "full-width-digits", "arabic-indic-digits"],  # float() takes the last three (45, 90, 12)
)
def test_parse_number_rejects_with_field_name(value):
    with pytest.raises(ConsoleInputError, match="threshold"):
        parse_number(value, "threshold", unit="m")


def test_parse_number_messages_name_the_unit_and_quote_the_entry():
    with pytest.raises(ConsoleInputError) as e:
        parse_number("abc", "left/joint1", unit="deg")
    assert str(e.value) == "left/joint1: expected a number (deg), got 'abc'"
    with pytest.raises(ConsoleInputError) as e:
        parse_number(" 1e309 ", "threshold", unit="m")
    assert str(e.value) == "threshold: expected a finite number (m), got '1e309'"  # what was typed, not inf
    with pytest.raises(ConsoleInputError) as e:
        parse_number("", "threshold", unit="m")
    assert str(e.value) == "threshold: expected a number (m), got an empty entry"
    with pytest.raises(ConsoleInputError) as e:
        parse_number("x", "v")
    assert str(e.value) == "v: expected a number, got 'x'"


def test_parse_number_range_and_scale():
    assert parse_number(" 12.5 ", "x") == 12.5
    assert parse_number("90", "q", scale=math.pi / 180) == pytest.approx(math.pi / 2)
    with pytest.raises(ConsoleInputError, match=r"outside \[0, 10\] m"):
        parse_number(-0.5, "threshold", lo=0.0, hi=10.0, unit="m")
    assert issubclass(ConsoleInputError, ArmguardError) and issubclass(ConsoleInputError, ValueError)


@pytest.mark.parametrize(
    "text,expect",
    [("1, 2, 3", [1, 2, 3]), ("1 2 3", [1, 2, 3]), ("1;2; 3", [1, 2, 3]), ((1, 2, 3), [1, 2, 3])],
    ids=["commas", "spaces", "semicolons", "tuple"],
)
def test_parse_numbers_ok(text, expect):
    np.testing.assert_array_equal(parse_numbers(text, "v", 3), expect)


@pytest.mark.parametrize("text", ["1, 2", "1, 2, 3, 4", "1, x, 3", "1, nan, 3"], ids=["short", "long", "word", "nan"])
def test_parse_numbers_bad(text):
    with pytest.raises(ConsoleInputError, match="corner"):
        parse_numbers(text, "corner", 3)


# ---------------------------------------------------------------------------- time line
def test_timeline_play_pause_and_stop_at_end():
    tl = Timeline(2.0)
    assert tl.advance(0.5) == 0.0  # paused: time does not move
    tl.play()
    assert tl.advance(0.5) == pytest.approx(0.5)
    tl.pause()
    assert tl.advance(1.0) == pytest.approx(0.5)
    tl.play()
    assert tl.advance(10.0) == 2.0 and not tl.playing  # the end is shown, then it stops
    tl.play()  # from the end, play restarts at 0
    assert tl.t == 0.0 and tl.playing


def test_timeline_faster_slower_backwards():
    tl = Timeline(10.0)
    tl.seek(5.0)
    assert tl.faster() == 2.0
    tl.play()
    assert tl.advance(1.0) == pytest.approx(7.0)  # 2x speed
    assert tl.slower() == 1.0 and tl.slower() == 0.5
    assert tl.reverse() == -0.5
    assert tl.advance(2.0) == pytest.approx(6.0)  # backwards at half speed
    assert tl.state.direction == "backward"
    assert tl.advance(100.0) == 0.0 and not tl.playing  # stops at the start
    tl.play()  # backwards from the start restarts from the end
    assert tl.t == 10.0


def test_timeline_rate_bounds():
    tl = Timeline(1.0)
    for _ in range(20):
        tl.faster()
    assert tl.rate == MAX_RATE
    for _ in range(40):
        tl.slower()
    assert tl.rate == MIN_RATE


@pytest.mark.parametrize("bad", ["x", float("nan"), float("inf"), ""], ids=["word", "nan", "inf", "empty"])
def test_timeline_seek_rejects_and_keeps_time(bad):
    tl = Timeline(3.0)
    tl.seek(1.25)
    with pytest.raises(ConsoleInputError):
        tl.seek(bad)
    assert tl.t == 1.25


def test_timeline_seek_clamps():
    tl = Timeline(3.0)
    assert tl.seek(-1) == 0.0 and tl.seek(99) == 3.0 and tl.seek_fraction(0.5) == 1.5


@settings(max_examples=60, derandomize=True, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(["play", "pause", "faster", "slower", "reverse", "seek", "advance"]),
                          st.floats(0.0, 5.0)), max_size=30))
def test_timeline_time_stays_in_range(ops):
    tl = Timeline(4.0)
    for op, x in ops:
        if op == "seek":
            tl.seek(x)
        elif op == "advance":
            tl.advance(x)
        else:
            getattr(tl, op)()
        s = tl.state
        assert 0.0 <= s.t <= 4.0
        assert MIN_RATE <= abs(s.rate) <= MAX_RATE


# ---------------------------------------------------------------------------- panel
@dataclass
class _Pair:
    distance: float
    link: str = "link4"
    obstacle: str = "tail"
    a: str = "left/link4"
    p_WA: np.ndarray = field(default_factory=lambda: np.zeros(3))
    p_WB: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 0.1]))


def _report(status, d, threshold=0.05, cats=("environment",)):
    near = None if d is None else _Pair(d)
    return SimpleNamespace(status=SimpleNamespace(value=status), nearest=near, threshold=threshold,
                           by_category={c: _Pair(d if d is not None else 1.0) for c in cats}, elapsed_us=12.0)


@pytest.mark.parametrize(
    "status,d,color,within",
    [("clear", 0.3, "#2e9e44", False), ("warning", 0.02, "#f2c200", True), ("collision", -0.01, "#d62828", True),
     ("incomplete", 0.3, PANEL_COLORS[PanelStatus.INCOMPLETE], False)],
    ids=["green", "yellow", "red", "incomplete-not-green"],
)
def test_panel_colour_follows_status(status, d, color, within):
    r = readout_from_report(_report(status, d))
    assert r.color == color and r.within_threshold is within
    assert r.line_color == ((220, 30, 30) if within else (255, 210, 0))
    html = panel_html(r)
    assert f'data-status="{status}"' in html and color in html


def test_panel_rows_in_category_order_and_escaped():
    r = readout_from_report(_report("clear", 0.3, cats=("payload", "arm", "workspace")))
    assert [row.category for row in r.rows] == ["arm", "workspace", "payload"]
    html = panel_html(r, message="<bad> value")
    assert "&lt;bad&gt; value" in html and "<bad>" not in html


def test_panel_off_and_no_pairs():
    off = readout_off(0.05)
    assert off.status is PanelStatus.OFF and off.color == PANEL_COLORS[PanelStatus.OFF]
    r = readout_from_report(_report("clear", None))
    assert r.p_WA is None and math.isinf(r.distance) and "—" in panel_html(r)


# ---------------------------------------------------------------------------- meshes
_SHAPES = {
    "sphere": Sphere([0.1, 0.2, 0.3], 0.2),
    "capsule": Capsule([0, 0, 0], [0.3, 0.4, 0.0], 0.05),
    "box": Box([1, 0, 0], [0.1, 0.2, 0.3], np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]])),
    "prism": Prism([0, 1, 0], np.eye(3), 0.2, 0.3, 8),
    "polyhedron": ConvexPolyhedron([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]),
    "polygon": Polygon([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]),
}


@pytest.mark.parametrize("name", list(_SHAPES), ids=list(_SHAPES))
def test_mesh_matches_shape_bounds(name):
    shape = _SHAPES[name]
    v, f = mesh_of(shape)
    lo, hi = shape.aabb()
    # the mesh is inscribed in the shape: inside its box, and reaching it to within the tessellation
    tol = 0.02 if name in ("sphere", "capsule") else 1e-9
    assert np.all(v.min(axis=0) >= lo - 1e-9) and np.all(v.max(axis=0) <= hi + 1e-9)
    np.testing.assert_allclose(v.min(axis=0), lo, atol=tol)
    np.testing.assert_allclose(v.max(axis=0), hi, atol=tol)
    assert f.ndim == 2 and f.shape[1] == 3 and f.max() < len(v)


def _random_rotation(rng):
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]), q


def test_rigid_motion_recovers_a_known_motion():
    rng = np.random.default_rng(5)
    for _ in range(20):
        R, q = _random_rotation(rng)
        t = rng.normal(size=3)
        P0 = rng.normal(size=(6, 3))
        R_fit, t_fit = rigid_motion(P0, P0 @ R.T + t)
        np.testing.assert_allclose(R_fit, R, atol=1e-9)
        np.testing.assert_allclose(t_fit, t, atol=1e-9)
        wxyz = quat_wxyz_from_matrix(R)
        np.testing.assert_allclose(wxyz, q if q[0] >= 0 else -q, atol=1e-9)


def test_rigid_motion_two_points_maps_the_segment():
    rng = np.random.default_rng(1)
    R, _ = _random_rotation(rng)
    P0 = np.array([[0.0, 0, 0], [0.3, 0.4, 0.0]])
    P = P0 @ R.T + [1, 2, 3]
    R_fit, t_fit = rigid_motion(P0, P)
    np.testing.assert_allclose(P0 @ R_fit.T + t_fit, P, atol=1e-9)


# ---------------------------------------------------------------------------- plot, views
def test_clearance_plot_marker_moves_with_time():
    t = np.linspace(0, 4, 50)
    plot = ClearancePlot(t, 0.2 - 0.1 * t, threshold=0.05, first_collision=2.0)
    cols = [plot.column_of(x) for x in (0.0, 1.0, 2.0, 4.0)]
    assert cols == sorted(cols) and cols[0] < cols[-1]
    assert cols[2] - cols[0] == pytest.approx(2 * (cols[1] - cols[0]), abs=1)
    img = plot.image_at(2.0)
    assert img.dtype == np.uint8 and img.shape == plot.shape
    mid_row = img.shape[0] // 2
    assert tuple(img[mid_row, cols[2]]) == (30, 90, 220)
    assert not np.array_equal(img, plot.image_at(3.0))


class _Widget:
    """Records what the feed sends, as a viser image or markdown handle would receive it."""

    def __init__(self) -> None:
        self.sent: list = []

    image = property(lambda self: self.sent[-1], lambda self, v: self.sent.append(np.array(v)))
    content = property(lambda self: self.sent[-1], lambda self, v: self.sent.append(v))


def test_marker_feed_throttles_while_playing_and_sends_the_stop_at_once(monkeypatch):
    """While playing, at most one image per PLOT_PERIOD and only when the marker moved a column;
    paused, the image at the stop goes out at once; a caption goes out only when it changed."""
    from armguard.console import _plot

    clock = [100.0]
    monkeypatch.setattr(_plot.time, "perf_counter", lambda: clock[0])
    t = np.linspace(0, 4, 50)
    plot = ClearancePlot(t, 0.2 - 0.1 * t, threshold=0.05)
    feed, img, cap = _plot.MarkerFeed(), _Widget(), _Widget()
    assert feed.push(plot, 0.0, True, "t = 0", img, cap)  # the first one goes out
    assert len(img.sent) == 1 and cap.sent == ["t = 0"]
    clock[0] += _plot.PLOT_PERIOD / 2
    assert not feed.push(plot, 1.0, True, "t = 1", img, cap)  # too soon while playing
    clock[0] += _plot.PLOT_PERIOD
    assert feed.push(plot, 1.0, True, "t = 1", img, cap)
    np.testing.assert_array_equal(img.sent[-1], plot.image_at(1.0))
    clock[0] += _plot.PLOT_PERIOD
    same_column = 1.0 + 0.1 * (t[-1] - t[0]) / plot.shape[1]  # a tenth of a pixel later
    assert plot.column_of(same_column) == plot.column_of(1.0)
    assert not feed.push(plot, same_column, True, "t = 1", img, cap)  # nothing moved: nothing sent
    assert len(img.sent) == 2 and len(cap.sent) == 2
    clock[0] += 0.001
    assert feed.push(plot, 2.5, False, "t = 2.5 paused", img, cap)  # stopped: at once
    np.testing.assert_array_equal(img.sent[-1], plot.image_at(2.5))
    assert cap.sent[-1] == "t = 2.5 paused"
    feed.reset()  # a new plot: everything again
    assert feed.push(plot, 2.5, True, "t = 2.5 paused", img, cap) and len(img.sent) == 4


@pytest.mark.parametrize("label", VIEWS, ids=list(VIEWS))
def test_views_look_at_the_scene_from_outside(label):
    c = np.array([1.0, 2.0, 0.5])
    pos, look = view_pose(label, c, 2.0)
    np.testing.assert_array_equal(look, c)
    assert np.linalg.norm(pos - c) == pytest.approx(5.0, rel=1e-3)
    if label == "top":
        assert pos[2] - c[2] == pytest.approx(5.0, rel=1e-3)


def test_ranger_has_its_ten_vista_points_each_clear_of_the_scene():
    """Seed 000 section 6: "select from ten vista points for viewing the simulation".  Each vista
    point, framed as the console frames Ranger (the bounding box of every shape), is outside every
    shape at every canned test's setup, looking at the scene; together they see each arm's tool
    past the vehicle and the other arms (at the first test's setup)."""
    from armguard.console._view import visible_count
    from armguard.geometry import Sphere, distance
    from armguard.scene import load_scene

    vistas = [v for v in VIEWS if v.startswith("vista ")]
    assert len(vistas) == len(VISTA_POINTS) == 10
    s = load_scene("ranger")
    for k, ct in enumerate(s.canned_tests.values()):
        items = s.shapes_at(ct.setup)
        V = np.concatenate([mesh_of(it.shape)[0] for it in items])
        lo, hi = V.min(axis=0), V.max(axis=0)
        c, r = 0.5 * (lo + hi), max(0.5, 0.5 * float(np.linalg.norm(hi - lo)))
        eyes = []
        for v in vistas:
            eye, look = view_pose(v, c, r)
            np.testing.assert_array_equal(look, c)
            assert all(distance(Sphere(eye, 0.05), it.shape).distance > 0.0 for it in items), (ct.name, v)
            eyes.append(eye)
        if k == 0:
            D = np.array([(e - c) / np.linalg.norm(e - c) for e in eyes])
            cos = D @ D.T - 2.0 * np.eye(10)
            assert cos.max() < math.cos(math.radians(30.0))  # ten distinct directions, 30 deg apart at least
            assert (D[:, 2] > 0).sum() == 6 and (D[:, 2] < 0).sum() == 4  # six from above, four from below
            for rn in s.robots:
                tool = s.robots[rn].link_pose(ct.setup[rn])[:3, 3]
                others = [it.shape for it in items if not it.owner.startswith(rn + "/")]
                assert any(visible_count(e, [tool], others, 0.01) == 1 for e in eyes), rn


def test_field_text_never_negative_zero():
    from armguard.console._app import _fmt, _vec

    assert _fmt(-0.0) == "0" and _fmt(-47.03291234) == "-47.0329" and _fmt(1e-3) == "0.001"
    assert _vec((-0.0, -0.392, 2.5)) == "0, -0.392, 2.5" and _vec(None) == ""


def test_joint_fields_and_pose_line_round_and_never_show_negative_zero():
    from armguard.console._app import joint_text, pose_line

    assert joint_text(-47.03291234, "deg") == "-47.03" and joint_text(45.0, "deg") == "45"
    assert joint_text(-0.001, "deg") == "0" and joint_text(-0.0, "deg") == "0"
    assert joint_text(0.123456, "m") == "0.1235" and joint_text(-4e-5, "m") == "0"
    for x in np.linspace(-180.0, 180.0, 721) + 1e-7:  # what is shown parses back within half a step
        assert abs(float(joint_text(x, "deg")) - x) <= 0.005 + 1e-12
    line = pose_line("arm", (-1e-5, 0.3, -0.39249), (-1e-4, 0.0, math.pi / 2))
    assert line == "tool now (arm): x y z = +0.000 +0.300 -0.392 m; roll pitch yaw = +0.0 +0.0 +90.0 deg"


def test_arm_angle_only_for_seven_joints_with_its_value_and_no_self_compare():
    from armguard.console._app import arm_angle_label, compare_options, has_arm_angle

    assert [has_arm_angle(SimpleNamespace(n_joints=n)) for n in (3, 6, 7, 8)] == [False, False, True, False]
    assert arm_angle_label(0.2) == "arm angle +11.5 deg" and arm_angle_label(-1e-4) == "arm angle +0.0 deg"
    assert compare_options(("analytic", "coal", "fcl"), "coal") == ("off", "analytic", "fcl")
    assert compare_options(("analytic",), "analytic") == ("off",)


def test_the_verification_report_wraps_in_the_panel():
    from armguard.console._app import report_html

    h = report_html("a" * 300 + " <b>")
    assert "white-space:pre-wrap" in h and "overflow-wrap:anywhere" in h and "&lt;b&gt;" in h and "```" not in h
