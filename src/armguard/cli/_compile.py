"""Compile the numba kernels before a command's real work, with a progress bar only when compiling.

numba compiles each kernel on its first call and caches it on disk, so the first run of a fresh
checkout spends its first seconds compiling and later runs only load the cache.
:func:`warm_up` calls each group of kernels once on a small built-in model, in stages, in a
worker thread, and listens to numba's ``numba:compile`` event (sent for a compilation, never for
a cache load): only when one starts does a rich progress bar say "compiling kernels (first run
only)", until the stages end.
"""

from __future__ import annotations

import threading

__all__ = ["warm_up", "STAGES", "SIDE_STAGES", "POLL_S"]

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


def _detector() -> None:
    import numpy as np

    from ..detect import Detector

    sc = _scene()
    det = Detector(sc, threshold=0.05)
    q = sc.flat_q(sc.default_q())
    det.check(q)
    det.check_many(np.tile(q, (4, 1)))


def _verifier() -> None:
    from ..verify import Verifier

    sc = _scene()
    name, traj = next(iter(sc.trajectories.items()))
    Verifier(sc, robot=traj.robot_name).verify(traj, name=name)


STAGES = (("detector kernels", _detector), ("verifier kernels", _verifier), ("geometry kernels", _geometry))
"""The warm-up stages: (label, function); the detector's first, so that a compilation starts at once
and the side stages (last here) are already compiling in their own process when they come up."""
SIDE_STAGES = ("_geometry",)
"""Stages compiled in a second process beside the others when compiling starts (names of this
module's functions): :func:`armguard.geometry.distance`'s pair kernels share nothing with the
detector's fused kernel, so on two cores both compile at once; each process writes numba's
on-disk cache and the main one then loads the side stages' kernels from it."""


def _spawn_side(names):
    """Start a process compiling the stages ``names`` (None when there are none or it cannot start)."""
    import subprocess
    import sys

    if not names:
        return None
    code = "from armguard.cli import _compile as c\n" + "".join(f"c.{n}()\n" for n in names)
    try:
        return subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    except OSError:
        return None


def warm_up(stages=STAGES, *, console=None, side=SIDE_STAGES) -> bool:
    """Run ``stages``; while numba compiles, show a progress bar (on ``console``, stderr by default).

    When a compilation starts, the stages named in ``side`` (:data:`SIDE_STAGES`) are compiled
    in a second process at the same time and skipped here; the bar lasts until both end (a
    side process that fails only costs its time: the kernels compile here when first called).
    Returns whether anything was compiled.  An exception in a stage is raised here.
    """
    from numba.core import event
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    done, error, compiling = [], [], [False]
    label = [stages[0][0] if stages else ""]

    side = tuple(side or ())
    skip = {getattr(fn, "__name__", "") for _, fn in stages} & set(side)
    child = []

    def work() -> None:
        try:
            for name, fn in stages:
                if getattr(fn, "__name__", "") in skip and child and child[0] is not None:
                    done.append(name)
                    continue
                label[0] = name
                fn()
                done.append(name)
        except BaseException as exc:  # handed to the caller's thread
            error.append(exc)

    listener = _compile_listener(compiling)
    event.register("numba:compile", listener)
    try:
        th = threading.Thread(target=work, name="armguard-warm-up", daemon=True)
        th.start()
        while th.is_alive() and not compiling[0]:
            th.join(POLL_S)
        if compiling[0] and th.is_alive():
            child.append(_spawn_side(sorted(skip)))
        if compiling[0] and (th.is_alive() or (child and child[0] is not None)):
            console = console or Console(stderr=True)
            with Progress(TextColumn("compiling kernels (first run only): {task.description}"), BarColumn(),
                          MofNCompleteColumn(), TimeElapsedColumn(), console=console) as bar:
                task = bar.add_task(label[0], total=len(stages))
                while th.is_alive() or (child and child[0] is not None and child[0].poll() is None):
                    th.join(POLL_S)
                    bar.update(task, completed=len(done), description=label[0] if th.is_alive() else "pair kernels")
                bar.update(task, completed=len(done), description="done")
        th.join()
    finally:
        event.unregister("numba:compile", listener)
    if error:
        raise error[0]
    return compiling[0]
