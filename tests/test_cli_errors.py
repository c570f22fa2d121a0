"""What a newcomer sees when a file or a value is wrong: every problem, with its file, place and line.

Files with deliberate mistakes are written here (the scene and trajectory formats:
docs/scene-format.md, docs/trajectory-format.md); the CLI runs in-process (click's CliRunner).
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner

from armguard.cli import ExitCode, main
from armguard.kinematics import Trajectory
from armguard.scene import load_scene

URDF = Path(__file__).resolve().parents[1] / "urdf"

BAD_SCENE = """\
armguard_scene: 1
name: bad
bodies:
  - name: table
    shapes:
      - type: box
        sise: [1, 1, 1]
  - name: post
    colour: red
    shapes:
      - type: sphere
        radius: -1
"""

BAD_TRAJECTORY = """\
format: armguard.trajectory
version: 1
robot: puma560
joint_names: [j1, j2, j3, j4, j5, j6]
tiems: [0.0, 1.0]
waypoints:
  - [0, 0, 0, 0, 0, 0]
  - [0.1, 0, 0, 0, 0]
"""

GOOD_TRAJECTORY = """\
format: armguard.trajectory
version: 1
robot: {robot}
joint_names: [{joints}]
times: [0.0, {t1}]
waypoints:
  - [0, 0, 0, 0, 0, 0]
  - [0.1, 0, 0, 0, 0, 0]
"""


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_a_scene_file_lists_every_schema_problem_with_its_line(tmp_path):
    f = tmp_path / "bad.yaml"
    f.write_text(BAD_SCENE)
    res = _run("check", f)
    assert res.exit_code == ExitCode.INPUT
    out = res.output
    assert "bodies[0].shapes[0].size (line 6): required key is missing" in out  # the mapping that lacks it
    assert "misspelling of 'size'" in out
    assert "bodies[0].shapes[0].sise (line 7): unknown key" in out
    assert "bodies[1].colour (line 9): unknown key" in out
    assert "bodies[1].shapes[0].radius (line 12)" in out
    assert "3 more problems" in out


def test_a_trajectory_file_lists_every_problem_with_its_line(tmp_path):
    f = tmp_path / "t.yaml"
    f.write_text(BAD_TRAJECTORY)
    with pytest.raises(Exception) as exc:
        Trajectory.load_yaml(f)
    msg = str(exc.value)
    assert msg.startswith(f"{f}: times: missing required key (the unknown key 'tiems' looks like a misspelling of 'times')")
    assert "tiems (line 5): unknown key" in msg
    assert "waypoints[1] (line 8): expected 6 joint values (one per joint_names entry), got 5" in msg
    f.write_text(GOOD_TRAJECTORY.format(robot="puma560", joints="j1, j2, j3, j4, j5, j6", t1="0.0"))
    with pytest.raises(Exception) as exc:
        Trajectory.load_yaml(f)
    assert "times (line 5): must be strictly increasing" in str(exc.value) and "times: times" not in str(exc.value)


def test_verify_names_the_file_for_a_robot_or_joints_the_scene_lacks(tmp_path):
    f = tmp_path / "t.yaml"
    f.write_text(GOOD_TRAJECTORY.format(robot="pumaX", joints="j1, j2, j3, j4, j5, j6", t1="1.0"))
    res = _run("verify", "puma560", f)
    assert res.exit_code == ExitCode.INPUT and f"{f}: robot (line 3): robot 'pumaX' is not in scene 'puma560'" in res.output
    f.write_text(GOOD_TRAJECTORY.format(robot="puma560", joints="j1, j2, j3, j4, j5, jx", t1="1.0"))
    res = _run("verify", "puma560", f)
    assert res.exit_code == ExitCode.INPUT and f"{f}: joint_names (line 4)" in res.output
    f.write_text(GOOD_TRAJECTORY.format(robot="puma560", joints="j1, j2, j3, j4, j5, j6", t1="1.0"))
    assert _run("verify", "puma560", f).exit_code == 0


def test_option_errors_use_the_option_names():
    """An option's value refused: the option named (click reads the number: a usage error, exit 2)."""
    res = _run("verify", "puma560", "pick_and_place", "--stopping-distance", "-1")
    assert res.exit_code == ExitCode.USAGE and "--stopping-distance" in res.output and "'-1' must be >= 0" in res.output


