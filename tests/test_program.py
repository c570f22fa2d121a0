"""WORKMATE's task programs: the file format (errors located), the camera's noise (against its stated
covariance), the expansion through IK (the tool reaches bound frame @ taught pose), the run on the
emulated cell (every motion verified, a colliding one stops the program), and the exported program
(run as a separate process, it reproduces the same motions exactly)."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from armguard import SceneFileError
from armguard.program import Camera, load_program, pose

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = ROOT / "examples" / "workmate"

PROGRAM = """\
armguard_program: 1
name: p
cell: {cell}
units: {{angle: deg, length: m}}
tasks:
{tasks}
"""
PICK = """\
  - pickup: cylinder_a
    approach: {xyz: [0, 0, 0.12], rpy: [180, 0, 0]}
    grasp: {xyz: [0, 0, 0.02], rpy: [180, 0, 0]}
    depart: {xyz: [0, 0, 0.15], rpy: [180, 0, 0]}
"""


def _write(tmp_path, tasks: str, cell: str = "puma560", name: str = "p.yaml") -> Path:
    p = tmp_path / name
    p.write_text(PROGRAM.format(cell=cell, tasks=tasks), encoding="utf-8")
    return p


# ------------------------------------------------------------------ the format
def test_the_example_program_expands_into_the_primitives_in_order():
    prog = load_program(EXAMPLE / "stack.yaml")
    ops = [s.op for s in prog.steps()]
    assert ops == ["find", "find", "frame", "move", "move", "grasp", "move", "frame", "move", "move", "release", "move", "home"]
    moves = [s for s in prog.steps() if s.op == "move"]
    assert [m.args[2] for m in moves] == ["joint", "line", "line", "joint", "line", "line"]  # the documented defaults
    assert moves[4].args[3] == ("cylinder_b",)  # PLACE's release may touch the target
    np.testing.assert_allclose(pose(*moves[1].args[:2]), pose([0, 0, 0.02], [math.pi, 0, 0]), atol=1e-15)


def test_a_misspelt_key_is_located_with_its_line(tmp_path):
    p = _write(tmp_path, PICK.replace("grasp:", "grsp:"))
    with pytest.raises(SceneFileError) as ei:
        load_program(p)
    msg = str(ei.value)
    assert str(p) in msg and "tasks[0].grasp" in msg and "required key is missing" in msg
    assert "tasks[0].grsp (line 8): unknown key (not part of the armguard_program format" in msg


def test_a_task_with_two_kinds_or_none_is_refused(tmp_path):
    p = _write(tmp_path, "  - {find: cylinder_a, move: home}\n  - {goto: x}\n")
    with pytest.raises(SceneFileError) as ei:
        load_program(p)
    msg = str(ei.value)
    assert "tasks[0] (line 6)" in msg and "exactly one of the keys" in msg and "tasks[1]" in msg


def test_a_non_finite_number_and_a_bad_mode_are_refused(tmp_path):
    bad = PICK.replace("[0, 0, 0.12]", "[0, .nan, 0.12]").replace("rpy: [180, 0, 0]}\n    grasp", "rpy: [180, 0, 0], mode: curve}\n    grasp")
    with pytest.raises(SceneFileError) as ei:
        load_program(_write(tmp_path, bad))
    msg = str(ei.value)
    assert "tasks[0].approach.xyz[1]" in msg and "finite" in msg and "tasks[0].approach.mode" in msg


def test_an_object_not_in_the_cell_is_located(tmp_path):
    from armguard.program import load_cell

    prog = load_program(_write(tmp_path, "  - find: cylinder_c\n  - {move: pose, frame: nowhere, xyz: [0.5, 0, 1]}\n"))
    with pytest.raises(SceneFileError) as ei:
        prog.check(load_cell("puma560"))
    msg = str(ei.value)
    assert "tasks[0].find" in msg and "'cylinder_c'" in msg and "tasks[1].frame" in msg


def test_a_joint_target_outside_the_limits_is_located_in_the_files_unit(tmp_path):
    """``move: joints`` with 9999 deg: the error came from the trajectory deep inside (``waypoints[1]``, in
    rad, no file), and ``program export`` wrote a script that failed the same way when run."""
    from armguard.program import export_program, load_cell

    p = _write(tmp_path, "  - move: joints\n    joints: [0, 0, 0, 0, 0, 9999]\n")
    with pytest.raises(SceneFileError) as ei:
        load_program(p).check(load_cell("puma560"))
    assert ei.value.where == "tasks[0].joints[5]" and ei.value.line == 7, ei.value
    assert "joint 'j6' = 9999 deg is outside its limits [-266, 266] deg" in ei.value.message
    with pytest.raises(SceneFileError, match=r"tasks\[0\]\.joints\[5\]"):
        export_program(p, tmp_path / "out.py")
    assert not (tmp_path / "out.py").exists()


def test_a_cell_file_error_names_the_cell_file(tmp_path):
    from armguard.program import load_cell

    c = tmp_path / "c.yaml"
    c.write_text("armguard_cell: 1\nmodel: puma560\ncamera: {fov: 200}\n", encoding="utf-8")
    with pytest.raises(SceneFileError, match=r"c\.yaml: camera\.fov \(line 3\)"):
        load_cell(c)
    c.write_text("armguard_cell: 1\nmodel: puma560\nreal: {cylinder_z: {xyz: [0, 0, 0]}}\n", encoding="utf-8")
    with pytest.raises(SceneFileError, match="cylinder_z"):
        load_cell(c)


# ------------------------------------------------------------------ the camera
def _camera(sig) -> Camera:
    X = pose([0.5, 0.0, 1.5], [math.pi, 0.0, 0.0])
    return Camera(X, math.radians(60.0), np.diag(np.asarray(sig, dtype=float) ** 2))


def test_find_noise_has_the_stated_covariance():
    """δp and δφ of many measurements (recovered from the poses) have the stated covariance."""
    from scipy.spatial.transform import Rotation

    cam = _camera([0.002, 0.001, 0.0005, 0.01, 0.0, 0.02])
    X_true = pose([0.55, 0.1, 0.6], [0.0, 0.0, 0.4])
    rng = np.random.default_rng(1)
    xs = []
    for _ in range(2000):
        X = cam.measure(X_true, rng)
        dphi = Rotation.from_matrix(X[:3, :3] @ X_true[:3, :3].T).as_rotvec()
        xs.append(np.concatenate([X[:3, 3] - X_true[:3, 3], dphi]))
    cov = np.cov(np.array(xs).T)
    sd = np.sqrt(np.diag(cam.cov_origin))
    np.testing.assert_allclose(np.sqrt(np.diag(cov)), sd, rtol=0.06, atol=1e-9)
    assert abs(np.mean(xs, axis=0)).max() < 0.1 * sd.max()


def test_the_bound_frame_is_the_left_perturbation_of_the_measurements():
    """UncertainPose3 of a FIND: log(X_found X_mean^-1) of measurements has its covariance."""
    from armguard.uncertainty import se3

    cam = _camera([0.002, 0.002, 0.001, 0.0, 0.0, 0.03])
    X = pose([0.6, -0.2, 0.6], [0.0, 0.0, 0.3])
    rng = np.random.default_rng(2)
    xi = np.array([se3.log(cam.measure(X, rng) @ np.linalg.inv(X)) for _ in range(2000)])
    want = cam.uncertain(X).cov
    np.testing.assert_allclose(np.cov(xi.T), want, atol=0.08 * np.abs(want).max())


def test_the_field_of_view_is_a_cone_about_the_optical_axis():
    cam = _camera([0.0] * 6)
    rng = np.random.default_rng(3)
    for p in rng.uniform([-1, -1, -0.5], [2, 1, 2.5], size=(300, 3)):
        d = p - cam.X_WC[:3, 3]
        angle = math.degrees(math.acos(np.clip(d @ cam.X_WC[:3, 2] / np.linalg.norm(d), -1, 1)))
        if abs(angle - 30.0) > 1e-6:
            assert cam.sees(p) == (angle < 30.0)


# ------------------------------------------------------------------ running on the emulated cell
@pytest.fixture(scope="module")
def exact_calibration(tmp_path_factory):
    """A calibration file putting the example cell's camera where it really stands (an exact
    calibration): FIND's error is then its noise alone.  The cell's own calibration file is the
    nominal layout, whose camera is 27 mm off (tests/test_program_calibration.py)."""
    from armguard.program import Calibration, load_cell, write_calibration

    cell = load_cell(EXAMPLE / "cell.yaml")
    return write_calibration(Calibration(X_camera=cell.camera.X_WC_real), tmp_path_factory.mktemp("cal") / "exact.yaml")


@pytest.fixture(scope="module")
def stack_run(exact_calibration):
    from armguard.program import run_program

    return run_program(EXAMPLE / "stack.yaml", seed=0, calibration=exact_calibration)


def test_the_stacking_program_verifies_and_runs(stack_run):
    run = stack_run
    assert run.ok, run.stopped
    assert [m.status for m in run.motions] == ["ran"] * 7
    for m in run.motions:  # certified SAFE on the believed cell (grown by k sigma while frames are bound)
        assert m.report.safe and m.report.details.method == "certified" and m.real_report.safe
    assert all(m.k > 3.0 for m in run.motions[:2])  # two frames of 4 dof (x, y, z, yaw): chi2_4(0.999 ** 0.5), k = 4.47
    # FIND: found near the true pose, and the true pose differs from the nominal one
    for f in run.finds:
        assert np.linalg.norm(f.found[:3, 3] - f.true[:3, 3]) < 0.01
        assert np.linalg.norm(f.true[:3, 3] - f.nominal[:3, 3]) > 0.01


def test_each_motion_ends_at_its_bound_frame_times_the_taught_pose(stack_run):
    from armguard.program import load_cell

    cell = load_cell(EXAMPLE / "cell.yaml")
    arm = cell.model.scene.robots["puma560"]
    prog = load_program(EXAMPLE / "stack.yaml")
    found = {f.object: f.found for f in stack_run.finds}
    moves = [s for s in prog.steps() if s.op == "move"]
    frames = ["cylinder_a"] * 3 + ["cylinder_b"] * 3
    for rec, step, fr in zip(stack_run.motions, moves, frames):
        X_goal = found[fr] @ pose(*step.args[:2])
        X_got = arm.link_pose(rec.trajectory.waypoints[-1], arm.tool_link)
        np.testing.assert_allclose(X_got, X_goal, atol=1e-6)


def test_the_placed_cylinder_lands_on_the_other_within_the_find_noise(stack_run):
    """Real axis offset after stacking: a few FIND sigmas (1.5 mm per axis), far below the
    real cell's displacement of the two cylinders (about 27 mm) that a blind program would carry."""
    off = stack_run.axis_offset("cylinder_a", "cylinder_b")
    assert off < 0.008
    a, b = stack_run.real["cylinder_a"], stack_run.real["cylinder_b"]
    assert abs((a[2, 3] - 0.05) - (b[2, 3] + 0.04)) < 0.004  # a's base on b's top (z noise 0.5 mm per FIND)


