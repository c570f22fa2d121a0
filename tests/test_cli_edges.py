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
    assert "held still" in res.output
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


def _damaged(path, good):
    """``good`` (an .npz) with bytes flipped inside its first member's compressed data (zip CRC then fails)."""
    import zipfile

    np.savez_compressed(good, Q0=np.zeros((3, 6)), Q1=np.full((3, 6), 0.1))
    raw = bytearray(good.read_bytes())
    with zipfile.ZipFile(good) as z:
        info = z.infolist()[0]
    start = info.header_offset + 30 + len(info.filename) + len(info.extra)
    for k in range(start + 20, start + 30):
        raw[k] ^= 0xFF
    path.write_bytes(bytes(raw))


def test_a_damaged_or_odd_edges_file_is_named_not_an_internal_error(tmp_path):
    """Object arrays, a damaged member, no edge at all, joint_names of two dimensions or an unknown group: each
    named with the file and the array (exit 3), never an internal error (exit 4) or a vacuous 'all clear'."""
    np.savez(tmp_path / "obj.npz", Q0=np.array([np.zeros(6)], dtype=object), Q1=np.zeros((1, 6)))
    res = _run("edges", "ur5", str(tmp_path / "obj.npz"))
    assert res.exit_code == ExitCode.INPUT and "obj.npz: Q0: expected numbers (M, n), got an object array" in res.output
    np.savez(tmp_path / "str.npz", Q0=np.array([["a"] * 6]), Q1=np.zeros((1, 6)))  # it said "got ndarray"
    res = _run("edges", "ur5", str(tmp_path / "str.npz"))
    assert res.exit_code == ExitCode.INPUT and "str.npz: Q0: expected numbers (M, 6) or (6,), got an array of text" in res.output, res.output
    _damaged(tmp_path / "crc.npz", tmp_path / "good.npz")
    res = _run("edges", "ur5", str(tmp_path / "crc.npz"))
    assert res.exit_code == ExitCode.INPUT and "crc.npz: Q0: cannot read this array" in res.output, res.output
    np.savez(tmp_path / "empty.npz", Q0=np.zeros((0, 6)), Q1=np.zeros((0, 6)))
    res = _run("edges", "ur5", str(tmp_path / "empty.npz"))
    assert res.exit_code == ExitCode.INPUT and "empty.npz: Q0 holds no configuration" in res.output
    np.savez(tmp_path / "n2.npz", Q0=np.zeros((1, 6)), Q1=np.zeros((1, 6)), joint_names=np.array([["a", "b", "c"]] * 2))
    res = _run("edges", "ur5", str(tmp_path / "n2.npz"))
    assert res.exit_code == ExitCode.INPUT and "n2.npz: joint_names: expected one name per column" in res.output
    np.savez(tmp_path / "grp.npz", Q0=np.zeros((1, 7)), Q1=np.zeros((1, 7)), joint_names=np.array("no_such_group"))
    res = _run("edges", "panda", str(tmp_path / "grp.npz"))
    assert res.exit_code == ExitCode.INPUT and "grp.npz: joint_names:" in res.output and "no_such_group" in res.output
    names = list(armguard.load_model("ur5").scene.robots["ur5"].joint_names)
    np.savez(tmp_path / "bytes.npz", Q0=np.zeros((1, 6)), Q1=np.full((1, 6), 0.1), joint_names=np.array(names, dtype="S"))
    res = _run("edges", "ur5", str(tmp_path / "bytes.npz"))  # b'...' names read as text (were "b'shoulder_pan_joint'")
    assert res.exit_code in (ExitCode.OK, ExitCode.UNSAFE) and "1 edges of 'ur5'" in res.output, res.output
    np.savez(tmp_path / "nan.npz", Q0=np.zeros((2, 6)), Q1=np.full((2, 6), np.nan))
    res = _run("edges", "ur5", str(tmp_path / "nan.npz"))
    assert res.exit_code == ExitCode.INPUT and "Q1[0, 0]: NaN or infinite" in res.output, res.output


