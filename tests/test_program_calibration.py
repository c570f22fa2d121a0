"""Calibration files and the robot–camera calibration (WORKMATE, seed 004, §III.D.5).

The camera's real pose against its believed one (FIND is off by the difference), the calibration
file (round trip exact, errors located, the cell regenerated from it), the calibration program on
the emulated example cell whose camera really stands 27 mm and 2.8° from its nominal pose
(recovered within the noise: Mahalanobis distances against the reported covariance follow χ²
with 6 dof over many seeds), the written file reloading to the updated cell, the command line,
and the demonstration (calibrated placement error below the uncalibrated one)."""

from __future__ import annotations

import dataclasses
import importlib.util
import math
import os
import stat
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import stats

from armguard import SceneFileError
from armguard.program import (Calibration, Camera, calibrate_camera, fit_camera, fit_rigid_transform, load_cell,
                              pose, read_calibration, write_calibration)
from armguard.uncertainty import se3

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = ROOT / "examples" / "workmate"


# ------------------------------------------------------------------ the estimator with anisotropic noise
def test_anisotropic_noise_has_the_sandwich_covariance():
    """Noise 3x larger along one axis than the others: the Mahalanobis distances of 400 fits
    against the reported covariance follow chi-square with 6 dof; with cov = sigma² I the
    covariance is the isotropic one exactly."""
    rng = np.random.default_rng(4)
    X_true = pose([0.1, -0.3, 0.9], [2.9, -0.1, 0.4])
    p_B = rng.uniform([-0.15, -0.15, 0.0], [0.15, 0.15, 0.2], size=(10, 3))
    clean = p_B @ X_true[:3, :3].T + X_true[:3, 3]
    L = np.array([[0.0015, 0.0, 0.0], [0.0004, 0.0012, 0.0], [0.0, 0.0, 0.0005]])
    C = L @ L.T
    d2 = []
    for _ in range(400):
        fit = fit_rigid_transform(clean + rng.normal(size=clean.shape) @ L.T, p_B, cov=C)
        xi = se3.log(X_true @ np.linalg.inv(fit.X_AB))
        d2.append(float(xi @ np.linalg.solve(fit.pose.cov, xi)))
    d2 = np.array(d2)
    assert abs(d2.mean() / 6.0 - 1.0) < 0.15
    assert np.mean(d2 > stats.chi2.ppf(0.99, 6)) < 0.03
    iso = fit_rigid_transform(clean, p_B, sigma=0.002)
    np.testing.assert_allclose(fit_rigid_transform(clean, p_B, cov=0.002 ** 2 * np.eye(3)).pose.cov, iso.pose.cov,
                               rtol=1e-12, atol=1e-20)
    with pytest.raises(Exception, match="not both"):
        fit_rigid_transform(clean, p_B, 0.001, cov=C)
    with pytest.raises(Exception, match="positive semi-definite"):
        fit_rigid_transform(clean, p_B, cov=-C)


def test_the_sandwich_covariance_is_the_estimators_propagated_noise():
    """Reference: the estimator's Jacobian by central differences (each coordinate of p_A moved
    by ±1e-7 m, the left perturbation of the fitted pose read back by se3.log), propagated as
    Σ_i J_i C J_iᵀ — the first-order covariance without any of the closed form's algebra."""
    rng = np.random.default_rng(6)
    X_true = pose([0.2, 0.1, 0.8], [3.0, 0.2, -0.5])
    p_B = rng.uniform(-0.2, 0.2, size=(7, 3))
    p_A = p_B @ X_true[:3, :3].T + X_true[:3, 3]
    L = np.array([[0.002, 0.0, 0.0], [0.0005, 0.001, 0.0], [0.0003, -0.0002, 0.0007]])
    C = L @ L.T
    fit = fit_rigid_transform(p_A, p_B, cov=C)
    X0, h = fit.X_AB, 1e-7
    ref = np.zeros((6, 6))
    for i in range(len(p_A)):
        J = np.zeros((6, 3))
        for k in range(3):
            up, down = p_A.copy(), p_A.copy()
            up[i, k] += h
            down[i, k] -= h
            J[:, k] = (se3.log(fit_rigid_transform(up, p_B, sigma=1.0).X_AB @ np.linalg.inv(X0))
                       - se3.log(fit_rigid_transform(down, p_B, sigma=1.0).X_AB @ np.linalg.inv(X0))) / (2 * h)
        ref += J @ C @ J.T
    np.testing.assert_allclose(fit.pose.cov, ref, rtol=1e-5, atol=1e-6 * np.abs(ref).max())


