"""Every ``armguard`` exit status means one thing (armguard.cli.ExitCode), and every command's
``--help`` says which: 0 done / clear, 1 unsafe, 2 usage, 3 a file or value refused, 4 internal
error, 5 incomplete, 130 interrupted, 141 output closed early.  In-process with click's CliRunner, and one real SIGINT in
a subprocess."""

from __future__ import annotations

import json

import os
import signal
import subprocess
import sys
from types import SimpleNamespace

import click
import pytest
from click.testing import CliRunner

import armguard.scene
from armguard.cli import ExitCode, main
from armguard.cli._verify import verify_exit_code
from armguard.verify import VerificationStatus


def _run(*args, env=None):
    return CliRunner().invoke(main, [str(a) for a in args], env=env)


def test_codes_are_distinct_and_fixed():
    """Scripts rely on the numbers: they are part of the interface."""
    assert [int(c) for c in ExitCode] == [0, 1, 2, 3, 4, 5, 130, 141]
    assert click.UsageError("x").exit_code == ExitCode.USAGE


def test_usage_error_is_2():
    res = _run("check", "hermes", "--no-such-option")
    assert res.exit_code == ExitCode.USAGE and "No such option" in res.output


def test_refused_input_is_3_and_one_line():
    res = _run("check", "no_such_scene")
    assert res.exit_code == ExitCode.INPUT, res.output
    assert res.output.startswith("error:") and res.output.strip().count("\n") == 0
    assert "no_such_scene" in res.output


@pytest.mark.parametrize("args", [
    ("compare", "ur5", "--backends", "analytic,nosuch", "--configs", "2", "--trajectory", "none"),
    ("srdf", "ur5", "--out", "unused.srdf", "--evaluator", "nosuch"),
    ("check-srdf", "ur5", "--evaluator", "nosuch"),
    ("compare", "ur5", "--q", "1,2,3"),
])
def test_a_bad_backend_name_or_q_length_is_a_usage_error_everywhere(args):
    """An unknown backend name, or a --q of the wrong length, is 2 in every command (as the group's
    --backend and check's --q), not 3; the message names what is installed or what --q holds."""
    res = _run(*args)
    assert res.exit_code == ExitCode.USAGE, res.output
    assert ("installed backends are" in res.output) or ("6 values in pin_model's order" in res.output), res.output


def test_os_error_reading_input_is_3(monkeypatch, tmp_path):
    def unreadable(spec, *a, **k):
        raise PermissionError(13, "Permission denied", str(tmp_path / "scene.yaml"))

    monkeypatch.setattr(armguard.scene, "load_scene", unreadable)
    res = _run("check", tmp_path / "scene.yaml")
    assert res.exit_code == ExitCode.INPUT, res.output
    assert f"error: {tmp_path / 'scene.yaml'}: Permission denied" in res.output


def _boom(*a, **k):
    raise RuntimeError("boom: an unexpected state\nsecond line")


def test_unexpected_exception_is_4_with_a_hint(monkeypatch):
    monkeypatch.setattr(armguard.scene, "load_scene", _boom)
    res = _run("check", "hermes", env={"ARMGUARD_DEBUG": ""})
    assert res.exit_code == ExitCode.INTERNAL, res.output
    assert "Traceback" not in res.output and "second line" not in res.output
    line = res.output.strip()
    assert line.count("\n") == 0 and line.startswith("error: internal error: RuntimeError: boom: an unexpected state")
    assert "--traceback" in line and "ARMGUARD_DEBUG=1" in line


@pytest.mark.parametrize("how", ["option", "env"])
def test_traceback_on_request(monkeypatch, how):
    monkeypatch.setattr(armguard.scene, "load_scene", _boom)
    if how == "option":
        res = CliRunner().invoke(main, ["--traceback", "check", "hermes"], env={"ARMGUARD_DEBUG": ""})
    else:
        res = _run("check", "hermes", env={"ARMGUARD_DEBUG": "1"})
    assert res.exit_code == ExitCode.INTERNAL, res.output
    assert "Traceback (most recent call last)" in res.output and "_boom" in res.output