def test_an_out_that_cannot_be_written_is_refused_before_the_work(tmp_path, monkeypatch):
    """A read-only or full folder for --out: refused before the edges are certified (their verdicts would be
    lost), as srdf's --out before its matrix."""
    import errno

    import armguard._io as io

    np.savez(tmp_path / "e.npz", Q0=np.zeros((1, 6)), Q1=np.full((1, 6), 0.1))

    def read_only(*a, **k):
        raise OSError(errno.EROFS, "Read-only file system")

    monkeypatch.setattr(io.tempfile, "mkstemp", read_only)
    monkeypatch.setattr(Verifier, "check_edges", lambda *a, **k: pytest.fail("certified before --out was checked"))
    res = _run("edges", "ur5", str(tmp_path / "e.npz"), "--out", str(tmp_path / "r.npz"))
    assert res.exit_code == ExitCode.INPUT and "Read-only file system" in res.output and "r.npz" in res.output, res.output
    import armguard.srdfgen as srdfgen

    monkeypatch.setattr(srdfgen, "collision_matrix", lambda *a, **k: pytest.fail("computed before --out was checked"))
    res = _run("srdf", "ur5", "--out", str(tmp_path / "sub" / "ur5.srdf"))
    assert res.exit_code == ExitCode.INPUT and "Read-only file system" in res.output and "ur5.srdf" in res.output, res.output
    assert not list(tmp_path.glob("**/*.probe"))


def test_an_out_in_a_missing_folder_is_made_with_the_file_and_nothing_is_left_on_refusal(ur5, tmp_path):
    """--out under folders not made yet: checked where they would be made (nothing made before the work),
    then made with the file; a refused run (an unknown robot) leaves no folder behind."""
    m, Q = ur5
    np.savez(tmp_path / "e.npz", Q0=Q[:2], Q1=Q[2:4])
    res = _run("edges", "ur5", str(tmp_path / "e.npz"), "--out", str(tmp_path / "new" / "dir" / "r.npz"))
    assert res.exit_code in (ExitCode.OK, ExitCode.UNSAFE), res.output
    assert (tmp_path / "new" / "dir" / "r.npz").is_file()
    res = _run("srdf", "no_such_robot", "--out", str(tmp_path / "srdfout" / "a" / "x.srdf"))
    assert res.exit_code == ExitCode.INPUT and not (tmp_path / "srdfout").exists(), res.output
    (tmp_path / "afile").write_text("x")
    res = _run("edges", "ur5", str(tmp_path / "e.npz"), "--out", str(tmp_path / "afile" / "sub" / "r.npz"))
    assert res.exit_code == ExitCode.INPUT and "afile" in res.output, res.output


def test_too_few_columns_are_told_in_the_command_lines_words(tmp_path):
    """The hint for a subset of the joints named the Python argument ``joints=``; the file's array
    ``joint_names`` is what names the columns on the command line."""
    np.savez(tmp_path / "few.npz", Q0=np.zeros((2, 3)), Q1=np.full((2, 3), 0.1))
    r = CliRunner().invoke(main, ["edges", "puma560", str(tmp_path / "few.npz")])
    assert r.exit_code == 3 and "joint_names array" in r.output and "joints=" not in r.output, r.output