# ------------------------------------------------------------------ the camera: real against believed pose
def test_the_camera_measures_from_its_real_pose_and_reports_through_its_believed_one():
    X_WC = pose([0.5, 0.0, 1.5], [math.pi, 0.0, 0.0])
    X_real = pose([0.52, -0.01, 1.49], [math.pi + 0.02, 0.01, 0.05])
    cam = Camera(X_WC, math.radians(60.0), np.zeros((6, 6)), X_real)
    X_WO = pose([0.6, 0.1, 0.6], [0.0, 0.0, 0.3])
    rng = np.random.default_rng(0)
    np.testing.assert_allclose(cam.measure_C(X_WO, rng), np.linalg.inv(X_real) @ X_WO, atol=1e-15)
    np.testing.assert_allclose(cam.measure(X_WO, rng), X_WC @ np.linalg.inv(X_real) @ X_WO, atol=1e-15)
    assert np.linalg.norm(cam.measure(X_WO, rng)[:3, 3] - X_WO[:3, 3]) > 0.01  # off by the camera's error (16 mm)
    # the field of view is the real camera's: a point on the real axis near the cone's edge
    edge = X_real[:3, 3] + X_real[:3, :3] @ [math.tan(math.radians(29.0)), 0.0, 1.0]
    far = X_real[:3, 3] + X_real[:3, :3] @ [math.tan(math.radians(31.0)), 0.0, 1.0]
    assert cam.sees(edge) and not cam.sees(far)


def test_the_noise_is_in_the_cameras_axes():
    """A camera turned 90° about W's z: the noise stated in its axes (x 3 mm, y 0.5 mm) shows in W
    with x and y swapped, and the bound frame's covariance says so."""
    X_WC = pose([0.5, 0.0, 1.5], [math.pi, 0.0, math.pi / 2])
    cam = Camera(X_WC, math.radians(60.0), np.diag([0.003, 0.0005, 0.001, 0.0, 0.0, 0.0]) ** 2)
    X_WO = pose([0.5, 0.05, 0.6])
    rng = np.random.default_rng(5)
    d = np.array([cam.measure(X_WO, rng)[:3, 3] - X_WO[:3, 3] for _ in range(3000)])
    sd = d.std(axis=0)
    np.testing.assert_allclose(sd, [0.0005, 0.003, 0.001], rtol=0.06)
    np.testing.assert_allclose(np.sqrt(np.diag(cam.uncertain(X_WO).cov)[:3]), [0.0005, 0.003, 0.001], rtol=1e-12)


# ------------------------------------------------------------------ calibration files
def test_the_example_calibration_file_is_the_nominal_layout():
    cell = load_cell(EXAMPLE / "cell.yaml")
    cal = read_calibration(EXAMPLE / "calibration.yaml")
    nominal = cell.nominal_calibration()
    assert set(cal.bodies) == set(cell.model.scene.bodies) and set(cal.robots) == {"puma560"}
    for k in nominal.bodies:
        np.testing.assert_allclose(cal.bodies[k], nominal.bodies[k], atol=1e-12)
    np.testing.assert_allclose(cal.robots["puma560"], cell.model.scene.robots["puma560"].X_WB, atol=1e-12)
    np.testing.assert_allclose(cal.X_camera, nominal.X_camera, atol=1e-12)
    np.testing.assert_allclose(cell.camera.X_WC, cell.nominal_camera.X_WC, atol=1e-12)
    assert cal.camera_cov is None and not np.any(cell.camera.cov_pose)


