"""A review of the console's state (no browser): each test is a defect found by running it.

A verified trajectory said safe through the terrain, a canned run stopped checking the arm it moved
when another arm was selected, the coal and fcl panels measured a removed workspace box, Stop during
an avoidance run's filtering was ignored, and stale state (run status, uncertain placements, the
arm angle) outlived what it described.
"""

from __future__ import annotations

import math
import threading
from pathlib import Path

import numpy as np
import pytest

from armguard.console import ConsoleInputError, ConsoleState
from armguard.console._serve import make_state
from armguard.scene import load_scene

DATA = Path(__file__).parent / "data"
SCENE = DATA / "console_scene.yaml"
ROOT = Path(__file__).resolve().parents[1]


def test_a_verified_trajectory_is_checked_against_the_loaded_terrain():
    """rover's place_instrument goes 22 mm into reference/terrain/rocky.npz (`armguard verify ... --terrain`):
    the console said "safe" and its clearance plot left the terrain out."""
    st = make_state("rover", terrain=str(ROOT / "reference" / "terrain" / "rocky.npz"))
    p = st.load_trajectory("place_instrument")
    assert "NOT safe" in st.snapshot().message and not p.report.safe
    assert p.clearance.min() < 0.0  # the terrain's contact shows in the profile


def test_another_arm_cannot_be_selected_while_a_run_moves_one():
    """The run stops on the active arm's readout: selecting the right arm mid-run let the left arm play through
    the post with the panel CLEAR."""
    st = ConsoleState(load_scene(SCENE), threshold=0.05)
    st.set_stopping_distance("0.05")
    st.run("hit_post")
    st.tick(0.1)
    with pytest.raises(ConsoleInputError, match="left is running hit_post: stop it before selecting another arm"):
        st.set_active("right")
    for _ in range(400):
        st.tick(0.05)
    assert st.snapshot().run_state == "stopped by detection"
    st.set_active("right")  # once it stopped


def test_a_loaded_trajectory_ends_the_runs_running_status():
    st = ConsoleState(load_scene(SCENE), threshold=0.05)
    st.run("fold_right")
    st.tick(0.2)
    assert st.snapshot().run_state == "running"
    st.load_trajectory("fold_safely")
    assert st.snapshot().run_state == "stopped"  # said "running" with no run


@pytest.mark.parametrize("backend", ["coal", "fcl"])
def test_every_backend_measures_the_workspace_box_as_edited(backend):
    st = make_state(str(SCENE))
    st.set_workspace("-1, -1, -1", "0, 1, 1")
    st.set_joint("left", 0, "0", deg=True)  # left arm along +x: out of the box
    analytic = st.snapshot().readout.distance
    st.set_backend(backend)
    assert st.snapshot().readout.distance == pytest.approx(analytic, abs=1e-6)  # was the old box: +300 mm, clear
    st.remove_workspace()
    st.set_backend("analytic")
    d = st.snapshot().readout.distance
    st.set_backend(backend)
    assert st.snapshot().readout.distance == pytest.approx(d, abs=1e-6)


def _acting_while_filtered(monkeypatch, act) -> None:
    """Make the avoidance filter run ``act`` on another thread (the operator, meanwhile) before it filters."""
    import armguard.console._avoid as avoid

    real = avoid.avoid_canned

    def filtering_while_the_operator_acts(*args, **kwargs):
        t = threading.Thread(target=act)
        t.start()
        t.join()
        return real(*args, **kwargs)

    monkeypatch.setattr(avoid, "avoid_canned", filtering_while_the_operator_acts)


def test_stop_while_an_avoidance_run_is_filtered_keeps_the_arm_still(monkeypatch):
    st = make_state(str(SCENE))
    st.set_avoidance(True)
    _acting_while_filtered(monkeypatch, st.stop)  # Stop arrives on another thread meanwhile
    with pytest.raises(ConsoleInputError, match="stopped while the motion was filtered"):
        st.run("hit_post")
    s = st.snapshot()
    assert s.run_state == "stopped" and s.player is None
    q = s.q["left"].copy()
    for _ in range(10):
        st.tick(0.05)
    np.testing.assert_array_equal(st.snapshot().q["left"], q)


def test_uncertain_placements_move_with_their_body_on_reload(tmp_path):
    moved = tmp_path / "moved.yaml"
    text = SCENE.read_text()
    assert "xyz: [-0.8, 0.8, 0.0]" in text
    moved.write_text(text.replace("xyz: [-0.8, 0.8, 0.0]", "xyz: [-0.8, 1.3, 0.0]"))
    st = make_state(str(SCENE), uncertain=["post=0.02,5"])
    np.testing.assert_allclose(st.ellipsoids()[0].center[:2], [-0.8, 0.8])
    st.reload(load_scene(moved))
    np.testing.assert_allclose(st.ellipsoids()[0].center[:2], [-0.8, 1.3])  # stayed at 0.8
    fresh = make_state(str(moved), uncertain=["post=0.02,5"])
    fresh.set_q(st.snapshot().q)
    a, b = st.snapshot().sigmas.overall.nearest, fresh.snapshot().sigmas.overall.nearest
    assert (a.a, a.b) == (b.a, b.b) and a.sigmas == pytest.approx(b.sigmas, rel=1e-9)


def test_the_arm_angle_goes_back_to_0_when_the_arm_moves_otherwise():
    from armguard.console._jog import jog

    st = make_state("ranger")
    arm = st.snapshot().active
    for move in (lambda: st.set_joint(arm, 3, "10", deg=True), lambda: jog(st, "world", "x", translate=0.01),
                 lambda: st.set_q(st.scene.default_q())):
        st.set_arm_angle(math.radians(20))
        assert st.snapshot().arm_angle == pytest.approx(math.radians(20))
        move()
        assert st.snapshot().arm_angle == 0.0


def test_console_commands_refuse_what_is_not_a_number():
    st = make_state(str(SCENE))
    for args in (("post", "abc"), ("post", None), ("post", True), ("post", 0.02, "x")):
        with pytest.raises(ConsoleInputError, match="uncertain placement: sigma"):
            st.add_uncertain(*args)
    with pytest.raises(ConsoleInputError, match="joint index 'x'"):
        st.set_joint("left", "x", 0)


@pytest.mark.parametrize("meanwhile", ["setup", "arm", "joint"])
def test_a_setup_an_arm_or_a_joint_while_an_avoidance_run_is_filtered_drops_it(monkeypatch, meanwhile):
    """Ranger: Run test1 with avoidance, and while its motion is filtered, Setup test7 (or select another arm, or
    type a joint): test1's filtered motion then started anyway, the left arm moving under the right arm's panel."""
    from armguard.console._serve import make_state as make_named

    st = make_named("ranger")
    st.set_avoidance(True)
    _acting_while_filtered(monkeypatch, {"setup": lambda: st.setup("test7_right_inward"),
                                         "arm": lambda: st.set_active("right_arm"),
                                         "joint": lambda: st.set_joint("left_arm", 0, "-20", deg=True)}[meanwhile])
    with pytest.raises(ConsoleInputError, match="stopped while the motion was filtered"):
        st.run("test1_left_inward")
    s = st.snapshot()
    assert s.player is None and s.run_state in ("stopped", "")
