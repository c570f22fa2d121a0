"""Outputs are written whole or not at all (armguard._io), and the commands that write them say so
in one line with exit status 3 (or 130 when interrupted), never a traceback, never "written".

Unwritable targets: a path under a regular file, a FIFO (os.mkfifo), a folder, /proc, and a full
disk simulated by making ``os.write`` raise ENOSPC (the only writer in armguard._io) -- no disk is
ever filled.
"""

from __future__ import annotations

import errno
import json
import os
import shutil
import sys
import tempfile
from pathlib import Path

import pytest
from click.testing import CliRunner

from armguard import OutputError
from armguard import _io
from armguard._io import atomic_write, output_set
from armguard.cli import ExitCode, main

fifo_only = pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs here")


def _full_disk(monkeypatch, after: int = 0):
    """``os.write`` accepts ``after`` calls, then fails as a full file system does."""
    real = os.write
    calls = [0]

    def write(fd, data):
        calls[0] += 1
        if calls[0] > after:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real(fd, data)

    monkeypatch.setattr(_io.os, "write", write)


def _leftovers(folder):
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("."))


# ------------------------------------------------------------------ one file

def test_atomic_write_replaces_whole(tmp_path):
    p = tmp_path / "a.json"
    atomic_write(p, "old")
    assert atomic_write(p, b"new bytes") == p and p.read_bytes() == b"new bytes"
    atomic_write(p, lambda f: f.write(b"from a writer"))
    assert p.read_bytes() == b"from a writer" and _leftovers(tmp_path) == []
    assert oct(p.stat().st_mode & 0o777) == oct(0o666 & ~_umask())


def test_a_replaced_file_keeps_its_permissions(tmp_path):
    """A report made private (0600) came back 0644 after it was rewritten: readable by every user."""
    p = tmp_path / "report.json"
    atomic_write(p, "old")
    for mode in (0o600, 0o755):
        os.chmod(p, mode)
        atomic_write(p, "new")
        assert oct(p.stat().st_mode & 0o777) == oct(mode) and p.read_text() == "new"


def _umask():
    m = os.umask(0)
    os.umask(m)
    return m


def test_short_writes_are_continued(tmp_path, monkeypatch):
    real = os.write
    monkeypatch.setattr(_io.os, "write", lambda fd, data: real(fd, bytes(data[:3])))
    p = tmp_path / "x.bin"
    blob = bytes(range(256)) * 5
    atomic_write(p, blob)
    assert p.read_bytes() == blob


def test_full_disk_leaves_the_old_file(tmp_path, monkeypatch):
    p = tmp_path / "map.agmap"
    p.write_bytes(b"previous")
    _full_disk(monkeypatch)
    with pytest.raises(OutputError) as exc:
        atomic_write(p, b"x" * 100_000)
    assert str(exc.value) == f"cannot write {p}: {os.strerror(errno.ENOSPC)}"
    assert p.read_bytes() == b"previous" and _leftovers(tmp_path) == []