def test_a_calibration_moves_the_believed_cell_and_not_the_real_one(tmp_path):
    """A calibration that moves the robot's base, the table and block_a, and puts the camera
    relative to the robot: the believed scene is regenerated from it; the real one stays."""
    cell = load_cell(EXAMPLE / "cell.yaml")
    scene0 = cell.nominal_scene()
    D = pose([0.01, -0.02, 0.005], [0.0, 0.0, 0.03])
    X_WB = D @ cell.model.scene.robots["puma560"].X_WB
    X_BC = pose([0.6, 0.01, 0.83], [math.pi, 0.0, 0.02])
    cal = Calibration({"puma560": X_WB}, {"table": D @ cell.layout["table"], "block_a": pose([0.8, 0.31, 0.59])},
                      X_BC, "puma560", np.diag([1e-6] * 3 + [1e-5] * 3))
    path = write_calibration(cal, tmp_path / "cal.yaml")
    back = read_calibration(path)
    for k in ("table", "block_a"):
        np.testing.assert_allclose(back.bodies[k], cal.bodies[k], atol=1e-14)
    np.testing.assert_allclose(back.X_camera, X_BC, atol=1e-14)
    np.testing.assert_allclose(back.camera_cov, cal.camera_cov, rtol=1e-15)
    c = load_cell(EXAMPLE / "cell.yaml", calibration=path)
    scene, real = c.nominal_scene(), c.real_scene()
    arm, arm0 = scene.robots["puma560"], scene0.robots["puma560"]
    q = scene.home("puma560")
    np.testing.assert_allclose(arm.link_pose(q, arm.tool_link), D @ arm0.link_pose(q, arm0.tool_link), atol=1e-12)
    for k, want in (("table", D @ cell.layout["table"]), ("block_a", pose([0.8, 0.31, 0.59]))):
        lo0, hi0 = np.asarray(scene0.bodies[k].shapes[0].aabb()).reshape(2, 3)
        moved = [s.transformed(want @ np.linalg.inv(cell.layout[k])).aabb() for s in scene0.bodies[k].shapes]
        got = [s.aabb() for s in scene.bodies[k].shapes]
        np.testing.assert_allclose(np.array(got, dtype=float), np.array(moved, dtype=float), atol=1e-12)
        np.testing.assert_allclose(np.asarray(real.bodies[k].shapes[0].aabb(), dtype=float).reshape(2, 3),
                                   np.array([lo0, hi0]), atol=1e-12)
    np.testing.assert_allclose(c.camera.X_WC, X_WB @ X_BC, atol=1e-12)
    ad = se3.adjoint(X_WB)
    np.testing.assert_allclose(c.camera.cov_pose, ad @ cal.camera_cov @ ad.T, rtol=1e-12)
    np.testing.assert_allclose(c.camera.X_WC_real, cell.camera.X_WC_real, atol=0)  # the truth does not move
    np.testing.assert_allclose(real.robots["puma560"].X_WB, cell.model.scene.robots["puma560"].X_WB, atol=0)


_finite = st.floats(-2.0, 2.0, allow_nan=False, width=64)


@settings(max_examples=40, deadline=None)
@given(xyz=st.lists(_finite, min_size=3, max_size=3), rpy=st.lists(st.floats(-3.1, 3.1), min_size=3, max_size=3),
       cam=st.lists(_finite, min_size=6, max_size=6), scale=st.floats(1e-9, 1e-2))
