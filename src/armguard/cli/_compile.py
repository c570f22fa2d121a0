"""Compile the numba kernels before a command's real work, with a progress bar only when compiling.

numba compiles each kernel on its first call and caches it on disk, so the first run of a fresh
checkout spends its first seconds compiling and later runs only load the cache.
:func:`warm_up` calls each group of kernels once on a small built-in model, in stages, in a
worker thread, and listens to numba's ``numba:compile`` event (sent for a compilation, never for
a cache load): only when one starts does a rich progress bar say "compiling kernels (first run
only)", until the stages end.  The detector stage is the default backend's own (its optional
``warm_up(scene)`` and ``warm_up_leaves()``, see :class:`armguard.backends.Backend`): the
framework names no backend's kernels.
"""

from __future__ import annotations

import inspect
import threading
from contextlib import contextmanager

from .._numba_cache import signature

__all__ = ["warm_up", "leaves", "signature", "STAGES", "SIDE_STAGES", "POLL_S"]

POLL_S = 0.1
"""How often the main thread looks whether a compilation has started (s)."""


def _compile_listener(flag: list):
    from numba.core import event

    class _Listener(event.Listener):
        def on_start(self, ev) -> None:
            flag[0] = True

        def on_end(self, ev) -> None:
            pass

    return _Listener()


def _geometry() -> None:
    import numpy as np

    from ..geometry import Box, Capsule, ConvexPolyhedron, Sphere, distance

    cap = Capsule([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], 0.1)
    shapes = [Sphere([0.0, 2.0, 0.0], 0.1), Box(center=[0.5, 0.5, 0.0], half_extents=[0.2, 0.2, 0.2]),
              ConvexPolyhedron(np.array([[0, 0, 1], [1, 0, 1], [0, 1, 1], [0, 0, 2.0]]))]
    for s in shapes:
        distance(cap, s)


def _scene():
    from ..scene import load_scene

    return load_scene("puma560")


def _backend():
    """The default backend (``$ARMGUARD_BACKEND`` > ``armguard.toml`` > ``"analytic"``), as
    ``Detector(scene)`` picks it."""
    from ..backends import get_backend, resolve

    return get_backend(resolve(None, None)[0])


def _detector() -> None:
    sc = _scene()
    warm = getattr(_backend(), "warm_up", None)
    if warm is not None:  # the backend compiles its own kernels (the analytic one: its fused Detector and Checker)
        if _side_wait[0] is not None and "wait" in inspect.signature(warm).parameters:
            warm(sc, wait=_side_wait[0])  # it waits for the kernels the side process compiles
        else:
            warm(sc)
        return
    import numpy as np

    from ..detect import Detector

    det = Detector(sc, threshold=0.05)
    q = sc.flat_q(sc.default_q())
    det.check(q)
    det.check_many(np.tile(q, (4, 1)))


def _verifier() -> None:
    from ..verify import Verifier

    sc = _scene()
    name, traj = next(iter(sc.trajectories.items()))
    Verifier(sc, robot=traj.robot_name).verify(traj, name=name)


# ---- the backend's largest leaf kernels, compiled ahead of its chain in two processes at once
#
# A backend may name leaf kernels that its first call would otherwise compile one after another
# (``Backend.warm_up_leaves()``: ``(main, side)`` or ``(main, side, after)``, tuples of ``(module,
# function, signature codes)``; the analytic backend's: ``armguard_analytic._engine._warm``).
# Compiled first, with the signatures its chain calls them with, they are in numba's on-disk cache
# when the chain reaches them; ``after`` (kernels calling both lists' leaves) compiles in the second
# process once the first reports ``main`` done.  Codes: F1/F2 float64 C arrays (1-D/2-D), I1/I2
# int64 ones, f float64, i int64, b boolean.
def leaves() -> tuple:
    """``(main, side, after)``: the default backend's leaf kernels (``warm_up_leaves``; a backend
    that gives ``(main, side)`` has no ``after``), else ``((), (), ())``."""
    plan = getattr(_backend(), "warm_up_leaves", None)
    got = tuple(plan()) if plan is not None else ()
    return tuple(got) + ((),) * (3 - len(got))


def _compile_leaves(plan, report=None) -> None:
    import importlib

    for module, name, codes in plan:
        getattr(importlib.import_module(module), name).compile(signature(codes))
        if report is not None:
            report(name)


def _leaves_main() -> None:
    _compile_leaves(leaves()[0])


def _leaves_side() -> None:
    _compile_leaves(leaves()[1])


