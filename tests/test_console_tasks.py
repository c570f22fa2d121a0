"""The console's task menu, jogging and training views without a browser (issue 24, item 7).

Jogging: the pose arithmetic against a slow reference built from homogeneous matrices and
scipy's rotations (hypothesis), then through the PUMA 560's IK in a console state.  The task
menu: the PLACE release height from the objects' sizes equals the hand-written demonstration
program's; a saved file reads back to the same listing; bad answers are refused and change
nothing; a program runs, lands on the time line, and one whose motion collides stops there with
the report.  Training views: the camera quaternions against their definition.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from armguard.console import ConsoleInputError
from armguard.console._jog import frame_pose, jog, jogged_pose, parse_step_mm, parse_turn_deg
from armguard.console._serve import make_state
from armguard.console._tasks import TaskComposer, carried, held_intervals, program_timeline, task_ends
from armguard.console._views import camera_wxyz, eye_in_hand, inset_camera
from armguard.program import load_cell, load_program

CELL = Path(__file__).resolve().parent.parent / "examples" / "workmate" / "cell.yaml"
STACK = CELL.parent / "stack.yaml"


def _pose(rotvec, p) -> np.ndarray:
    X = np.eye(4)
    X[:3, :3] = Rotation.from_rotvec(rotvec).as_matrix()
    X[:3, 3] = p
    return X


vec = st.lists(st.floats(-2.0, 2.0, allow_nan=False), min_size=3, max_size=3)


@settings(max_examples=60, deadline=None)
@given(vec, vec, vec, vec, st.integers(0, 2), st.floats(-0.5, 0.5), st.floats(-3.0, 3.0))
def test_jogged_pose_matches_the_matrix_reference(rE, pE, rF, pF, k, s, theta):
    X_WE, X_WF = _pose(rE, pE), _pose(rF, pF)
    e = np.zeros(3)
    e[k] = 1.0
    # reference: the step expressed in F, conjugated into W, applied on the left (about the tool point)
    T = np.eye(4)
    T[:3, 3] = s * e
    moved = X_WF @ T @ np.linalg.inv(X_WF) @ X_WE
    assert np.allclose(jogged_pose(X_WE, X_WF, k, translate=s), moved, atol=1e-12)
    R = np.eye(4)
    R[:3, :3] = Rotation.from_rotvec(theta * e).as_matrix()
    to_p, back = np.eye(4), np.eye(4)
    to_p[:3, 3], back[:3, 3] = X_WE[:3, 3], -X_WE[:3, 3]
    R_F = np.eye(4)
    R_F[:3, :3] = X_WF[:3, :3]  # F's axes, through the tool point
    turned = to_p @ R_F @ R @ R_F.T @ back @ X_WE
    assert np.allclose(jogged_pose(X_WE, X_WF, k, turn=theta), turned, atol=1e-12)
    # in the tool's own frame the jog is a right multiplication
    assert np.allclose(jogged_pose(X_WE, X_WE, k, translate=s), X_WE @ T, atol=1e-12)
    assert np.allclose(jogged_pose(X_WE, X_WE, k, turn=theta), X_WE @ R, atol=1e-12)


@pytest.fixture(scope="module")
def puma():
    return make_state(str(CELL))


def test_jog_in_tool_base_and_object_axes_through_ik(puma):
    stt = puma
    q_home = stt.snapshot().q["puma560"].copy()
    try:
        X0 = stt.ee_pose()
        jog(stt, "tool", "x", translate=0.02)
        X1 = stt.ee_pose()
        assert np.allclose(X1[:3, 3] - X0[:3, 3], 0.02 * X0[:3, 0], atol=1e-6)  # along the tool's own x
        assert np.allclose(X1[:3, :3], X0[:3, :3], atol=1e-6)
        jog(stt, "tool", "z", turn=math.radians(10.0))
        X2 = stt.ee_pose()
        assert np.allclose(X2[:3, 3], X1[:3, 3], atol=1e-6)  # turned about the tool point
        assert np.allclose(X2[:3, :3], X1[:3, :3] @ Rotation.from_euler("z", 10, degrees=True).as_matrix(), atol=1e-6)
        jog(stt, "base", "z", translate=-0.01)
        X3 = stt.ee_pose()
        assert np.allclose(X3[:3, 3] - X2[:3, 3], -0.01 * np.asarray(stt.scene.robots["puma560"].X_WB)[:3, 2], atol=1e-6)
        X_WO = frame_pose(stt, "cylinder_a", stt.cell)
        assert np.array_equal(X_WO, stt.cell.objects["cylinder_a"])
        jog(stt, "cylinder_a", "y", translate=0.015, cell=stt.cell)
        assert np.allclose(stt.ee_pose()[:3, 3] - X3[:3, 3], 0.015 * X_WO[:3, 1], atol=1e-6)
        # an unreachable jog: refused, the arm where it was
        q = stt.snapshot().q["puma560"].copy()
        with pytest.raises(ConsoleInputError, match="arm kept where it was"):
            jog(stt, "world", "x", translate=5.0)
        assert np.array_equal(stt.snapshot().q["puma560"], q)
        with pytest.raises(ConsoleInputError, match="unknown frame"):
            jog(stt, "nowhere", "x", translate=0.01)
        with pytest.raises(ConsoleInputError, match="unknown axis"):
            jog(stt, "tool", "w", translate=0.01)
    finally:
        stt.set_joints("puma560", q_home)


@pytest.mark.parametrize("text", ["0", "-5", "abc", "nan", "1e309", "501"])
def test_jog_steps_are_validated(text):
    with pytest.raises(ConsoleInputError):
        parse_step_mm(text)
    with pytest.raises(ConsoleInputError):
        parse_turn_deg(text if text != "501" else "91")
    assert parse_step_mm("20") == pytest.approx(0.02) and parse_turn_deg("90") == pytest.approx(math.pi / 2)


@pytest.fixture(scope="module")
def cell():
    return load_cell(CELL)


def _stack(cell) -> TaskComposer:
    tc = TaskComposer(cell, cell_ref=str(CELL), name="stack_cylinders")
    tc.add("FIND", object="cylinder_a")
    tc.add("FIND", object="cylinder_b")
    tc.add("PICKUP", object="cylinder_a")
    tc.add("PLACE", object="cylinder_a", onto="cylinder_b")
    tc.add("MOVE", home=True)
    return tc


def test_menu_poses_match_the_demonstration_program(cell):
    """The grasp and the release made from the objects' sizes are the hand-written program's."""
    mine = {(s.label.split(" ", 1)[1], s.op): s.args for s in _stack(cell).program().steps()}
    ref = {(s.label.split(" ", 1)[1], s.op): s.args for s in load_program(STACK).steps()}
    assert set(mine) == set(ref)
    for key in (("PICKUP cylinder_a grasp", "move"), ("PLACE cylinder_a release", "move")):
        assert np.allclose(mine[key][0], ref[key][0], atol=1e-12) and np.allclose(mine[key][1], ref[key][1])
        assert mine[key][2:] == ref[key][2:]  # mode and what it may touch
    assert [s.op for s in _stack(cell).program().steps()] == [s.op for s in load_program(STACK).steps()]


def test_saved_program_reads_back_to_the_same_listing(cell, tmp_path):
    tc = _stack(cell)
    stt = make_state(str(CELL))
    tc.add("MOVE", frame="cylinder_b", xyz=(0.01, -0.02, 0.3), rpy_deg=(180.0, 0.0, 12.5), mode="line")
    out = tc.save(tmp_path / "p.yaml")
    back = load_program(out)
    assert Path(back.cell).resolve() == CELL and back.name == "stack_cylinders"
    a, b = tc.program().steps(), back.steps()
    assert [(s.op, s.args, s.label) for s in a] == [(s.op, s.args, s.label) for s in b]
    assert tc.lines()[-1].startswith("6. MOVE to cylinder_b")
    del stt


def test_a_saved_program_finds_its_cell_from_any_folder(cell, tmp_path, monkeypatch):
    """The console was given the cell as ``examples/workmate/cell.yaml`` (relative to where it ran): the saved
    file named it so, and ``armguard program run`` found it only from that folder; a program file's cell is read
    relative to the program file, never from the working directory (another folder's ``cell.yaml`` ran)."""
    root = CELL.parents[2]
    monkeypatch.chdir(root)
    tc = TaskComposer(cell, cell_ref=str(CELL.relative_to(root)))
    tc.add("FIND", object="cylinder_a")
    (tmp_path / "saved").mkdir()
    out = tc.save(tmp_path / "saved" / "p.yaml")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "cell.yaml").write_text("not this one\n")
    monkeypatch.chdir(elsewhere)
    assert Path(load_program(out).cell).resolve() == CELL
    lone = tmp_path / "lone"
    lone.mkdir()
    (lone / "p.yaml").write_text(re.sub(r"(?m)^cell: .*$", "cell: cell.yaml", out.read_text()))
    assert load_program(lone / "p.yaml").spec.cell == "cell.yaml"
    assert load_program(lone / "p.yaml").cell == str(lone / "cell.yaml")  # not elsewhere/cell.yaml