def test_a_written_calibration_reads_back_the_same(tmp_path_factory, xyz, rpy, cam, scale):
    """Property: any relationships and any covariance written are read back (m and degrees in
    the file, every number repr-exact: poses within 1e-12, the covariance bit for bit)."""
    A = np.random.default_rng(abs(hash((tuple(xyz), scale))) % 2**32).normal(size=(6, 6))
    cov = scale * (A @ A.T)
    cal = Calibration({"puma560": pose(xyz, rpy)}, {"table": pose(cam[:3], cam[3:])}, pose(cam[3:], rpy), "puma560",
                      cov, {"points": 7, "rms": scale, "seed": 3}, "c", 'a "quoted" text')
    path = write_calibration(cal, tmp_path_factory.mktemp("prop") / "cal.yaml")
    back = read_calibration(path)
    np.testing.assert_allclose(back.robots["puma560"], cal.robots["puma560"], atol=1e-12)
    np.testing.assert_allclose(back.bodies["table"], cal.bodies["table"], atol=1e-12)
    np.testing.assert_allclose(back.X_camera, cal.X_camera, atol=1e-12)
    assert back.camera_relative_to == "puma560" and back.description == cal.description
    np.testing.assert_array_equal(back.camera_cov, 0.5 * (cov + cov.T))
    assert back.record == cal.record


BAD = [
    ("armguard_calibration: 1\nbodeis: {}\n", "bodeis (line 2)", "unknown key"),
    ("armguard_calibration: 1\nbodies:\n  cylinder_z: {xyz: [0, 0, 0]}\n", "bodies.cylinder_z (line 3)",
     "no body 'cylinder_z'"),
    ("armguard_calibration: 1\nrobots:\n  puma: {}\n", "robots.puma (line 3)", "no robot 'puma'"),
    ("armguard_calibration: 1\ncamera: {relative_to: table}\n", "camera.relative_to", "'world' or a robot's base"),
    ("armguard_calibration: 1\ncamera:\n  cov: [[1, 0], [0, 1]]\n", "camera.cov", "6"),
    ("armguard_calibration: 1\ncamera:\n  cov:\n" + "".join(f"    - [{', '.join('1' if j == i or (i, j) == (0, 1) else '0' for j in range(6))}]\n"
                                                        for i in range(6)), "camera.cov", "symmetric"),
    ("armguard_calibration: 1\ncamera:\n  cov:\n" + "".join(f"    - [{', '.join('-1' if j == i else '0' for j in range(6))}]\n"
                                                        for i in range(6)), "camera.cov", "positive semi-definite"),
    ("armguard_calibration: 1\nbodies: {table: {xyz: [0, .inf, 0]}}\n", "bodies.table.xyz[1]", "finite"),
    ("armguard_calibration: 2\n", "armguard_calibration", "1"),
]


@pytest.mark.parametrize("text, where, what", BAD)
def test_a_bad_calibration_file_is_located(tmp_path, text, where, what):
    p = tmp_path / "cal.yaml"
    p.write_text(text, encoding="utf-8")
    with pytest.raises(SceneFileError) as ei:
        load_cell(EXAMPLE / "cell.yaml", calibration=p)
    msg = str(ei.value)
    assert msg.startswith(str(p)) and where in msg and what in msg, msg


def test_a_cell_file_naming_a_missing_calibration_file_is_located(tmp_path):
    c = tmp_path / "c.yaml"
    c.write_text("armguard_cell: 1\nmodel: puma560\ncalibration: nowhere.yaml\n", encoding="utf-8")
    with pytest.raises(SceneFileError, match=r"c\.yaml: calibration \(line 3\): expected a calibration file"):
        load_cell(c)


# ------------------------------------------------------------------ the calibration program
@pytest.fixture(scope="module")
def calibration():
    return calibrate_camera(load_cell(EXAMPLE / "cell.yaml"), seed=0)


def _X_BC_true(cell) -> np.ndarray:
    return np.linalg.inv(cell.model.scene.robots[cell.robot].X_WB) @ cell.camera.X_WC_real


