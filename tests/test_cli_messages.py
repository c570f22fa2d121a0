"""What the commands say where a reader of the documentation ran them as written and was misled.

A sidecar's relative URDF path is read from the sidecar's folder: the error names the absolute path
it tried.  armguard's own options (``-q``, ``--backend``, ...) placed after the command were
"No such option" with no hint.  A malformed ``console --uncertain`` was exit 3, not a usage error.
``tools/compare.py --help`` printed a usage line (``compare.py compare MODEL``) that failed.
``info --rad`` printed velocities without a unit; ``1 disabled pairs were``; the SRDF progress bar
named the URDF's robot (``talos``), not the name given (``talos_left_arm``); ``verify --terrain
--workers 2`` ignored the workers; a stopping-distance violation reported a clearance above the
limit with no word of the tolerance.  docs/program.md and docs/trajectory-format.md quote errors
that the commands print.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest
from click.testing import CliRunner

from armguard.cli import ExitCode, main

ROOT = Path(__file__).resolve().parents[1]
ROBOTS = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix/share/example-robot-data/robots"


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


# ------------------------------------------------------------------ a sidecar's relative URDF (docs/models.md)

def _romeo_sidecar() -> str:
    text = (ROOT / "docs" / "models.md").read_text(encoding="utf-8")
    block = next(b for b in re.findall(r"```yaml\n(.*?)```", text, re.S) if "name: romeo" in b)
    assert "urdf: robots/romeo_description/urdf/romeo.urdf" in block
    return block


def test_a_missing_sidecar_urdf_names_the_absolute_path_and_the_folder(tmp_path, monkeypatch):
    (tmp_path / "cell").mkdir()
    (tmp_path / "cell" / "romeo.yaml").write_text(_romeo_sidecar())
    monkeypatch.chdir(tmp_path)  # the file is given relative to the working directory, its URDF to its folder
    res = _run("check", "cell/romeo.yaml")
    assert res.exit_code == ExitCode.INPUT, res.output
    tried = tmp_path / "cell" / "robots" / "romeo_description" / "urdf" / "romeo.urdf"
    assert f"model.urdf (line 3): URDF file not found: {tried} " in res.output, res.output
    assert f"relative to the folder of romeo.yaml, {tmp_path / 'cell'}" in res.output, res.output


def test_a_missing_robot_urdf_of_a_scene_file_names_the_absolute_path(tmp_path):
    scene = tmp_path / "s.yaml"
    scene.write_text("armguard_scene: 1\nname: s\nrobots:\n  - name: r\n    urdf: nope/arm.urdf\n")
    res = _run("check", scene)
    assert res.exit_code == ExitCode.INPUT
    assert f"robots[0].urdf (line 5): URDF file not found: {tmp_path / 'nope' / 'arm.urdf'} " in res.output, res.output


@pytest.mark.skipif(not (ROBOTS / "romeo_description").is_dir(), reason="example-robot-data's romeo is not installed")
def test_the_romeo_sidecar_of_docs_models_works_as_the_guide_says(tmp_path):
    """Saved beside a link to example-robot-data's robots folder, it loads; romeo collides at that pose."""
    (tmp_path / "robots").symlink_to(ROBOTS, target_is_directory=True)
    (tmp_path / "romeo.yaml").write_text(_romeo_sidecar())
    res = _run("check", tmp_path / "romeo.yaml")
    assert res.exit_code == ExitCode.UNSAFE, res.output
    assert "status: COLLISION" in res.output and "144 of 903 pairs evaluated" in res.output, res.output
    guide = (ROOT / "docs" / "models.md").read_text(encoding="utf-8")
    assert "144 of 903 pairs evaluated" in guide and "LWristRollLink" in res.output and "LWristRollLink" in guide


# ------------------------------------------------------------------ armguard's own options after the command

@pytest.mark.parametrize("args,option,fixed", [
    (["check", "z1", "-q"], "-q", "armguard -q check ..."),
    (["check", "z1", "--quiet"], "--quiet", "armguard --quiet check ..."),
    (["check", "z1", "--backend", "coal"], "--backend", "armguard --backend NAME check ..."),
    (["cspace", "build", "hermes", "--config", "a.toml"], "--config", "armguard --config PATH cspace build ..."),
    (["verify", "hermes", "all", "--traceback"], "--traceback", "armguard --traceback verify ..."),
    (["check", "z1", "--version"], "--version", "armguard --version"),
])
def test_a_group_option_after_the_command_says_where_it_goes(args, option, fixed):
    res = CliRunner().invoke(main, args, prog_name="armguard")
    assert res.exit_code == ExitCode.USAGE, res.output
    assert f"No such option '{option}'" in res.output, res.output
    assert "armguard's own options (--version, --backend NAME, --config PATH, --traceback, -q/--quiet) go before " \
           f"the command: {fixed}" in res.output, res.output


