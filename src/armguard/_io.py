"""Writing output files so that a crash, an interruption or a full disk cannot leave a lie.

One file (:func:`atomic_write`): the bytes go to a temporary file beside the target, every write's
count is checked, the file is flushed to the disk (``fsync``) and renamed over the target, so the
target is either the old file or the whole new one (pip's ``adjacent_tmp_file`` then ``replace``).
A set of files (:func:`output_set`): all are written into a temporary folder inside the target
folder, then moved into place one rename each with Ctrl-C held back, so an interrupted run leaves
the previous run's set whole, never a new file beside old ones.

A target that exists and is not a regular file (a folder, a FIFO, a device) is refused, as is a
folder that cannot be made; every failure is an :class:`~armguard._errors.OutputError` naming the
path and the reason.  ``os.write`` is the only writer here (tests simulate a full disk through it).
"""

from __future__ import annotations

import contextlib
import io
import os
import shutil
import signal
import stat
import tempfile
import threading
from pathlib import Path

from ._errors import OutputError

__all__ = ["atomic_write", "make_folder", "output_set", "check_not_input", "check_target", "check_writable", "figure_format",
           "save_figure"]


def _reason(exc: OSError) -> str:
    return exc.strerror or str(exc)


def _file_above(path: Path) -> Path:
    """The first of ``path``'s folders that exists as something other than a folder (else its parent)."""
    return next((p for p in path.parents if p.exists() and not p.is_dir()), path.parent)


def make_folder(folder) -> Path:
    """``folder`` (made with its parents when missing); OutputError when it cannot be (a path under a
    regular file, no permission, a read-only or full file system) or is not a folder."""
    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except FileExistsError:
        raise OutputError(f"cannot write into {folder}: it exists and is not a folder") from None
    except NotADirectoryError:  # a file above it: named
        raise OutputError(f"cannot create the folder {folder}: {_file_above(folder)} exists and is not a folder") from None
    except OSError as exc:
        raise OutputError(f"cannot create the folder {folder}: {_reason(exc)}") from None
    if not folder.is_dir():
        raise OutputError(f"cannot write into {folder}: it is not a folder")
    return folder


def check_target(path) -> Path:
    """``path`` as the file to replace: a symbolic link is followed (the file it names is written);
    OutputError when the target exists and is not a regular file (a folder, FIFO, device, socket)."""
    path = Path(path)
    if path.is_symlink():
        path = Path(os.path.realpath(path))
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        return path
    except NotADirectoryError:  # a file where a folder of the path should be: said as make_folder says it
        raise OutputError(f"cannot write {path}: {_file_above(path)} exists and is not a folder") from None
    except OSError as exc:
        raise OutputError(f"cannot write {path}: {_reason(exc)}") from None
    if not stat.S_ISREG(mode):
        kind = ("a folder" if stat.S_ISDIR(mode) else "a FIFO" if stat.S_ISFIFO(mode) else
                "a device" if stat.S_ISCHR(mode) or stat.S_ISBLK(mode) else "a socket" if stat.S_ISSOCK(mode)
                else "not a regular file")
        raise OutputError(f"cannot write {path}: it exists and is {kind}, not a regular file (not replaced)")
    return path


def check_not_input(path, inputs=()) -> None:
    """OutputError when ``path`` is one of the files ``inputs`` (the same file, by ``os.path.samefile``:
    another spelling or a link to it included): an output written over the file it was read from
    (``verify t.yaml --report t.yaml``, ``program export p.yaml --out p.yaml``) destroyed the input."""
    for inp in inputs:
        if inp is None:
            continue
        try:
            same = os.path.samefile(path, inp)
        except (OSError, ValueError, TypeError):  # either one not there (or not a path): not the same file
            same = False
        if same:
            raise OutputError(f"cannot write {path}: it is the input file {inp} (it would be replaced by the output); "
                              "name another file")


def check_writable(path, inputs=()) -> Path:
    """``path`` as :func:`check_target` gives it, once a file could be written where it goes: a temporary
    file made and removed in its folder, or, where that folder is missing (the write makes it), in the
    nearest folder above it that exists.  OutputError, naming the path and the reason, for a folder that
    is read-only, full or not ours, or a file where a folder of the path should be.  Nothing is left
    behind (no folder made).  For a command that computes for minutes before it writes: refused
    before the work, not after it (nothing computed is then lost).  ``inputs``: the files the command
    read, which ``path`` must not be (:func:`check_not_input`)."""
    check_not_input(path, inputs)
    target = check_target(path)
    folder = target.parent
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    if not folder.is_dir():
        raise OutputError(f"cannot write {path}: {folder} exists and is not a folder")
    try:
        fd, tmp = tempfile.mkstemp(prefix=_tmp_prefix(target), suffix=".probe", dir=folder)
    except OSError as exc:
        raise OutputError(f"cannot write {path}: {_reason(exc)}") from None
    os.close(fd)
    with contextlib.suppress(OSError):
        os.unlink(tmp)
    return target