def test_ctrl_c_is_130_not_a_collision(monkeypatch):
    def interrupted(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(armguard.scene, "load_scene", interrupted)
    res = _run("check", "hermes")
    assert res.exit_code == ExitCode.INTERRUPTED and "interrupted" in res.output


def test_real_sigint_is_130():
    """A real SIGINT to a running command (a command added for the test that waits)."""
    # the child restores Python's SIGINT handler: a test runner's worker may start it with SIGINT
    # ignored, and an ignored disposition is inherited (Python then installs no handler)
    code = ("import signal, time, click\nsignal.signal(signal.SIGINT, signal.default_int_handler)\n"
            "from armguard.cli import main\n"
            "@main.command('nap')\ndef nap():\n    print('ready', flush=True)\n    time.sleep(60)\n"
            "main(['nap'])\n")
    child = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert child.stdout.readline().strip() == "ready"
        child.send_signal(signal.SIGINT)
        _, err = child.communicate(timeout=120)
    finally:
        if child.poll() is None:
            child.kill()
    assert child.returncode == ExitCode.INTERRUPTED and "interrupted" in err and "Traceback" not in err


@pytest.mark.parametrize("args", [("info", "ur5"), ("check", "hermes", "--q", "195,0,0,0,0,0", "--deg")])
def test_output_closed_early_is_141_never_a_verdict(args):
    """Output into a pipe whose reader has gone (``| head``): 141, not rich's or click's 1, which
    here means "unsafe" (the check of hermes at 195 deg is a collision, info has no verdict)."""
    child = subprocess.Popen([sys.executable, "-m", "armguard.cli", *args], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE)
    child.stdout.close()  # the reader goes before the command writes
    _, err = child.communicate(timeout=300)
    assert child.returncode == ExitCode.OUTPUT_CLOSED, err.decode()
    assert b"Traceback" not in err, err.decode()


def test_check_verdicts_map_to_their_codes():
    assert _run("check", "hermes").exit_code == ExitCode.OK
    hit = _run("check", "hermes", "--q", "195,0,0,0,0,0", "--deg")
    assert hit.exit_code == ExitCode.UNSAFE and "COLLISION" in hit.output
    spent = _run("check", "hermes", "--q", "195,0,0,0,0,0", "--deg", "--budget-us", "0")
    assert spent.exit_code == ExitCode.INCOMPLETE and "INCOMPLETE" in spent.output
    as_json = _run("check", "hermes", "--q", "195,0,0,0,0,0", "--deg", "--budget-us", "0", "--json")
    assert as_json.exit_code == ExitCode.INCOMPLETE
    doc = json.loads(as_json.output, parse_constant=lambda c: pytest.fail(f"{c} is not JSON"))  # strict JSON
    assert doc["status"] == "incomplete" and doc["not_evaluated"]
    assert "Infinity" not in as_json.output and "NaN" not in as_json.output


@pytest.mark.parametrize("statuses, code", [
    (["safe", "safe"], ExitCode.OK),
    (["safe", "collision"], ExitCode.UNSAFE),
    (["incomplete", "safe"], ExitCode.INCOMPLETE),
    (["incomplete", "collision"], ExitCode.UNSAFE),  # a collision found outranks a missing verdict
], ids=["all-safe", "one-collides", "one-incomplete", "incomplete-and-collision"])
def test_verify_exit_code(statuses, code):
    reports = [SimpleNamespace(status=VerificationStatus(s), safe=s == "safe") for s in statuses]
    assert verify_exit_code(reports) == code


def _commands(group, prefix=()):
    for name, cmd in group.commands.items():
        yield (*prefix, name), cmd
        if isinstance(cmd, click.Group):
            yield from _commands(cmd, (*prefix, name))


@pytest.mark.parametrize("path", [p for p, _ in _commands(main)] + [()], ids=lambda p: " ".join(p) or "armguard")
def test_every_help_lists_the_exit_codes(path):
    res = _run(*path, "--help")
    assert res.exit_code == 0, res.output
    text = res.output.split("Exit status:", 1)[1]
    rows = {int(line.split()[0]) for line in text.splitlines() if line.strip()[:1].isdigit()}
    assert {0, 2, 3, 4, 130} <= rows and rows <= {int(c) for c in ExitCode}
    if path in (("check",), ("verify",)):
        assert {1, 5} <= rows
    if path == ("compare",):  # 5: a backend refused some configurations
        assert {1, 5} <= rows
    if path == ("check-urdf",):
        assert 1 in rows and 5 not in rows


def _row(text: str, code: int) -> str:
    """The line of an "Exit status" list (``--help``) or the README's table row for ``code``."""
    return next(line for line in text.splitlines() if line.split()[:1] == [str(code)] or line.startswith(f"| {code} |"))


@pytest.mark.parametrize("code", [ExitCode.UNSAFE, ExitCode.INCOMPLETE])
def test_the_general_lists_name_every_command_that_exits_so(code):
    """``armguard --help`` and the README list exit 1 (and 5) with the commands that give it, as each command's
    own ``--help`` does: ``program run``, ``program calibrate``, ``cspace info``, ``check-srdf`` were missing."""
    group = _run("--help").output.split("Exit status:", 1)[1]
    readme = open(os.path.dirname(os.path.dirname(os.path.abspath(__file__))) + "/README.md", encoding="utf-8").read()
    table = readme.split("### Exit status", 1)[1].split("\n## ", 1)[0]
    users = []
    for path, cmd in _commands(main):
        if cmd.epilog and any(line.split()[:1] == [str(int(code))] for line in cmd.epilog.splitlines()):
            users.append(" ".join(path))
    assert users
    if code is ExitCode.UNSAFE:
        assert {"program run", "program calibrate", "cspace info", "check-srdf"} <= set(users)
    for name in users:
        assert name in _row(group, int(code)), (name, _row(group, int(code)))
        if code is ExitCode.UNSAFE:  # the README's row 5 speaks of "the check or verification" in general
            assert f"`{name}`" in _row(table, int(code)) or f"`{name} " in _row(table, int(code)), name


def test_readme_documents_the_codes():
    readme = (os.path.dirname(os.path.dirname(os.path.abspath(__file__))) + "/README.md")
    text = open(readme, encoding="utf-8").read()
    section = text.split("### Exit status", 1)[1].split("\n## ", 1)[0]
    for c in ExitCode:
        assert f"| {int(c)} " in section, c


# ------------------------------------------------------------------ every command: 3, 4, 130

_BAD = {
    "yaml": "armguard_scene: 1\nbodies: [unclosed\n",  # not YAML
    "urdf": "<robot name='x'><link name='a'>\n",  # not well-formed XML
    "srdf": "<robot name='x'><group\n",
    "agmap": "not a forbidden-values map\n",
    "npz": "not a terrain file\n",
}


def _bad_files(tmp_path):
    files = {}
    for ext, text in _BAD.items():  # each in its own folder (a URDF's SRDF is found beside it, or in ../srdf/)
        (tmp_path / f"in_{ext}").mkdir(exist_ok=True)
        files[ext] = tmp_path / f"in_{ext}" / f"bad.{ext}"
        files[ext].write_text(text)
    return files


def _edges_file(tmp_path):
    import numpy as np

    p = tmp_path / "edges.npz"
    np.savez(p, Q0=np.zeros((1, 6)), Q1=np.zeros((1, 6)))
    return p


def _file_cases(f, tmp_path):
    """Each command given one file it must refuse (``f[ext]``): (command path, argv, the file named)."""
    return [
        (("check",), ["check", f["yaml"]], f["yaml"]),
        (("check",), ["check", "rover", "--terrain", f["npz"]], f["npz"]),
        (("check-srdf",), ["check-srdf", "hermes", f["srdf"]], f["srdf"]),
        (("compare",), ["compare", f["urdf"], "--configs", "2", "--trajectory", "none"], f["urdf"]),
        (("console",), ["console", f["yaml"], "--port", "0"], f["yaml"]),
        (("demo",), ["demo", "--scene", f["yaml"], "--out", tmp_path / "demo"], f["yaml"]),
        (("fk",), ["fk", f["yaml"]], f["yaml"]),
        (("info",), ["info", f["yaml"]], f["yaml"]),
        (("srdf",), ["srdf", f["urdf"], "--out", tmp_path / "x.srdf"], f["urdf"]),
        (("verify",), ["verify", f["yaml"], "all"], f["yaml"]),
        (("verify",), ["verify", "hermes", f["yaml"]], f["yaml"]),
        (("edges",), ["edges", f["urdf"], _edges_file(tmp_path)], f["urdf"]),
        (("edges",), ["edges", "ur5", f["npz"]], f["npz"]),
        (("cspace", "build"), ["cspace", "build", f["yaml"], "--out", tmp_path / "m.agmap"], f["yaml"]),
        (("cspace", "info"), ["cspace", "info", f["agmap"]], f["agmap"]),
        (("cspace", "plot"), ["cspace", "plot", f["agmap"], "--q2", "30", "--out", tmp_path / "s.png"], f["agmap"]),
        (("program", "run"), ["program", "run", f["yaml"]], f["yaml"]),
        (("program", "export"), ["program", "export", f["yaml"], "--out", tmp_path / "p.py"], f["yaml"]),
        (("program", "calibrate"), ["program", "calibrate", f["yaml"], "--out", tmp_path / "c.yaml"], f["yaml"]),
    ]


_NO_FILE_INPUT = {("distance",)}  # commands that read no file
_LINTERS = {("check-urdf",)}  # "the model does not load" is its error-level finding (1), tested below


def _leaves():
    return [p for p, cmd in _commands(main) if not isinstance(cmd, click.Group)]


def test_every_command_refuses_a_bad_file_with_3(tmp_path):
    """A file that does not parse is one line naming it and exit status 3 -- never 1 (unsafe), never
    a traceback -- for every command that reads one."""
    cases = _file_cases(_bad_files(tmp_path), tmp_path)
    assert {c[0] for c in cases} | _NO_FILE_INPUT | _LINTERS == set(_leaves())  # a new command joins the table
    for _, argv, named in cases:
        res = _run(*argv)
        assert res.exit_code == ExitCode.INPUT, (argv, res.output)
        assert "Traceback" not in res.output and str(named) in res.output, (argv, res.output)
        errors = [ln for ln in res.output.splitlines() if ln.startswith("error:")]
        assert len(errors) == 1, (argv, res.output)
    assert not (tmp_path / "m.agmap").exists() and not (tmp_path / "s.png").exists()


@pytest.mark.parametrize("raised, code", [(KeyboardInterrupt, ExitCode.INTERRUPTED),
                                          (RuntimeError, ExitCode.INTERNAL),
                                          (lambda: armguard.SceneFileError("f.yaml", "line 3", "bad"), ExitCode.INPUT)],
                         ids=["ctrl-c", "internal", "refused"])
def test_every_command_maps_what_it_raises_to_one_code(tmp_path, monkeypatch, raised, code):
    """Whatever a command's body raises reaches the same mapping (130 / 4 / 3), for every command."""
    argv = {c[0]: c[1] for c in reversed(_file_cases(_bad_files(tmp_path), tmp_path))}
    argv[("distance",)] = ["distance"]
    argv[("check-urdf",)] = ["check-urdf", tmp_path / "in_urdf" / "bad.urdf"]

    def body(*a, **k):
        raise raised()

    for path in _leaves():
        cmd = main
        for name in path:
            cmd = cmd.commands[name]
        with monkeypatch.context() as m:
            m.setattr(cmd, "callback", body)
            res = _run(*argv[path], env={"ARMGUARD_DEBUG": ""})
        assert res.exit_code == code, (path, res.output)
        assert "Traceback" not in res.output


def test_check_urdf_reports_a_model_that_does_not_load_as_its_finding(tmp_path):
    f = _bad_files(tmp_path)["urdf"]
    res = _run("check-urdf", f, "--json")
    assert res.exit_code == ExitCode.UNSAFE, res.output
    doc = __import__("json").loads(res.output)
    assert doc["status"] == "errors" and any(x["check"] == "load" and str(f) in x["message"] for x in doc["findings"])
    assert _run("check-urdf", tmp_path / "missing.urdf").exit_code == ExitCode.INPUT


def test_output_closed_early_still_writes_the_files(tmp_path):
    """``armguard edges ... --out`` and ``armguard verify ... --report`` into a pipe whose reader has gone: 141,
    and the files written all the same (they were written after the verdicts were printed: lost)."""
    import numpy as np

    np.savez(tmp_path / "e.npz", Q0=np.zeros((2, 6)), Q1=np.full((2, 6), 0.2))
    for args, out in ((("edges", "ur5", str(tmp_path / "e.npz"), "--out", str(tmp_path / "r.npz")), tmp_path / "r.npz"),
                      (("verify", "hermes", "unstow", "--report", str(tmp_path / "r.json")), tmp_path / "r.json")):
        child = subprocess.Popen([sys.executable, "-m", "armguard.cli", *args], stdout=subprocess.PIPE,
                                 stderr=subprocess.PIPE)
        child.stdout.close()
        _, err = child.communicate(timeout=300)
        assert child.returncode == ExitCode.OUTPUT_CLOSED, err.decode()
        assert out.is_file() and out.stat().st_size > 100, args


@pytest.mark.parametrize("args", [
    ("compare", "hermes", "--configs", "10000000000", "--trajectory", "none"),  # MemoryError, exit 4
    ("compare", "hermes", "--configs", "99999999999999999999", "--trajectory", "none"),
    ("check-urdf", "hermes", "--configs", "10000000000"),
    ("srdf", "hermes", "--method", "sampled", "--samples", "99999999999999999999", "--out", "x.srdf"),  # ran on and on
    ("compare", "hermes", "--seed", "-1", "--configs", "3", "--trajectory", "none"),  # exit 3
    ("program", "calibrate", "examples/workmate/cell.yaml", "--out", "c.yaml", "--seed", "-1"),  # NumPy's ValueError, exit 4
])
def test_counts_beyond_reason_and_negative_seeds_are_usage_errors(args):
    res = _run(*args)
    assert res.exit_code == ExitCode.USAGE, res.output
    assert "Invalid value for '--" in res.output and "internal error" not in res.output


def test_the_srdf_progress_bar_goes_to_stderr():
    """On stdout it went into piped output, and ``check-srdf hermes | head -1`` exited 1 (the pipe closed under it)."""
    out = subprocess.run([sys.executable, "-m", "armguard", "check-srdf", "hermes"], capture_output=True, text=True,
                         timeout=300)
    assert out.returncode == 0, out.stderr
    assert "linting" not in out.stdout and "linting hermes.srdf" in out.stderr