def test_category_margins_from_the_command_line(tmp_path):
    """``--margin 0.03 --category-margin arm-arm=0``: check_edges' margin by category, in the summary and the
    file (``margin_categories``, ``margins``); a bad one is a usage error, an unknown category exit 3."""
    m = armguard.load_model("hermes")
    rob = m.scene.robots["hera"]
    rng = np.random.default_rng(4)
    lo, hi = np.asarray(rob.lower), np.asarray(rob.upper)
    Q0 = lo + (hi - lo) * rng.random((40, 6))
    Q1 = np.clip(Q0 + 0.15 * (hi - lo) * (rng.random((40, 6)) - 0.5), lo, hi)
    np.savez(tmp_path / "e.npz", Q0=Q0, Q1=Q1)
    res = _run("edges", "hermes", str(tmp_path / "e.npz"), "--margin", "0.03", "--category-margin", "arm-arm=0",
               "--out", str(tmp_path / "r.npz"))
    ref = Verifier(m).check_edges(Q0, Q1, margin={"*": 0.03, "arm-arm": 0.0})
    assert res.exit_code == (ExitCode.UNSAFE if ref.counts()["collision"] else ExitCode.OK), res.output
    assert f"{ref.counts()['clear']} clear, {ref.counts()['collision']} in collision or within their category's margin " \
           "(arm-arm 0 mm, arm-payload 30 mm, arm-vehicle 30 mm, payload-vehicle 30 mm)" in res.output
    with np.load(tmp_path / "r.npz") as f:
        np.testing.assert_array_equal(f["code"], ref.code)
        assert list(f["margin_categories"]) == ["arm-arm", "arm-payload", "arm-vehicle", "payload-vehicle"]
        assert list(f["margins"]) == [0.0, 0.03, 0.03, 0.03] and "margin" not in f.files
    bad = _run("edges", "hermes", str(tmp_path / "e.npz"), "--category-margin", "arm-arm")
    assert bad.exit_code == ExitCode.USAGE and "expected CATEGORY=M" in bad.output
    unknown = _run("edges", "hermes", str(tmp_path / "e.npz"), "--category-margin", "arm-arms=0")
    assert unknown.exit_code == ExitCode.USAGE and "'arm-arms' is not a pair category; the categories: arm-arm" in unknown.output
    star = _run("edges", "hermes", str(tmp_path / "e.npz"), "--category-margin", "*=0.05")
    assert star.exit_code == ExitCode.USAGE and "'*' is --margin's" in star.output
    absent = _run("edges", "hermes", str(tmp_path / "e.npz"), "--margin", "0.03", "--category-margin", "arm-arm=0",
                  "--category-margin", "workspace=0.5")  # a category hermes has no pair in: passed over
    assert absent.exit_code == res.exit_code
    assert absent.output.split("(evaluations")[0] == res.output.split("(evaluations")[0]


def test_category_margins_that_agree_are_still_written_per_category(tmp_path):
    """``--margin 0.02 --category-margin arm-arm=0.02``: every category's margin the same, the file held one
    ``margin`` where ``--help`` promises ``margin_categories`` and ``margins`` (the mapping collapsed to a float)."""
    m = armguard.load_model("hermes")
    rob = m.scene.robots["hera"]
    lo, hi = np.asarray(rob.lower), np.asarray(rob.upper)
    Q0 = lo + (hi - lo) * np.random.default_rng(5).random((6, 6))
    np.savez(tmp_path / "e.npz", Q0=Q0, Q1=Q0[::-1])
    ref = Verifier(m).check_edges(Q0, Q0[::-1], margin={"*": 0.02, "arm-arm": 0.02})
    assert ref.margin == {"arm-arm": 0.02, "arm-payload": 0.02, "arm-vehicle": 0.02, "payload-vehicle": 0.02}
    _run("edges", "hermes", str(tmp_path / "e.npz"), "--margin", "0.02", "--category-margin", "arm-arm=0.02",
         "--out", str(tmp_path / "r.npz"))
    with np.load(tmp_path / "r.npz") as f:
        assert list(f["margins"]) == [0.02] * 4 and "margin" not in f.files
    assert Verifier(m).check_edges(Q0, Q0[::-1], margin=0.02).margin == 0.02  # one number given: one number


def test_an_unknown_array_such_as_a_misspelt_joint_names_is_refused(ur5, tmp_path):
    """``joint_name`` (for joint_names) was ignored: the columns, in another order, were read in the robot's
    own, and a colliding edge was certified CLEAR (exit 0)."""
    m, Q = ur5
    names = list(reversed(m.scene.robots[next(iter(m.scene.robots))].joint_names))
    np.savez(tmp_path / "typo.npz", Q0=Q[:3, ::-1], Q1=Q[3:6, ::-1], joint_name=np.array(names))
    res = _run("edges", "ur5", str(tmp_path / "typo.npz"))
    assert res.exit_code == ExitCode.INPUT, res.output
    assert "unknown array 'joint_name': did you mean 'joint_names'?" in res.output, res.output
    np.savez(tmp_path / "ok.npz", Q0=Q[:3, ::-1], Q1=Q[3:6, ::-1], joint_names=np.array(names), costs=np.ones(3))
    assert _run("edges", "ur5", str(tmp_path / "ok.npz")).exit_code in (ExitCode.OK, ExitCode.UNSAFE)  # (a roadmap's
    np.savez(tmp_path / "ids.npz", Q0=Q[:3], Q1=Q[3:6], ids=np.arange(3))  # other arrays are its own)
    assert _run("edges", "ur5", str(tmp_path / "ids.npz")).exit_code in (ExitCode.OK, ExitCode.UNSAFE)