def _data_bytes(data) -> bytes:
    if callable(data):  # a writer (matplotlib's savefig, np.save): into memory, then written here
        buf = io.BytesIO()
        data(buf)
        return buf.getvalue()
    if isinstance(data, str):
        return data.encode("utf-8")
    return bytes(data)


def _write_all(fd: int, blob: bytes) -> None:
    """Every byte of ``blob`` to ``fd``: a short write is continued, a write of 0 bytes is an error."""
    view = memoryview(blob)
    while len(view):
        n = os.write(fd, view)
        if n <= 0:
            raise OSError(0, "the file system accepted no bytes")
        view = view[n:]


def _fsync_folder(folder: Path) -> None:
    """Make a rename in ``folder`` durable (best effort: some file systems cannot open a folder)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _mode() -> int:
    """0o666 less the process's umask: read from /proc where it is (setting it to read it, as elsewhere, changes
    it for every thread for a moment: a file another thread makes then would be world-writable)."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return 0o666 & ~int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    with _UMASK_LOCK:
        umask = os.umask(0)
        os.umask(umask)
    return 0o666 & ~umask


_UMASK_LOCK = threading.Lock()


def _tmp_prefix(path: Path) -> str:
    """A temporary file's name start beside ``path``: its name cut to 64 characters (a name of 246 to 255, which the
    file system takes, was refused: the temporary name around it passed 255)."""
    return f".{path.name[:64]}."


def _write_file(path: Path, blob: bytes) -> None:
    """``blob`` into a new temporary file beside ``path``, synced, then renamed over ``path``."""
    fd, tmp = tempfile.mkstemp(prefix=_tmp_prefix(path), suffix=".tmp", dir=path.parent)
    try:
        try:
            _write_all(fd, blob)
            try:  # the replaced file's permissions kept (a private 0600 report came back 0644, readable by all)
                mode = stat.S_IMODE(os.stat(path).st_mode)
            except OSError:
                mode = _mode()  # a new file: mkstemp makes it 0600, a plainly opened file's permissions instead
            os.fchmod(fd, mode)
            os.fsync(fd)
        finally:
            os.close(fd)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def atomic_write(path, data, *, parents: bool = False) -> Path:
    """Write ``data`` to the file ``path`` all at once or not at all; returns ``path``.

    ``data``: bytes, text (UTF-8), or a callable given a binary file object to write into (e.g.
    ``lambda f: fig.savefig(f, format="png")``; it writes into memory first).  The folder must
    exist (:func:`make_folder`).  OutputError names the path and the reason when the folder or
    the file cannot be written (full disk, no permission, the target a FIFO or a folder); the
    previous file, if any, is then left as it was.  ``parents``: make the missing folders first."""
    if parents:
        try:
            make_folder(Path(path).parent)
        except OutputError as exc:
            raise OutputError(f"cannot write {path}: {exc}") from None
    path = check_target(path)
    blob = _data_bytes(data)
    if not path.parent.is_dir():
        why = "is not a folder" if path.parent.exists() else "does not exist"
        raise OutputError(f"cannot write {path}: the folder {path.parent} {why}")
    try:
        _write_file(path, blob)
    except OSError as exc:
        raise OutputError(f"cannot write {path}: {_reason(exc)}") from None
    _fsync_folder(path.parent)
    return path


def figure_format(path) -> str:
    """The plot format ``path``'s suffix names (``.png``, ``.pdf``, ``.svg``, ...; none: ``png``); a
    suffix matplotlib cannot write is an OutputError naming the path and the formats it can (checked
    before any work, so a typo does not cost a run or leave PNG bytes in a ``.pdf``)."""
    from matplotlib.backend_bases import FigureCanvasBase

    fmt = Path(path).suffix[1:].lower() or "png"
    supported = FigureCanvasBase.get_supported_filetypes()
    if fmt not in supported:
        raise OutputError(f"cannot write {path}: matplotlib writes no .{fmt} plots (it writes "
                          f"{', '.join('.' + k for k in sorted(supported))})")
    return fmt


def save_figure(fig, path, *, parents: bool = False, **savefig) -> Path:
    """A matplotlib Figure at ``path`` in the format of its suffix (:func:`figure_format`), all or nothing
    (:func:`atomic_write`); ``savefig``: more of ``Figure.savefig``'s options (dpi, bbox_inches)."""
    fmt = figure_format(path)
    return atomic_write(path, lambda f: fig.savefig(f, format=fmt, **savefig), parents=parents)