def _leaves_after() -> None:
    """The ``after`` kernels (they call kernels of both ``main`` and ``side``), in this process."""
    _compile_leaves(leaves()[2])


def _side_after() -> None:
    """The side process's ``after`` stage: wait until the main process reports ``_leaves_main``
    done on this process's stdin (or closes it), then compile the ``after`` kernels, reporting each
    one's name on stdout as it is compiled (the main process's backend ``warm_up`` waits for them)."""
    import sys

    for line in sys.stdin:
        if line.strip() == "_leaves_main":
            break
    _compile_leaves(leaves()[2], report=lambda name: print(name, flush=True))


STAGES = (("pair kernels", _leaves_main), ("geometry kernels", _geometry), ("detector kernels", _detector),
          ("verifier kernels", _verifier))
"""The warm-up stages: (label, function), in order; a compilation starts at once in the first."""
SIDE_STAGES = ("_leaves_side", "_side_after")
"""Stages compiled in a second process beside the others when compiling starts (names of this
module's functions, in order): on two cores both processes compile at once; each writes numba's
on-disk cache and the other loads what it finds there.  The side process reports each stage's
end (and each ``after`` kernel) on its stdout; a main stage listed in :data:`SIDE_WAITS` first
waits for the side stage it needs, and a main stage of the same name as a side stage is skipped.
The main process reports each of its stages' end on the side process's stdin (``_side_after``
waits for ``_leaves_main``: the ``after`` kernels call the main process's leaves)."""
SIDE_WAITS = {"_detector": "_leaves_side"}
"""Main stage -> the side stage it waits for (its kernels' callees), when a side process runs."""
SIDE_WAIT_S = 600.0
"""The longest a main stage waits for the side process (s); then it compiles what it needs itself."""


GC_THRESHOLDS = (50_000, 20, 20)
"""The garbage collector's thresholds while kernels compile (Python's: 700, 10, 10).  numba's
compiler makes millions of short-lived objects, and at Python's thresholds the collector walks
the whole heap (every module, every type numba has inferred) again and again.  With these, and
the heap as it is when compiling starts frozen (never walked), a kernel compiles ~10-20 % faster
for a little more peak memory; with the collector off, a little faster still for ~2x the memory
(``python -m bench compile``, ``docs/performance.md``)."""


@contextmanager
def _compiling_gc():
    """The collector tuned for compiling (:data:`GC_THRESHOLDS`, the heap so far frozen) inside the
    block; the thresholds restored and the frozen objects handed back to it after.  A process that
    froze objects of its own (``gc.freeze``) keeps them frozen: then only the thresholds change."""
    import gc

    old, ours = gc.get_threshold(), gc.get_freeze_count() == 0
    if ours:
        gc.freeze()
    gc.set_threshold(*GC_THRESHOLDS)
    try:
        yield
    finally:
        gc.set_threshold(*old)
        if ours:
            gc.unfreeze()


_side_wait = [None]
"""While a side process runs: ``wait(name)``, blocking until it reports ``name`` (or ends, or
:data:`SIDE_WAIT_S` passes); handed to a backend ``warm_up`` that takes ``wait``."""


def _spawn_side(names):
    """Start a process compiling the stages ``names`` (None when there are none or it cannot start);
    it prints each stage's name on its stdout when that stage ends, and reads the main process's
    reports on its stdin."""
    import subprocess
    import sys

    if not names:
        return None
    code = ("from armguard.cli import _compile as c\nwith c._compiling_gc():\n"
            + "".join(f"    c.{n}(); print({n!r}, flush=True)\n" for n in names))
    try:
        return subprocess.Popen([sys.executable, "-c", code], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                stderr=subprocess.DEVNULL)
    except OSError:
        return None


def _tell(child, fname: str | None) -> None:
    """Write ``fname`` as a line on the side process's stdin, or close it (``None``); a process
    that ended: nothing."""
    try:
        if fname is None:
            child.stdin.close()
        else:
            child.stdin.write((fname + "\n").encode())
            child.stdin.flush()
    except (OSError, ValueError, AttributeError):
        pass


def _wait_for(child, name: str, seen: set, timeout_s: float) -> None:
    """Block until the side process ``child`` reports stage ``name`` done (or ends, or ``timeout_s``).

    Its stdout is read unbuffered (``os.read`` on the pipe once ``select`` says it has data), so a
    report already written is never left in a buffer while the wait goes on."""
    import os
    import select
    import time

    fd = child.stdout.fileno()
    pending = getattr(child, "_armguard_pending", "")
    t_end = time.monotonic() + timeout_s
    while name not in seen:
        left = t_end - time.monotonic()
        if left <= 0.0:
            break  # it takes too long: whatever it has not compiled compiles here
        try:
            ready, _, _ = select.select([fd], [], [], left)
        except (OSError, ValueError):  # no select on this pipe: a blocking read
            ready = [fd]
        if not ready:
            break
        chunk = os.read(fd, 4096)
        if not chunk:  # it ended (or failed): whatever it did not compile compiles here
            break
        pending += chunk.decode("utf-8", "replace")
        *lines, pending = pending.split("\n")
        seen.update(ln.strip() for ln in lines)
    child._armguard_pending = pending