def test_an_unknown_option_of_the_command_itself_is_left_as_click_says_it():
    res = CliRunner().invoke(main, ["check", "z1", "--qq"], prog_name="armguard")
    assert res.exit_code == ExitCode.USAGE and "No such option '--qq'" in res.output
    assert "go before the command" not in res.output


# ------------------------------------------------------------------ console --uncertain: a usage error

@pytest.mark.parametrize("value,said", [("chassis=abc", "must be numbers"), ("chassis", "expected BODY=SIGMA_M"),
                                        ("chassis=-1", "finite and >= 0"), ("chassis=0,0", "both 0"),
                                        ("chassis=0.1,2,3", "SIGMA_M,SIGMA_DEG")])
def test_a_malformed_uncertain_value_is_refused_where_click_reads_it(value, said, monkeypatch):
    """Exit 2 before anything is loaded or served (make_state is never reached)."""
    import armguard.console._serve as serve

    def never(*a, **k):
        raise AssertionError("the console was started")

    monkeypatch.setattr(serve, "make_state", never)
    res = _run("console", "rover", "--port", "0", "--uncertain", value)
    assert res.exit_code == ExitCode.USAGE, res.output
    assert "Invalid value for '--uncertain'" in res.output and said in res.output, res.output


def test_a_well_formed_uncertain_value_reaches_the_console(monkeypatch):
    import armguard.console._serve as serve

    seen = {}

    class Stop(Exception):
        pass

    def fake(scene, **kw):
        seen.update(kw, scene=scene)
        raise Stop

    monkeypatch.setattr(serve, "make_state", fake)
    res = _run("console", "rover", "--port", "0", "--uncertain", "chassis=0.01,0.5", "--uncertain", "mast=0.02")
    assert "Stop" in res.output, res.output  # stopped where the console would load the scene: nothing served
    assert seen["uncertain"] == ("chassis=0.01,0.5", "mast=0.02")
    assert getattr(seen["scene"], "source", seen["scene"]) == "rover"  # the scene read before any kernel compiles


# ------------------------------------------------------------------ the tool scripts' usage lines

@pytest.mark.parametrize("script,usage,args", [
    ("compare.py", "Usage: compare.py [OPTIONS] MODEL", ["z1", "--configs", "0"]),
    ("check_urdf.py", "Usage: check_urdf.py [OPTIONS] PATH", ["z1", "--configs", "0"]),
])
def test_a_tool_script_prints_the_usage_that_works(script, usage, args):
    def run(*a):
        return subprocess.run([sys.executable, str(ROOT / "tools" / script), *a], capture_output=True, text=True,
                              timeout=120, cwd=ROOT)

    helped = run("--help")
    assert helped.returncode == 0 and helped.stdout.startswith(usage + "\n"), helped.stdout
    # the usage line as written: MODEL right after the script's name (a bad --configs, so nothing runs)
    bad = run(*args)
    assert bad.returncode == ExitCode.USAGE, bad.stderr
    assert usage in bad.stderr and "--configs" in bad.stderr and "unexpected extra argument" not in bad.stderr


def test_run_as_script_exits_with_the_command_s_status(tmp_path):
    from armguard.cli import run_as_script

    with pytest.raises(SystemExit) as e:
        run_as_script("check-urdf", [str(tmp_path / "absent.urdf")], name="check_urdf.py")
    assert e.value.code == ExitCode.INPUT


# ------------------------------------------------------------------ info: units of the velocities

PRISMATIC = """\
armguard_scene: 1
name: slide
robots:
  - name: arm
    convention: standard
    joints:
      - {name: s1, type: prismatic, a: 0, alpha: 0, d: 0, theta: 0, limits: [0, 0.5], max_velocity: 0.25}
      - {name: r2, a: 0.3, alpha: 0, d: 0, theta: 0, limits: [-1, 1], max_velocity: 1.0}
    link_shapes:
      link2: [{type: sphere, radius: 0.05}]
bodies:
  - name: post
    shapes: [{type: box, xyz: [1, 1, 0], size: [0.1, 0.1, 0.1]}]
"""


def _row(output: str, joint: str) -> list[str]:
    line = next(ln for ln in output.splitlines() if re.match(rf"\W*{joint}\s", ln))
    return [c.strip() for c in re.split(r"[│|]", line) if c.strip()]