def test_the_calibration_recovers_the_real_camera_within_its_covariance(calibration):
    cal = calibration
    assert cal.ok, cal.stopped
    assert [m.status for m in cal.run.motions] == ["ran"] * 13  # 12 points and home, each verified
    assert all(m.report.safe and m.report.details.method == "certified" for m in cal.run.motions)
    X_true = _X_BC_true(cal.cell)
    xi = se3.log(X_true @ np.linalg.inv(cal.X_BC.mean))
    assert float(xi @ np.linalg.solve(cal.X_BC.cov, xi)) < stats.chi2.ppf(0.999, 6)
    err_after = np.linalg.norm(cal.X_WC_after[:3, 3] - cal.cell.camera.X_WC_real[:3, 3])
    err_before = np.linalg.norm(cal.X_WC_before[:3, 3] - cal.cell.camera.X_WC_real[:3, 3])
    assert err_before > 0.025 and err_after < 0.2 * err_before
    # each stop: the calibration object's base-frame position is the tool point by forward kinematics
    arm = cal.cell.model.scene.robots["puma560"]
    for s in cal.stops:
        np.testing.assert_allclose(np.linalg.inv(arm.X_WB) @ np.append(arm.link_pose(s.q, arm.tool_link)[:3, 3], 1.0),
                                   np.append(s.p_B, 1.0), atol=1e-12)


def test_over_many_seeds_the_error_follows_the_reported_covariance(calibration):
    """The same trained trajectory, 300 draws of the camera's noise (the measurement and fit the
    calibration makes): Mahalanobis distances to the real camera follow chi-square, 6 dof."""
    cell, stops = calibration.cell, calibration.stops
    X_true = _X_BC_true(cell)
    rng = np.random.default_rng(11)
    d2 = []
    for _ in range(300):
        _, _, X_BC = fit_camera(cell, stops, rng)
        xi = se3.log(X_true @ np.linalg.inv(X_BC.mean))
        d2.append(float(xi @ np.linalg.solve(X_BC.cov, xi)))
    d2 = np.array(d2)
    assert abs(d2.mean() / 6.0 - 1.0) < 0.15
    assert np.mean(d2 > stats.chi2.ppf(0.99, 6)) < 0.03
    assert stats.kstest(d2, stats.chi2(6).cdf).pvalue > 0.001


def test_the_written_calibration_file_reloads_to_the_updated_cell(calibration, tmp_path):
    cal = calibration
    path = write_calibration(cal.calibration(), tmp_path / "calibrated.yaml")
    text = path.read_text(encoding="utf-8")
    assert "relative_to: puma560" in text and "calibrated: {points: 12" in text
    cell = load_cell(EXAMPLE / "cell.yaml", calibration=path)
    np.testing.assert_allclose(cell.camera.X_WC, cal.X_WC_after, atol=1e-12)
    np.testing.assert_allclose(cell.camera.cov_pose, se3.adjoint(cell.bases["puma560"]) @ cal.X_BC.cov
                               @ se3.adjoint(cell.bases["puma560"]).T, rtol=1e-9, atol=1e-20)
    for k, X in cal.cell.objects.items():  # every other relationship as it was
        np.testing.assert_allclose(cell.objects[k], X, atol=1e-12)
    np.testing.assert_allclose(cell.camera.X_WC_real, cal.cell.camera.X_WC_real, atol=0)
    rec = read_calibration(path).record
    assert rec["points"] == 12 and rec["seed"] == 0 and rec["rms"] == pytest.approx(cal.fit.rms, rel=1e-15)
    # the bound frames now carry the calibration's uncertainty too (X_WO = X_WC X_CO compounded)
    X = cell.objects["cylinder_a"]
    exact = dataclasses.replace(cell.camera, cov_pose=None)
    np.testing.assert_allclose(cell.camera.uncertain(X).cov - exact.uncertain(X).cov, cell.camera.cov_pose,
                               rtol=1e-9, atol=1e-20)


def test_a_point_the_camera_cannot_see_stops_the_calibration():
    cell = load_cell(EXAMPLE / "cell.yaml")
    cell.nominal_camera = dataclasses.replace(cell.nominal_camera, fov=math.radians(2.0))  # a 2° cone
    cell.calibrate(None)
    cal = calibrate_camera(cell, n=3)
    assert not cal.ok and "outside the camera's field of view" in cal.stopped
    assert cal.fit is None and not cal.stops and len(cal.run.motions) == 1  # stopped at the first point
    with pytest.raises(Exception, match="no calibration"):
        cal.calibration()


