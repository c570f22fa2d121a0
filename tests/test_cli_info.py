"""``armguard info`` and ``armguard fk``: output and one-line errors with exit code 2."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from armguard.cli import main
from armguard.harness import seed_data
from armguard.scene import compile_scene, load_scene


def test_info_hermes_counts_and_size():
    res = CliRunner().invoke(main, ["info", "hermes"], terminal_width=200)
    assert res.exit_code == 0, res.output
    total = [line for line in res.output.splitlines() if "total" in line][0]
    cells = [c.strip() for c in total.split("│")]
    hermes = seed_data("hermes")["model"]  # reference/seeds/hermes.yaml
    assert cells[3:6] == [str(hermes["polyhedra"]), str(hermes["faces"]), str(hermes["vertices"])]
    assert f"compiled size: {compile_scene(load_scene('hermes')).nbytes} bytes" in res.output
    assert "3072 bytes" in res.output and "link1-link3" in res.output
    assert "360.0°" in res.output  # revolute limits in degrees


def test_info_and_check_take_an_srdf_for_any_model(tmp_path):
    """``--srdf`` on a public robot's name (not only a .urdf path, as docs/models.md says): the given file's
    disabled pairs, or ``none``: none; ``check`` with it checks that many pairs."""
    import armguard

    srdf = tmp_path / "mine.srdf"
    srdf.write_text('<robot name="ur5"><disable_collisions link1="upper_arm_link" link2="wrist_1_link" reason="Never"/></robot>')
    res = CliRunner().invoke(main, ["info", "ur5", "--srdf", str(srdf)], terminal_width=300)
    assert res.exit_code == 0, res.output
    assert f"SRDF: {srdf} (given (srdf=))" in res.output
    none = CliRunner().invoke(main, ["info", "ur5", "--srdf", "none"], terminal_width=300)
    assert none.exit_code == 0 and "SRDF: none (--srdf none" in none.output, none.output
    for arg, model in ((str(srdf), armguard.load_model("ur5", srdf=srdf)), ("none", armguard.load_model("ur5", srdf=False))):
        chk = CliRunner().invoke(main, ["check", "ur5", "--srdf", arg], terminal_width=300)
        assert chk.exit_code in (0, 1) and f"of {len(model.pairs)} pairs evaluated" in chk.output, chk.output
    assert len(armguard.load_model("ur5", srdf=False).pairs) == len(armguard.load_model("ur5", srdf=srdf).pairs) + 1
    hermes = CliRunner().invoke(main, ["info", "hermes", "--srdf", "none"], terminal_width=300)  # a sidecar: groups kept
    assert hermes.exit_code == 0 and "SRDF: none of pairs (" in hermes.output and "hermes.srdf names the arms" in hermes.output
    chk = CliRunner().invoke(main, ["check", "hermes", "--srdf", "none"], terminal_width=300)
    assert f"of {len(armguard.load_model('hermes', srdf=False).pairs)} pairs evaluated" in chk.output, chk.output
    plain = tmp_path / "plain.yaml"  # a scene file (no model:) names its robots' SRDFs itself: --srdf was ignored
    plain.write_text("armguard_scene: 1\nname: p\nrobots:\n  - name: a\n    joints: [{a: 0.3, alpha: 0, d: 0, theta: 0}]\n")
    res = CliRunner().invoke(main, ["info", str(plain), "--srdf", "none"])
    assert res.exit_code == 2 and "--srdf goes with a model" in res.output, res.output


def test_info_calls_a_continuous_joint_continuous():
    """kinova's joints 1, 4 and 6 are continuous in its URDF (no limits; Pinocchio's (cos, sin)): not
    "revolute -inf inf"."""
    res = CliRunner().invoke(main, ["info", "kinova"], terminal_width=200)
    assert res.exit_code == 0, res.output
    rows = {line.split("│")[1].strip(): line.split("│")[2].strip() for line in res.output.splitlines()
            if line.count("│") > 3 and "j2s6s200_joint_" in line}
    assert rows == {f"j2s6s200_joint_{k}": ("continuous" if k in (1, 4, 6) else "revolute") for k in range(1, 7)}


def test_info_on_a_public_robot_says_it_has_no_static_bodies():
    # a public robot's URDF has no scene bodies: one line, not a table whose only row is a total of 0
    res = CliRunner().invoke(main, ["info", "ur5"], terminal_width=200)
    assert res.exit_code == 0, res.output
    assert "static bodies: none" in res.output and "bodies" not in res.output.replace("static bodies: none", "")
    assert "shoulder_pan_joint" in res.output  # the joint table follows


def test_fk_prints_link_frames_in_degrees():
    res = CliRunner().invoke(main, ["fk", "puma560", "--q", "0,45,-135,0,-45,0", "--deg"], terminal_width=200)
    assert res.exit_code == 0, res.output
    s = load_scene("puma560")
    r = s.robots["puma560"]
    X = r.forward_kinematics(np.radians([0, 45, -135, 0, -45, 0]))
    tool = [line for line in res.output.splitlines() if line.startswith("│ tool")][0]
    xyz = [float(v) for v in tool.split("│")[2:5]]
    assert np.allclose(xyz, X[-1, :3, 3], atol=1e-6)


def test_errors_are_one_line_exit_3():
    for args in (["info", "no_such_scene"], ["fk", "hermes", "--robot", "x"]):
        res = CliRunner().invoke(main, args)
        assert res.exit_code == 3, (args, res.output)  # ExitCode.INPUT: a value refused
        assert res.output.strip().count("\n") == 0 and res.output.startswith("error:")


@pytest.mark.parametrize("args, words", [
    (["fk", "hermes", "--q", "1,2"], ["has 6 joints", "got 2 values"]),
    (["fk", "hermes", "--q", "a,b"], ["expected numbers"]),
    (["fk", "ur5", "--q", "0,nan,0,0,0,0"], ["shoulder_lift_joint (value 2 of 6) = nan", "finite"]),
    (["compare", "ur5", "--q", "0,0,inf,0,0,0"], ["value 3 of 6 = inf", "finite"]),
    (["compare", "ur5", "--q", "9,0,0,0,0,0"], ["shoulder_pan_joint", "outside its limits"]),  # exit 3 (as a file's)
    (["check", "ur5", "--q", "9,0,0,0,0,0"], ["shoulder_pan_joint", "outside its limits"]),
])
def test_q_that_is_not_finite_numbers_is_a_usage_error(args, words):
    """--q typed wrong is a usage error (exit status 2) in fk and compare as in check, naming the value."""
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 2, (args, res.output)
    for w in words:
        assert w in res.output, res.output


def test_quiet_drops_the_file_warnings_for_that_command_only():
    """talos_left_arm's SRDF is the whole humanoid's: each command warned of its 8 skipped elements;
    ``-q`` drops them (``info`` still lists them in its SRDF section), and the caller's filters are
    left as they were."""
    import warnings

    quiet = CliRunner().invoke(main, ["-q", "check", "talos_left_arm"])  # first: nothing loaded before it
    loud = CliRunner().invoke(main, ["check", "talos_left_arm"])
    assert loud.exit_code == quiet.exit_code and "warning: " not in quiet.stderr
    assert loud.stderr.count("warning: ") >= 1 and "talos.srdf" in loud.stderr
    assert quiet.stdout.split("(")[0] == loud.stdout.split("(")[0]  # the same headline status
    info = CliRunner().invoke(main, ["-q", "info", "talos_left_arm"], terminal_width=300)
    assert info.exit_code == 0 and info.stdout.count("  warning: ") >= 8
    before = list(warnings.filters)
    CliRunner().invoke(main, ["-q", "info", "talos_left_arm"])
    assert list(warnings.filters) == before