def test_check_json_holds_every_feature_as_data():
    res = _run("check", "hermes", "--q", "195,0,0,0,0,0", "--deg", "--json", "--threshold", "2.0")
    doc = json.loads(res.output)
    feats = [doc["nearest"]["feature"]] + [r["feature"] for r in doc["by_category"].values()] + \
            [r["feature"] for r in doc["within_threshold"]]
    assert doc["within_threshold"] and any(f is not None for f in feats)
    for f in feats:
        assert f is None or (set(f) == {"kind", "index"} and f["kind"] in ("face", "edge", "vertex", "surface"))


def test_check_piped_keeps_whole_names():
    res = _run("check", "ranger")
    assert "manipulator_module" in res.output and "environm…" not in res.output


def test_demo_output_folder_errors_and_scene_files(tmp_path):
    res = _run("demo", "--scene", "puma560", "--out", "/proc/armguard-cannot")
    assert res.exit_code == ExitCode.INPUT and "cannot create the folder /proc/armguard-cannot" in res.output
    assert "Traceback" not in res.output
    model = tmp_path / "model"
    shutil.copytree(URDF / "puma560", model)
    out = tmp_path / "out"
    res = _run("demo", "--scene", model / "puma560.yaml", "--out", out)
    assert res.exit_code == 0, res.output
    assert sorted(p.name for p in out.iterdir()) == [f"puma560__pick_and_place__{m}.{x}" for m in ("hermes100mm", "sd0mm")
                                                     for x in ("json", "png")]
    assert not list(model.glob("*.json"))  # nothing written beside the scene file


def test_verify_checks_only_the_moving_arm():
    sc = load_scene("ranger")
    from armguard.verify import Verifier

    traj = sc.trajectories["left_arm_sweep"]
    r = Verifier(sc, robot=traj.robot_name).verify(traj)
    # the camera arm and the module never move here: their 140 mm is not the left arm's clearance
    assert r.min_clearance_at.a.startswith("left_arm/") or r.min_clearance_at.b.startswith("left_arm/")
    from armguard.detect import Detector

    still = Detector(sc, threshold=0.0).pair_distances(sc.flat_q(sc.default_q()))
    static = min(d for a, b, d in zip(still.owner_a, still.owner_b, still.distance)
                 if not str(a).startswith("left_arm/") and not str(b).startswith("left_arm/"))
    assert static < r.min_clearance  # a closer static pair exists, and is not what the report gives


def test_check_without_a_verdict_is_not_a_success():
    spent = _run("check", "hermes", "--q", "195,0,0,0,0,0", "--deg", "--budget-us", "0")
    assert "INCOMPLETE" in spent.output and spent.exit_code == ExitCode.INCOMPLETE
    assert _run("check", "hermes").exit_code == 0


def _doc_example_scene() -> str:
    """The runnable scene example of docs/scene-format.md."""
    text = (Path(__file__).resolve().parents[1] / "docs" / "scene-format.md").read_text()
    block = text.split("## Example (runnable)", 1)[1].split("```yaml", 1)[1].split("```", 1)[0]
    return block.lstrip("\n")


def test_independent_scene_problems_are_listed_together(tmp_path):
    good = _doc_example_scene()
    wave = "  - {name: wave, robot: arm, profile: trapezoidal, waypoints: [[0, 30, -60], [45, 10, -30], [0, 30, -60]]}"
    assert wave in good
    bad = good.replace(wave, wave.replace("robot: arm", "robot: armX") + "\n"
                       + "  - {name: wave2, robot: arm, profile: trapezoidal, waypoints: [[0, 30, -60], [45, 10], [0, 30, -60]]}")
    f = tmp_path / "cell.yaml"
    f.write_text(bad)
    res = _run("check", f)
    assert res.exit_code == ExitCode.INPUT
    assert "trajectories[0].robot (line" in res.output and "unknown robot 'armX'" in res.output
    assert "1 more problem:" in res.output and "trajectories[1].waypoints[1] (line" in res.output
    f.write_text(good)
    assert _run("check", f).exit_code in (0, 1)  # the example itself loads