def test_bad_answers_are_refused_and_add_nothing(cell):
    tc = TaskComposer(cell)
    for kw, msg in ((dict(kind="PLACE", object="cylinder_a", onto="cylinder_b"), "does not hold"),
                    (dict(kind="PICKUP", object="robot"), "not an object"),
                    (dict(kind="FIND", object=None), "not an object"),
                    (dict(kind="MOVE", frame="moon"), "not a frame"),
                    (dict(kind="PICKUP", object="cylinder_a", grasp="abc"), "grasp height"),
                    (dict(kind="PICKUP", object="cylinder_a", lift=-1), "approach lift"),
                    (dict(kind="JUMP"), "expected one of")):
        with pytest.raises(ConsoleInputError, match=msg):
            tc.add(**kw)
    assert tc.entries == []
    tc.add("PICKUP", object="cylinder_a")
    with pytest.raises(ConsoleInputError, match="already holds"):
        tc.add("PICKUP", object="cylinder_b")
    with pytest.raises(ConsoleInputError, match="onto itself"):
        tc.add("PLACE", object="cylinder_a", onto="cylinder_a")
    with pytest.raises(ConsoleInputError, match="holds cylinder_a"):
        tc.add("FIND", object="cylinder_a")
    assert len(tc.entries) == 1
    with pytest.raises(ConsoleInputError, match="no tasks"):
        TaskComposer(cell).text()