def test_a_motion_that_would_collide_stops_the_program(tmp_path):
    from armguard.program import run_program

    p = _write(tmp_path, "  - {move: pose, frame: world, xyz: [0.65, 0.0, 0.45], rpy: [180, 0, 0]}\n  - move: home\n")
    run = run_program(p, seed=0)
    assert not run.ok and len(run.motions) == 1
    rec = run.motions[0]
    assert rec.status.startswith("refused") and rec.report.status.value == "collision"
    assert rec.report.first_collision is not None and "refused" in run.stopped


def test_the_emulated_real_cell_catches_what_the_nominal_model_misses(tmp_path):
    """Without FIND the program moves to the nominal cylinder; in the real cell it stands 6 cm
    higher, into the hand: the believed cell verifies the grasp SAFE, the emulation stops it."""
    from armguard.program import run_program

    cell = tmp_path / "cell.yaml"
    cell.write_text("armguard_cell: 1\nmodel: puma560\nreal: {cylinder_a: {xyz: [0, 0, 0.06]}}\n"
                    "camera: {xyz: [0.55, 0, 1.5], rpy: [3.141592653589793, 0, 0]}\n", encoding="utf-8")
    run = run_program(_write(tmp_path, PICK, cell="cell.yaml"), seed=0)
    assert not run.ok
    last = run.motions[-1]
    assert last.report.safe and not last.real_report.safe and "real cell" in last.status
    run2 = run_program(_write(tmp_path, "  - find: cylinder_a\n" + PICK, cell="cell.yaml", name="q.yaml"), seed=0)
    assert run2.ok, run2.stopped  # with vision the same task follows the real cylinder