def test_the_command_line_calibrates_and_writes_the_file(tmp_path):
    from click.testing import CliRunner

    from armguard.cli import main

    runner = CliRunner()
    out = tmp_path / "cal.yaml"
    r = runner.invoke(main, ["program", "calibrate", str(EXAMPLE / "cell.yaml"), "--out", str(out), "--points", "5"])
    assert r.exit_code == 0 and "5 points" in r.output and out.is_file(), r.output
    cell = load_cell(EXAMPLE / "cell.yaml", calibration=out)
    assert np.linalg.norm(cell.camera.X_WC[:3, 3] - cell.camera.X_WC_real[:3, 3]) < 0.01
    narrow = tmp_path / "narrow.yaml"
    narrow.write_text((EXAMPLE / "cell.yaml").read_text(encoding="utf-8").replace("fov: 60", "fov: 2")
                      .replace("calibration: calibration.yaml", f"calibration: {EXAMPLE / 'calibration.yaml'}"),
                      encoding="utf-8")
    out2 = tmp_path / "never.yaml"
    r = runner.invoke(main, ["program", "calibrate", str(narrow), "--out", str(out2), "--points", "3"])
    assert r.exit_code == 1 and "STOPPED" in r.output and not out2.exists(), r.output
    fifo = tmp_path / "fifo.yaml"
    os.mkfifo(fifo)
    r = runner.invoke(main, ["program", "calibrate", str(EXAMPLE / "cell.yaml"), "--out", str(fifo), "--points", "3"])
    assert r.exit_code == 3 and str(fifo) in r.output and stat.S_ISFIFO(os.stat(fifo).st_mode), r.output
    r = runner.invoke(main, ["program", "calibrate", "puma560"])
    assert r.exit_code == 2 and "--out" in r.output
    bad = tmp_path / "bad.yaml"
    bad.write_text("armguard_calibration: 1\nbodies: {nothing: {}}\n", encoding="utf-8")
    r = runner.invoke(main, ["program", "calibrate", str(EXAMPLE / "cell.yaml"), "--calibration", str(bad),
                             "--out", str(out2)])
    assert r.exit_code == 3 and "bodies.nothing" in r.output and not out2.exists(), r.output