def test_body_and_robot_problems_are_listed_together(tmp_path):
    good = _doc_example_scene()
    bad = good.replace("limits: [-90, 90]", "limits: [90, -90]").replace(
        "shapes: [{type: prism, n_sides: 16, apothem: 0.03, length: 0.1}]",
        "shapes: [{type: polyhedron, vertices: [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]}]")
    assert bad.count("\n") == good.count("\n") and bad != good
    f = tmp_path / "cell.yaml"
    f.write_text(bad)
    res = _run("check", f)
    assert res.exit_code == ExitCode.INPUT
    assert "bodies[1].shapes[0] (line" in res.output and "no volume" in res.output
    assert "1 more problem:" in res.output and "robots[0].joints[1].limits (line" in res.output


def test_the_command_shows_an_armguard_warning_as_one_line(capsys):
    """``armguard``'s warnings hook: an ArmguardWarning (its message names the file and the element)
    is ``warning: <message>`` on stderr, without Python's source line of the library under it; other
    warnings keep Python's form."""
    import warnings

    from armguard import ArmguardWarning
    from armguard.cli._output import one_line_warnings

    before = []  # the hook in place before: it still shows the other warnings
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        warnings.showwarning = lambda message, category, *a, **k: before.append((category, str(message)))
        one_line_warnings()
        one_line_warnings()  # a second call wraps nothing twice
        warnings.warn(ArmguardWarning("robot.srdf: group_state[0] (home): no attribute 'group'"))
        warnings.warn(UserWarning("not armguard's"))
    err = capsys.readouterr().err.splitlines()
    assert err == ["warning: robot.srdf: group_state[0] (home): no attribute 'group'"]  # once, no source line
    assert before == [(UserWarning, "not armguard's")]


def test_verify_all_on_a_model_without_canned_trajectories_says_what_to_give():
    from armguard.harness import repo_root

    res = CliRunner().invoke(main, ["verify", str(repo_root() / "urdf" / "puma560" / "puma560.urdf"), "all"])
    assert res.exit_code == int(ExitCode.INPUT), res.output
    assert "has no canned trajectory: give trajectory files (.yaml, docs/trajectory-format.md" in res.output


def test_located_messages_say_the_place_once(tmp_path):
    """"line 12 (line 12): not well-formed XML: no element found: line 12, column 0" and "blend_times[0] = 1.5
    must lie in [...] (line 9): " (the place run into the message): each place said once, then what is wrong."""
    urdf = tmp_path / "u.urdf"
    urdf.write_text("<robot name='x'>\n  <link name='a'>\n")
    res = _run("info", urdf)
    assert res.exit_code == ExitCode.INPUT, res.output
    assert f"{urdf}: line 3, column 1: not well-formed XML: no element found" in res.output, res.output
    assert res.output.count("line 3") == 1
    traj = tmp_path / "t.yaml"
    traj.write_text("format: armguard.trajectory\nversion: 1\nrobot: puma560\njoint_names: [j1, j2, j3]\n"
                    "times: [0.0, 1.0, 2.0]\nwaypoints:\n  - [0.0, 0.5, -1.0]\n  - [0.1, 0.6, -1.0]\n  - [0.2, 0.5, -1.0]\n"
                    "blend_times: [1.5, 0.5]\n")
    res = _run("verify", "puma560", traj)
    assert res.exit_code == ExitCode.INPUT, res.output
    assert f"{traj}: blend_times[0] (line 10): 1.5 s must lie in [0, half the segment duration 0.5 s]" in res.output, res.output
