"""The console's fourth UX review, without a browser: each test is a defect the review found.

The Time line tab showed a stopped canned test's time (the slider at 7.9 s of ``18.346304``, no
plot, no report) before anything was loaded, labelled its end unrounded, and kept naming a scene
trajectory after a program run had replaced it; the clearance plot drew a constant clearance on
its top edge.  The follow view framed the arm partly under the control panel; MOVE tasks showed
the grasp height and approach lift; ``armguard console`` with a mistyped path said "file not
found" only after compiling the kernels; Ranger's greyed-out "URDF visual geometry" said not why.
"""

from __future__ import annotations

import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from click.testing import CliRunner

from armguard.console import ConsoleInputError, ConsoleState
from armguard.console._plot import ClearancePlot, Y_MARGIN, clearance_ylim
from armguard.console._timeline_panel import (NOTHING_LOADED, program_entry, slider_end, slider_time,
                                              timeline_view)
from armguard.console._view import PANEL_SHARE, follow_view, visible_offset
from armguard.console._views import canvas_of, urdf_hints
from armguard.scene import load_scene

DATA = Path(__file__).parent / "data"
SCENE = DATA / "console_scene.yaml"
CELL = Path(__file__).resolve().parent.parent / "examples" / "workmate" / "cell.yaml"


@pytest.fixture(scope="module")
def scene():
    return load_scene(str(SCENE))


# ---------------------------------------------------------------------- 1. the time line tab
def test_nothing_loaded_and_a_stopped_run_leave_the_slider_disabled_at_zero(scene):
    st = ConsoleState(scene, threshold=0.05)
    trajs = st.trajectories()
    v = timeline_view(st.snapshot().player, trajs)
    assert (v.loaded, v.enabled, v.value, v.selected) == (NOTHING_LOADED, False, 0.0, None)
    st.run("fold_right")  # a canned test from the Tests tab: on the time line while it is there
    for _ in range(10):
        st.tick(0.1)
    v = timeline_view(st.snapshot().player, trajs)
    assert v.enabled and v.value == pytest.approx(1.0) and v.loaded == "loaded: canned test fold_right (run from Tests)"
    st.stop()  # stopped: nothing is loaded any more, and the tab says so
    v = timeline_view(st.snapshot().player, trajs)
    assert (v.loaded, v.enabled, v.value, v.end) == (NOTHING_LOADED, False, 0.0, 1.0)


def test_slider_end_is_rounded_and_still_reaches_the_end():
    assert slider_end(18.346304) == 18.35 and repr(slider_end(7.443864)) == "7.44"
    assert slider_end(28.5) == 28.5 and slider_end(0.001) == 0.01
    assert slider_time(18.35, 18.346304) == 18.346304  # the end of the slider is the motion's end
    assert slider_time(7.44, 7.443864) == 7.443864
    assert slider_time(3.0, 7.443864) == 3.0


def test_dropdown_names_a_verified_trajectory_or_the_program_run(scene):
    st = ConsoleState(scene, threshold=0.05)
    trajs = st.trajectories()
    p = st.load_trajectory("fold_safely", samples=20)
    v = timeline_view(p, trajs)
    assert v.selected == "fold_safely" and v.options == trajs and v.enabled
    assert v.end == round(p.timeline.duration, 2) and v.loaded == "loaded: trajectory fold_safely, verified"
    # a program run from the Tasks tab: not a scene trajectory; its own entry, selected
    q = st.show_verified("console_program", p.trajectory, p.times, p.clearance, p.report, "program ran")
    v = timeline_view(q, trajs)
    assert v.options == (program_entry("console_program"),) + trajs
    assert v.selected == "program console_program (run from Tasks)"
    assert v.loaded == "loaded: program console_program (run from Tasks)"


def test_time_line_tab_in_process_after_a_stopped_run_and_a_program_run():
    """The widgets: a stopped canned run leaves the slider at 0, disabled; after a program run the
    dropdown names it and "verify and load" on that entry is refused with the reason."""
    from armguard.console._serve import serve

    app = serve(str(CELL), port=0, block=False)
    try:
        st, tab = app.state, app._timeline
        assert tab.w_time.disabled and tab.w_time.value == 0.0 and NOTHING_LOADED in tab.w_loaded.content
        panel = app._tasks
        panel.composer.add("PICKUP", object="cylinder_a")
        run = panel.run()
        assert run.ok
        app._redraw(force=True)
        entry = program_entry(run.name)
        p = st.snapshot().player
        assert tab.w_traj.value == entry and entry in tab.w_traj.options and tab.b_load.disabled
        assert not tab.w_time.disabled and tab.w_time.max == slider_end(p.timeline.duration)
        assert len(repr(tab.w_time.max).split(".")[-1]) <= 2  # its label: 0.01 s, not 7.443864
        with pytest.raises(ConsoleInputError, match="already on the time line"):
            tab.load()
        tab._seek(tab.w_time.max)  # the slider's end: the motion's very end
        assert st.snapshot().player.timeline.t == pytest.approx(p.timeline.duration)
        app._redraw(force=True)
        assert tab.w_time.value == pytest.approx(tab.w_time.max)
        st.stop()  # dropped: the tab shows nothing loaded, the slider back at 0
        app._redraw(force=True)
        assert tab.w_time.disabled and tab.w_time.value == 0.0 and tab.w_rate.content == ""
        assert NOTHING_LOADED in tab.w_loaded.content and not tab.w_plot.visible
        assert tab.w_traj.value in st.trajectories() or tab.w_traj.value == "(none)"
    finally:
        app.stop()


