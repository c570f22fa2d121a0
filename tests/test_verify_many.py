"""verify_many: serial equals one-by-one; a 2-worker Dask LocalCluster equals serial; the CLI."""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest

from armguard.verify import verify, verify_many

from _verify_fixtures import thin_suite


def _strip(report):
    """A report without its wall time (the only field that differs between runs)."""
    d = report.to_dict()
    d.pop("elapsed_s")
    return json.dumps(d, sort_keys=True)


def _cases(n):
    rng = np.random.default_rng(99)
    cases = thin_suite(rng, n, n_obstacles=4)
    sc = cases[0][0]  # one scene, many trajectories of its arm
    model_trajs = [(f"t{i}", c[1]) for i, c in enumerate(cases)]
    return sc, model_trajs


def test_verify_many_serial_equals_one_by_one():
    sc, items = _cases(6)
    seen = []
    reports = verify_many(sc, items, progress=lambda d, t: seen.append((d, t)))
    assert [r.trajectory for r in reports] == [n for n, _ in items]
    for (name, traj), r in zip(items, reports):
        assert _strip(r) == _strip(verify(sc, traj, name=name))
    assert seen[-1] == (6, 6)


def test_verify_many_on_local_cluster_equals_serial():
    sc, items = _cases(8)
    serial = verify_many(sc, items, method="certified", stopping_distance=0.01)
    done = []
    dask = verify_many(sc, items, workers=2, method="certified", stopping_distance=0.01, chunk_size=2,
                       progress=lambda d, t: done.append(d))
    assert [_strip(r) for r in dask] == [_strip(r) for r in serial]
    assert done[-1] == len(items)


def test_the_workers_use_the_backend_chosen_here():
    """The command line's ``--backend`` (and ``--config``) lived in this process only: with ``--workers`` every
    worker took its own default (analytic), and ``--backend fcl``, refused serially, verified SAFE."""
    from armguard.backends import command_line_choice

    sc, items = _cases(2)
    undo = command_line_choice("coal")
    try:
        serial = verify_many(sc, items, method="certified", stopping_distance=0.01)
        dask = verify_many(sc, items, workers=1, method="certified", stopping_distance=0.01)
    finally:
        undo()
    assert {r.details.backend for r in serial} == {r.details.backend for r in dask} == {"coal"}
    assert [_strip(r) for r in dask] == [_strip(r) for r in serial]


def test_workers_and_scheduler_are_exclusive():
    from armguard import VerificationError

    sc, items = _cases(1)
    with pytest.raises(VerificationError):
        verify_many(sc, items, workers=2, scheduler="tcp://127.0.0.1:1")


def test_cli_verify_builtin_scene(tmp_path):
    out = subprocess.run(
        [sys.executable, "-m", "armguard.cli", "verify", "puma560", "pick_and_place",
         "--report", str(tmp_path / "r.json"), "--plot", str(tmp_path / "r.png")],
        capture_output=True, text=True,
    )
    assert out.returncode in (0, 1), out.stderr
    doc = json.loads((tmp_path / "r.json").read_text())
    assert doc["status"] in ("safe", "collision") and (out.returncode == 0) == doc["safe"]
    assert (tmp_path / "r.png").read_bytes()[:4] == b"\x89PNG"
    assert "verdict" in out.stdout


def test_cli_verify_yaml_trajectory_and_unknown_name(tmp_path):
    import armguard

    sc = armguard.load_scene("puma560")
    traj = sc.trajectories["pick_and_place"]
    path = tmp_path / "t.yaml"
    traj.save_yaml(path)
    out = subprocess.run([sys.executable, "-m", "armguard.cli", "verify", "puma560", str(path), "--method", "sampled",
                          "--frequency", "20"], capture_output=True, text=True)
    assert out.returncode in (0, 1), out.stderr
    assert "sampled at 20 Hz" in out.stdout
    bad = subprocess.run([sys.executable, "-m", "armguard.cli", "verify", "puma560", "no_such"], capture_output=True, text=True)
    assert bad.returncode == 3 and "pick_and_place" in bad.stderr  # ExitCode.INPUT


