"""What the console's panel and fields say, without a browser (a UX review's findings, one test each).

Long link names shortened in the per-category table; a continuous joint's typed angle wrapped into
its slider's range; a refusal cleared when its field accepts a value; the Cartesian target shown
rounded; the Tests tab's Stop on top and red; a near miss of an arm that is not the active one
named in the panel; in a deep contact the obstacle translucent for every backend.  The console's
GUI is built on a viser server on a free loopback port (no browser connects).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from armguard.console import ConsoleInputError, panel_html
from armguard.console._readout import CategoryRow, PanelStatus, Readout, short_name
from armguard.console._serve import make_state, serve

LEFT_NEAR_MODULE = {1: "90", 3: "80"}
"""Ranger's left arm, j2 90 deg and j4 80 deg: link5 41.3 mm from the manipulator module."""
LEFT_IN_MODULE = {1: "90", 3: "135"}
"""Ranger's left arm, j2 90 deg and j4 135 deg: link7 245 mm inside the manipulator module."""


def _kinova_available() -> bool:
    from armguard.model import known_models

    return "kinova" in {m.name for m in known_models() if m.available}


def _kinova():
    if not _kinova_available():
        pytest.skip("kinova's package (example-robot-data) is not installed")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return make_state("kinova")


@pytest.fixture()
def ranger_app():
    app = serve("ranger", port=0, block=False)
    try:
        yield app
    finally:
        app.stop()


def _pose(st, robot: str, joints: dict) -> None:
    for j, deg in joints.items():
        st.set_joint(robot, j, deg, deg=True)


# -- 1: long names -------------------------------------------------------------------------------
def test_the_table_names_the_active_arms_links_without_its_prefix_and_cuts_long_names_in_the_middle():
    assert short_name("end_effector/j2s6s200_link_6", "end_effector") == "j2s6s200_link_6"
    assert short_name("right_arm/link3", "left_arm") == "right_arm/link3"  # another arm's link keeps its arm
    long = "end_effector/j2s6s200_link_finger_tip_2_with_a_longer_name"
    cut = short_name(long, None)
    assert len(cut) == 32 and "…" in cut and cut.startswith(long[:15]) and cut.endswith(long[-16:])
    r = Readout(PanelStatus.WARNING, 0.029, "end_effector/j2s6s200_link_6", "end_effector/j2s6s200_link_finger_tip_2",
                "end_effector/j2s6s200_link_6", None, None, 0.05, True,
                (CategoryRow("arm", 0.029, "end_effector/j2s6s200_link_6", long),), 97.0)
    html = panel_html(r, active="end_effector")
    table = html[html.index('id="armguard-categories"'):]
    assert ">j2s6s200_<wbr>link_<wbr>6</td>" in table  # the wrap falls after a "_" (or a "/") where it can
    table = table.replace("<wbr>", "")
    assert "table-layout:fixed" in table and "overflow-wrap:anywhere" in table
    shown = short_name(long, "end_effector")
    assert shown == "j2s6s200_link_f…th_a_longer_name"
    assert ">j2s6s200_link_6</td>" in table and f'title="{long}">{shown}</td>' in table
    head = html[:html.index('id="armguard-categories"')]
    assert "link: end_effector/j2s6s200_link_6" in head  # the status block keeps the whole name, wrapped
    assert "overflow-wrap:anywhere" in head[:head.index(">")]


# -- 2: continuous joints ----------------------------------------------------------------------------
@pytest.mark.parametrize("typed, shown", [("450", 90.0), ("720", 0.0), ("-400", -40.0), ("-540", 180.0)])
def test_a_continuous_joints_typed_angle_past_its_span_is_wrapped(typed, shown):
    st = _kinova()
    robot = st.robots[0]
    lo, hi = st.joint_limits(robot)
    assert not np.isfinite(lo[0]) and not np.isfinite(hi[0])  # j2s6s200_joint_1 is continuous
    st.set_joint(robot, 0, typed, deg=True)
    snap = st.snapshot()
    assert abs(math.remainder(math.degrees(snap.q[robot][0]) - shown, 360.0)) < 1e-9
    assert -180.0 <= math.degrees(snap.q[robot][0]) <= 180.0
    assert not snap.message_is_error and f"{typed} deg wrapped to" in snap.message


