"""The detector's kernels compile from an empty numba cache (a fresh clone's first run).

numba's on-disk cache hides compilation failures: a kernel that once compiled loads from the
cache even after an edit that makes LLVM crash when it compiles from scratch (seen with numba's
``_nrt=False`` on functions that link the convex kernels: a segfault in LLVM's code generator,
see :mod:`armguard_analytic._engine._step`).  This test compiles every detector entry point in a fresh
process with a fresh, empty cache directory and checks the process exits normally and computes
the same answers as this (possibly warm-cached) process.

The process compiles the way a first run does (``armguard.cli._compile``): the leaf kernels first,
with the signatures the analytic backend's warm-up plan gives them (``warm_up_leaves``: the leaves of both
processes, then the kernels above them the second process compiles), then the detector's entry points.  It records which
kernels the chain still compiles: a planned leaf among them means its planned signature no
longer matches the chain's call, and the first run's two processes would compile it twice.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import numpy as np

from armguard.backends import get_backend
from armguard.detect import Detector
from armguard.scene import load_scene

_SCRIPT = textwrap.dedent(
    """
    import json, sys
    import numpy as np
    from numba.core import event
    from armguard.cli import _compile as plan
    from armguard.detect import Detector
    from armguard.scene import load_scene

    plan._leaves_main()
    plan._leaves_side()
    plan._leaves_after()
    compiled = []

    class Listener(event.Listener):
        def on_start(self, ev):
            d = ev.data["dispatcher"]
            compiled.append((d.py_func.__module__, d.py_func.__name__))

        def on_end(self, ev):
            pass

    event.register("numba:compile", Listener())
    scene = load_scene("ranger")
    det = Detector(scene, threshold=0.05, active="left_arm")
    q = np.asarray(json.loads(sys.argv[1]))
    out = {
        "check": det.check(q).nearest.distance,
        "lazy": det.check(q, lazy=True).status.value,
        "anytime": det.check(q, budget_us=1e6).status.value,
        "many": det.check_many(q[None, :]).min_distance.tolist(),
        "yesno": det.collides_many(q[None, :]).tolist(),
        "brute": det.check_many_bruteforce(q[None, :]).min_distance.tolist(),
        "pairs": det.pair_distances(q).distance.tolist(),
        "compiled": compiled,
    }
    print(json.dumps(out))
    """
)


def test_detector_kernels_compile_from_an_empty_cache(tmp_path):
    scene = load_scene("ranger")
    q = np.zeros(len(scene.joint_names))
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba-cache"))
    res = subprocess.run([sys.executable, "-X", "faulthandler", "-c", _SCRIPT, json.dumps(q.tolist())],
                         capture_output=True, text=True, env=env, timeout=900)
    assert res.returncode == 0, f"cold compile failed (exit {res.returncode}):\n{res.stderr[-4000:]}"
    got = json.loads(res.stdout.strip().splitlines()[-1])
    det = Detector(scene, threshold=0.05, active="left_arm")
    assert got["check"] == det.check(q).nearest.distance
    assert got["lazy"] == det.check(q, lazy=True).status.value
    assert got["anytime"] == det.check(q, budget_us=1e6).status.value
    assert got["many"] == det.check_many(q[None, :]).min_distance.tolist()
    assert got["yesno"] == det.collides_many(q[None, :]).tolist()
    assert got["brute"] == det.check_many_bruteforce(q[None, :]).min_distance.tolist()
    assert got["pairs"] == det.pair_distances(q).distance.tolist()
    main, side, after = get_backend("analytic").warm_up_leaves()  # what the subprocess compiled first (the default backend)
    planned = {(m, n) for m, n, _ in main + side + after}
    assert planned
    again = planned & {tuple(x) for x in got["compiled"]}
    assert not again, f"the warm-up plan's signatures no longer match the detector's calls of {sorted(again)}"
    assert ("armguard_analytic._engine._entry", "detect_entry") in {tuple(x) for x in got["compiled"]}  # the listener saw the chain