def test_under_a_regular_file(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(OutputError, match=f"cannot write {blocker / 'out.png'}"):
        atomic_write(blocker / "out.png", b"png")
    with pytest.raises(OutputError, match=f"cannot write {blocker / 'sub' / 'out.png'}"):
        atomic_write(blocker / "sub" / "out.png", b"png", parents=True)
    for parents in (False, True):  # one wording, which names the file in the way (it said "Not a directory")
        with pytest.raises(OutputError) as e:
            atomic_write(blocker / "sub" / "out.png", b"png", parents=parents)
        assert f"{blocker} exists and is not a folder" in str(e.value)
    assert blocker.read_text() == "x"


@fifo_only
def test_a_fifo_or_folder_is_refused_not_replaced(tmp_path):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    with pytest.raises(OutputError, match="it exists and is a FIFO, not a regular file"):
        atomic_write(fifo, b"data")
    assert fifo.is_fifo()
    (tmp_path / "dir").mkdir()
    with pytest.raises(OutputError, match="is a folder"):
        atomic_write(tmp_path / "dir", b"data")


def test_a_device_is_refused():
    if not os.path.exists("/dev/null"):
        pytest.skip("no /dev/null")
    with pytest.raises(OutputError, match="is a device"):
        atomic_write("/dev/null", b"data")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc is Linux's")
def test_proc_is_refused():
    with pytest.raises(OutputError, match="cannot"):
        atomic_write("/proc/armguard-cannot/x.json", b"{}", parents=True)


def test_symlink_writes_its_target(tmp_path):
    real = tmp_path / "real.json"
    real.write_text("old")
    link = tmp_path / "link.json"
    link.symlink_to(real)
    atomic_write(link, "new")
    assert link.is_symlink() and real.read_text() == "new"


# ------------------------------------------------------------------ a set of files

def _previous_set(folder):
    folder.mkdir()
    (folder / "compare.json").write_text("old json")
    (folder / "scatter.png").write_text("old plot")
    (folder / "mine.txt").write_text("not an output")


def test_set_interrupted_leaves_the_previous_set(tmp_path):
    out = tmp_path / "out"
    _previous_set(out)
    with pytest.raises(KeyboardInterrupt):
        with output_set(out) as staging:
            atomic_write(staging / "compare.json", "new json")
            raise KeyboardInterrupt  # before the plots
    assert (out / "compare.json").read_text() == "old json" and (out / "scatter.png").read_text() == "old plot"
    assert _leftovers(out) == []


def test_set_replaces_all_and_removes_the_stale_ones(tmp_path):
    out = tmp_path / "out"
    _previous_set(out)
    with output_set(out, stale=("compare.json", "scatter.png", "../mine.txt")) as staging:
        atomic_write(staging / "compare.json", "new json")
        atomic_write(staging / "timing.png", "new plot")
    assert sorted(p.name for p in out.iterdir()) == ["compare.json", "mine.txt", "timing.png"]
    assert (out / "compare.json").read_text() == "new json"


def test_a_set_with_a_subfolder_moves_its_files_first(tmp_path, monkeypatch):
    """Files staged in a subfolder go to that subfolder (made when missing), before the files above
    them (a URDF arrives after the meshes it names); a file at the subfolder's name is refused
    before anything moves."""
    out = tmp_path / "out"
    moved = []
    real = os.replace
    def replace(a, b):  # the set's moves (not atomic_write's own renames inside the staging folder)
        if ".armguard-" not in str(b):
            moved.append(os.path.relpath(b, tmp_path))
        return real(a, b)

    monkeypatch.setattr(_io.os, "replace", replace)
    with output_set(out) as staging:
        atomic_write(staging / "robot.urdf", "urdf")
        (staging / "meshes").mkdir()
        atomic_write(staging / "meshes" / "b.obj", "b")
        atomic_write(staging / "meshes" / "a.obj", "a")
    assert moved == ["out/meshes/a.obj", "out/meshes/b.obj", "out/robot.urdf"]
    assert (out / "meshes" / "a.obj").read_text() == "a" and (out / "robot.urdf").read_text() == "urdf"
    assert _leftovers(out) == []
    other = tmp_path / "other"
    other.mkdir()
    (other / "meshes").write_text("a file")
    moved.clear()
    with pytest.raises(OutputError, match="meshes: it exists and is not a folder; nothing was replaced"):
        with output_set(other) as staging:
            atomic_write(staging / "robot.urdf", "urdf")
            (staging / "meshes").mkdir()
            atomic_write(staging / "meshes" / "a.obj", "a")
    assert moved == [] and sorted(p.name for p in other.iterdir()) == ["meshes"]


@fifo_only
def test_set_with_a_fifo_target_moves_nothing(tmp_path):
    out = tmp_path / "out"
    _previous_set(out)
    os.mkfifo(out / "timing.png")
    with pytest.raises(OutputError, match="FIFO"):
        with output_set(out) as staging:
            atomic_write(staging / "compare.json", "new json")
            atomic_write(staging / "timing.png", "new plot")
    assert (out / "compare.json").read_text() == "old json" and (out / "timing.png").is_fifo()
    assert _leftovers(out) == []


def test_set_under_a_regular_file(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(OutputError, match=f"cannot create the folder {blocker / 'out'}: "):
        with output_set(blocker / "out"):
            pass


# ------------------------------------------------------------------ the commands

def _one_line_error(res, *words):
    assert res.exit_code == ExitCode.INPUT, res.output
    assert "Traceback" not in res.output and "wrote" not in res.output
    last = [ln for ln in res.output.splitlines() if ln.strip()][-1]
    assert last.startswith("error: ")
    for w in words:
        assert w in last, (w, last)


@pytest.fixture(scope="module")
def small_map(tmp_path_factory):
    out = tmp_path_factory.mktemp("map") / "hermes.agmap"
    r = CliRunner().invoke(main, ["cspace", "build", "hermes", "--resolution", "30deg", "--max-depth", "0",
                                  "--out", str(out)])
    assert r.exit_code == 0, r.output
    return out


@fifo_only
def test_cspace_build_refuses_a_fifo_before_building(tmp_path):
    fifo = tmp_path / "map.agmap"
    os.mkfifo(fifo)
    r = CliRunner().invoke(main, ["cspace", "build", "hermes", "--resolution", "30deg", "--max-depth", "0",
                                  "--out", str(fifo)])
    _one_line_error(r, str(fifo), "FIFO")
    assert fifo.is_fifo() and not (tmp_path / "map.agmap.partial").exists()


def test_cspace_build_under_a_file_and_on_a_full_disk(tmp_path, monkeypatch):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    args = ["cspace", "build", "hermes", "--resolution", "30deg", "--max-depth", "0", "--out"]
    _one_line_error(CliRunner().invoke(main, args + [str(blocker / "m.agmap")]), str(blocker))
    out = tmp_path / "m.agmap"
    _full_disk(monkeypatch)
    r = CliRunner().invoke(main, args + [str(out)])
    _one_line_error(r, str(out), os.strerror(errno.ENOSPC))
    assert not out.exists()  # not reported written, and not there


def test_cspace_plot_outputs(small_map, tmp_path, monkeypatch):
    args = ["cspace", "plot", str(small_map), "--q2", "30", "--out"]
    blocker = tmp_path / "file"
    blocker.write_text("x")
    _one_line_error(CliRunner().invoke(main, args + [str(blocker / "s.png")]), str(blocker / "s.png"))
    if hasattr(os, "mkfifo"):
        os.mkfifo(tmp_path / "pipe.png")
        _one_line_error(CliRunner().invoke(main, args + [str(tmp_path / "pipe.png")]), "FIFO")
        assert (tmp_path / "pipe.png").is_fifo()
    png = tmp_path / "s.png"
    png.write_bytes(b"previous")
    with monkeypatch.context() as m:
        _full_disk(m)
        _one_line_error(CliRunner().invoke(main, args + [str(png)]), str(png), os.strerror(errno.ENOSPC))
    assert png.read_bytes() == b"previous"
    r = CliRunner().invoke(main, args + [str(png)])
    assert r.exit_code == 0 and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


_COMPARE = ["compare", "gmf_s480", "--backends", "analytic,coal", "--configs", "8", "--trajectory", "none"]


def test_compare_writes_its_outputs_as_a_set(tmp_path, monkeypatch):
    out = tmp_path / "out"
    r = CliRunner().invoke(main, _COMPARE + ["--out", str(out)], terminal_width=200)
    assert r.exit_code == 0, r.output
    first = json.loads((out / "compare.json").read_text())
    assert sorted(first["outputs"]) == sorted(p.name for p in out.iterdir())
    assert any(n.endswith(".png") for n in first["outputs"])
    before = {p.name: p.read_bytes() for p in out.iterdir()}

    import armguard.harness._plots as plots

    real = plots.write_plots

    def interrupted(comp, folder):  # the first plots written, then Ctrl-C
        real(comp, folder)
        raise KeyboardInterrupt

    with monkeypatch.context() as m:
        m.setattr(plots, "write_plots", interrupted)
        r = CliRunner().invoke(main, _COMPARE + ["--seed", "1", "--out", str(out)], terminal_width=200)
    assert r.exit_code == ExitCode.INTERRUPTED, r.output
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before  # the previous set, whole

    with monkeypatch.context() as m:
        _full_disk(m)
        r = CliRunner().invoke(main, _COMPARE + ["--seed", "1", "--out", str(out)], terminal_width=200)
    _one_line_error(r, str(out), os.strerror(errno.ENOSPC))
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before

    r = CliRunner().invoke(main, _COMPARE + ["--seed", "1", "--no-plots", "--out", str(out)], terminal_width=200)
    assert r.exit_code == 0, r.output
    assert sorted(p.name for p in out.iterdir()) == ["compare.json"]  # the previous run's plots went with it
    assert json.loads((out / "compare.json").read_text())["outputs"] == ["compare.json"]


def test_compare_out_under_a_file(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    r = CliRunner().invoke(main, _COMPARE + ["--no-plots", "--out", str(blocker / "out")], terminal_width=200)
    _one_line_error(r, str(blocker / "out"))


# ------------------------------------------------------------------ devices, /proc, the build journal

_BUILD = ["cspace", "build", "hermes", "--resolution", "30deg", "--max-depth", "0", "--out"]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc and /dev/full are Linux's")
@pytest.mark.parametrize("target", ["/dev/null", "/dev/full", "/proc/armguard-cannot/x"])
def test_outputs_to_a_device_or_proc_are_refused(small_map, target):
    if target.startswith("/dev") and not os.path.exists(target):
        pytest.skip(f"no {target}")
    _one_line_error(CliRunner().invoke(main, _BUILD + [target]), target.rsplit("/", 1)[0] if "proc" in target else target)
    _one_line_error(CliRunner().invoke(main, ["cspace", "plot", str(small_map), "--q2", "30", "--out", target]),
                    target.rsplit("/", 1)[0] if "proc" in target else target)
    _one_line_error(CliRunner().invoke(main, _COMPARE + ["--no-plots", "--out", target], terminal_width=200), target)
    if target.startswith("/dev"):
        assert not stat_is_regular(target)  # still the device


def stat_is_regular(path) -> bool:
    import stat

    return stat.S_ISREG(os.stat(path).st_mode)


class _FullFile:
    """A journal file on a full disk: ``room`` writes are accepted, then ENOSPC (what a real file
    object raises at write or flush time)."""

    def __init__(self, f, room):
        self._f, self._room = f, [room]

    def write(self, data):
        if self._room[0] <= 0:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        self._room[0] -= 1
        return self._f.write(data)

    def __getattr__(self, name):
        return getattr(self._f, name)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self._f.close()


def _journal_disk(monkeypatch, room):
    """The build journal's files (opened for writing in armguard.cspace._format) accept ``room`` writes in all."""
    import builtins

    import armguard.cspace._format as fmt

    left = [room]

    def fake_open(path, mode="r", *a, **k):
        f = builtins.open(path, mode, *a, **k)
        if "w" in mode or "a" in mode:
            ff = _FullFile(f, left[0])
            ff._room = left  # shared by every file of the journal
            return ff
        return f

    monkeypatch.setattr(fmt, "open", fake_open, raising=False)


@pytest.mark.parametrize("room", [0, 3], ids=["journal-header", "journal-record"])
def test_cspace_build_journal_on_a_full_disk(tmp_path, monkeypatch, room):
    """The journal is written before the map: a full disk there is the journal's one-line error, no
    map, and (when not even its header fits) no empty journal that a later build would refuse."""
    out = tmp_path / "m.agmap"
    with monkeypatch.context() as m:
        _journal_disk(m, room)
        r = CliRunner().invoke(main, _BUILD + [str(out)])
    _one_line_error(r, f"cannot write the build journal {out}.partial", os.strerror(errno.ENOSPC))
    assert not out.exists()
    assert (tmp_path / "m.agmap.partial").exists() == (room > 0)
    r = CliRunner().invoke(main, _BUILD + [str(out)])  # space again: built (resumed past a cut record)
    assert r.exit_code == 0 and "wrote" in r.output and out.exists(), r.output
    assert not (tmp_path / "m.agmap.partial").exists()


def test_a_set_file_that_cannot_be_written_is_named_as_its_output(tmp_path, monkeypatch):
    out = tmp_path / "out"
    _previous_set(out)
    _full_disk(monkeypatch)
    with pytest.raises(OutputError) as exc:
        with output_set(out) as staging:
            atomic_write(staging / "compare.json", "new json")
    assert str(exc.value) == f"cannot write {out / 'compare.json'}: {os.strerror(errno.ENOSPC)}"
    assert (out / "compare.json").read_text() == "old json" and _leftovers(out) == []


def test_ctrl_c_while_the_set_moves_in_waits_for_the_whole_set(tmp_path, monkeypatch):
    """A real SIGINT during the renames: every file of the new set is moved in, then KeyboardInterrupt."""
    import signal

    if not hasattr(signal, "SIGINT") or not hasattr(os, "kill"):
        pytest.skip("no SIGINT")
    out = tmp_path / "out"
    _previous_set(out)
    real = os.replace
    calls = []

    def replace(src, dst):
        if os.path.dirname(dst) != str(out):
            return real(src, dst)  # a staged file's own rename (atomic_write)
        calls.append(dst)
        if len(calls) == 1:
            os.kill(os.getpid(), signal.SIGINT)  # Ctrl-C after the first rename has begun
        return real(src, dst)

    monkeypatch.setattr(_io.os, "replace", replace)
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises(KeyboardInterrupt):
            with output_set(out, stale=("compare.json", "scatter.png")) as staging:
                atomic_write(staging / "compare.json", "new json")
                atomic_write(staging / "timing.png", "new plot")
    finally:
        signal.signal(signal.SIGINT, previous)
    assert len(calls) >= 2  # the second rename ran after the signal arrived
    assert sorted(p.name for p in out.iterdir()) == ["compare.json", "mine.txt", "timing.png"]
    assert (out / "compare.json").read_text() == "new json" and (out / "timing.png").read_text() == "new plot"


@fifo_only
def test_compare_refuses_a_fifo_among_its_outputs(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    os.mkfifo(out / "compare.json")
    (out / "scatter_analytic_coal.png").write_bytes(b"previous")
    r = CliRunner().invoke(main, _COMPARE + ["--no-plots", "--out", str(out)], terminal_width=200)  # never blocks on it
    _one_line_error(r, str(out / "compare.json"), "FIFO")
    assert (out / "compare.json").is_fifo() and (out / "scatter_analytic_coal.png").read_bytes() == b"previous"
    assert _leftovers(out) == []


def _tmpfs_namespace() -> bool:
    """A private mount namespace where a small tmpfs can be mounted (unshare -rm; Linux, no root needed
    where unprivileged user namespaces are allowed)."""
    import shutil as sh
    import subprocess

    if not sys.platform.startswith("linux") or sh.which("unshare") is None or sh.which("mount") is None:
        return False
    probe = subprocess.run(["unshare", "--user", "--map-root-user", "--mount", "sh", "-c",
                            "d=$(mktemp -d) && mount -t tmpfs -o size=64k tmpfs $d && umount $d && rmdir $d"],
                           capture_output=True, timeout=30)
    return probe.returncode == 0


_ON_A_FULL_DISK = r"""
import json, os, sys
from click.testing import CliRunner
from armguard.cli import main
full, small_map = sys.argv[1], sys.argv[2]
runs = {
    "build": ["cspace", "build", "hermes", "--resolution", "30deg", "--max-depth", "0", "--out", full + "/m.agmap"],
    "plot": ["cspace", "plot", small_map, "--q2", "30", "--out", full + "/s.png"],
    "compare": ["compare", "gmf_s480", "--backends", "analytic,coal", "--configs", "8", "--trajectory", "none",
                "--out", full + "/cmp"],
}
res = {k: (lambda r: [r.exit_code, r.output])(CliRunner().invoke(main, a, terminal_width=200)) for k, a in runs.items()}
res["left"] = sorted(os.path.relpath(os.path.join(d, f), full) for d, _, fs in os.walk(full) for f in fs)
print(json.dumps(res))
"""


@pytest.mark.skipif(not _tmpfs_namespace(), reason="no private tmpfs (unshare --user --mount) here")
def test_a_real_full_disk(small_map, tmp_path):
    """A 64 KiB tmpfs filled to the last byte in a private mount namespace: every command that writes
    says which file it could not write (exit 3) and leaves nothing but the filler."""
    import subprocess

    full = tmp_path / "full"
    full.mkdir()
    script = tmp_path / "run.py"
    script.write_text(_ON_A_FULL_DISK)
    shell = (f'mount -t tmpfs -o size=64k tmpfs "{full}" && (dd if=/dev/zero of="{full}/filler" bs=4k 2>/dev/null; '
             f'exec "{sys.executable}" "{script}" "{full}" "{small_map}")')
    p = subprocess.run(["unshare", "--user", "--map-root-user", "--mount", "sh", "-c", shell],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr[-2000:]
    res = json.loads(p.stdout.strip().splitlines()[-1])
    enospc = os.strerror(errno.ENOSPC)
    for name, what in [("build", f"cannot write the build journal {full}/m.agmap.partial"),
                       ("plot", f"cannot write {full}/s.png"), ("compare", f"cannot write {full}/cmp/")]:
        code, output = res[name]
        last = output.strip().splitlines()[-1]
        assert code == ExitCode.INPUT and last.startswith(f"error: {what}") and enospc in last, (name, output)
        assert "wrote" not in output and "Traceback" not in output
    assert res["left"] == ["filler"]  # no map, PNG, compare.json, journal or temporary file


def test_program_and_srdf_outputs_refuse_a_fifo_and_write_whole(tmp_path):
    """``program run --save``, ``program export --out`` and ``srdf --out`` write through atomic_write: a FIFO
    at the target is refused (exit 3) and left a FIFO; a regular target is replaced whole."""
    import os
    import stat

    from click.testing import CliRunner

    from armguard.cli import main

    fifo = tmp_path / "out.fifo"
    os.mkfifo(fifo)
    prog = Path(__file__).resolve().parent.parent / "examples" / "workmate" / "stack.yaml"
    runs = [["program", "export", str(prog), "--out", str(fifo)],
            ["srdf", "puma560", "--out", str(fifo), "--max-evaluations", "200"]]
    for args in runs:
        r = CliRunner().invoke(main, args)
        assert r.exit_code == 3, (args, r.output)
        assert stat.S_ISFIFO(os.stat(fifo).st_mode), args
    out = tmp_path / "stack.py"
    r = CliRunner().invoke(main, ["program", "export", str(prog), "--out", str(out)])
    assert r.exit_code == 0, r.output
    assert "armguard" in out.read_text() and not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


def test_a_folder_target_is_refused_like_every_unwritable_output_and_missing_folders_are_made(tmp_path):
    """A folder given as an output file exited 2 (click's path check) where the README says 3 (a target that is
    not a regular file is refused); ``srdf --out`` and ``program export --out`` refused a missing folder that
    ``verify --report`` and ``compare --out`` make."""
    from click.testing import CliRunner

    from armguard.cli import main

    folder = tmp_path / "adir"
    folder.mkdir()
    prog = Path(__file__).resolve().parent.parent / "examples" / "workmate" / "stack.yaml"
    for args in (["verify", "gmf_s480", "reach_over_fixture", "--report", str(folder)],
                 ["program", "export", str(prog), "--out", str(folder)],
                 ["srdf", "gmf_s480", "--out", str(folder), "--max-evaluations", "200"]):
        r = CliRunner().invoke(main, args)
        assert r.exit_code == 3 and "adir" in r.output and "folder" in r.output, (args, r.output)
        assert folder.is_dir() and not list(folder.iterdir())
    for args, made in ((["program", "export", str(prog), "--out", str(tmp_path / "new" / "stack.py")], "new/stack.py"),
                       (["srdf", "gmf_s480", "--out", str(tmp_path / "new2" / "g.srdf"), "--max-evaluations", "200"],
                        "new2/g.srdf")):
        r = CliRunner().invoke(main, args)
        assert r.exit_code == 0 and (tmp_path / made).is_file(), (args, r.output)


def test_the_file_mode_is_read_without_changing_the_umask(monkeypatch, tmp_path):
    """The umask was set to 0 and back to read it: for that moment a file another thread made was world-writable."""
    import os
    from pathlib import Path

    from armguard import _io

    if not Path("/proc/self/status").exists():
        pytest.skip("no /proc: the umask is read under a lock")
    old = os.umask(0o027)
    try:
        monkeypatch.setattr(os, "umask", lambda *a: (_ for _ in ()).throw(AssertionError("umask changed")))
        assert _io._mode() == 0o640
        _io.atomic_write(tmp_path / "f.txt", "x")
        assert (tmp_path / "f.txt").stat().st_mode & 0o777 == 0o640
    finally:
        monkeypatch.undo()
        os.umask(old)


def test_program_run_and_calibrate_refuse_an_unwritable_output_before_the_work(tmp_path, monkeypatch):
    """``program run --save`` and ``program calibrate --out`` ran the whole program (or calibration) and then
    found the output could not be written (exit 3, the result lost); ``verify``, ``edges`` and ``srdf``
    refuse first. Now they do too: nothing is run."""
    from click.testing import CliRunner

    import armguard.program as program
    from armguard.cli import main

    ran = []
    monkeypatch.setattr(program, "run_program", lambda *a, **k: ran.append("run"))
    monkeypatch.setattr(program, "calibrate_camera", lambda *a, **k: ran.append("calibrate"))
    (tmp_path / "afile").write_text("a file where a folder should be")
    blocked = tmp_path / "afile" / "out.json"
    examples = Path(__file__).resolve().parent.parent / "examples" / "workmate"
    for args in (["program", "run", str(examples / "stack.yaml"), "--save", str(blocked)],
                 ["program", "calibrate", str(examples / "cell.yaml"), "--out", str(blocked)]):
        r = CliRunner().invoke(main, args)
        assert r.exit_code == 3 and "afile" in r.output, (args, r.output)
    assert ran == []


def test_verify_says_which_outputs_it_wrote_before_one_that_cannot_be(tmp_path, monkeypatch):
    """verify with a report and a plot per trajectory stopped at the second plot (exit 3) without a word of the
    report and first plot it had written: the output set was mixed, the user left to guess.  A folder at the second
    plot's name is now refused before the work; a disk that fills at the second plot is said with what was written."""
    args = ["verify", "hermes", "unstow", "payload_sweep", "--report", str(tmp_path / "r.json"),
            "--plot", str(tmp_path / "pp.png")]
    (tmp_path / "pp_payload_sweep.png").mkdir()  # the second trajectory's plot: a folder, never replaced
    r = CliRunner().invoke(main, args)
    assert r.exit_code == ExitCode.INPUT and "pp_payload_sweep.png: it exists and is a folder" in r.output, r.output
    assert not (tmp_path / "r.json").exists() and not (tmp_path / "pp_unstow.png").exists()
    (tmp_path / "pp_payload_sweep.png").rmdir()
    n = [0]

    def full_at_the_third(fd, blob, real=_io._write_all):
        n[0] += 1
        if n[0] == 3:
            raise OSError(28, "No space left on device")
        real(fd, blob)

    monkeypatch.setattr(_io, "_write_all", full_at_the_third)
    r = CliRunner().invoke(main, args)
    assert r.exit_code == ExitCode.INPUT, r.output
    assert "pp_payload_sweep.png" in r.output and "written before it:" in r.output, r.output
    assert str(tmp_path / "r.json") in r.output and str(tmp_path / "pp_unstow.png") in r.output
    assert (tmp_path / "r.json").is_file() and (tmp_path / "pp_unstow.png").is_file()


def _second_file_system(tmp_path):
    other = Path(tempfile.mkdtemp(dir="/dev/shm")) if Path("/dev/shm").is_dir() else None
    if other is None or os.stat(other).st_dev == os.stat(tmp_path).st_dev:
        if other is not None:
            shutil.rmtree(other, ignore_errors=True)
        pytest.skip("no second file system here")
    return other


def test_a_set_member_linked_to_another_file_system_is_written_whole(tmp_path, monkeypatch):
    """compare --out: ``timing.png`` a link to a file on another file system; the renames moved the first files of
    the set, then failed ("Invalid cross-device link"): half new, half old.  A copy beside the linked file is made
    before anything moves, then every file is renamed into place; a copy that cannot be made replaces nothing."""
    other = _second_file_system(tmp_path)
    try:
        out = tmp_path / "out"
        out.mkdir()
        (out / "a.json").write_text("old a")
        (other / "b.png").write_text("old b")
        (out / "b.png").symlink_to(other / "b.png")
        with output_set(out) as staging:
            atomic_write(staging / "a.json", "new a")
            atomic_write(staging / "b.png", "new b")
        assert (out / "a.json").read_text() == "new a" and (other / "b.png").read_text() == "new b"
        assert (out / "b.png").is_symlink()
        assert sorted(p.name for p in out.iterdir()) == ["a.json", "b.png"] and sorted(p.name for p in other.iterdir()) == ["b.png"]

        def full(fd, blob):  # the other file system is full: the copy beside the link's target fails
            raise OSError(errno.ENOSPC, "No space left on device")

        with pytest.raises(OutputError, match=r"b\.png: No space left on device; nothing was replaced"):
            with output_set(out) as staging:
                atomic_write(staging / "a.json", "newer a")
                atomic_write(staging / "b.png", "newer b")
                monkeypatch.setattr(_io, "_write_all", full)
        assert sorted(p.name for p in other.iterdir()) == ["b.png"]  # the copy's temporary file removed
        assert (out / "a.json").read_text() == "new a" and (other / "b.png").read_text() == "new b"
        assert sorted(p.name for p in out.iterdir()) == ["a.json", "b.png"]  # no staging folder left
    finally:
        shutil.rmtree(other, ignore_errors=True)


def test_a_set_keeps_the_permissions_of_the_files_it_replaces(tmp_path):
    """A private 0600 file of a set came back 0644 (readable by all) when the set was written again."""
    out = tmp_path / "out"
    with output_set(out) as staging:
        atomic_write(staging / "a.json", "a")
        (staging / "meshes").mkdir()
        atomic_write(staging / "meshes" / "m.obj", "m")
    os.chmod(out / "a.json", 0o600)
    os.chmod(out / "meshes" / "m.obj", 0o640)
    with output_set(out) as staging:
        atomic_write(staging / "a.json", "a2")
        (staging / "meshes").mkdir()
        atomic_write(staging / "meshes" / "m.obj", "m2")
    assert (out / "a.json").read_text() == "a2" and (out / "meshes" / "m.obj").read_text() == "m2"
    assert oct(os.stat(out / "a.json").st_mode & 0o777) == oct(0o600)
    assert oct(os.stat(out / "meshes" / "m.obj").st_mode & 0o777) == oct(0o640)


def test_a_long_name_the_file_system_takes_is_written(tmp_path):
    """A 250-character name was refused ("File name too long"): the temporary and probe names around it passed 255."""
    from armguard._io import check_writable

    p = tmp_path / ("r" * 245 + ".json")
    assert len(p.name) == 250
    check_writable(p)
    atomic_write(p, "whole")
    assert p.read_text() == "whole" and sorted(x.name for x in tmp_path.iterdir()) == [p.name]
