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

__all__ = ["warm_up", "STAGES", "POLL_S"]

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


STAGES = (("geometry kernels", _geometry), ("detector kernels", _detector), ("verifier kernels", _verifier))
"""The warm-up stages: (label, function)."""


def warm_up(stages=STAGES, *, console=None) -> bool:
    """Run ``stages``; while numba compiles, show a progress bar (on ``console``, stderr by default).

    Returns whether anything was compiled.  An exception in a stage is raised here.
    """
    from numba.core import event
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    done, error, compiling = [], [], [False]
    label = [stages[0][0] if stages else ""]

    def work() -> None:
        try:
            for name, fn in stages:
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
            console = console or Console(stderr=True)
            with Progress(TextColumn("compiling kernels (first run only): {task.description}"), BarColumn(),
                          MofNCompleteColumn(), TimeElapsedColumn(), console=console) as bar:
                task = bar.add_task(label[0], total=len(stages))
                while th.is_alive():
                    th.join(POLL_S)
                    bar.update(task, completed=len(done), description=label[0])
                bar.update(task, completed=len(done), description="done")
        th.join()
    finally:
        event.unregister("numba:compile", listener)
    if error:
        raise error[0]
    return compiling[0]