def test_cli_verify_gives_files_of_the_same_name_their_own_report_and_plot(tmp_path):
    """Two trajectory files named alike in different folders: two reports named apart (``t``, ``t_2``)
    and two plots, none written over the other (both were named ``t``: one plot was printed twice, the
    other lost)."""
    import armguard
    from click.testing import CliRunner

    from armguard.cli import main

    sc = armguard.load_scene("puma560")
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    sc.trajectories["pick_and_place"].save_yaml(tmp_path / "a" / "t.yaml")
    sc.trajectories["pick_and_place"].save_yaml(tmp_path / "b" / "t.yaml")
    r = CliRunner().invoke(main, ["verify", "puma560", str(tmp_path / "a" / "t.yaml"), str(tmp_path / "b" / "t.yaml"),
                                  "--method", "sampled", "--frequency", "20", "--report", str(tmp_path / "r.json"),
                                  "--plot", str(tmp_path / "p.png")])
    assert r.exit_code in (0, 1), r.output
    doc = json.loads((tmp_path / "r.json").read_text())
    assert [d["trajectory"] for d in doc] == ["t", "t_2"]
    for name in ("p_t.png", "p_t_2.png"):
        assert (tmp_path / name).read_bytes()[:4] == b"\x89PNG"
        assert r.output.count(f"plot: {tmp_path / name}") == 1, r.output
    r = CliRunner().invoke(main, ["verify", "puma560", "pick_and_place", "--plot", str(tmp_path / "p.xyz")])
    assert r.exit_code == 3 and "matplotlib writes no .xyz plots" in r.output, r.output


def test_cli_verify_names_the_waypoint_outside_the_limits(tmp_path):
    """A waypoint outside its joint's limits: the file, the waypoint's place and line (it said "trajectory
    waypoints[1]: ... (at index (np.int64(2),))", with neither file nor line)."""
    from click.testing import CliRunner

    from armguard.cli import main

    path = tmp_path / "out.yaml"
    path.write_text("format: armguard.trajectory\nversion: 1\nrobot: puma560\njoint_names: [j1, j2, j3]\n"
                    "times: [0.0, 1.0, 2.0]\nwaypoints:\n  - [0.0, 0.5, -1.0]\n  - [0.1, 10.0, -1.0]\n  - [0.2, 0.5, -1.0]\n")
    r = CliRunner().invoke(main, ["verify", "puma560", str(path)])
    assert r.exit_code == 3, r.output
    assert f"{path}: waypoints[1][1] (line 8): joint 'j2' = 10 is outside its limits" in r.output, r.output


def test_verify_takes_a_trajectory_file_and_locates_its_errors(tmp_path):
    """armguard.verify(model, path): the file read and checked against the scene as the CLI does (a knot
    outside the limits named by file, place and line; it was "trajectory waypoints[1]: ..." from a
    Trajectory loaded by hand, and an AttributeError from a path); anything else is refused by name."""
    import armguard
    from armguard import SceneFileError, VerificationError
    from armguard.verify import load_trajectory

    model = armguard.load_model("puma560")
    text = ("format: armguard.trajectory\nversion: 1\nrobot: puma560\njoint_names: [j1, j2, j3]\n"
            "times: [0.0, 1.0, 2.0]\nwaypoints:\n  - [0.0, 0.5, -1.0]\n  - [0.1, {}, -1.0]\n  - [0.2, 0.5, -1.0]\n")
    bad, good = tmp_path / "out.yaml", tmp_path / "fine.yaml"
    bad.write_text(text.format("10.0"))
    good.write_text(text.format("0.6"))
    for call in (lambda: verify(model, bad), lambda: verify(model, str(bad)), lambda: load_trajectory(model, bad)):
        with pytest.raises(SceneFileError, match=r"out\.yaml: waypoints\[1\]\[1\] \(line 8\): joint 'j2' = 10 is outside"):
            call()
    r = verify(model, good, method="sampled", frequency=20)
    assert r.trajectory == "fine"
    same = verify(model, load_trajectory(model, good), method="sampled", frequency=20, name="fine")
    assert _strip(r) == _strip(same)
    with pytest.raises(VerificationError, match="expected an armguard.kinematics.Trajectory or the path"):
        verify(model, 3)


@pytest.mark.parametrize("q_others, said", [
    ({"puma560": [0, 9, 0, 0, 0, 0]}, r"q_others\['puma560'\]: joint 'j2' = 9 is outside its limits"),
    ({"puma560": [0, 0.5, 0, 0, 0]}, r"q_others\['puma560'\]: expected 6 values"),
    (np.zeros(6), "q_others: expected a mapping robot name -> joint values, got ndarray"),
])
def test_q_others_is_checked_where_it_is_given(q_others, said):
    """The held joints' values come from q_others: a value outside its limits is named there (it was
    called "trajectory waypoints[0]"), and an array where a mapping belongs is refused (a TypeError)."""
    import armguard
    from armguard import VerificationError
    from armguard.kinematics import Trajectory

    model = armguard.load_model("puma560")
    traj = Trajectory("puma560", ["j1"], [0.0, 1.0], [[0.0], [0.3]])
    with pytest.raises(VerificationError, match=said):
        verify(model, traj, q_others=q_others, method="sampled", frequency=5)
    held = verify(model, traj, q_others={"puma560": [0, 0.5, -1, 0, 0, 0]}, method="sampled", frequency=5)
    assert held.held_joints == {"j2": 0.5, "j3": -1.0, "j4": 0.0, "j5": 0.0, "j6": 0.0}


