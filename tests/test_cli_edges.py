"""``armguard edges MODEL EDGES.npz``: the verdicts of ``Verifier.check_edges``, its exit status, its file."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

import armguard
from armguard.cli import ExitCode, main
from armguard.verify import EdgeStatus, Verifier


@pytest.fixture(scope="module")
def ur5():
    m = armguard.load_model("ur5")
    Q = m.random_q(400, 4)
    return m, m.scene_q(Q[~armguard.checker(m).collides(Q)])


def _run(*args):
    return CliRunner().invoke(main, list(args))


def test_the_verdicts_and_the_file_are_check_edges(ur5, tmp_path):
    m, Q = ur5
    Q0, Q1 = Q[:40], Q[40:80]
    np.savez(tmp_path / "e.npz", Q0=Q0, Q1=Q1)
    res = _run("edges", "ur5", str(tmp_path / "e.npz"), "--out", str(tmp_path / "r.npz"), "--first-contact")
    ref = Verifier(m.scene).check_edges(Q0, Q1, first_contact=True)
    assert ref.counts()["collision"] > 0
    assert res.exit_code == ExitCode.UNSAFE, res.output
    assert f"40 edges of 'ur5': {ref.counts()['clear']} clear, {ref.counts()['collision']} in collision" in res.output
    with np.load(tmp_path / "r.npz") as f:
        np.testing.assert_array_equal(f["code"], ref.code)
        np.testing.assert_array_equal(f["s"], ref.s)
        np.testing.assert_array_equal(f["s_free"], ref.s_free)
        hit = ref.code == EdgeStatus.COLLISION
        assert list(f["pair_a"][hit]) == [p[0] for p in ref.pair[hit]]
        assert list(f["q_joint_names"]) == list(m.scene.robots["ur5"].joint_names)
        assert str(f["robot"]) == "ur5" and float(f["margin"]) == 0.0 and len(f["held_names"]) == 0


def test_clear_edges_exit_0_and_a_spent_budget_exits_5(ur5, tmp_path):
    m, Q = ur5
    v = Verifier(m.scene)
    Q0 = Q[:30]
    Q1 = Q0 + np.clip(Q[30:60] - Q0, -0.02, 0.02)  # short edges between free configurations
    ref = v.check_edges(Q0, Q1)
    keep = ref.clear
    assert keep.sum() >= 10
    np.savez(tmp_path / "ok.npz", Q0=Q0[keep], Q1=Q1[keep])
    ok = _run("edges", "ur5", str(tmp_path / "ok.npz"))
    assert ok.exit_code == ExitCode.OK, ok.output
    long = Q0 + np.clip(Q[30:60] - Q0, -1.0, 1.0)
    r = v.check_edges(Q0, long)
    need = r.clear & (r.evaluations > 2)
    assert need.any()
    np.savez(tmp_path / "inc.npz", Q0=Q0[need], Q1=long[need])
    inc = _run("edges", "ur5", str(tmp_path / "inc.npz"), "--max-evaluations", "2")
    assert inc.exit_code == ExitCode.INCOMPLETE, inc.output
    assert f"{need.sum()} incomplete" in inc.output


def test_a_joint_subset_and_every_robot(tmp_path):
    """``joint_names`` in the file (Panda's arm group, the finger held); ``--robot '*'`` on Ranger."""
    m = armguard.load_model("panda")
    arm = list(m.group_joints("arm"))
    robot = next(iter(m.scene.robots))
    full = list(m.scene.robots[robot].joint_names)
    Q = m.scene_q(m.random_q(20, 3))[:, [full.index(j) for j in arm]]
    np.savez(tmp_path / "p.npz", Q0=Q[:10], Q1=Q[10:], joint_names=np.array(arm))
    res = _run("edges", "panda", str(tmp_path / "p.npz"))
    ref = Verifier(m.scene).check_edges(Q[:10], Q[10:], joints=arm)
    assert res.exit_code == (ExitCode.OK if ref.clear.all() else ExitCode.UNSAFE), res.output
    r = armguard.load_model("ranger")
    home = r.scene.flat_q(r.scene.default_q())
    np.savez(tmp_path / "r.npz", Q0=home[None], Q1=home[None], joint_names=np.array(r.scene.joint_names))
    res = _run("edges", "ranger", str(tmp_path / "r.npz"))
    assert res.exit_code == ExitCode.INPUT and "pass --robot (" in res.output, res.output  # several robots
    res = _run("edges", "ranger", str(tmp_path / "r.npz"), "--robot", "*")
    assert res.exit_code == ExitCode.OK and "1 edges of every robot (*): 1 clear" in res.output, res.output
    np.savez(tmp_path / "pin.npz", Q0=r.pin_q(home)[None], Q1=r.pin_q(home)[None])  # Pinocchio's order, unnamed
    res = _run("edges", "ranger", str(tmp_path / "pin.npz"), "--robot", "*")
    assert res.exit_code == ExitCode.INPUT and "orders its joints for Pinocchio otherwise" in res.output, res.output
    np.savez(tmp_path / "group.npz", Q0=Q[:10], Q1=Q[10:], joint_names=np.array("arm"))  # an SRDF group
    res = _run("edges", "panda", str(tmp_path / "group.npz"), "--out", str(tmp_path / "g.npz"))
    assert res.exit_code == (ExitCode.OK if ref.clear.all() else ExitCode.UNSAFE), res.output
    assert "held at home" in res.output
    with np.load(tmp_path / "g.npz") as f:
        assert list(f["joint_names"]) == arm and len(f["held_names"]) == 1
        np.testing.assert_array_equal(f["code"], ref.code)


def test_one_start_and_many_goals_past_the_progress_bar(ur5, tmp_path):
    """One start against 300 goals (past the bar's threshold): every edge is checked, as ``check_edges`` does."""
    m, Q = ur5
    goals = Q[1:] if len(Q) > 300 else np.concatenate([Q[1:]] * (300 // (len(Q) - 1) + 1))
    goals = goals[:300]
    np.savez(tmp_path / "fan.npz", Q0=Q[0], Q1=goals)
    res = _run("edges", "ur5", str(tmp_path / "fan.npz"), "--out", str(tmp_path / "fan_out.npz"))
    ref = Verifier(m.scene).check_edges(Q[0], goals)
    assert len(ref) == 300 and res.exit_code == (ExitCode.OK if ref.clear.all() else ExitCode.UNSAFE), res.output
    with np.load(tmp_path / "fan_out.npz") as f:
        np.testing.assert_array_equal(f["code"], ref.code)
    bad = goals.copy()
    bad[270, 2] = 9.0  # out of limits far past the first 256: named at its own index
    np.savez(tmp_path / "late.npz", Q0=Q[0], Q1=bad)
    res = _run("edges", "ur5", str(tmp_path / "late.npz"))
    assert res.exit_code == ExitCode.INPUT and "Q1[270]" in res.output, res.output


def test_a_file_that_is_no_edges_file_is_named(tmp_path):
    (tmp_path / "bad.npz").write_text("not an archive")
    res = _run("edges", "ur5", str(tmp_path / "bad.npz"))
    assert res.exit_code == ExitCode.INPUT and "bad.npz: not an .npz file of edges" in res.output
    np.savez(tmp_path / "keys.npz", A=np.zeros((1, 6)))
    res = _run("edges", "ur5", str(tmp_path / "keys.npz"))
    assert res.exit_code == ExitCode.INPUT and "expected arrays 'Q0' and 'Q1'" in res.output and "['A']" in res.output
    np.savez(tmp_path / "wide.npz", Q0=np.zeros((1, 9)), Q1=np.zeros((1, 9)))
    res = _run("edges", "ur5", str(tmp_path / "wide.npz"))
    assert res.exit_code == ExitCode.INPUT and "Q0: expected shape (M, 6)" in res.output
    res = _run("edges", "ur5", str(tmp_path / "none.npz"))
    assert res.exit_code == ExitCode.INPUT and "none.npz: no such file" in res.output
    assert _run("edges", "ur5", str(tmp_path / "keys.npz"), "--max-evaluations", "1").exit_code == ExitCode.USAGE
    np.savez(tmp_path / "names.npz", Q0=np.zeros((1, 6)), Q1=np.zeros((1, 6)), joint_names=np.array(["a", "b"]))
    res = _run("edges", "ur5", str(tmp_path / "names.npz"))
    assert res.exit_code == ExitCode.INPUT and "joint_names names 2 joints, Q0 has 6 columns" in res.output
    np.savez(tmp_path / "unknown.npz", Q0=np.zeros((1, 1)), Q1=np.zeros((1, 1)), joint_names=np.array(["wrist3_joint"]))
    res = _run("edges", "ur5", str(tmp_path / "unknown.npz"))
    assert res.exit_code == ExitCode.INPUT and "unknown.npz: joint_names: 'wrist3_joint' is not a joint" in res.output
    (tmp_path / "folder").mkdir()
    res = _run("edges", "ur5", str(tmp_path / "names.npz"), "--out", str(tmp_path / "folder"))
    assert res.exit_code == ExitCode.INPUT and "folder" in res.output and "joint_names" not in res.output  # before the work
