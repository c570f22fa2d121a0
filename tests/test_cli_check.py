"""``armguard check --deg`` and its exit codes, the scene schema's error listing, the warm-up message."""

from __future__ import annotations

import io
import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from armguard.cli import main

SCENE = str(Path(__file__).parent / "data" / "console_scene.yaml")
HOME_DEG = "-90,0,0,-90,0,0"


def _check(*args):
    return CliRunner().invoke(main, ["check", SCENE, *args])


def test_check_deg_clear_warning_collision_exit_codes():
    clear = _check("--q", HOME_DEG, "--deg", "--json")
    assert clear.exit_code == 0, clear.output
    assert json.loads(clear.stdout)["status"] == "clear"
    warn = _check("--q", HOME_DEG, "--deg", "--json", "--threshold", "2.0")  # everything within 2 m
    assert warn.exit_code == 0, warn.output
    assert json.loads(warn.stdout)["status"] == "warning"
    hit = _check("--q", "90,0,0,-90,0,0", "--deg", "--json")  # left link 2 through the post
    assert hit.exit_code == 1, hit.output
    data = json.loads(hit.stdout)
    assert data["status"] == "collision" and data["nearest"]["obstacle"] == "post"
    assert data["nearest"]["feature"] is None or set(data["nearest"]["feature"]) == {"kind", "index"}
    table = _check("--q", "90,0,0,-90,0,0", "--deg")
    assert table.exit_code == 1 and "COLLISION" in table.output


def test_check_deg_is_degrees_not_radians():
    # 90 (rad) is far outside joint 1's limits; 90 deg is in them
    rad = _check("--q", "90,0,0,-90,0,0")
    assert rad.exit_code == 2 and "left/joint1 = 90 rad" in rad.output
    assert "[-2.967059728, 2.967059728] rad" in rad.output


@pytest.mark.parametrize("q, words", [
    ("-300,0,0,-90,0,0", ["left/joint1 = -300 deg", "[-170, 170] deg"]),
    ("1,2", ["expected 6 values"]),
    ("a,b,c,d,e,f", ["comma-separated numbers"]),
    ("nan,0,0,0,0,0", ["finite"]),
])
def test_check_bad_input_exits_2(q, words):
    res = _check("--q", q, "--deg")
    assert res.exit_code == 2, res.output
    for w in words:
        assert w in res.output, res.output


def test_schema_error_lists_every_problem_with_the_misspelling_hint(tmp_path):
    text = Path(SCENE).read_text()
    text = text.replace("size: [0.2, 0.2, 0.6]", "sise: [0.2, 0.2, 0.6]")  # a misspelt required key
    text = text.replace("radius: 0.05}]\n      link2", "radius: -1}]\n      link2", 1)  # and a bad value
    text = text.replace("units: {angle: deg, length: m}", "units: {angle: deg, length: m}\ncolour: red")
    bad = tmp_path / "bad.yaml"
    bad.write_text(text)
    from armguard._errors import ArmguardError
    from armguard.scene import load_scene

    with pytest.raises(ArmguardError) as exc:
        load_scene(str(bad))
    msg = str(exc.value)
    assert "required key is missing" in msg
    assert "'sise'" in msg and "misspelling of 'size'" in msg
    assert "colour" in msg  # the unknown top-level key is listed too, not hidden behind "and 1 more"
    assert "more problem" in msg
    res = CliRunner().invoke(main, ["check", str(bad)])
    assert res.exit_code != 0 and "sise" in res.output


def _warm(stages):
    from rich.console import Console

    from armguard.cli._compile import warm_up

    buf = io.StringIO()
    compiled = warm_up(stages, console=Console(file=buf, force_terminal=False, width=120))
    return compiled, buf.getvalue()


def test_warm_up_message_only_when_compiling():
    import time

    import numba

    def fresh():  # a kernel numba has never seen: a real compilation, then the stage goes on a while
        f = numba.njit(cache=False)(lambda x: x * 2.0)
        assert f(1.5) == 3.0
        time.sleep(0.5)

    def quiet():
        time.sleep(0.5)

    compiled, out = _warm((("test kernels", fresh),))
    assert compiled and "compiling kernels (first run only)" in out
    compiled, out = _warm((("nothing to compile", quiet),))
    assert not compiled and out == ""


def test_waiting_for_the_side_process_ends_on_its_report_its_exit_or_the_timeout():
    import subprocess
    import sys
    import time

    from armguard.cli._compile import _wait_for

    def child(code):
        return subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE)

    seen = set()
    p = child("import time; print('other', flush=True); print('_leaves_side', flush=True); time.sleep(30)")
    t0 = time.monotonic()
    _wait_for(p, "_leaves_side", seen, 20.0)
    assert seen == {"other", "_leaves_side"} and time.monotonic() - t0 < 10.0
    p.kill()
    p = child("import time; time.sleep(30)")  # silent: the timeout ends the wait
    t0 = time.monotonic()
    _wait_for(p, "_leaves_side", set(), 0.5)
    assert 0.4 < time.monotonic() - t0 < 5.0
    p.kill()
    p = child("pass")  # ends without a word
    _wait_for(p, "_leaves_side", set(), 20.0)
    assert p.wait(5) == 0