@pytest.mark.parametrize("value,said", [("on", "a boolean"), ("true", "a boolean"), ("null", "nothing (null"),
                                        ("'0.5'", "the text '0.5'")])
def test_a_trajectory_value_that_is_not_a_number_is_refused(tmp_path, value, said):
    """YAML reads on/yes/true as True, which numpy took as 1.0 rad (a SAFE verdict on a motion nobody wrote);
    null was called "NaN or inf"; quoted text was read as its number."""
    from click.testing import CliRunner

    from armguard.cli import main

    path = tmp_path / "t.yaml"
    path.write_text("format: armguard.trajectory\nversion: 1\nrobot: puma560\njoint_names: [j1, j2, j3]\n"
                    f"times: [0.0, 1.0, 2.0]\nwaypoints:\n  - [0.0, 0.5, -1.0]\n  - [{value}, 0.6, -1.0]\n  - [0.2, 0.5, -1.0]\n")
    r = CliRunner().invoke(main, ["verify", "puma560", str(path)])
    assert r.exit_code == 3, r.output
    assert f"{path}: waypoints[1][0] (line 8): expected a number, got {said}" in r.output, r.output


def test_a_trajectory_file_with_a_repeated_key_is_refused(tmp_path):
    """The second ``times:`` won silently (a 9 s trajectory verified SAFE in place of the 2 s one written first)."""
    import armguard
    from armguard import SceneFileError

    path = tmp_path / "t.yaml"
    path.write_text("format: armguard.trajectory\nversion: 1\nrobot: puma560\njoint_names: [j1, j2, j3]\n"
                    "times: [0.0, 1.0, 2.0]\ntimes: [0.0, 4.0, 9.0]\nwaypoints:\n  - [0.0, 0.5, -1.0]\n"
                    "  - [0.1, 0.6, -1.0]\n  - [0.2, 0.5, -1.0]\n")
    with pytest.raises(SceneFileError, match="duplicate key 'times' \\(first given at line 5\\)"):
        armguard.Trajectory.load_yaml(path)


def _with_a_bad_one(n, bad):
    """``n`` trajectories, the one at ``bad`` taking its first joint 10 rad past its upper limit."""
    from armguard.kinematics import Trajectory

    sc, items = _cases(n)
    name, t = items[bad]
    W = np.array(t.waypoints, dtype=float)
    W[-1, 0] = sc.robots[t.robot_name].upper[0] + 10.0
    items[bad] = (name, Trajectory(t.robot_name, t.joint_names, t.times, W))
    return sc, items


@pytest.mark.parametrize("workers", [None, 2])
def test_a_trajectory_that_cannot_be_verified_keeps_the_reports_already_made(workers):
    """One trajectory outside its limits lost every report made before it, and the error named none."""
    from armguard import ArmguardError

    sc, items = _with_a_bad_one(6, 4)
    with pytest.raises(ArmguardError) as info:
        verify_many(sc, items, workers=workers, chunk_size=2 if workers else None)
    err = info.value
    assert err.failed_index == 4 and len(err.reports) == 6 and err.reports[4] is None
    assert any("verifying trajectory 4 ('t4') of 6" in n for n in err.__notes__), err.__notes__
    serial = verify_many(sc, items[:4])
    kept = [r for r in err.reports if r is not None]
    assert kept and all(_strip(err.reports[i]) == _strip(serial[i]) for i in range(4) if err.reports[i] is not None)
    if workers is None:
        assert all(r is not None for r in err.reports[:4]) and err.reports[5] is None


def test_knots_too_close_for_a_finite_speed_are_refused_where_the_file_says_so(tmp_path):
    """``times: [0.0, 1.0e-320]`` parsed, then verify said only "trajectory velocity: contains NaN or infinite
    values", naming neither the file nor the key."""
    from click.testing import CliRunner

    from armguard.cli import main

    p = tmp_path / "t.yaml"
    p.write_text("format: armguard.trajectory\nversion: 1\nrobot: puma560\njoint_names: [j1, j2, j3, j4, j5, j6]\n"
                 "times: [0.0, 1.0e-320]\nwaypoints:\n  - [0.0, 0.79, -2.36, 0.0, -0.79, 0.0]\n"
                 "  - [0.53, 1.25, -3.06, 0.0, -1.33, -2.61]\n")
    r = CliRunner().invoke(main, ["verify", "puma560", str(p)])
    assert r.exit_code == 3
    assert "t.yaml: times (line 5): times[0] = 0.0 and times[1] = 1e-320 are so close that the speed from waypoints[0] " \
           "to waypoints[1] is not a finite number" in r.output, r.output