# ------------------------------------------------------------------ export and the command line
def test_the_exported_program_reproduces_the_same_motions(tmp_path, stack_run, exact_calibration):
    from armguard.program import export_program

    out = export_program(EXAMPLE / "stack.yaml", tmp_path / "stack_program.py")
    text = out.read_text(encoding="utf-8")
    assert "wc.find('cylinder_a')" in text and "F = wc.frame('cylinder_b')" in text
    save = tmp_path / "run.json"
    r = subprocess.run([sys.executable, str(out), "--seed", "0", "--calibration", str(exact_calibration),
                        "--save", str(save)], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout + r.stderr
    got = json.loads(save.read_text(encoding="utf-8"))
    want = stack_run.to_dict()
    assert [m["label"] for m in got["motions"]] == [m["label"] for m in want["motions"]]
    for g, w in zip(got["motions"], want["motions"]):
        assert g["waypoints"] == w["waypoints"] and g["times"] == w["times"]  # the same floats
    assert got["finds"] == want["finds"]


def test_the_command_line_exit_status(tmp_path):
    from click.testing import CliRunner

    from armguard.cli import main

    runner = CliRunner()
    bad = _write(tmp_path, "  - {move: pose, frame: world, xyz: [0.65, 0.0, 0.45], rpy: [180, 0, 0]}\n")
    r = runner.invoke(main, ["program", "run", str(bad)])
    assert r.exit_code == 1 and "STOPPED" in r.output, r.output
    good = _write(tmp_path, "  - {move: pose, frame: tool, xyz: [0, 0, -0.05], mode: line}\n", name="g.yaml")
    r = runner.invoke(main, ["program", "run", str(good), "--seed", "3"])
    assert r.exit_code == 0 and "every motion verified and ran" in r.output, r.output
    r = runner.invoke(main, ["program", "run", str(tmp_path / "missing.yaml")])
    assert r.exit_code == 3 and "file not found" in r.output
    r = runner.invoke(main, ["program", "export", str(good), "--out", str(tmp_path / "g.py")])
    assert r.exit_code == 0 and "wc.move(F @ pose(" in (tmp_path / "g.py").read_text(encoding="utf-8")


def test_run_and_export_refuse_another_robot_a_self_placement_and_unknown_names(tmp_path):
    """The program's robot: was never read (a program for 'nobody' ran on the PUMA); placing an object
    onto itself ran until inverse kinematics failed (exit 1); export wrote a program run refuses, whose
    script then failed with a traceback; each is now a located SceneFileError, and the exported
    script's errors are one line with exit status 3."""
    from armguard.program import export_program, run_program

    robot = tmp_path / "robot.yaml"
    robot.write_text(PROGRAM.format(cell=EXAMPLE / "cell.yaml", tasks=PICK).replace("tasks:", "robot: nobody\ntasks:"))
    with pytest.raises(SceneFileError, match=r"robot \(line \d+\): 'nobody' is not the robot of cell 'workmate_cell'"):
        run_program(robot)
    onto = PICK + "  - place: cylinder_a\n    onto: cylinder_a\n    approach: {xyz: [0, 0, 0.22], rpy: [180, 0, 0]}\n" \
                  "    release: {xyz: [0, 0, 0.11], rpy: [180, 0, 0]}\n    depart: {xyz: [0, 0, 0.22], rpy: [180, 0, 0]}\n"
    with pytest.raises(SceneFileError, match=r"tasks\[1\]\.onto \(line \d+\): cannot place 'cylinder_a' onto itself"):
        run_program(_write(tmp_path, onto, cell=str(EXAMPLE / "cell.yaml"), name="onto.yaml"))
    unknown = _write(tmp_path, "  - find: cylinder_c\n", cell=str(EXAMPLE / "cell.yaml"), name="c.yaml")
    with pytest.raises(SceneFileError, match=r"tasks\[0\]\.find \(line \d+\): 'cylinder_c' is not in cell"):
        export_program(unknown, tmp_path / "c.py")
    assert not (tmp_path / "c.py").exists()
    script = export_program(EXAMPLE / "stack.yaml", tmp_path / "s.py")
    r = subprocess.run([sys.executable, str(script), "--cell", "nosuch"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 3 and r.stderr.strip().startswith("error: unknown model 'nosuch'"), r.stderr
    assert r.stderr.strip().count("\n") == 0, r.stderr
    (tmp_path / "run.json").mkdir()  # --save where a folder is: refused before the run, one line, exit 3
    r = subprocess.run([sys.executable, str(script), "--save", str(tmp_path / "run.json")], capture_output=True,
                       text=True, timeout=300)
    assert r.returncode == 3 and r.stderr.strip().startswith("error: cannot write"), r.stderr
    assert r.stdout == "" and r.stderr.strip().count("\n") == 0, (r.stdout, r.stderr)


def test_every_problem_of_every_task_is_listed_once(tmp_path):
    """Each task's schema problems were joined into one message and the file's listing then joined those
    again ("2 more problems:" under "2 more problems:"): now one listing, one line per problem."""
    bad = PICK.replace("grasp:", "grsp:")
    p = _write(tmp_path, "  - find: cylinder_a\n    move: joints\n" + bad + bad)
    with pytest.raises(SceneFileError) as ei:
        load_program(p)
    msg = str(ei.value)
    assert msg.count("more problems:") == 1 and "4 more problems:" in msg, msg  # PICK has its depart
    assert msg.count("tasks[1].grsp") == 1 and msg.count("tasks[2].grasp") == 1, msg


def test_loaders_refuse_what_is_no_path():
    """load_program(None), load_cell(None), read_calibration(None) were TypeErrors from pathlib, and
    write_calibration(None, path) an AttributeError."""
    from armguard import SceneError
    from armguard.program import load_cell, read_calibration, write_calibration

    for call, said in ((lambda: load_program(None), "path of an armguard_program file"),
                       (lambda: load_cell(None), "load_cell: expected a cell file"),
                       (lambda: read_calibration(None), "path of an armguard_calibration file"),
                       (lambda: write_calibration(None, "x.yaml"), "expected a Calibration")):
        with pytest.raises(SceneError, match=said):
            call()


def test_a_missing_cell_file_is_the_programs_error_at_its_cell_key(tmp_path):
    """``cell: nosuch.yaml`` said "nosuch.yaml: file not found", naming neither the program nor its key."""
    from armguard.program import export_program, run_program

    p = _write(tmp_path, "  - move: home\n", cell="nosuch.yaml")
    for call in (lambda: run_program(p), lambda: export_program(p, tmp_path / "out.py")):
        with pytest.raises(SceneFileError) as ei:
            call()
        assert ei.value.file == str(p) and ei.value.where == "cell" and ei.value.line == 3
        assert "nosuch.yaml: file not found" in ei.value.message
    assert not (tmp_path / "out.py").exists()


def test_a_refused_motion_says_what_hit_what_and_when(tmp_path):
    """A cell planner's review: "refused: collision (1.33 s, clearance 0.0 mm)" named nothing, though the report
    held the first contact; and "clearance 60.0 mm" on most motions was a pair of the robot's own links."""
    import shutil

    from armguard.program import run_program

    shutil.copytree(EXAMPLE, tmp_path / "w")
    p = tmp_path / "w" / "c1.yaml"
    p.write_text(PROGRAM.format(cell="cell.yaml", tasks="  - move: pose\n    frame: table\n    xyz: [0, 0, 0.2]\n"
                                                        "    rpy: [180, 0, 0]\n"), encoding="utf-8")
    run = run_program(p, seed=0)
    assert not run.ok
    m = run.motions[-1]
    c = m.report.first_collision
    assert m.why()[0].startswith(f"contact (distance {c.distance * 1e3:.1f} mm): tool with table face ")
    assert f"t = {c.time:.4f} s" in m.why()[0]
    text = run.summary()
    assert "clearance 0.0 mm between puma560/tool and table" in text and m.why()[0] in text
    assert run.to_dict()["motions"][-1]["why"] == m.why()


def test_a_refusal_at_confidence_says_the_objects_as_found_are_clear(tmp_path):
    """A refusal of the bound objects grown to the confidence asked read as a plain collision."""
    import shutil

    import yaml

    from armguard.program import run_program

    shutil.copytree(EXAMPLE, tmp_path / "w")
    cal = tmp_path / "w" / "calibration.yaml"
    doc = yaml.safe_load(cal.read_text())
    text = cal.read_text()
    assert "camera" in doc
    big = tmp_path / "w" / "big.yaml"
    cam = doc["camera"]
    cam["cov"] = (np.diag([1e-4, 1e-4, 1e-4, 3e-4, 3e-4, 3e-4])).tolist()
    big.write_text(yaml.safe_dump(doc), encoding="utf-8")
    assert text  # the original untouched
    run = run_program(tmp_path / "w" / "stack.yaml", seed=0, calibration=big)
    refused = [m for m in run.motions if m.status.startswith("refused")]
    assert refused and refused[-1].k > 0.0 and refused[-1].nominal_clearance is not None
    assert any("not verified at the confidence asked" in line for line in refused[-1].why())


def test_a_depart_that_pushes_the_object_into_its_support_is_refused(tmp_path):
    """The supports' pairs were unchecked for the whole depart: one lowering cylinder A 6 cm ran through the
    table, "every motion verified and ran"; the same motion as a MOVE was refused."""
    import shutil

    from armguard.program import run_program

    shutil.copytree(EXAMPLE, tmp_path / "w")
    down = PICK.replace("depart: {xyz: [0, 0, 0.15]", "depart: {xyz: [0, 0, -0.04]")
    assert down != PICK
    for tasks, ok in ((PICK, True), (down, False)):
        p = tmp_path / "w" / "d.yaml"
        p.write_text(PROGRAM.format(cell="cell.yaml", tasks=tasks), encoding="utf-8")
        run = run_program(p, seed=0)
        assert run.ok is ok, run.summary()
    m = run.motions[-1]
    assert m.label.endswith("depart") and m.status == "refused: collision"
    assert "cylinder_a sinks into table, which it rested on, 2 mm deeper than at the grasp" in " ".join(m.why())


@pytest.mark.parametrize("seed", range(20))
def test_an_eroded_shape_is_the_points_a_ball_fits_about(seed):
    """Erosion by ``r``: every point of the eroded shape is at least ``r`` inside the shape (its face planes,
    or a sphere of radius ``r`` about its support points within the shape)."""
    from armguard.geometry import Box, ConvexPolyhedron, Cylinder, Sphere, distance
    from armguard.program._supports import eroded

    rng = np.random.default_rng(seed)
    r = 0.01
    poly = ConvexPolyhedron(rng.normal(size=(12, 3)) * 0.2)
    e = eroded(poly, r)
    if e is not None:
        P = np.asarray(poly.planes)
        assert np.all(P[:, :3] @ e.vertices.T - P[:, 3:4] <= -r + 1e-12)
    R = np.linalg.qr(rng.normal(size=(3, 3)))[0] * np.sign(np.linalg.det(np.linalg.qr(rng.normal(size=(3, 3)))[0]))
    R = R if np.linalg.det(R) > 0 else -R
    for shape in (Box(rng.normal(size=3), rng.uniform(0.02, 0.2, 3), R),
                  Cylinder(rng.normal(size=3), R, float(rng.uniform(0.02, 0.2)), float(rng.uniform(0.02, 0.2)))):
        e = eroded(shape, r)
        for p in rng.normal(size=(30, 3)) * 0.3 + shape.center:
            inner = distance(Sphere(p, 1e-9), e).distance  # a point of the eroded shape has its r-ball inside
            if inner < 0.0:
                assert distance(Sphere(p, r - 1e-9), shape).distance < 0.0
                assert distance(Sphere(p, 1e-9), shape).distance <= -r + 1e-9


def test_runtime_and_cell_body_errors_give_their_line(tmp_path):
    """``real.tabel: no body ...`` and ``tasks[0]: PLACE ...: the hand does not hold ...`` were the only errors
    without "(line N)"."""
    import shutil

    from armguard.program import load_cell, run_program

    shutil.copytree(EXAMPLE, tmp_path / "w")
    p = tmp_path / "w" / "w1.yaml"
    p.write_text(PROGRAM.format(cell="cell.yaml", tasks="  - place: cylinder_a\n    onto: cylinder_b\n"
                                "    approach: {xyz: [0, 0, 0.22], rpy: [180, 0, 0]}\n"
                                "    release: {xyz: [0, 0, 0.11], rpy: [180, 0, 0]}\n"
                                "    depart: {xyz: [0, 0, 0.22], rpy: [180, 0, 0]}\n"), encoding="utf-8")
    with pytest.raises(SceneFileError) as err:
        run_program(p, seed=0)
    assert err.value.where == "tasks[0]" and err.value.line == 6 and "the hand does not hold 'cylinder_a'" in str(err.value)
    cell = tmp_path / "w" / "cell.yaml"
    text = cell.read_text()
    assert "real:" in text and "  cylinder_a:" in text
    i = text.index("real:")
    bad = text[:i] + text[i:].replace("  cylinder_a:", "  tabel:", 1)
    cell.write_text(bad, encoding="utf-8")
    with pytest.raises(SceneFileError) as err:
        load_cell(cell)
    line = bad[:bad.index("  tabel:")].count("\n") + 1
    assert err.value.where == "real.tabel" and err.value.line == line and f"real.tabel (line {line})" in str(err.value)


def test_a_find_with_a_camera_pose_without_covariance_is_warned_of(tmp_path):
    """With the nominal camera (no covariance) "verified SAFE with probability 0.999" covered FIND's noise only:
    seed 0's FIND put cylinder B 40 mm from its true place."""
    from armguard.program import Calibration, load_cell, run_program, write_calibration

    nominal = run_program(EXAMPLE / "stack.yaml", seed=0, calibration=EXAMPLE / "calibration.yaml")
    assert len(nominal.warnings) == 1 and "a pose without covariance" in nominal.warnings[0]
    assert "  warning: FIND used the camera" in nominal.summary() and nominal.to_dict()["warnings"] == nominal.warnings
    cell = load_cell(EXAMPLE / "cell.yaml")
    measured = write_calibration(Calibration(X_camera=cell.camera.X_WC_real, camera_cov=np.diag([1e-6] * 3 + [1e-6] * 3)),
                                 tmp_path / "measured.yaml")
    assert not run_program(EXAMPLE / "stack.yaml", seed=0, calibration=measured).warnings


def test_a_missing_example_says_where_examples_come_from(tmp_path, monkeypatch):
    """From a wheel the docs' ``examples/workmate/stack.yaml`` is not there: the error says examples/ is the source
    checkout's; another missing file says only that it is missing."""
    from click.testing import CliRunner

    from armguard.cli import main

    monkeypatch.chdir(tmp_path)
    r = CliRunner().invoke(main, ["program", "run", "examples/workmate/stack.yaml"])
    assert r.exit_code == 3 and "examples/ comes with the source checkout" in r.output, r.output
    r = CliRunner().invoke(main, ["program", "run", "mine/stack.yaml"])
    assert r.exit_code == 3 and "file not found" in r.output and "checkout" not in r.output, r.output


def test_a_refusal_of_a_motion_into_an_object_as_found_says_they_collide(tmp_path):
    """An approach 5 cm inside cylinder A, refused at the confidence asked, said "as found they are 0.0 mm
    clear (calibrate the camera, or ask less confidence)": the clearance of a verification stops at its first
    contact.  A contact as found is said as one."""
    import shutil

    from armguard.program import run_program

    shutil.copytree(EXAMPLE, tmp_path / "w")
    prog = tmp_path / "w" / "stack.yaml"
    text = prog.read_text()
    old = "approach: {xyz: [0, 0, 0.12], rpy: [180, 0, 0]}"
    assert old in text
    prog.write_text(text.replace(old, "approach: {xyz: [0, 0, -0.05], rpy: [180, 0, 0]}", 1))
    run = run_program(prog, seed=0)
    refused = [m for m in run.motions if m.status.startswith("refused")]
    assert refused and refused[-1].k > 0.0 and refused[-1].nominal_clearance <= 0.0
    why = refused[-1].why()
    assert "the bound objects collide as found, without their growth" in why and not any("calibrate" in w for w in why), why