def test_the_collector_is_tuned_only_while_compiling_and_restored_after():
    import gc

    from armguard.cli._compile import GC_THRESHOLDS, _compiling_gc, _spawn_side

    gc.unfreeze()
    before = gc.get_threshold()
    with pytest.raises(RuntimeError, match="inside"):
        with _compiling_gc():
            assert gc.get_threshold() == GC_THRESHOLDS
            assert gc.get_freeze_count() > 0  # the heap so far is not walked while compiling
            raise RuntimeError("a stage failed inside")
    assert gc.get_threshold() == before and gc.get_freeze_count() == 0
    gc.freeze()  # a host process that froze its own heap keeps it frozen
    try:
        frozen = gc.get_freeze_count()
        with _compiling_gc():
            assert gc.get_threshold() == GC_THRESHOLDS
        # still frozen (unfrozen, the count is 0); not == frozen: a frozen object freed meanwhile leaves the
        # permanent generation (a run under xdist saw 1533331 of 1533334)
        assert gc.get_threshold() == before and gc.get_freeze_count() > frozen // 2
    finally:
        gc.unfreeze()
    # the side process runs its stages in the same block and reports each one
    p = _spawn_side(("POLL_S.__class__",))  # a harmless call: float()
    assert p.stdout.read().decode().split() == ["POLL_S.__class__"]
    assert p.wait(60) == 0


def test_the_side_process_compiles_its_after_kernels_once_the_main_process_reports_its_leaves():
    import subprocess
    import sys
    import time

    from armguard.cli._compile import _tell

    # _side_after with the compile replaced by a report: nothing before "_leaves_main" arrives on stdin
    code = ("from armguard.cli import _compile as c\n"
            "c._compile_leaves = lambda plan, report=None: report('after')\n"
            "print('ready', flush=True)\nc._side_after()\n")
    p = subprocess.Popen([sys.executable, "-c", code], stdin=subprocess.PIPE, stdout=subprocess.PIPE)
    try:
        assert p.stdout.readline().strip() == b"ready"
        _tell(p, "_geometry")  # another stage's report: still waiting
        time.sleep(0.5)
        assert p.poll() is None
        _tell(p, "_leaves_main")
        assert p.stdout.readline().strip() == b"after"
        assert p.wait(30) == 0
    finally:
        p.kill()
    _tell(p, "_leaves_main")  # a process that ended: nothing happens
    p = subprocess.Popen([sys.executable, "-c", code], stdin=subprocess.PIPE, stdout=subprocess.PIPE)
    p.stdin.close()  # the main process ended: the side process goes on
    assert p.stdout.read().split() == [b"ready", b"after"]
    assert p.wait(30) == 0


def test_the_detector_stage_hands_the_side_wait_to_a_backend_that_takes_it(monkeypatch):
    from armguard.cli import _compile as c

    calls = []

    class Waits:
        def warm_up(self, scene, wait=None):
            calls.append(("waits", scene, wait))

    class Plain:
        def warm_up(self, scene):
            calls.append(("plain", scene))

    def wait(name):
        return None

    monkeypatch.setattr(c, "_scene", lambda: "scene")
    for backend in (Waits(), Plain()):
        monkeypatch.setattr(c, "_backend", lambda b=backend: b)
        monkeypatch.setattr(c, "_side_wait", [wait])
        c._detector()
        monkeypatch.setattr(c, "_side_wait", [None])  # no side process: no wait
        c._detector()
    assert calls == [("waits", "scene", wait), ("waits", "scene", None), ("plain", "scene"), ("plain", "scene")]
    # the plan of a backend that gives (main, side) only: no after kernels
    monkeypatch.setattr(c, "_backend", lambda: type("Two", (), {"warm_up_leaves": lambda self: ((1,), (2,))})())
    assert c.leaves() == ((1,), (2,), ())


def test_a_stage_that_fails_while_the_side_process_waits_for_it_is_raised_not_waited_on():
    import time

    from numba import njit
    from rich.console import Console

    from armguard.cli._compile import warm_up

    def failing():
        njit(lambda x: x + 1)(1)  # a compilation: the side process starts
        time.sleep(0.5)
        raise RuntimeError("the leaves failed")

    t0 = time.monotonic()
    with pytest.raises(RuntimeError, match="the leaves failed"):
        # the side stage waits for "_leaves_main", which never comes: the failed stage closes its stdin
        # and the side process is stopped
        warm_up((("pair kernels", failing),), console=Console(file=io.StringIO()), side=("_side_after",),
                waits={"failing": "never reported"})
    assert time.monotonic() - t0 < 60.0