def test_a_continuous_joint_within_its_span_is_kept_and_a_limited_joint_is_refused():
    st = _kinova()
    robot = st.robots[0]
    st.set_joint(robot, 0, "270", deg=True)  # within -360..360: as typed, no note
    assert math.degrees(st.snapshot().q[robot][0]) == pytest.approx(270.0) and not st.snapshot().message
    before = st.snapshot().q[robot].copy()
    with pytest.raises(ConsoleInputError, match=r"j2s6s200_joint_2: 400 deg is outside \[47, 313\] deg"):
        st.set_joint(robot, 1, "400", deg=True)
    assert np.array_equal(st.snapshot().q[robot], before)


def test_the_box_and_the_slider_both_show_the_wrapped_angle():
    if not _kinova_available():
        pytest.skip("kinova's package (example-robot-data) is not installed")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        app = serve("kinova", port=0, block=False)
    try:
        robot = app.state.robots[0]
        fields, sliders, _ = app._w_joints[robot]
        assert "continuous" in fields[0].handle.hint and "continuous" not in fields[1].handle.hint
        fields[0].enter("450")
        assert fields[0].shown == "90" and fields[0].handle.value == "90"
        assert sliders[0].value == pytest.approx(90.0) and (sliders[0].min, sliders[0].max) == (-360.0, 360.0)
    finally:
        app.stop()


# -- 3: a refusal goes when its field accepts a value ---------------------------------------------
def test_an_accepted_value_clears_its_fields_refusal(ranger_app):
    app, st = ranger_app, ranger_app.state
    st.set_mode("cartesian")
    step = app._jog.f_step
    step.enter("-5")
    snap = st.snapshot()
    assert snap.message_is_error and snap.message == "jog step: -5 mm is outside (0, 500] mm; value kept unchanged"
    step.enter("0")  # 0 is excluded, and the range says so
    assert st.snapshot().message == "jog step: 0 mm is outside (0, 500] mm; value kept unchanged"
    step.enter("20")
    assert app._jog.step == pytest.approx(0.02)
    assert not st.snapshot().message_is_error and not st.snapshot().message
    assert 'id="armguard-message"' not in app._panel.content

    # the threshold typed equal to the value in force: nothing to apply, the refusal goes all the same
    thr = app._fields["thr"]
    thr.enter("-5")
    assert st.snapshot().message_is_error and "threshold" in st.snapshot().message
    thr.enter(thr.shown)
    assert not st.snapshot().message_is_error and not st.snapshot().message


def test_another_fields_accepted_value_leaves_a_refusal_in_place(ranger_app):
    app, st = ranger_app, ranger_app.state
    app._jog.f_step.enter("-5")
    app._jog.f_turn.enter("10")  # another field: the step's refusal stays until the step is fixed
    assert st.snapshot().message_is_error and "jog step" in st.snapshot().message
    st.note_error("display error: something else")
    assert not st.clear_error("jog step (mm)")  # a newer message is not the step's
    assert st.snapshot().message == "display error: something else"


# -- 4: the Cartesian target rounded for display --------------------------------------------------
def test_the_cartesian_target_fields_show_rounded_values_and_the_target_stays_exact(ranger_app):
    from armguard.console._app import target_texts

    pos, rpy = target_texts([0.791021, 1.529183, 3.90433e-16], np.radians([-90.0, 2.53928e-14, -86.34737]))
    assert (pos, rpy) == ("0.791, 1.5292, 0", "-90, 0, -86.35")
    app, st = ranger_app, ranger_app.state
    st.set_mode("cartesian")
    _pose(st, "left_arm", {0: "33.3333", 1: "47.7777"})
    app._redraw(force=True)
    p, r, _ = st.snapshot().target
    for field, exact, k in ((app._fields["pos"], p, 1.0), (app._fields["rpy"], np.degrees(r), 1.0)):
        shown = np.array([float(x) for x in field.shown.split(",")])
        assert "e" not in field.shown
        assert np.all(np.abs(shown - exact * k) <= (0.5e-4 if field is app._fields["pos"] else 0.5e-2) + 1e-12)
    assert not np.array_equal(np.round(p, 4), p)  # the state kept the exact target, not the shown one


