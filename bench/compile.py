"""The first run's kernel compile (``make run`` on a fresh clone compiles every numba kernel once).

Each figure is a fresh process with an empty numba cache directory of its own, so nothing is
loaded from the checkout's cache:

* the whole warm-up ``armguard.cli._compile.warm_up()`` (two processes, the leaf plan of
  ``armguard_analytic._engine._warm``), wall time and the first process's peak memory;
* ``convex_convex_fast`` alone, with Python's collector thresholds, with the warm-up's tuning
  (``_compiling_gc``: ``GC_THRESHOLDS``, the heap frozen) and with the collector off;
* ``gjk_dir_rel`` alone, and how much of that is numba's IR inlining of the GJK body
  (``numba.core.inline_closurecall.InlineWorker.inline_ir``: it deep-copies the callee's IR block
  by block, each block taking the whole variable scope along), the cost ``_gjk`` avoids by being
  built from the body's own function instead of a wrapper that inlines it.

No peer compiles anything ahead of time (coal, python-fcl, pybullet and MuJoCo ship compiled
code), so there is no peer column.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile

TITLE = "First-run kernel compile (empty numba cache)"

_PRE = """
import json, resource, sys, time
from armguard.cli import _compile as c
"""
_WARM = _PRE + """
t = time.perf_counter()
c.warm_up(console=None)
out = {"s": time.perf_counter() - t}
"""
_CCF = _PRE + """
import gc
from contextlib import nullcontext
mode = sys.argv[1]
ctx = {"python": nullcontext(), "tuned": c._compiling_gc(), "off": nullcontext()}[mode]
if mode == "off":
    gc.disable()
import armguard.geometry._pair_epa as e
t = time.perf_counter()
with ctx:
    e.convex_convex_fast.compile(c.signature("F2 F2 F2 I1 I2 f F2 F2 F2 I1 I2 f F1 F1 f f f i f f"))
out = {"s": time.perf_counter() - t}
"""
_INLINE = _PRE + """
import numba.core.inline_closurecall as icc
spent = {}
orig = icc.InlineWorker.inline_ir
def timed(self, caller_ir, block, i, callee_ir, *args, **kw):
    t0 = time.perf_counter()
    try:
        return orig(self, caller_ir, block, i, callee_ir, *args, **kw)
    finally:
        name = callee_ir.func_id.func_qualname
        spent[name] = spent.get(name, 0.0) + time.perf_counter() - t0
icc.InlineWorker.inline_ir = timed
import armguard.geometry._pair_gjk as g
t = time.perf_counter()
with c._compiling_gc():
    g.gjk_dir_rel.compile(c.signature("F2 I1 I1 F2 I1 I1 F1 f f f f f f f f i F1 f I1"))
out = {"s": time.perf_counter() - t, "body": spent.get("_gjk_body", 0.0), "all": sum(spent.values())}
"""
_POST = """
out["rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
print(json.dumps(out))
"""


def _fresh(code: str, *args: str) -> dict:
    """Run ``code`` in a new process with an empty numba cache; its printed JSON result."""
    with tempfile.TemporaryDirectory(prefix="armguard-ncache-") as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        res = subprocess.run([sys.executable, "-c", code + _POST, *args], capture_output=True, text=True, env=env,
                             timeout=1800)
    if res.returncode != 0:
        raise RuntimeError(f"bench compile: the child process failed:\n{res.stderr[-3000:]}")
    return json.loads(res.stdout.strip().splitlines()[-1])


def run(quick: bool) -> str:
    warm = [_fresh(_WARM) for _ in range(1 if quick else 2)]
    ccf = {m: _fresh(_CCF, m) for m in ("python", "tuned", "off")}
    inl = _fresh(_INLINE)
    load = ", ".join(f"{x:.1f}" for x in os.getloadavg())
    lines = [
        "| what compiles | wall time | peak memory (that process) |",
        "|---|---:|---:|",
    ]
    for i, w in enumerate(warm, 1):
        lines.append(f"| the whole warm-up (`armguard.cli._compile.warm_up()`, two processes), run {i} "
                     f"| {w['s']:.1f} s | {w['rss_mb']:.0f} MB |")
    names = {"python": "Python's collector thresholds", "tuned": "the warm-up's tuning (`_compiling_gc`)",
             "off": "the collector off"}
    for m, r in ccf.items():
        lines.append(f"| `convex_convex_fast` alone, {names[m]} | {r['s']:.1f} s | {r['rss_mb']:.0f} MB |")
    lines.append(f"| `gjk_dir_rel` alone (the GJK body inlined once) | {inl['s']:.1f} s | {inl['rss_mb']:.0f} MB |")
    lines += [
        "",
        f"Of `gjk_dir_rel`'s compile, numba's IR inlining took {inl['all']:.1f} s, {inl['body']:.1f} s of it "
        "inlining the GJK body `_gjk_body` (224 blocks): the cost each signature of `_gjk` paid while it was a "
        "wrapper inlining the body, and no longer pays now that it is compiled from the body's own function. "
        "Compile times of the same kernels vary from run to run by more than the machine's load explains; "
        "read the warm-up rows together.",
        "",
        f"Machine load while measuring (1/5/15-minute load average on {os.cpu_count()} cores): {load}.",
    ]
    return "\n".join(lines)