def test_info_prints_every_max_velocity_with_its_unit(tmp_path):
    f = tmp_path / "slide.yaml"
    f.write_text(PRISMATIC)
    deg, rad = _run("info", f), _run("info", f, "--rad")
    assert deg.exit_code == 0 and rad.exit_code == 0, deg.output + rad.output
    assert _row(deg.output, "s1")[4] == "0.25 m/s" and _row(deg.output, "r2")[4] == "57.3°/s"
    assert _row(rad.output, "s1")[4] == "0.25 m/s" and _row(rad.output, "r2")[4] == "1 rad/s"
    hermes = _run("info", "hermes", "--rad")
    assert _row(hermes.output, "shoulder_yaw")[4] == "0.03491 rad/s", hermes.output


# ------------------------------------------------------------------ one pair, not "1 pairs"; the bar's name

def test_a_single_stale_certificate_is_worded_in_the_singular(monkeypatch):
    import armguard.model._certificate as certificate
    from armguard.model._load import _warn_stale

    class Stale:
        link1, link2, reason = "a", "b", "Never"

    class Srdf:
        file, said = "x.srdf", []

        def warn(self, message):
            self.said.append(message)

    for n in (1, 2):
        monkeypatch.setattr(certificate, "stale_certificates", lambda *a, n=n: [Stale()] * n)
        srdf = Srdf()
        srdf.said = []
        _warn_stale(srdf, None, None)
        (said,) = srdf.said
        if n == 1:
            assert said.startswith("1 disabled pair was certified") and "proves it again" in said, said
        else:
            assert said.startswith("2 disabled pairs were certified") and "proves them again" in said, said


def test_the_srdf_progress_bar_names_the_robot_as_given(tmp_path):
    """A URDF whose <robot name> is not the name given (talos_left_arm.urdf is robot 'talos')."""
    shutil.copytree(ROOT / "urdf" / "puma560", tmp_path / "p")
    (tmp_path / "p" / "puma560.urdf").rename(tmp_path / "p" / "my_arm.urdf")
    res = _run("srdf", tmp_path / "p" / "my_arm.urdf", "--out", tmp_path / "out.srdf", "--max-evaluations", "50")
    assert res.exit_code == 0, res.output
    assert "my_arm.urdf: certified collision matrix" in res.output and "puma560: certified" not in res.output


# ------------------------------------------------------------------ verify --terrain: serial

@pytest.mark.parametrize("extra,named", [(["--workers", "2"], "--workers"), (["--scheduler", "tcp://x:1"], "--scheduler")])
def test_verify_terrain_refuses_what_it_would_ignore(extra, named):
    res = _run("verify", "rover", "place_instrument", "--terrain", ROOT / "reference/terrain/rocky.npz", *extra)
    assert res.exit_code == ExitCode.USAGE, res.output
    assert f"{named} does not go with --terrain" in res.output and "one trajectory after another" in res.output


def test_verify_help_says_what_terrain_does_with_method():
    text = " ".join(_run("verify", "--help").output.split())
    assert "the terrain sweep is certified whatever --method" in text and "not with --workers or --scheduler" in text


# ------------------------------------------------------------------ a violation within the tolerance

def test_a_violation_within_the_contact_tolerance_says_so():
    """hermes/stow_misaligned at 100 mm: the clearance 100.0008 mm is within ``verify_contact`` of the limit."""
    from armguard.scene import load_scene
    from armguard.verify import CollisionKind, Verifier
    from armguard._tolerance import DEFAULT_TOLERANCES

    sc = load_scene("hermes")
    t = sc.trajectories["stow_misaligned"]
    r = Verifier(sc, robot=t.robot_name).verify(t, stopping_distance=0.1)
    c = r.first_collision
    assert r.verdict() == "unsafe (stopping distance)" and c.kind is CollisionKind.STOPPING_DISTANCE  # unchanged
    assert c.stopping_distance <= c.distance <= c.stopping_distance + DEFAULT_TOLERANCES.verify_contact
    assert c.describe() == (f"reaches the stopping distance 100.0000 mm (clearance {c.distance * 1e3:.4f} mm, within "
                            "the verifier's contact tolerance)")


# ------------------------------------------------------------------ errors the guides quote

def test_docs_program_quotes_the_misspelt_grasp_error(tmp_path, monkeypatch):
    shutil.copytree(ROOT / "examples" / "workmate", tmp_path / "examples" / "workmate")
    stack = tmp_path / "examples" / "workmate" / "stack.yaml"
    lines = stack.read_text().splitlines(keepends=True)
    assert lines[14].lstrip().startswith("grasp:")  # line 15
    lines[14] = lines[14].replace("grasp:", "grsp:", 1)
    stack.write_text("".join(lines))
    monkeypatch.chdir(tmp_path)
    res = _run("program", "run", "examples/workmate/stack.yaml")
    assert res.exit_code == ExitCode.INPUT
    guide = (ROOT / "docs" / "program.md").read_text(encoding="utf-8")
    for line in res.output.strip().splitlines():
        assert line in guide, line


