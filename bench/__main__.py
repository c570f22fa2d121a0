"""Run the benchmarks and rewrite ``docs/performance.md``.

Usage: ``python -m bench [NAME ...]`` (default: all).  Each benchmark module defines
``TITLE`` and ``run(quick: bool) -> str`` returning a Markdown section with its table; its
peers (python-fcl, coal, pybullet, MuJoCo where they install) are measured in the same run.
Sections of benchmarks not run this time are kept from the previous file.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import importlib
import os
import platform
import re
import sys
from pathlib import Path

BENCHES = ["pairwise", "kinematics", "scene", "detector", "verify", "edges", "backends", "robots", "pair_profile", "terrain", "uncertainty", "clip", "cspace", "harness", "agreement", "paper_fidelity", "paper_hermes", "seeds", "avoidance", "srdf", "sweep", "console", "compile"]
DOC = Path(__file__).resolve().parent.parent / "docs" / "performance.md"
_SECTION = re.compile(r"^<!-- bench:(\w+) -->$.*?^<!-- /bench:\1 -->$", re.S | re.M)


def _machine() -> str:
    try:
        cpu = next(
            line.split(":", 1)[1].strip()
            for line in open("/proc/cpuinfo", encoding="utf-8")
            if line.startswith("model name")
        )
    except (OSError, StopIteration):
        cpu = platform.processor() or "unknown CPU"
    return f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m bench")
    ap.add_argument("names", nargs="*", help=f"benchmarks to run (default: all of {BENCHES})")
    ap.add_argument("--quick", action="store_true", help="fewer repetitions (smoke run)")
    args = ap.parse_args(argv)
    names = args.names or [b for b in BENCHES if importlib.util.find_spec(f"bench.{b}")]
    old = DOC.read_text(encoding="utf-8") if DOC.exists() else ""
    sections = {m.group(1): m.group(0) for m in _SECTION.finditer(old)}
    for name in names:
        mod = importlib.import_module(f"bench.{name}")
        print(f"== {name}: {mod.TITLE}", flush=True)
        body = mod.run(quick=args.quick)
        print(body, flush=True)
        stamp = _dt.date.today().isoformat()
        quick = " --quick" if args.quick else ""  # the figures' own command
        sections[name] = (
            f"<!-- bench:{name} -->\n## {mod.TITLE}\n\nReproduce: `.venv/bin/python -m bench {name}{quick}` "
            f"(measured {stamp}; {_machine()}).\n\n{body.strip()}\n<!-- /bench:{name} -->"
        )
    order = [b for b in BENCHES if b in sections] + [b for b in sections if b not in BENCHES]
    head = (
        "# Performance\n\n"
        "Written by `make bench` (`python -m bench`); every table compares armguard with its peers "
        "measured in the same run on the same machine. Times are medians over repeated runs; "
        "these machines are shared and noisy, so read ratios rather than absolute numbers.\n\n"
    )
    DOC.parent.mkdir(exist_ok=True)
    DOC.write_text(head + "\n\n".join(sections[b] for b in order) + "\n", encoding="utf-8")
    print(f"wrote {DOC}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
