"""The installed package, as a user gets it (``make smoke-wheel``; ``make test`` runs it after pytest).

Builds the sdist and the wheel from it (``uv build``: so MANIFEST.in and setup.py's data copy are
exercised), installs the wheel in a fresh virtual environment in a temp folder outside the
checkout, makes the installed package read-only, and from another folder: loads a built-in model,
lists the bundled backends, reads the reference data and runs ``armguard check ranger``.

numba kernels: a fresh install has no compiled kernels, and compiling them all takes minutes on a
busy machine.  The checkout's own kernel cache (``src/**`` and ``plugins/**/__pycache__/*.nbi|nbc``, written by the
test run before) is valid for the installed copy of each file when the bytes are the same: the
installed file is given its checkout twin's mtime (numba's cache is keyed by the source's
(mtime, size) and each kernel's bytecode) and the cache files are copied where
``$NUMBA_CACHE_DIR`` makes numba look for them.  A file that differs, or a cold checkout cache,
compiles as a user's first run would.  The report says how many kernels were compiled.

    .venv/bin/python tools/smoke_wheel.py [--keep]
"""

from __future__ import annotations

import argparse
import filecmp
import os
import shutil
import stat
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SOURCES = {"armguard": ROOT / "src" / "armguard", **{p.name: p for p in (ROOT / "plugins").glob("armguard_*")}}

CHECK_PY = """
import armguard
import armguard.backends
from armguard.harness import reference_dir, seed_data

m = armguard.load_model("hermes")
assert m.name == "hermes" and len(m.pairs) > 0, m
found = set(armguard.backends.available())
assert {"analytic", "clip", "coal", "fcl", "forbidden"} <= found, found
assert (reference_dir() / "models" / "hermes.json").is_file(), reference_dir()
assert seed_data("hermes")["model"]
print(f"hermes: {len(m.pairs)} pairs; backends {sorted(found)}; reference data in {reference_dir()}")
"""


def run(cmd, **kw) -> subprocess.CompletedProcess:
    return subprocess.run([str(c) for c in cmd], check=True, **kw)


def seed_kernel_cache(site: Path, cache_dir: Path) -> int:
    """Copy the checkout's numba cache for each installed file identical to its checkout twin; returns the
    number of cache files copied."""
    from numba.core.caching import _CacheLocator

    copied = 0
    for pkg, src_root in SOURCES.items():
        for installed in (site / pkg).rglob("*.py"):
            twin = src_root / installed.relative_to(site / pkg)
            cached = sorted((twin.parent / "__pycache__").glob(f"{twin.stem}.*.nb[ic]"))
            if not cached or not twin.is_file() or not filecmp.cmp(installed, twin, shallow=False):
                continue
            st = twin.stat()
            os.utime(installed, ns=(st.st_atime_ns, st.st_mtime_ns))
            dest = cache_dir / _CacheLocator.get_suitable_cache_subpath(str(installed))
            dest.mkdir(parents=True, exist_ok=True)
            for f in cached:
                shutil.copy2(f, dest / f.name)
                copied += 1
    return copied


def set_writable(paths, writable: bool) -> None:
    for top in paths:
        for p in [top, *top.rglob("*")]:
            mode = p.stat().st_mode
            p.chmod(mode | stat.S_IWUSR if writable else mode & ~(stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--keep", action="store_true", help="Keep the temp folder (its path is printed).")
    args = ap.parse_args(argv)
    uv, python = ROOT / ".venv" / "bin" / "uv", ROOT / ".venv" / "bin" / "python"
    work = Path(tempfile.mkdtemp(prefix="armguard-smoke-")).resolve()
    if ROOT in work.parents:
        raise SystemExit(f"smoke-wheel: {work} lies inside the checkout; set TMPDIR to a folder outside it")
    times, site, pkgs = {}, None, []
    try:
        t = time.perf_counter()
        run([uv, "build", "-q", "--python", python, "-o", work / "dist", ROOT])
        times["uv build (sdist, wheel from it)"] = time.perf_counter() - t
        wheel = next((work / "dist").glob("armguard-*.whl"))

        t = time.perf_counter()
        venv = work / "venv"
        run([uv, "venv", "-q", "--python", python, venv])
        run([uv, "pip", "install", "-q", "--python", venv / "bin" / "python", wheel])
        times["fresh venv + install the wheel"] = time.perf_counter() - t

        site = Path(run([venv / "bin" / "python", "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                        capture_output=True, text=True).stdout.strip())
        pkgs = [site / p for p in SOURCES]
        missing = [p.name for p in pkgs if not p.is_dir()]
        if missing:
            raise SystemExit(f"smoke-wheel: the wheel lacks {missing}")
        cache = work / "numba"
        seeded = seed_kernel_cache(site, cache)
        started = time.time()
        set_writable(pkgs, False)  # nothing may write into the installed package

        elsewhere = work / "elsewhere"
        elsewhere.mkdir()
        env = {k: v for k, v in os.environ.items() if k not in ("ARMGUARD_MODELS", "ARMGUARD_REFERENCE", "PYTHONPATH")}
        env["NUMBA_CACHE_DIR"] = str(cache)
        env["ARMGUARD_CACHE_DIR"] = str(work / "armguard-cache")  # the hull cache: never the user's own
        t = time.perf_counter()
        out = run([venv / "bin" / "python", "-c", CHECK_PY], cwd=elsewhere, env=env, capture_output=True, text=True)
        times["load_model('hermes'), backends"] = time.perf_counter() - t
        print("  " + out.stdout.strip())

        t = time.perf_counter()
        res = subprocess.run([venv / "bin" / "armguard", "check", "ranger"], cwd=elsewhere, env=env,
                             capture_output=True, text=True)
        times["armguard check ranger"] = time.perf_counter() - t
        print("  " + (res.stdout.strip().splitlines() or ["(no output)"])[0])
        if res.returncode != 0 or "status:" not in res.stdout:
            print(res.stdout, res.stderr, sep="\n")
            raise SystemExit(f"smoke-wheel: armguard check ranger failed (exit {res.returncode})")
        compiled = sum(f.stat().st_mtime >= started for f in cache.rglob("*.nbc"))
        for what, s in times.items():
            print(f"  {what:34s} {s:6.1f} s")
        print(f"  kernel cache: {seeded} files from the checkout, {compiled} kernels compiled in the smoke")
        print(f"smoke-wheel: ok ({sum(times.values()):.0f} s, in {work})")
        return 0
    finally:
        if pkgs:
            set_writable([p for p in pkgs if p.exists()], True)
        if args.keep:
            print(f"smoke-wheel: kept {work}")
        else:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