# ------------------------------------------------------------------ the demonstration
def test_the_demonstration_places_better_calibrated(tmp_path):
    """examples/workmate_demo.py, seed 0: calibrated, the placed cylinder's axis lands within 6.4 mm
    of the other's (3 sigma of the difference of two FINDs' horizontal errors, sqrt(2) x 1.5 mm per
    axis); with the nominal camera pose it lands further off than that."""
    from click.testing import CliRunner

    from armguard.cli import main

    spec = importlib.util.spec_from_file_location("workmate_demo", ROOT / "examples" / "workmate_demo.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # its dataclass looks its module up
    try:
        spec.loader.exec_module(mod)
    finally:
        sys.modules.pop(spec.name, None)
    lines = []
    demo = mod.demonstration(tmp_path, seed=0, echo=lines.append)
    assert demo.ok and demo.uncalibrated.ok
    bound = 3 * math.sqrt(2) * 0.0015
    assert demo.offset_calibrated < bound < demo.offset_uncalibrated
    assert demo.offset_calibrated < 0.5 * demo.offset_uncalibrated
    assert f"calibrated: {1e3 * demo.offset_calibrated:.1f} mm" in "\n".join(lines)
    assert load_cell(EXAMPLE / "cell.yaml", calibration=demo.calibration_file).calibration.record["points"] == 12
    text = demo.program_file.read_text(encoding="utf-8")
    assert f"calibration={str(demo.calibration_file.resolve())!r}" in text and "wc.find('cylinder_b')" in text
    r = CliRunner().invoke(main, ["demo", "--list"])
    assert r.exit_code == 0 and "python examples/workmate_demo.py" in r.output
    assert "from the root of the source checkout; a wheel installs none of them" in r.output
    examples = [line for line in r.output.splitlines() if line.startswith("python ")]
    assert len(examples) == 4 and any("examples/prm_edges.py" in line for line in examples)
    for line in examples:
        assert (ROOT / line.split()[1].rstrip(":")).is_file(), line


@pytest.mark.parametrize("kw, said", [
    (dict(n=2), "n: expected an integer >= 3"), (dict(n=2.5), "n: expected an integer >= 3"),
    (dict(n=0), "n: expected an integer >= 3"),
    (dict(poses=np.zeros((3, 3))), r"poses\[0\]"), (dict(poses=np.full((3, 4, 4), np.nan)), r"poses\[0\]"),
    (dict(poses=[np.eye(4)] * 2), "at least 3 tool poses"),
    (dict(X_EK=np.full((4, 4), np.nan)), "X_EK"), (dict(X_EK=[1, 2, 3]), "X_EK"),
])
def test_calibrate_camera_checks_its_inputs_before_moving(kw, said):
    """A NaN X_EK gave STOPPED "outside the camera's field of view" after a motion; NaN poses were
    "unreachable"; n = 2 moved the arm twice before the fit refused it; n = 2.5 ran as 2."""
    from armguard import UncertaintyError

    with pytest.raises(UncertaintyError, match=said):
        calibrate_camera(load_cell(EXAMPLE / "cell.yaml"), **kw)


def test_calibrate_a_bare_model_cell_with_the_defaults():
    """`armguard program calibrate puma560` stopped at point 6 ("8 solutions exist but each violates a
    joint limit"): the default spiral under the bare cell's camera reached beyond the PUMA's limits.
    Unreachable points are now drawn in towards the camera's axis; every default point is reachable."""
    from armguard.program import calibration_poses
    from armguard.program._calibration import _reachable

    cell = load_cell("puma560")
    poses = calibration_poses(cell, 12)
    assert len(poses) == 12 and all(_reachable(cell, X) for X in poses)
    cal = calibrate_camera(cell, n=6)
    assert cal.status.value == "calibrated", cal.stopped


def test_the_summary_gives_the_cameras_own_position_sigma(calibration):
    """The summary printed rho's sigma (the perturbation at the base's origin) as the camera's position sigma
    ([0.85, 2.98, 2.28] mm where the camera's own were [2.75, 2.42, 0.17]).  It prints the camera origin's, and
    those match Monte Carlo draws of the calibrated pose."""
    import re

    from scipy.linalg import expm

    from armguard.uncertainty import UncertainPlacement

    line = next(ln for ln in calibration.summary().splitlines() if "camera in" in ln)
    printed = [float(x) for x in re.search(r"sigma \[([^\]]*)\] mm", line)[1].split(",")]
    cov = UncertainPlacement("camera", calibration.X_BC).cov_origin
    np.testing.assert_allclose(printed, np.round(1e3 * np.sqrt(np.diag(cov)[:3]), 2), atol=0.006)
    rng = np.random.default_rng(1)
    T, C = calibration.X_BC.mean, calibration.X_BC.cov

    def hat(xi):
        M = np.zeros((4, 4))
        M[:3, :3] = [[0, -xi[5], xi[4]], [xi[5], 0, -xi[3]], [-xi[4], xi[3], 0]]
        M[:3, 3] = xi[:3]
        return M

    drawn = np.array([(expm(hat(xi)) @ T)[:3, 3] for xi in rng.multivariate_normal(np.zeros(6), C, 4000)])
    np.testing.assert_allclose(1e3 * drawn.std(axis=0), printed, rtol=0.1)


def test_calibrating_a_robot_alone_flies_above_the_floor(tmp_path):
    """A cell with no static body (panda, ur5, kinova by name): max() of no body's height was an internal error."""
    from click.testing import CliRunner

    from armguard.cli import main
    from armguard.model import known_models

    if "panda" not in {m.name for m in known_models() if m.available}:
        pytest.skip("panda's package (example-robot-data) is not installed")
    r = CliRunner().invoke(main, ["program", "calibrate", "panda", "--out", str(tmp_path / "c.yaml"), "--points", "3"])
    assert r.exit_code == 0, r.output
    assert (tmp_path / "c.yaml").is_file() and "internal error" not in r.output