def test_docs_program_quotes_the_calibration_errors_in_their_order(tmp_path, monkeypatch):
    """The guide said the three problems of its cal.yaml were listed at once: the form's come first, then the
    names the cell lacks, together."""
    shutil.copytree(ROOT / "examples" / "workmate", tmp_path, dirs_exist_ok=True)
    monkeypatch.chdir(tmp_path)
    guide = (ROOT / "docs" / "program.md").read_text(encoding="utf-8")
    head = "armguard_calibration: 1\nbodies:\n  cylinder_z: {xyz: [0, 0, 0]}\ncamera:\n  relative_to: table\n"
    for cov in ("  cov: [[1, 2]]\n", ""):
        (tmp_path / "cal.yaml").write_text(head + cov)
        res = _run("program", "run", "stack.yaml", "--calibration", "cal.yaml")
        assert res.exit_code == ExitCode.INPUT, res.output
        for line in res.output.strip().removeprefix("error: ").splitlines():
            assert line in guide, line


def test_docs_trajectory_format_quotes_the_limits_error(tmp_path):
    f = tmp_path / "reach.yaml"
    f.write_text("format: armguard.trajectory\nversion: 1\nrobot: puma560\njoint_names: [j1, j2, j3, j4, j5, j6]\n"
                 "times: [0.0, 1.5, 3.0]\nwaypoints:\n  - [0.0, 0.79, -2.36, 0.0, -0.79, 0.0]\n"
                 "  - [0.53, 10, -3.06, 0.0, -1.33, -2.61]\n  - [0.53, 1.13, -3.22, 0.0, -1.05, -2.61]\n")
    res = _run("verify", "puma560", f)
    assert res.exit_code == ExitCode.INPUT
    said = res.output.strip().removeprefix(f"error: {f}: ")
    guide = " ".join((ROOT / "docs" / "trajectory-format.md").read_text(encoding="utf-8").split())
    assert said.startswith("waypoints[1][1] (line 8)") and f"reach.yaml: {said}" in guide, said


def test_check_srdf_help_lists_coal_distance():
    text = " ".join(_run("check-srdf", "--help").output.split())
    assert "coal_distance" in text and "proven_disabled" in text



def test_check_says_when_its_collision_is_the_stopping_distance_not_a_contact():
    """``check ur5 --stopping-distance 0.03`` printed COLLISION beside a nearest row of +0.0198 m, the
    stopping distance nowhere in the text (verify said "within the stopping distance, no contact")."""
    r = CliRunner().invoke(main, ["check", "ur5", "--stopping-distance", "0.03"], env={"COLUMNS": "250"})
    assert r.exit_code == int(ExitCode.UNSAFE), r.output
    head = r.output.splitlines()[0]
    assert "COLLISION (within the stopping distance, no contact)" in head and "stopping distance 0.03 m" in head, head
    r = CliRunner().invoke(main, ["check", "ur5", "--stopping-distance", "0.01"], env={"COLUMNS": "250"})
    assert "within the stopping distance" not in r.output and "stopping distance 0.01 m" in r.output.splitlines()[0]


def test_console_says_why_it_cannot_serve_before_it_starts():
    """``--host`` with an address this machine lacks and ``--port 0`` hung silently (viser retried it
    forever); with a port it read "port in use"; a port in use still says so."""
    import socket

    from armguard import ArmguardError
    from armguard.console._app import PortInUseError, _check_port_free

    with socket.socket() as held:
        held.bind(("127.0.0.1", 0))
        held.listen()
        port = held.getsockname()[1]
        with pytest.raises(PortInUseError, match=f"port {port} on 127.0.0.1 is in use"):
            _check_port_free("127.0.0.1", port)
    _check_port_free("127.0.0.1", 0)  # any free port of this machine: no error
    _check_port_free("", 0)  # every interface, as before
    for port in (0, 8123):
        with pytest.raises(ArmguardError, match="cannot serve on 192.0.2.1 .*address of this machine") as info:
            _check_port_free("192.0.2.1", port)  # TEST-NET-1: never this machine's
        assert not isinstance(info.value, PortInUseError)
    with pytest.raises(ArmguardError, match="'nosuchhost.invalid' does not resolve"):
        _check_port_free("nosuchhost.invalid", 0)
    res = _run("console", "gmf_s480", "--host", "192.0.2.1", "--port", "0")
    assert res.exit_code == ExitCode.INPUT and "cannot serve on 192.0.2.1" in res.output