# -- 5: Stop on top of the Tests tab, red ----------------------------------------------------------
def test_the_stop_button_comes_first_in_the_tests_tab_and_is_red(ranger_app):
    app = ranger_app
    assert app._b_stop.visible and app._b_stop.color == "red"
    assert app._b_stop.order < app._w_run_state.order < app._w_tests.order


# -- 6: another arm's near miss stays in view ------------------------------------------------------
def test_a_near_miss_of_an_arm_that_is_not_active_is_named_in_the_panel():
    st = make_state("ranger")
    st.set_threshold("0.1")
    _pose(st, "left_arm", LEFT_NEAR_MODULE)
    assert st.snapshot().readout.status is PanelStatus.WARNING and st.snapshot().others == ()  # it is the panel's
    st.set_active("right_arm")
    snap = st.snapshot()
    assert snap.readout.status is PanelStatus.CLEAR
    (o,) = snap.others
    assert (o.robot, o.status, o.link, o.obstacle) == ("left_arm", PanelStatus.WARNING, "left_arm/link5",
                                                       "manipulator_module")
    assert o.distance == pytest.approx(0.04133, abs=1e-4) and st.others_us > 0.0
    html = panel_html(snap.readout, others=snap.others, active=snap.active)
    assert 'data-arms="left_arm"' in html and "left_arm</b> (not active): WARNING 41.3 mm" in html
    _pose(st, "left_arm", LEFT_IN_MODULE)  # in collision: said as such
    assert [(o.robot, o.status) for o in st.snapshot().others] == [("left_arm", PanelStatus.COLLISION)]
    st.set_threshold("0.01")
    _pose(st, "left_arm", {3: "60"})  # 133 mm away, beyond the threshold: no notice
    assert st.snapshot().others == ()
    st.set_detection(False)
    assert st.snapshot().others == () and st.others_us == 0.0


# -- 7: a deep contact drawn alike for every backend -----------------------------------------------
def test_in_a_deep_contact_the_obstacle_is_translucent_for_every_backend(ranger_app):
    app, st = ranger_app, ranger_app.state
    _pose(st, "left_arm", LEFT_IN_MODULE)
    for backend in [b for b in ("analytic", "coal", "fcl") if b in st.backends]:
        st.set_backend(backend)
        snap = st.snapshot()
        r = snap.readout
        assert r.distance == pytest.approx(-0.245, abs=1e-3) and r.owner_b == "manipulator_module", backend
        clear = {app.drawer.items[k].owner for k in app.drawer.see_through(snap)}
        assert "manipulator_module" in clear and "left_arm/link7" not in clear, (backend, clear)


def test_a_refusal_names_the_joint_limits_not_the_tolerance_that_widens_them():
    """A value a hair outside a limit (within the Model's joint-limit tolerance) is taken, clipped; a refusal names
    the limits as the URDF gives them: Ranger's camera-arm shoulder's lower limit 0 read "-1e-09" before."""
    st = make_state("ranger")
    robot = next(r for r in st.robots if "camera" in r)
    lo, hi = (math.degrees(x[1]) for x in st.joint_limits(robot))  # the shoulder, joint 1
    assert lo == 0.0
    with pytest.raises(ConsoleInputError) as err:
        st.set_joint(robot, 1, "-5", deg=True)
    assert f"is outside [0, {hi:g}] deg; value kept unchanged" in str(err.value) and "e-" not in str(err.value)
    st.set_joint(robot, 1, "-1e-8", deg=True)  # within the tolerance (1e-9 rad, 5.7e-8 deg): taken at the limit
    assert st.snapshot().q[robot][1] == 0.0