@contextlib.contextmanager
def _sigint_held():
    """Ctrl-C waits until the block ends (then raises KeyboardInterrupt); only in the main thread."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    got = []
    previous = signal.signal(signal.SIGINT, lambda signum, frame: got.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
    if got:
        raise KeyboardInterrupt


@contextlib.contextmanager
def output_set(folder, *, stale=()):
    """A staging folder to write a set of output files into; on leaving the block without an
    exception they replace their namesakes in ``folder`` (made when missing), and the files of
    ``folder`` named in ``stale`` (a previous run's set) that the new set lacks are removed.

    Files staged in subfolders (``staging / "meshes" / "a.obj"``) go to the same subfolders of
    ``folder`` (made when missing), and before the files above them: a file that names them (a
    URDF naming its meshes) never arrives before they do.  Any exception in the block (Ctrl-C
    included) removes the staging folder and leaves ``folder`` as it was.  The moves run with
    Ctrl-C held back; each is a rename within one file system (a target on another one, a link or
    a linked subfolder, gets a synced copy beside it first, before anything moves), and a replaced
    file keeps its permissions.  Write the staged files with :func:`atomic_write` (checked, synced).
    """
    folder = make_folder(folder)
    temps: list = []  # copies made beside targets on another file system, removed unless moved
    try:
        staging = Path(tempfile.mkdtemp(prefix=".armguard-", suffix=".partial", dir=folder))
    except OSError as exc:
        raise OutputError(f"cannot write into {folder}: {_reason(exc)}") from None
    try:
        yield staging
        # the staged files, those in subfolders first (deepest first), each level in name order
        names = sorted((p.relative_to(staging).as_posix() for p in staging.rglob("*") if not p.is_dir()),
                       key=lambda n: (-n.count("/"), n))
        subs = sorted({n.rsplit("/", 1)[0] for n in names if "/" in n})
        for sub in subs:
            if (folder / sub).exists() and not (folder / sub).is_dir():
                raise OutputError(f"cannot write into {folder / sub}: it exists and is not a folder; nothing was replaced")
        targets = [check_target(folder / n) for n in names]  # refuse before anything moves
        for sub in subs:  # made first: one under a folder linked elsewhere is on that file system
            make_folder(folder / sub)
        sources = _move_sources(staging, folder, names, targets, temps)
        with _sigint_held():
            for src, target in zip(sources, targets):
                os.replace(src, target)
            for name in stale:
                if name not in names and "/" not in name and name not in ("", ".", ".."):
                    old = folder / name
                    if old.is_file() and not old.is_symlink():
                        old.unlink()
            for parent in {t.parent for t in targets} | {folder}:
                _fsync_folder(parent)
    except OutputError as exc:
        if str(staging) not in str(exc):
            raise
        # a file that could not be staged, named as the output it was to be (the staging folder is gone)
        raise OutputError(str(exc).replace(str(staging), str(folder))) from None
    except OSError as exc:
        raise OutputError(f"cannot write into {folder}: {_reason(exc)}") from None
    finally:
        shutil.rmtree(staging, ignore_errors=True)
        for tmp in temps:
            with contextlib.suppress(OSError):
                os.unlink(tmp)


def _move_sources(staging: Path, folder: Path, names, targets, temps: list) -> list:
    """What :func:`output_set` renames onto each target: the staged file, given the replaced file's
    permissions (a private 0600 file came back 0644, readable by all); for a target on another file
    system than the staging folder (a link, a linked subfolder) a synced copy beside it, made here,
    before anything moves (a rename across file systems fails: the set was left half new)."""
    dev = os.stat(staging).st_dev
    out = []
    for n, t in zip(names, targets):
        src = staging / n
        try:
            mode = stat.S_IMODE(os.stat(t).st_mode)
        except FileNotFoundError:
            mode = None
        try:
            if os.stat(t.parent).st_dev == dev:
                if mode is not None:
                    os.chmod(src, mode)
                out.append(src)
                continue
            fd, tmp = tempfile.mkstemp(prefix=_tmp_prefix(t), suffix=".tmp", dir=t.parent)
            temps.append(tmp)
            try:
                _write_all(fd, src.read_bytes())
                os.fchmod(fd, mode if mode is not None else stat.S_IMODE(os.stat(src).st_mode))
                os.fsync(fd)
            finally:
                os.close(fd)
        except OSError as exc:
            raise OutputError(f"cannot write {folder / n}: {_reason(exc)}; nothing was replaced") from None
        out.append(Path(tmp))
    return out