def test_run_goes_on_the_time_line_and_a_collision_stops_it(cell):
    tc = TaskComposer(load_cell("puma560"), cell_ref="puma560")
    tc.add("PICKUP", object="cylinder_a")
    run = tc.run()
    assert run.ok and len(run.motions) == 3
    traj, times, clearance = program_timeline(run)
    assert traj.duration == pytest.approx(sum(m.trajectory.duration for m in run.motions))
    assert np.array_equal(traj.at(traj.duration), run.motions[-1].trajectory.waypoints[-1])
    assert np.all(np.diff(times) >= 0) and times[-1] == pytest.approx(traj.duration)
    assert np.nanmin(clearance) == pytest.approx(min(m.min_clearance for m in run.motions))
    # the tool driven into the table: verification refuses it, the run stops there with the report
    bad = TaskComposer(load_cell("puma560"), cell_ref="puma560")
    bad.add("MOVE", frame="table", xyz=(-0.1, 0.0, 0.2), rpy_deg=(180.0, 0.0, 0.0), mode="joint")
    bad.add("MOVE", home=True)
    r = bad.run()
    assert not r.ok and "refused" in r.motions[-1].status and "STOPPED" in r.summary()
    assert len(r.motions) == 1  # MOVE home never ran


def test_training_view_cameras():
    X = _pose([0.3, -1.1, 0.4], [0.5, 0.1, 0.7])
    p, look, up = eye_in_hand(X)
    assert np.allclose(p, X[:3, 3]) and np.allclose((look - p) / np.linalg.norm(look - p), X[:3, 2])
    R = Rotation.from_quat(np.roll(camera_wxyz(p, look, up), -1)).as_matrix()  # scipy: x, y, z, w
    assert np.allclose(R, X[:3, :3], atol=1e-12)  # camera axes = tool axes (x right, y down, z ahead)
    c = np.array([0.2, -0.1, 0.5])
    for label, ahead in (("top", [0, 0, -1]), ("front", [-1, 0, 0]), ("side", [0, 1, 0])):
        pos, wxyz, fov = inset_camera(label, c, 1.0)
        R = Rotation.from_quat(np.roll(wxyz, -1)).as_matrix()
        assert np.allclose(R[:, 2], ahead, atol=2e-3), label  # looking at the centre along the preset
        assert np.allclose(pos + R[:, 2] * np.linalg.norm(pos - c), c, atol=1e-9)  # its axis through the centre
        assert np.linalg.norm(pos - c) * math.sin(fov / 2) == pytest.approx(1.0)  # the scene's sphere fills it