def test_clearance_plot_leaves_room_above_a_constant_clearance():
    """Ranger's left_arm_sweep: 230 mm all along, drawn on the plot's top edge."""
    assert clearance_ylim(np.full(10, 230.0), 100.0) == pytest.approx((-Y_MARGIN * 230.0, 230.0 * (1 + Y_MARGIN)))
    t = np.linspace(0.0, 28.5, 50)
    plot = ClearancePlot(t, np.full(50, 0.23), threshold=0.1)
    img = plot.image_at(-1.0)
    green = np.all(np.abs(img.astype(int) - (0x2E, 0x9E, 0x44)) < 40, axis=2)
    x0, x1 = int(plot._x0) + 5, int(plot._x1) - 5
    rows = np.nonzero(green[:, x0:x1].any(axis=1))[0]
    assert len(rows)
    height = plot._y1 - plot._y0
    assert rows.min() - plot._y0 >= 0.07 * height  # the line well below the frame's top


# ---------------------------------------------------------------------- 2. framing beside the panel
def _ndc(eye, look, P, fov, aspect):
    f = (look - eye) / np.linalg.norm(look - eye)
    r = np.cross(f, [0.0, 0.0, 1.0])
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    rel = np.atleast_2d(P) - eye
    z = rel @ f
    t = math.tan(fov / 2)
    return (rel @ r) / (z * t * aspect), (rel @ u) / (z * t), z


@pytest.mark.parametrize("aspect", [1.6, 1.25, 2.2])
def test_follow_view_frames_the_points_left_of_the_control_panel(aspect):
    fov = math.radians(75.0)
    P = np.array([[1.0, 0.0, 0.0], [1.5, 0.3, 0.2], [1.2, -0.2, 0.5], [0.8, 0.4, 0.9]])
    eye, look = follow_view(P, np.zeros(3), fov_rad=fov, aspect=aspect)
    x, y, z = _ndc(eye, look, P, fov, aspect)
    free = 1.0 - 2.0 * PANEL_SHARE  # the panel covers NDC x in (free, 1]
    assert np.all(z > 0) and np.all(np.abs(y) < 1.0)
    assert np.all(x > -1.0) and np.all(x < free)  # every framed point left of the panel
    c = 0.5 * (P.min(axis=0) + P.max(axis=0))
    cx, _, _ = _ndc(eye, look, c, fov, aspect)
    assert cx[0] == pytest.approx(-PANEL_SHARE, abs=0.02)  # the middle of the visible part
    shift, half = visible_offset(fov, aspect)
    assert shift == pytest.approx(PANEL_SHARE * aspect * math.tan(fov / 2)) and half <= fov / 2


def test_canvas_of_reads_the_tabs_camera_and_falls_back_before_its_report():
    cam = SimpleNamespace(image_width=1000, image_height=500, aspect=2.0, fov=math.radians(60.0))
    assert canvas_of(SimpleNamespace(camera=cam)) == {"fov_rad": pytest.approx(math.radians(60.0)), "aspect": 2.0}

    class NoReport:
        @property
        def image_width(self):
            raise AssertionError  # viser: no camera message from the tab yet

    out = canvas_of(SimpleNamespace(camera=NoReport()))
    assert out == {"fov_rad": pytest.approx(math.radians(75.0)), "aspect": 1.6}


# ---------------------------------------------------------------------- 3. MOVE has no grasp
def test_task_fields_show_only_for_the_tasks_they_apply_to():
    from armguard.console._serve import serve

    app = serve(str(CELL), port=0, block=False)
    try:
        panel = app._tasks
        seen = {}
        for kind in ("FIND", "PICKUP", "PLACE", "MOVE"):
            panel.w_kind.value = kind
            panel._kind_changed()
            seen[kind] = (panel.f_grasp.visible, panel.f_lift.visible)
            assert (panel.f_grasp.form.visible, panel.f_lift.form.visible) == seen[kind]
        assert seen == {"FIND": (False, False), "PICKUP": (True, True), "PLACE": (False, True),
                        "MOVE": (False, False)}
    finally:
        app.stop()


# ---------------------------------------------------------------------- 4. a typo fails at once
@pytest.mark.parametrize("args, words", [
    (["nosuch/cell.yaml"], "nosuch/cell.yaml: file not found"),
    (["puma560", "--terrain", "nosuch.npz"], "terrain file 'nosuch.npz' does not exist"),
])
def test_console_refuses_a_missing_file_before_compiling(monkeypatch, args, words):
    import armguard.cli._compile as compile_mod
    from armguard.cli import main

    warmed = []
    monkeypatch.setattr(compile_mod, "warm_up", lambda *a, **k: warmed.append(1))
    res = CliRunner().invoke(main, ["console", *args, "--port", "0"])
    assert res.exit_code == 3 and words in res.output
    assert warmed == []  # refused before the kernels were warmed up (compiled on a first run)


# ---------------------------------------------------------------------- 5. why greyed out
def test_urdf_checkboxes_say_why_they_are_greyed_out():
    from armguard.console._serve import make_state

    ranger = make_state("ranger").model  # its URDF has collision geometry only
    vis, col = urdf_hints(ranger, True, False)
    assert vis == "unavailable: the model's URDF has no <visual> geometry" and "collision" in col
    vis, col = urdf_hints(None, False, False)  # a bare scene
    assert vis == col and "no URDF" in vis and vis.startswith("unavailable")
    vis, _ = urdf_hints(ranger, False, False)  # a URDF the view could not draw
    assert "could not be drawn" in vis
    vis, _ = urdf_hints(ranger, True, True)
    assert not vis.startswith("unavailable")


def test_ranger_views_tab_hint_in_process():
    from armguard.console._serve import serve

    app = serve("ranger", port=0, block=False)
    try:
        w = app._w_urdf_vis
        assert w.disabled and w.hint == "unavailable: the model's URDF has no <visual> geometry"
        assert not app._w_urdf_col.disabled
    finally:
        app.stop()