def warm_up(stages=STAGES, *, console=None, side=SIDE_STAGES, waits=None) -> bool:
    """Run ``stages``; while numba compiles, show a progress bar (on ``console``, stderr by default).

    When a compilation starts, the stages named in ``side`` (:data:`SIDE_STAGES`) are compiled in
    a second process at the same time; a stage here of the same name is skipped, and one named in
    ``waits`` (:data:`SIDE_WAITS`) first waits for the side stage it needs.  Each stage's end here
    is reported on the side process's stdin, which is closed when the stages here end (a side stage
    waiting for a report goes on then); while it runs, a backend ``warm_up`` that takes ``wait`` is
    handed one (:data:`_side_wait`).  The bar lasts until both processes end (a side process that
    fails only costs its time: the kernels compile here when first called).  Returns whether
    anything was compiled.  An exception in a stage is raised here (the side process is stopped).
    """
    from numba.core import event
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    done, error, compiling = [], [], [False]
    label = [stages[0][0] if stages else ""]
    side = tuple(side or ())
    waits = dict(SIDE_WAITS if waits is None else waits)
    names = {getattr(fn, "__name__", "") for _, fn in stages}
    # a side process only when it has work that one of these stages would otherwise do
    side = side if (names & set(side)) or (names & set(waits)) else ()
    child, reported, told, lock = [], set(), [], threading.Lock()

    def tell(fname: str | None) -> None:
        """Report a main stage's end to the side process (now, or when it starts); ``None``: this
        process's stages are over (its stdin is closed: a side stage waiting for a report goes on)."""
        with lock:
            told.append(fname)
            if child and child[0] is not None:
                _tell(child[0], fname)

    def work() -> None:
        try:
            for name, fn in stages:
                fname = getattr(fn, "__name__", "")
                running = child and child[0] is not None
                if running and fname in side:
                    done.append(name)
                    continue
                if running and fname in waits:
                    label[0] = f"{name} (waiting for the pair kernels)"
                    _wait_for(child[0], waits[fname], reported, SIDE_WAIT_S)
                label[0] = name
                fn()
                done.append(name)
                tell(fname)
        except BaseException as exc:  # handed to the caller's thread
            error.append(exc)
        finally:
            tell(None)

    listener = _compile_listener(compiling)
    event.register("numba:compile", listener)
    try:
        with _compiling_gc():  # the collector tuned for compiling (the side process tunes its own)
            th = threading.Thread(target=work, name="armguard-warm-up", daemon=True)
            th.start()
            while th.is_alive() and not compiling[0]:
                th.join(POLL_S)
            if compiling[0] and th.is_alive():
                with lock:
                    child.append(_spawn_side(side))
                    if child[0] is not None:
                        for fname in told:
                            _tell(child[0], fname)
                        _side_wait[0] = lambda kernel: _wait_for(child[0], kernel, reported, SIDE_WAIT_S)
            if compiling[0] and (th.is_alive() or (child and child[0] is not None)):
                console = console or Console(stderr=True)
                with Progress(TextColumn("compiling kernels (first run only): {task.description}"), BarColumn(),
                              MofNCompleteColumn(), TimeElapsedColumn(), console=console) as bar:
                    task = bar.add_task(label[0], total=len(stages))
                    while th.is_alive() or (child and child[0] is not None and child[0].poll() is None):
                        th.join(POLL_S)
                        if error and child and child[0] is not None and child[0].poll() is None:
                            child[0].kill()  # a stage failed here: its error is raised, nothing more compiles
                        bar.update(task, completed=len(done),
                                   description=label[0] if th.is_alive() else "the second process's kernels")
                    bar.update(task, completed=len(done), description="done")
            th.join()
    finally:
        event.unregister("numba:compile", listener)
        _side_wait[0] = None
        if child and child[0] is not None:
            for pipe in (child[0].stdin, child[0].stdout):
                if pipe is not None:
                    try:
                        pipe.close()
                    except OSError:
                        pass
    if error:
        raise error[0]
    return compiling[0]