def test_carried_objects_follow_the_hand_to_where_the_workcell_put_them():
    """The display's carry (the tool's motion since the grasp) puts the object where the emulation's
    own bookkeeping (ProgramRun.believed) has it: lifted by the depart, then set on the target."""
    cell = load_cell("puma560")
    tc = TaskComposer(cell, cell_ref="puma560")
    tc.add("PICKUP", object="cylinder_a")
    tc.add("PLACE", object="cylinder_a", onto="cylinder_b")
    run = tc.run()
    assert run.ok, run.summary()
    d = [m.trajectory.duration for m in run.motions]
    iv = held_intervals(run)
    assert iv == [("cylinder_a", pytest.approx(d[0] + d[1]), pytest.approx(sum(d[:5])))]
    traj = program_timeline(run)[0]
    arm = cell.model.scene.robots[cell.robot]
    at = lambda t: arm.link_pose(traj.at(t))  # noqa: E731
    X0 = cell.objects["cylinder_a"]
    D = carried(iv, at, d[0] + d[1] + d[2])  # after the depart: lifted straight up by the lift
    assert np.allclose(D["cylinder_a"][:3, 3], [0.0, 0.0, 0.10], atol=1e-6) and np.allclose(D["cylinder_a"][:3, :3], np.eye(3), atol=1e-6)
    assert np.allclose(carried(iv, at, 0.5 * d[0])["cylinder_a"], np.eye(4))  # not yet grasped
    D = carried(iv, at, traj.duration)
    assert np.allclose(D["cylinder_a"] @ X0, run.believed["cylinder_a"], atol=1e-9)
    ends = task_ends(run)
    assert [k for _, k in ends] == [0, 0, 0, 1, 1, 1] and ends[-1][0] == pytest.approx(traj.duration)


def test_tasks_panel_in_process_draws_bound_frames_and_stops_on_a_collision():
    """The panel's commands without a browser: prompts answered in turn by picks, a FIND's bound
    frame drawn beside its nominal one, a refused motion's report in the panel with the run stopped."""
    from armguard.console._serve import serve

    app = serve(str(CELL), port=0, block=False)
    try:
        panel, st = app._tasks, app.state
        app._jog._set_step("25")  # a typed step: in force and shown (a refusal puts the box back to it)
        assert app._jog.step == pytest.approx(0.025) and app._jog.f_step.shown == "25"
        with pytest.raises(ConsoleInputError):
            app._jog._set_step("-1")
        assert app._jog.step == pytest.approx(0.025) and app._jog.f_step.shown == "25"
        panel.w_kind.value = "PLACE"
        panel._kind_changed()
        assert panel.picked("cylinder_a") == "object" and panel.picked("cylinder_b") == "onto"
        assert (panel.w_object.value, panel.w_onto.value) == ("cylinder_a", "cylinder_b")
        with pytest.raises(ConsoleInputError, match="not an object"):
            panel.picked("puma560/link2")
        panel._do(panel._add)  # PLACE with nothing held: refused, said in the panel
        assert panel.composer.entries == [] and "does not hold" in st.snapshot().message
        panel.w_kind.value = "FIND"
        panel._kind_changed()
        panel.picked("cylinder_a")
        panel._add()
        run = panel.run()
        assert run.ok and len(run.finds) == 1 and len(panel._frames) == 2
        f = run.finds[0]
        nominal, found = panel._frames
        assert np.allclose(nominal.position, f.nominal[:3, 3]) and np.allclose(found.position, f.found[:3, 3])
        assert not np.allclose(f.found[:3, 3], f.nominal[:3, 3], atol=1e-3)  # the real cell differs: two frames
        # a motion into the table: refused by verification; the program stops there, the report says so
        panel.composer.clear()
        panel.composer.add("MOVE", frame="table", xyz=(-0.1, 0.0, 0.2), rpy_deg=(180.0, 0.0, 0.0))
        panel.composer.add("MOVE", home=True)
        run = panel.run()
        assert not run.ok and len(run.motions) == 1
        assert "STOPPED" in panel.w_report.content and st.snapshot().message_is_error
        p = st.snapshot().player
        assert p is not None and p.report is run and "refused" in p.report.summary()
    finally:
        app.stop()
